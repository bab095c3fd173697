//! The all-nodal sweep of a linear material with isotropic blocks (`Prony`;
//! `crates/adjoint/src/material/nodal.rs`) against the Gauss-point sweep
//! (`Adjoint::set_fused(false)`): the same gradient to 1e-12 relative for one to three
//! terms, over a trapezoid and over a history whose step lengths change (a force cost
//! on every step and on a few), the nodal sweep asserted on; left off (the Gauss-point
//! sweep) under normal contact; the same bits on one and two threads; against central
//! differences and the forward sensitivities.

mod common;

use common::{prony, small_model};
use indentify_adjoint::Adjoint;
use indentify_contact::{
    ContactKind, DirectSolver, Model, Punch, Schedule, Segment, SolverOptions, Trajectory,
    trapezoid,
};
use indentify_laws::Material;
use indentify_testkit::cone68 as cone;

fn schedules() -> [Schedule; 2] {
    let seg = |duration: f64, depth: f64, steps: usize| Segment {
        duration,
        depth,
        steps,
    };
    [
        Schedule::from_segments(&trapezoid(0.1, 1.0, 1.0, 1.0, 8)).unwrap(),
        // three step lengths (0.1, 0.3, 0.0625 s), a partial unload and a reload
        Schedule::from_segments(&[
            seg(0.5, 0.08, 5),
            seg(1.5, 0.08, 5),
            seg(0.5, 0.04, 8),
            seg(0.5, 0.1, 5),
            seg(0.5, 0.0, 8),
        ])
        .unwrap(),
    ]
}

fn run(m: &Model, mat: &dyn Material, c: &[f64], s: &Schedule) -> Trajectory {
    let opts = SolverOptions {
        residual_tol: 1e-11,
        ..SolverOptions::default()
    };
    DirectSolver::new(m).unwrap().run(mat, c, s, &opts).unwrap()
}

/// The largest `|a_k - b_k| |c_k|` relative to the largest `|a_k c_k|`.
fn rel(a: &[f64], b: &[f64], c: &[f64]) -> f64 {
    let big = a
        .iter()
        .zip(c)
        .fold(0.0f64, |m, (g, c)| m.max((g * c).abs()));
    (0..a.len()).fold(0.0f64, |m, k| m.max((a[k] - b[k]).abs() * c[k].abs() / big))
}

/// The system shall give, for a Prony solid of one to three terms under vertical
/// contact and small strain, the Gauss-point sweep's gradient to 1e-12 relative from
/// the all-nodal sweep (which it shall use there).
#[test]
fn nodal_prony_sweep_equals_the_gauss_point_sweep() {
    let m = small_model(cone(), ContactKind::Vertical);
    let mut worst = 0.0f64;
    for s in schedules() {
        for n in 1..=3 {
            let (mat, c) = prony(n);
            let t = run(&m, &mat, &c, &s);
            let steps = t.steps.len();
            // a cost on every step's force, and one on a few steps only
            let every: Vec<f64> = t.steps.iter().map(|r| r.force).collect();
            let few: Vec<f64> = (0..steps)
                .map(|i| if i % 7 == 3 { 1.0 + i as f64 } else { 0.0 })
                .collect();
            for rho in [every, few] {
                let mut adj = Adjoint::new(&m).unwrap();
                let nodal = adj.gradient(&mat, &c, &t, &rho).unwrap().dj_dc;
                assert!(adj.last_material_sweep_was_nodal(), "{n} terms");
                adj.set_fused(false);
                let points = adj.gradient(&mat, &c, &t, &rho).unwrap().dj_dc;
                assert!(!adj.last_material_sweep_was_nodal());
                assert!(points.iter().all(|g| g.is_finite() && *g != 0.0));
                let r = rel(&points, &nodal, &c);
                assert!(r <= 1e-12, "{n} terms: {nodal:?} vs {points:?} ({r:e})");
                worst = worst.max(r);
            }
        }
    }
    eprintln!("all-nodal against Gauss-point Prony sweep: {worst:e}");
}

/// The system shall keep the Gauss-point sweep where the nodal one does not apply
/// (normal contact), with the same gradient as before.
#[test]
fn nodal_prony_sweep_stays_off_under_normal_contact() {
    let m = small_model(Punch::Sphere { radius: 1.0 }, ContactKind::Normal);
    let (mat, c) = prony(2);
    let s = &schedules()[0];
    let t = run(&m, &mat, &c, s);
    let rho: Vec<f64> = t.steps.iter().map(|r| r.force).collect();
    let mut adj = Adjoint::new(&m).unwrap();
    let g = adj.gradient(&mat, &c, &t, &rho).unwrap().dj_dc;
    assert!(!adj.last_material_sweep_was_nodal());
    adj.set_fused(false);
    let h = adj.gradient(&mat, &c, &t, &rho).unwrap().dj_dc;
    assert_eq!(g, h);
}

/// The system shall give the nodal sweep's gradient with the same bits on one and two
/// threads.
#[test]
fn nodal_prony_sweep_is_bit_identical_on_one_and_two_threads() {
    let m = small_model(cone(), ContactKind::Vertical);
    let (mat, c) = prony(3);
    let s = &schedules()[1];
    let grad = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                let t = run(&m, &mat, &c, s);
                let rho: Vec<f64> = t.steps.iter().map(|r| r.force).collect();
                let mut adj = Adjoint::new(&m).unwrap();
                let g = adj.gradient(&mat, &c, &t, &rho).unwrap();
                assert!(adj.last_material_sweep_was_nodal());
                g.dj_dc.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
            })
    };
    assert_eq!(grad(1), grad(2));
}

/// The system shall give, from the all-nodal sweep of a two- and a three-term Prony
/// solid under vertical contact, the gradient of `J = sum_i r_i F_i` equal to central
/// differences of the direct solver's own cost (relative step 1e-6) to 1e-6 and to the
/// forward sensitivities' `J^T r` to 1e-9 (each relative to the largest `|g_k c_k|`).
#[test]
fn nodal_prony_gradient_matches_finite_differences() {
    use indentify_adjoint::check::central_difference;
    let m = small_model(cone(), ContactKind::Vertical);
    let s = Schedule::from_segments(&trapezoid(0.1, 1.0, 1.0, 1.0, 5)).unwrap();
    let opts = SolverOptions {
        residual_tol: 1e-13,
        ..SolverOptions::default()
    };
    let mut solver = DirectSolver::new(&m).unwrap();
    let mut worst = (0.0f64, 0.0f64);
    for n in [2, 3] {
        let (mat, c) = prony(n);
        let t = solver.run(&mat, &c, &s, &opts).unwrap();
        let steps = t.steps.len();
        let r: Vec<f64> = (0..steps)
            .map(|i| 1.0 + 0.37 * ((i * 7) % 5) as f64)
            .collect();
        let mut adj = Adjoint::new(&m).unwrap();
        let g = adj.gradient(&mat, &c, &t, &r).unwrap().dj_dc;
        assert!(adj.last_material_sweep_was_nodal());
        let from_sens = adj.sensitivities(&mat, &c, &t).unwrap().transpose_mul(&r);
        let fd: Vec<f64> = (0..c.len())
            .map(|k| {
                central_difference(
                    |p: &[f64]| -> Result<f64, String> {
                        let tp = solver.run(&mat, p, &s, &opts).map_err(|e| e.to_string())?;
                        assert_eq!(tp.steps.len(), steps, "a cut changed the steps");
                        Ok(tp.steps.iter().zip(&r).map(|(s, r)| s.force * r).sum())
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
        "nodal Prony gradient: fd {:e}, sensitivities {:e}",
        worst.0, worst.1
    );
}
