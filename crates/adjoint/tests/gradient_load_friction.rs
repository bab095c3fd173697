//! Coulomb friction under load control (docs/theory.md §13): the exact gradient of the
//! bordered system (`Adjoint::gradient_load`) and the forward sensitivities
//! (`Adjoint::sensitivities_load`) with the contact set and the stick/slip partition held,
//! against central differences of the direct solver's own load-controlled runs over a
//! load-hold-unload history (a sphere of 1 mm, mu = 0.1-0.3), with some nodes sticking and
//! some slipping (counted and asserted per case), small and finite strain: elastic,
//! Maxwell, a two-term Prony solid and J2 with Norton overstress (laws with internal
//! variables, through their blocks); a mixed depth-load-depth history; the checkpointed
//! sweep against the recorded one.
//!
//! The cost is a depth functional `J = sum_i w_i U_i` over every recorded step (the depth
//! is the observable under load control, `dJ/dF = 0`). Finite differences with friction
//! are meaningful only where no step's contact set or stick/slip status flips under the
//! perturbation (docs/theory.md §8): each central difference uses the largest relative
//! step among 1e-5, 1e-6 and 1e-4 (in that order) whose +-h runs keep every status of the base run.

mod common;

use common::{finite_model_with_friction, small_model, statuses};
use indentify_adjoint::check::relative_difference;
use indentify_adjoint::{Adjoint, LoadReplay};
use indentify_contact::{ContactKind, DirectSolver, LoadHistory, Model, SolverOptions, Trajectory};
use indentify_laws::{Elastic, Hardening, LawMaterial, Material, Maxwell, Plastic, Prony, Rate};
use indentify_testkit::{
    coulomb as friction, depth, force, force_lhu as lhu, recording, sphere1 as sphere, weights,
};

fn opts(record: bool) -> SolverOptions {
    recording(record, 1e-12)
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

/// What one case measured: the worst relative difference of the adjoint against central
/// differences and against `J^T w` of the sensitivities, the stick and slip node-steps.
struct Outcome {
    fd: f64,
    sens: f64,
    stick: usize,
    slip: usize,
}

/// The adjoint of `J = sum w_i U_i` at `c` on `m` over `h` against central differences
/// (statuses held) and against the forward sensitivities.
fn check(m: &Model, mat: &dyn Material, c: &[f64], h: &LoadHistory) -> Outcome {
    let mut solver = DirectSolver::new(m).unwrap();
    let traj = solver.run_history(mat, c, h, &opts(true)).unwrap();
    let n = traj.steps.len();
    let (stick, slip) = stick_slip(m, &traj);
    let sizes: Vec<usize> = traj.steps.iter().map(|s| s.active.len()).collect();
    println!(
        "{}: {n} steps, stick {stick}, slip {slip} node-steps; active {sizes:?}",
        mat.name()
    );
    assert!(stick >= 3 && slip >= 3, "stick {stick}, slip {slip}");
    let w = weights(n);
    let mut adj = Adjoint::new(m).unwrap();
    let g = adj
        .gradient_load(mat, c, &traj, h, &w, &vec![0.0; n])
        .unwrap();
    let sens = adj.sensitivities_load(mat, c, &traj, h).unwrap();
    let base = statuses(&traj);
    let mut out = Outcome {
        fd: 0.0,
        sens: 0.0,
        stick,
        slip,
    };
    for k in 0..c.len() {
        let jt: f64 = (0..n).map(|i| w[i] * sens.dh_dc[i][k]).sum();
        let rs = relative_difference(jt, g.dj_dc[k]);
        let mut found = None;
        for h_rel in [1e-5, 1e-6, 1e-4] {
            let step = h_rel * c[k].abs();
            let mut run = |x: f64| {
                let mut p = c.to_vec();
                p[k] = x;
                solver.run_history(mat, &p, h, &opts(false)).unwrap()
            };
            let (tp, tm) = (run(c[k] + step), run(c[k] - step));
            if statuses(&tp) == base && statuses(&tm) == base {
                let j = |t: &Trajectory| -> f64 {
                    t.steps.iter().zip(&w).map(|(s, w)| w * s.depth).sum()
                };
                found = Some(((j(&tp) - j(&tm)) / (2.0 * step), h_rel));
                break;
            }
            println!("  {}: h = {h_rel:e} flips a status", mat.params()[k].name);
        }
        let (fd, h_rel) = found.expect("no step keeps every status of the base run");
        let rf = relative_difference(g.dj_dc[k], fd);
        println!(
            "  {}: adjoint {:.12e} fd {fd:.12e} (h {h_rel:e}) sens {jt:.12e} | fd {rf:.1e} \
             sens {rs:.1e}",
            mat.params()[k].name,
            g.dj_dc[k]
        );
        out.fd = out.fd.max(rf);
        out.sens = out.sens.max(rs);
    }
    out
}

fn assert_outcome(name: &str, o: &Outcome) {
    println!(
        "{name}: worst fd {:.1e}, sens {:.1e}; stick {}, slip {}",
        o.fd, o.sens, o.stick, o.slip
    );
    assert!(
        o.fd <= 1e-7,
        "{name}: adjoint vs central differences {:.2e}",
        o.fd
    );
    assert!(o.sens <= 1e-9, "{name}: adjoint vs J^T w {:.2e}", o.sens);
}

const MAXWELL: [f64; 3] = [20000.0, 0.3, 30000.0];
const PRONY: [f64; 6] = [1e5, 0.3, 0.3, 0.2, 0.2, 2.0];
const POWER_NORTON: [f64; 6] = [1e5, 0.3, 500.0, 0.2, 1500.0, 5.0];

#[test]
fn elastic_and_maxwell_small_strain() {
    let m = small_model(sphere(), friction(0.1));
    let o = check(&m, &LawMaterial(&Elastic), &[20000.0, 0.3], &lhu(300.0, 6));
    assert_outcome("elastic mu 0.1", &o);
    let m = small_model(sphere(), friction(0.1));
    let o = check(&m, &LawMaterial(&Maxwell), &MAXWELL, &lhu(300.0, 6));
    assert_outcome("maxwell mu 0.1", &o);
}

#[test]
fn maxwell_finite_strain() {
    let m = finite_model_with_friction(sphere(), 0.3);
    let o = check(&m, &LawMaterial(&Maxwell), &MAXWELL, &lhu(300.0, 6));
    assert_outcome("maxwell finite mu 0.3", &o);
}

/// Laws with internal variables (their blocks, regime held): a two-term Prony solid
/// (small and finite strain) and J2 with power hardening and Norton overstress.
#[test]
fn internal_variables_small_and_finite_strain() {
    let p = Prony::new(2).unwrap();
    let m = small_model(sphere(), friction(0.1));
    let o = check(&m, &p, &PRONY, &lhu(1500.0, 6));
    assert_outcome("prony small mu 0.1", &o);
    let m = finite_model_with_friction(sphere(), 0.2);
    let o = check(&m, &p, &PRONY, &lhu(1500.0, 6));
    assert_outcome("prony finite mu 0.2", &o);
    let pl = Plastic::new(Hardening::Power, Rate::Norton);
    let m = small_model(sphere(), friction(0.15));
    let o = check(&m, &pl, &POWER_NORTON, &lhu(600.0, 6));
    assert_outcome("plastic small mu 0.15", &o);
}

/// Depth control, load control from the depth-controlled step's force, depth control
/// from the load-controlled step's depth: the segments' starts carry the ties' depth.
#[test]
fn mixed_depth_load_depth() {
    let m = small_model(sphere(), friction(0.2));
    let h = LoadHistory::from_segments(&[
        depth(1.0, 0.03, 4),
        force(1.0, 300.0, 6),
        force(1.0, 300.0, 4),
        depth(1.0, 0.03, 5),
    ])
    .unwrap();
    let o = check(&m, &LawMaterial(&Maxwell), &MAXWELL, &h);
    assert_outcome("maxwell mixed", &o);
    let o = check(&m, &Prony::new(2).unwrap(), &PRONY, &h);
    assert_outcome("prony mixed", &o);
}

/// A checkpointed run's gradient, its stretches replayed with the force drive, equals
/// the recorded one's.
#[test]
fn checkpointed_equals_recorded() {
    let m = small_model(sphere(), friction(0.2));
    let h = lhu(300.0, 6);
    let prony = Prony::new(2).unwrap();
    let cases: [(&dyn Material, &[f64]); 2] =
        [(&LawMaterial(&Maxwell), &MAXWELL), (&prony, &PRONY)];
    for (mat, c) in cases {
        let mut solver = DirectSolver::new(&m).unwrap();
        let traj = solver.run_history(mat, c, &h, &opts(true)).unwrap();
        let n = traj.steps.len();
        let w = weights(n);
        let mut adj = Adjoint::new(&m).unwrap();
        let g = adj
            .gradient_load(mat, c, &traj, &h, &w, &vec![0.0; n])
            .unwrap();
        let ck_opts = SolverOptions {
            record_fields: false,
            checkpoint_every: 5,
            ..opts(false)
        };
        let ck = solver.run_history(mat, c, &h, &ck_opts).unwrap();
        assert_eq!(ck.steps.len(), n);
        let g_ck = adj
            .gradient_load_replayed(
                mat,
                c,
                &ck,
                &h,
                &w,
                &vec![0.0; n],
                LoadReplay {
                    solver: &mut solver,
                    opts: &ck_opts,
                },
            )
            .unwrap();
        for (a, b) in g.dj_dc.iter().zip(&g_ck.dj_dc) {
            let r = relative_difference(*a, *b);
            println!(
                "{}: recorded {a:.12e} replayed {b:.12e} ({r:.1e})",
                mat.name()
            );
            assert!(r < 1e-10, "{}: {a} vs {b}", mat.name());
        }
    }
}

/// The cost, measured back to back (`cargo test --test gradient_load_friction -- --ignored
/// --nocapture`; no timed assertion): on a 24 x 24 mesh, Maxwell over the
/// load-hold-unload, the forward run (fields recorded), the adjoint and the forward
/// sensitivities, median of 5, frictionless normal contact and Coulomb mu = 0.2.
#[test]
#[ignore = "a measurement: run it on an idle machine"]
fn cost_ratios() {
    use indentify_testkit::cylinder;
    let mesh = cylinder(4.0, 24, 1.2);
    let h = lhu(300.0, 10);
    let mat = LawMaterial(&Maxwell);
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    for (name, kind) in [
        ("frictionless", ContactKind::Normal),
        ("mu 0.2", friction(0.2)),
    ] {
        let m = Model::with_contact(mesh.clone(), sphere(), kind).unwrap();
        let mut solver = DirectSolver::new(&m).unwrap();
        let mut adj = Adjoint::new(&m).unwrap();
        let (mut tf, mut ta, mut ts) = (Vec::new(), Vec::new(), Vec::new());
        for _ in 0..5 {
            let t0 = std::time::Instant::now();
            let traj = solver.run_history(&mat, &MAXWELL, &h, &opts(true)).unwrap();
            tf.push(t0.elapsed().as_secs_f64());
            let n = traj.steps.len();
            let g = adj
                .gradient_load(&mat, &MAXWELL, &traj, &h, &weights(n), &vec![0.0; n])
                .unwrap();
            ta.push(g.seconds);
            let s = adj.sensitivities_load(&mat, &MAXWELL, &traj, &h).unwrap();
            ts.push(s.seconds);
        }
        let (f, a, s) = (median(tf), median(ta), median(ts));
        println!(
            "{name}: forward {:.1} ms, adjoint {:.1} ms ({:.2}x), sensitivities {:.1} ms \
             ({:.2}x)",
            1e3 * f,
            1e3 * a,
            a / f,
            1e3 * s,
            s / f
        );
    }
}
