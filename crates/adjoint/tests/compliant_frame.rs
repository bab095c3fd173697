//! Depth control through the instrument's frame (docs/theory.md §13.7) for laws with
//! internal variables and with Coulomb friction: the forward sensitivities
//! (`Adjoint::sensitivities_compliant`) of every law, and the adjoint gradient
//! (`Adjoint::gradient_compliant`) with friction, against central differences of the
//! direct solver's own compliant runs (`DirectSolver::run_compliant`) over a
//! load-hold-unload of the machine depth; `J^T w` of the sensitivities against the
//! adjoint.
//!
//! References: each step's force and punch depth differenced per law parameter (central,
//! relative step 1e-5, residual tolerance 1e-12), and the adjoint's frame entries
//! (`Cf`, `vd`, `h0`) differenced through the cost `J = sum w_i F_i`. With friction a
//! central difference is kept only where its +-h runs hold every contact set and
//! stick/slip status of the base run (docs/theory.md §8; the steps tried are 1e-5, 1e-6,
//! 1e-4 in that order), and every case has at least 3 sticking and 3 slipping node-steps
//! (counted and asserted). With the later ties' depth term switched off
//! (`Adjoint::set_friction_depth_term(false)`) the frictional adjoint misses the
//! differences: the tests can fail.

mod common;

use common::{finite_model, finite_model_with_friction, small_model, statuses};
use indentify_adjoint::check::relative_difference;
use indentify_adjoint::{Adjoint, FrameIndex};
use indentify_contact::{
    ContactKind, DirectSolver, Frame, Model, Schedule, SolverOptions, Trajectory,
};
use indentify_laws::{Hardening, LawMaterial, Material, Maxwell, Plastic, Prony, Rate};
use indentify_testkit::{coulomb as friction, depth_lhu, recording, sphere1 as sphere, weights};

fn opts(record: bool) -> SolverOptions {
    recording(record, 1e-12)
}

/// Machine depth: ramp to `h` mm, hold, unload to `0.6 h`, `steps` steps per segment
/// (1 s each).
fn lhu(h: f64, steps: usize) -> Schedule {
    depth_lhu(h, 0.6 * h, steps)
}

const MAXWELL: [f64; 3] = [1e5, 0.3, 2e5];
const PRONY: [f64; 6] = [1e5, 0.3, 0.3, 0.2, 0.2, 2.0];
const POWER_NORTON: [f64; 6] = [1e5, 0.3, 500.0, 0.2, 1500.0, 5.0];

fn frame(cf: f64) -> Frame {
    Frame {
        compliance: cf,
        drift: 1e-3,
        offset: 1e-3,
    }
}

/// The sticking and slipping node-steps (off the axis) of a run.
fn stick_slip(m: &Model, traj: &Trajectory) -> (usize, usize) {
    let (mut stick, mut slip) = (0, 0);
    for s in &traj.steps {
        for (&k, &st) in s.active.iter().zip(&s.slip) {
            if m.candidate_r(k as usize) > 0.0 {
                if st == 0 {
                    stick += 1;
                } else {
                    slip += 1;
                }
            }
        }
    }
    (stick, slip)
}

/// What one case measured (worst relative differences): the sensitivities' force and
/// depth columns against central differences, the adjoint against central differences
/// (law and frame parameters), `J^T w` against the adjoint; stick and slip node-steps.
#[derive(Debug, Default)]
struct Outcome {
    sens_f: f64,
    sens_h: f64,
    adjoint: f64,
    jt_w: f64,
    stick: usize,
    slip: usize,
}

/// A compliant run at the law parameters `c` through `fr` (fields when `record`).
fn run(
    solver: &mut DirectSolver,
    mat: &dyn Material,
    c: &[f64],
    s: &Schedule,
    fr: &Frame,
    record: bool,
) -> Trajectory {
    solver.run_compliant(mat, c, s, fr, &opts(record)).unwrap()
}

/// A central difference of `f` over a run at `p` (law parameters, then `Cf`, `vd`, `h0`)
/// with `p_k` moved by `+-h_rel |p_k|`, keeping only steps whose runs hold every status of
/// `base` (with friction; tried 1e-5, 1e-6, 1e-4).
fn difference<T>(
    solver: &mut DirectSolver,
    (mat, nl): (&dyn Material, usize),
    (p, k): (&[f64], usize),
    s: &Schedule,
    base: Option<&common::Statuses>,
    f: impl Fn(&Trajectory, &Trajectory, f64) -> T,
) -> T {
    for h_rel in [1e-5, 1e-6, 1e-4] {
        let h = h_rel * p[k].abs();
        let mut at = |x: f64| {
            let mut q = p.to_vec();
            q[k] = x;
            let fr = Frame {
                compliance: q[nl],
                drift: q[nl + 1],
                offset: q[nl + 2],
            };
            run(solver, mat, &q[..nl], s, &fr, false)
        };
        let (tp, tm) = (at(p[k] + h), at(p[k] - h));
        assert_eq!(tp.steps.len(), tm.steps.len(), "a cut changed the steps");
        if base.is_none_or(|b| statuses(&tp) == *b && statuses(&tm) == *b) {
            return f(&tp, &tm, 2.0 * h);
        }
        println!("  parameter {k}: h = {h_rel:e} flips a status");
    }
    panic!("no step keeps every status of the base run");
}

/// The sensitivities and the adjoint of `J = sum w_i F_i` of a compliant run of `mat` at
/// `c` through `fr` against central differences; `ties` `false` switches the later ties'
/// depth term off (friction).
fn check(
    m: &Model,
    mat: &dyn Material,
    c: &[f64],
    fr: &Frame,
    s: &Schedule,
    ties: bool,
) -> Outcome {
    let mut solver = DirectSolver::new(m).unwrap();
    let traj = run(&mut solver, mat, c, s, fr, true);
    let n = traj.steps.len();
    let (stick, slip) = stick_slip(m, &traj);
    let fric = m.contact.friction() > 0.0;
    println!(
        "{} Cf {:e}: {n} steps, stick {stick}, slip {slip} node-steps",
        mat.name(),
        fr.compliance
    );
    let w = weights(n);
    let mut adj = Adjoint::new(m).unwrap();
    adj.set_friction_depth_term(ties);
    let g = adj.gradient_compliant(mat, c, &traj, (s, fr), &w).unwrap();
    let sens = adj
        .sensitivities_compliant(mat, c, &traj, (s, fr), FrameIndex::default())
        .unwrap();
    let base = fric.then(|| statuses(&traj));
    let nl = c.len();
    let mut p = c.to_vec();
    p.extend([fr.compliance, fr.drift, fr.offset]);
    let mut grad = g.dj_dc.clone();
    grad.extend(g.dj_dframe);
    let mut out = Outcome {
        stick,
        slip,
        ..Outcome::default()
    };
    // the adjoint's differences relative to the largest |dJ/dp_k p_k|
    let big = (0..p.len()).fold(0.0f64, |a, k| a.max((grad[k] * p[k]).abs()));
    for k in 0..p.len() {
        if p[k] == 0.0 {
            // (Cf = 0: its one-sided difference is `gradient_compliant.rs`'s)
            continue;
        }
        let (fd_j, fd_f, fd_h) = difference(
            &mut solver,
            (mat, nl),
            (&p, k),
            s,
            base.as_ref(),
            |tp, tm, d| {
                let col = |sel: fn(&indentify_contact::StepRecord) -> f64| -> Vec<f64> {
                    tp.steps
                        .iter()
                        .zip(&tm.steps)
                        .map(|(a, b)| (sel(a) - sel(b)) / d)
                        .collect()
                };
                let f = col(|r| r.force);
                let j = f.iter().zip(&w).map(|(a, b)| a * b).sum::<f64>();
                (j, f, col(|r| r.depth))
            },
        );
        let ra = (fd_j - grad[k]).abs() * p[k].abs() / big;
        out.adjoint = out.adjoint.max(ra);
        if k >= nl {
            println!(
                "  frame {k}: adjoint {:.10e} fd {fd_j:.10e} ({ra:.1e})",
                grad[k]
            );
            continue;
        }
        // the sensitivities' columns, relative to each column's largest entry
        let worst = |a: &[f64], b: &dyn Fn(usize) -> f64| -> f64 {
            let big = a.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            (0..a.len()).fold(0.0f64, |m, i| m.max((a[i] - b(i)).abs())) / big.max(1e-300)
        };
        let rf = worst(&fd_f, &|i| sens.df_dc[i][k]);
        let rh = worst(&fd_h, &|i| sens.dh_dc[i][k]);
        let jt: f64 = (0..n).map(|i| w[i] * sens.df_dc[i][k]).sum();
        let rj = relative_difference(jt, g.dj_dc[k]);
        println!(
            "  {}: adjoint {:.10e} fd {fd_j:.10e} ({ra:.1e}); sens dF {rf:.1e} dh {rh:.1e}; \
             J^T w {rj:.1e}",
            mat.params()[k].name,
            g.dj_dc[k]
        );
        out.sens_f = out.sens_f.max(rf);
        out.sens_h = out.sens_h.max(rh);
        out.jt_w = out.jt_w.max(rj);
    }
    println!("{} Cf {:e}: {out:?}", mat.name(), fr.compliance);
    out
}

/// The bounds every case meets: sensitivities and adjoint against central differences
/// (1e-6 of the column's or gradient's scale), `J^T w` against the adjoint (1e-12).
fn assert_outcome(name: &str, o: &Outcome) {
    assert!(
        o.sens_f <= 1e-6,
        "{name}: dF/dc vs differences {:.2e}",
        o.sens_f
    );
    assert!(
        o.sens_h <= 1e-6,
        "{name}: dh/dc vs differences {:.2e}",
        o.sens_h
    );
    assert!(
        o.adjoint <= 1e-6,
        "{name}: adjoint vs differences {:.2e}",
        o.adjoint
    );
    assert!(o.jt_w <= 1e-12, "{name}: J^T w vs adjoint {:.2e}", o.jt_w);
}

/// Laws with internal variables through their blocks, frictionless normal contact:
/// J2 with power hardening and Norton overstress (small strain, `Cf` 1.5e-5 and 0; finite
/// strain) and a two-term Prony solid (small and finite strain).
#[test]
fn internal_variables_sensitivities_through_the_frame() {
    let m = small_model(sphere(), ContactKind::Normal);
    let pl = Plastic::new(Hardening::Power, Rate::Norton);
    for cf in [1.5e-5, 0.0] {
        let o = check(&m, &pl, &POWER_NORTON, &frame(cf), &lhu(0.04, 6), true);
        assert_outcome(&format!("plastic Cf {cf:e}"), &o);
    }
    let pr = Prony::new(2).unwrap();
    let o = check(&m, &pr, &PRONY, &frame(1.5e-5), &lhu(0.04, 6), true);
    assert_outcome("prony small", &o);
    let m = finite_model(sphere());
    let o = check(&m, &pr, &PRONY, &frame(1.5e-5), &lhu(0.04, 6), true);
    assert_outcome("prony finite", &o);
    let o = check(&m, &pl, &POWER_NORTON, &frame(1.5e-5), &lhu(0.04, 6), true);
    assert_outcome("plastic finite", &o);
}

/// A named case: its model, material and parameters.
type Case = (&'static str, Model, Box<dyn Material>, &'static [f64]);

/// Coulomb friction through the frame: Maxwell (mu 0.2, small and finite strain), a
/// two-term Prony solid (mu 0.1) and J2 power + Norton (mu 0.15), each with at least 3
/// sticking and 3 slipping node-steps.
#[test]
fn coulomb_friction_through_the_frame() {
    let fr = frame(1.5e-5);
    let cases: Vec<Case> = vec![
        (
            "maxwell small mu 0.2",
            small_model(sphere(), friction(0.2)),
            Box::new(LawMaterial(&Maxwell)),
            &MAXWELL,
        ),
        (
            "maxwell finite mu 0.2",
            finite_model_with_friction(sphere(), 0.2),
            Box::new(LawMaterial(&Maxwell)),
            &MAXWELL,
        ),
        (
            "prony small mu 0.1",
            small_model(sphere(), friction(0.1)),
            Box::new(Prony::new(2).unwrap()),
            &PRONY,
        ),
        (
            "plastic small mu 0.15",
            small_model(sphere(), friction(0.15)),
            Box::new(Plastic::new(Hardening::Power, Rate::Norton)),
            &POWER_NORTON,
        ),
    ];
    for (name, m, mat, c) in &cases {
        let o = check(m, &**mat, c, &fr, &lhu(0.04, 6), true);
        assert!(
            o.stick >= 3 && o.slip >= 3,
            "{name}: stick {}, slip {}",
            o.stick,
            o.slip
        );
        assert_outcome(name, &o);
    }
}

/// `Cf = 0` with friction (plain depth control driven as the frame's limit): the frame's
/// derivatives are the force's sensitivity to the prescribed depth, with the ties' term.
#[test]
fn coulomb_friction_at_zero_compliance() {
    let m = small_model(sphere(), friction(0.2));
    let o = check(
        &m,
        &LawMaterial(&Maxwell),
        &MAXWELL,
        &frame(0.0),
        &lhu(0.04, 6),
        true,
    );
    assert_outcome("maxwell Cf 0 mu 0.2", &o);
}

/// The later sticking ties' depth term switched off: the frictional adjoint then misses
/// the central differences by far more than the bound (so the tests above can fail).
#[test]
fn without_the_ties_depth_term_the_adjoint_is_wrong() {
    let m = small_model(sphere(), friction(0.2));
    let o = check(
        &m,
        &LawMaterial(&Maxwell),
        &MAXWELL,
        &frame(1.5e-5),
        &lhu(0.04, 6),
        false,
    );
    println!("switched off: adjoint vs differences {:.2e}", o.adjoint);
    assert!(o.adjoint > 1e-4, "{:.2e}", o.adjoint);
}

/// A checkpointed compliant run (every 4 schedule steps), its stretches replayed with the
/// frame's drive (`DirectSolver::replay_compliant`), gives the fields the recorded run
/// (the same checkpoints, every field kept) has, bit for bit, and so the same adjoint
/// gradient and forward sensitivities: Coulomb friction (mu 0.2) with Maxwell and with J2
/// power + Norton (internal variables replayed).
#[test]
fn checkpointed_equals_recorded() {
    let m = small_model(sphere(), friction(0.2));
    let s = lhu(0.04, 6);
    let fr = frame(1.5e-5);
    let pl = Plastic::new(Hardening::Power, Rate::Norton);
    let maxwell = LawMaterial(&Maxwell);
    let cases: [(&dyn Material, &[f64]); 2] = [(&maxwell, &MAXWELL), (&pl, &POWER_NORTON)];
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    for (mat, c) in cases {
        let mut solver = DirectSolver::new(&m).unwrap();
        let ck = |record| SolverOptions {
            record_fields: record,
            checkpoint_every: 4,
            ..opts(record)
        };
        let recorded = solver.run_compliant(mat, c, &s, &fr, &ck(true)).unwrap();
        let stored = solver.run_compliant(mat, c, &s, &fr, &ck(false)).unwrap();
        assert!(stored.fields.is_empty() && stored.checkpoints.len() > 1);
        // the replayed stretches, in order, as one trajectory with every field
        let mut replayed = Trajectory {
            steps: stored.steps.clone(),
            ..Trajectory::default()
        };
        let last = s.t.len() - 1;
        for (j, cp) in stored.checkpoints.iter().enumerate() {
            let j_end = stored
                .checkpoints
                .get(j + 1)
                .map_or(last, |next| next.schedule_index);
            let seg = solver
                .replay_compliant(mat, c, &s, &fr, &ck(false), cp, j_end)
                .unwrap();
            let skip = usize::from(j > 0);
            replayed.fields.extend(seg.fields.into_iter().skip(skip));
        }
        assert_eq!(replayed.fields.len(), recorded.fields.len());
        for (a, b) in replayed.fields.iter().zip(&recorded.fields) {
            assert!(a == b, "{}: a replayed field differs", mat.name());
        }
        let n = recorded.steps.len();
        let w = weights(n);
        let mut adj = Adjoint::new(&m).unwrap();
        let at = FrameIndex::default();
        let g1 = adj
            .gradient_compliant(mat, c, &recorded, (&s, &fr), &w)
            .unwrap();
        let s1 = adj
            .sensitivities_compliant(mat, c, &recorded, (&s, &fr), at)
            .unwrap();
        let g2 = adj
            .gradient_compliant(mat, c, &replayed, (&s, &fr), &w)
            .unwrap();
        let s2 = adj
            .sensitivities_compliant(mat, c, &replayed, (&s, &fr), at)
            .unwrap();
        assert_eq!(bits(&g1.dj_dc), bits(&g2.dj_dc), "{}", mat.name());
        assert_eq!(bits(&g1.dj_dframe), bits(&g2.dj_dframe), "{}", mat.name());
        for (a, b) in s1.df_dc.iter().zip(&s2.df_dc) {
            assert_eq!(bits(a), bits(b), "{}", mat.name());
        }
        for (a, b) in s1.dh_dc.iter().zip(&s2.dh_dc) {
            assert_eq!(bits(a), bits(b), "{}", mat.name());
        }
        println!(
            "{}: {} stretches replayed, gradient and sensitivities bit for bit",
            mat.name(),
            stored.checkpoints.len()
        );
    }
}

/// The cost, measured back to back (`cargo test --test compliant_frame -- --ignored
/// --nocapture`; printed, no timed assertion): on the sphere's model, the compliant forward
/// (fields recorded), its adjoint and its forward sensitivities (the law's parameters), best
/// of 15 alternated rounds, against the plain depth-controlled sensitivities of the same
/// law on the same machine depths: J2 power + Norton frictionless, Maxwell and J2 with
/// Coulomb friction (mu 0.2).
#[test]
#[ignore = "a measurement: run it on an idle machine"]
fn cost_back_to_back() {
    let s = lhu(0.04, 20);
    let fr = frame(1.5e-5);
    let pl = Plastic::new(Hardening::Power, Rate::Norton);
    let maxwell = LawMaterial(&Maxwell);
    let cases: [(&str, Model, &dyn Material, &[f64]); 3] = [
        (
            "plastic frictionless",
            small_model(sphere(), ContactKind::Normal),
            &pl,
            &POWER_NORTON,
        ),
        (
            "maxwell mu 0.2",
            small_model(sphere(), friction(0.2)),
            &maxwell,
            &MAXWELL,
        ),
        (
            "plastic mu 0.2",
            small_model(sphere(), friction(0.2)),
            &pl,
            &POWER_NORTON,
        ),
    ];
    for (name, m, mat, c) in cases {
        let mut solver = DirectSolver::new(&m).unwrap();
        let mut adj = Adjoint::new(&m).unwrap();
        let mut best = [f64::INFINITY; 4];
        for _ in 0..15 {
            let t = std::time::Instant::now();
            let traj = run(&mut solver, mat, c, &s, &fr, true);
            best[0] = best[0].min(t.elapsed().as_secs_f64());
            let w = weights(traj.steps.len());
            let t = std::time::Instant::now();
            adj.gradient_compliant(mat, c, &traj, (&s, &fr), &w)
                .unwrap();
            best[1] = best[1].min(t.elapsed().as_secs_f64());
            let t = std::time::Instant::now();
            adj.sensitivities_compliant(mat, c, &traj, (&s, &fr), FrameIndex::default())
                .unwrap();
            best[2] = best[2].min(t.elapsed().as_secs_f64());
            let d = solver.run(mat, c, &s, &opts(true)).unwrap();
            let t = std::time::Instant::now();
            adj.sensitivities(mat, c, &d).unwrap();
            best[3] = best[3].min(t.elapsed().as_secs_f64());
        }
        println!(
            "{name}: compliant forward {:.1} ms, adjoint {:.1} ms ({:.2}x), sensitivities \
             ({} parameters) {:.1} ms ({:.2}x); depth-controlled sensitivities {:.1} ms \
             (through the frame / plain {:.2}x)",
            1e3 * best[0],
            1e3 * best[1],
            best[1] / best[0],
            c.len(),
            1e3 * best[2],
            best[2] / best[0],
            1e3 * best[3],
            best[2] / best[3]
        );
    }
}
