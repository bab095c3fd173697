//! The all-nodal sweep of a linear material with isotropic blocks (`Prony`;
//! `crates/adjoint/src/material/nodal.rs`) under load control, its step bordered (one
//! scalar per step from the depth column and the Schur complement, `load.rs`): the
//! Gauss-point load-controlled sweep's gradient (`Adjoint::set_fused(false)`) to 1e-12
//! for one to three terms over load-hold-unload histories with several step lengths and
//! a mixed depth-load-depth history, the nodal sweep asserted on (and with the forward's
//! factor taken); central differences of the direct solver's own load-controlled runs
//! and the forward sensitivities; the same bits on one and two threads; left off under
//! normal contact.

mod common;

use common::{prony, small_model};
use indentify_adjoint::Adjoint;
use indentify_adjoint::check::central_difference;
use indentify_contact::{ContactKind, DirectSolver, LoadHistory, Punch, SolverOptions, Trajectory};
use indentify_laws::Material;
use indentify_testkit::{cone68 as cone, depth, force};

/// The histories (peak 1000 N, about 0.08 mm under the cone):
/// - load, hold, unload to 0.4 of the peak, step lengths 1/6, 1/2 and 1/5 s;
/// - load-hold-unload-reload with step lengths 0.1, 0.3, 0.0625 and 0.1 s;
/// - depth to 0.03 mm, load to 1000 N, hold, depth back to 0.03 mm (mixed).
fn histories() -> [LoadHistory; 3] {
    let p = 1000.0;
    [
        LoadHistory::from_segments(&[force(1.0, p, 6), force(1.0, p, 2), force(1.0, 0.4 * p, 5)])
            .unwrap(),
        LoadHistory::from_segments(&[
            force(0.5, p, 5),
            force(1.5, p, 5),
            force(0.5, 0.4 * p, 8),
            force(0.5, 0.8 * p, 5),
        ])
        .unwrap(),
        LoadHistory::from_segments(&[
            depth(1.0, 0.03, 4),
            force(1.0, p, 6),
            force(1.0, p, 4),
            depth(1.0, 0.03, 5),
        ])
        .unwrap(),
    ]
}

fn opts(record: bool, tol: f64) -> SolverOptions {
    SolverOptions {
        record_fields: record,
        residual_tol: tol,
        ..SolverOptions::default()
    }
}

fn run(solver: &mut DirectSolver, mat: &dyn Material, c: &[f64], h: &LoadHistory) -> Trajectory {
    solver.run_history(mat, c, h, &opts(true, 1e-11)).unwrap()
}

/// The cost's weights: `dJ/dU_i = w_i` on the load-controlled steps, `dJ/dF_i` on the
/// depth-controlled ones (each side ignores the other kind's entries).
fn costs(t: &Trajectory) -> (Vec<f64>, Vec<f64>) {
    let n = t.steps.len();
    let w: Vec<f64> = (0..n).map(|i| 1.0 + 0.37 * ((i * 7) % 5) as f64).collect();
    let f: Vec<f64> = (0..n).map(|i| 1e-4 * (1.0 + (i % 3) as f64)).collect();
    (w, f)
}

/// The largest `|a_k - b_k| |c_k|` relative to the largest `|a_k c_k|`.
fn rel(a: &[f64], b: &[f64], c: &[f64]) -> f64 {
    let big = a
        .iter()
        .zip(c)
        .fold(0.0f64, |m, (g, c)| m.max((g * c).abs()));
    (0..a.len()).fold(0.0f64, |m, k| m.max((a[k] - b[k]).abs() * c[k].abs() / big))
}

/// The system shall give, for a Prony solid of one to three terms under vertical contact
/// and small strain driven by force (load-hold-unload with several step lengths, and
/// depth-load-hold-depth), the Gauss-point load-controlled sweep's gradient to 1e-12
/// relative from the all-nodal sweep (which it shall use there), with and without the
/// forward's factorization taken (a material's forward keys its factor by the tangent of
/// every point, the sweep by one uniform tangent: the sweep factorizes as a fresh one).
#[test]
fn nodal_load_sweep_equals_the_gauss_point_sweep() {
    let m = small_model(cone(), ContactKind::Vertical);
    let mut solver = DirectSolver::new(&m).unwrap();
    let mut worst = 0.0f64;
    for (k, h) in histories().iter().enumerate() {
        for n in 1..=3 {
            let (mat, c) = prony(n);
            let t = run(&mut solver, &mat, &c, h);
            let (w, f) = costs(&t);
            let mut adj = Adjoint::new(&m).unwrap();
            adj.take_factor(&mut solver);
            let reused = adj.gradient_load(&mat, &c, &t, h, &w, &f).unwrap();
            assert!(
                adj.last_material_sweep_was_nodal(),
                "history {k}, {n} terms"
            );
            let nodal = adj.gradient_load(&mat, &c, &t, h, &w, &f).unwrap();
            assert!(adj.last_material_sweep_was_nodal());
            adj.set_fused(false);
            let points = adj.gradient_load(&mat, &c, &t, h, &w, &f).unwrap().dj_dc;
            assert!(!adj.last_material_sweep_was_nodal());
            assert!(points.iter().all(|g| g.is_finite() && *g != 0.0));
            for (what, g) in [("fresh", &nodal.dj_dc), ("forward's factor", &reused.dj_dc)] {
                let r = rel(&points, g, &c);
                assert!(
                    r <= 1e-12,
                    "history {k}, {n} terms, {what}: {g:?} vs {points:?} ({r:e})"
                );
                worst = worst.max(r);
            }
        }
    }
    eprintln!("all-nodal against Gauss-point Prony sweep under load control: {worst:e}");
}

/// The system shall keep the Gauss-point sweep under load control where the nodal one
/// does not apply (normal contact), with the same gradient bit for bit.
#[test]
fn nodal_load_sweep_stays_off_under_normal_contact() {
    let m = small_model(Punch::Sphere { radius: 1.0 }, ContactKind::Normal);
    let (mat, c) = prony(2);
    let h = &histories()[0];
    let mut solver = DirectSolver::new(&m).unwrap();
    let t = run(&mut solver, &mat, &c, h);
    let (w, f) = costs(&t);
    let mut adj = Adjoint::new(&m).unwrap();
    let g = adj.gradient_load(&mat, &c, &t, h, &w, &f).unwrap().dj_dc;
    assert!(!adj.last_material_sweep_was_nodal());
    adj.set_fused(false);
    let p = adj.gradient_load(&mat, &c, &t, h, &w, &f).unwrap().dj_dc;
    assert_eq!(g, p);
}

/// The system shall give the nodal load-controlled sweep's gradient with the same bits on
/// one and two threads.
#[test]
fn nodal_load_sweep_is_bit_identical_on_one_and_two_threads() {
    let m = small_model(cone(), ContactKind::Vertical);
    let (mat, c) = prony(3);
    let hs = histories();
    let grad = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                let mut bits = Vec::new();
                for h in [&hs[1], &hs[2]] {
                    let mut solver = DirectSolver::new(&m).unwrap();
                    let t = run(&mut solver, &mat, &c, h);
                    let (w, f) = costs(&t);
                    let mut adj = Adjoint::new(&m).unwrap();
                    adj.take_factor(&mut solver);
                    let g = adj.gradient_load(&mat, &c, &t, h, &w, &f).unwrap();
                    assert!(adj.last_material_sweep_was_nodal());
                    bits.extend(g.dj_dc.iter().map(|v| v.to_bits()));
                }
                bits
            })
    };
    assert_eq!(grad(1), grad(2));
}

/// The system shall give, from the all-nodal sweep of a two- and a three-term Prony solid
/// under vertical contact and load control (the load-hold-unload-reload history with four
/// step lengths, and the mixed depth-load-depth one for two terms), the gradient of
/// `J = sum_i w_i U_i` (the depths, as a load-controlled fit sees them) equal to central
/// differences of the direct solver's own load-controlled runs (relative step 1e-6) to
/// 1e-6 and to the forward sensitivities' `J^T w` to 1e-9 (each relative to the largest
/// `|g_k c_k|`).
#[test]
fn nodal_load_gradient_matches_finite_differences() {
    let m = small_model(cone(), ContactKind::Vertical);
    let mut solver = DirectSolver::new(&m).unwrap();
    let hs = histories();
    let mut worst = (0.0f64, 0.0f64);
    for (n, h) in [(2, &hs[1]), (3, &hs[1]), (2, &hs[2])] {
        let (mat, c) = prony(n);
        let t = solver.run_history(&mat, &c, h, &opts(true, 1e-13)).unwrap();
        let steps = t.steps.len();
        let w: Vec<f64> = (0..steps)
            .map(|i| 1.0 + 0.37 * ((i * 7) % 5) as f64)
            .collect();
        // the depth cost on every step (a depth-controlled step's depth, prescribed, is
        // constant; its force is not weighted)
        let zero = vec![0.0; steps];
        let mut adj = Adjoint::new(&m).unwrap();
        let g = adj.gradient_load(&mat, &c, &t, h, &w, &zero).unwrap().dj_dc;
        assert!(adj.last_material_sweep_was_nodal());
        let sens = adj.sensitivities_load(&mat, &c, &t, h).unwrap();
        let from_sens: Vec<f64> = (0..c.len())
            .map(|k| (0..steps).map(|i| w[i] * sens.dh_dc[i][k]).sum())
            .collect();
        let fd: Vec<f64> = (0..c.len())
            .map(|k| {
                central_difference(
                    |p: &[f64]| -> Result<f64, String> {
                        let tp = solver
                            .run_history(&mat, p, h, &opts(false, 1e-13))
                            .map_err(|e| e.to_string())?;
                        assert_eq!(tp.steps.len(), steps, "a cut changed the steps");
                        Ok(tp.steps.iter().zip(&w).map(|(s, w)| s.depth * w).sum())
                    },
                    &c,
                    k,
                    1e-6,
                )
                .unwrap()
            })
            .collect();
        let (e_fd, e_sens) = (rel(&g, &fd, &c), rel(&g, &from_sens, &c));
        println!("{n} terms: adjoint {g:?}\n  fd {fd:?}: {e_fd:.2e}; sensitivities {e_sens:.2e}");
        assert!(e_fd < 1e-6, "{n} terms: fd {e_fd:e}");
        assert!(e_sens < 1e-9, "{n} terms: sensitivities {e_sens:e}");
        worst = (worst.0.max(e_fd), worst.1.max(e_sens));
    }
    eprintln!(
        "nodal Prony gradient under load control: fd {:e}, sensitivities {:e}",
        worst.0, worst.1
    );
}

/// The system shall give, through the instrument's frame (`gradient_compliant`: machine
/// depth `H = h + Cf F - vd t - h0`, the same bordered step), the Gauss-point sweep's
/// gradient (the law's parameters, `Cf`, `vd`, `h0` and `dJ/dH_i`) to 1e-12 relative from
/// the all-nodal sweep of a Prony solid of one to three terms (which it shall use there).
#[test]
fn nodal_compliant_sweep_equals_the_gauss_point_sweep() {
    use indentify_contact::{Frame, Schedule, Segment};
    let m = small_model(cone(), ContactKind::Vertical);
    let mut solver = DirectSolver::new(&m).unwrap();
    let seg = |duration: f64, depth: f64, steps: usize| Segment {
        duration,
        depth,
        steps,
    };
    // machine depth: load, hold, partial unload (step lengths 1/6, 1/2, 1/5 s)
    let s = Schedule::from_segments(&[seg(1.0, 0.08, 6), seg(1.0, 0.08, 2), seg(1.0, 0.05, 5)])
        .unwrap();
    let frame = Frame {
        compliance: 2e-5,
        drift: 1e-3,
        offset: 1e-3,
    };
    let mut worst = 0.0f64;
    for n in 1..=3 {
        let (mat, c) = prony(n);
        let t = solver
            .run_compliant(&mat, &c, &s, &frame, &opts(true, 1e-11))
            .unwrap();
        let w: Vec<f64> = (0..t.steps.len())
            .map(|i| 1.0 + 0.37 * ((i * 7) % 5) as f64)
            .collect();
        let mut adj = Adjoint::new(&m).unwrap();
        let nodal = adj
            .gradient_compliant(&mat, &c, &t, (&s, &frame), &w)
            .unwrap();
        assert!(adj.last_material_sweep_was_nodal(), "{n} terms");
        adj.set_fused(false);
        let points = adj
            .gradient_compliant(&mat, &c, &t, (&s, &frame), &w)
            .unwrap();
        assert!(!adj.last_material_sweep_was_nodal());
        let r = rel(&points.dj_dc, &nodal.dj_dc, &c);
        let scale = |v: &[f64]| v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let off = |a: &[f64], b: &[f64]| {
            let big = scale(a);
            a.iter()
                .zip(b)
                .fold(0.0f64, |m, (x, y)| m.max((x - y).abs() / big))
        };
        let r_frame = off(&points.dj_dframe, &nodal.dj_dframe);
        let r_h = off(&points.dj_dh, &nodal.dj_dh);
        assert!(points.dj_dframe.iter().all(|g| g.is_finite() && *g != 0.0));
        assert!(
            r <= 1e-12 && r_frame <= 1e-12 && r_h <= 1e-12,
            "{n} terms: law {r:e}, frame {r_frame:e}, dJ/dH {r_h:e}"
        );
        worst = worst.max(r).max(r_frame).max(r_h);
    }
    eprintln!("all-nodal against Gauss-point Prony sweep through the frame: {worst:e}");
}
