//! The one-pass sweep of a law with one tangent at every Gauss point (elasticity,
//! Maxwell; `crates/adjoint/src/affine.rs`) against the general two-pass sweep
//! (`Adjoint::set_fused(false)`): the same gradient to 1e-12 relative (the largest
//! `|dJ/dc_k|`) under load control (load-hold-unload, depth-load-hold-depth with costs on
//! depths and forces, checkpointed and replayed) and depth control, vertical and normal
//! contact; and the same bits on one and two threads.

mod common;

use common::small_model;
use indentify_adjoint::{Adjoint, LoadReplay};
use indentify_contact::{
    ContactKind, DirectSolver, LoadHistory, Model, Punch, Schedule, SolverOptions, trapezoid,
};
use indentify_laws::{Elastic, Law, LawMaterial, Maxwell};
use indentify_testkit::{cone68 as cone, depth, force, rel_to_largest as rel};

fn opts(record: bool, every: usize) -> SolverOptions {
    SolverOptions {
        record_fields: record,
        checkpoint_every: every,
        residual_tol: 1e-11,
        ..SolverOptions::default()
    }
}

fn histories() -> [LoadHistory; 2] {
    [
        LoadHistory::from_segments(&[
            force(1.0, 40.0, 6),
            force(1.0, 40.0, 6),
            force(1.0, 16.0, 6),
        ])
        .unwrap(),
        LoadHistory::from_segments(&[
            depth(1.0, 0.02, 4),
            force(1.0, 40.0, 6),
            force(1.0, 40.0, 6),
            depth(1.0, 0.02, 5),
        ])
        .unwrap(),
    ]
}

/// The largest difference relative to the largest `|g_k|`.
/// A cost on every step's depth and on every step's force (each used where it is the
/// observable).
fn costs(n: usize) -> (Vec<f64>, Vec<f64>) {
    let dj_dh = (0..n).map(|i| 1.0 + (i % 5) as f64).collect();
    let dj_df = (0..n).map(|i| 1e-3 * (1.0 + (i % 3) as f64)).collect();
    (dj_dh, dj_df)
}

/// `gradient_load` of the recorded run, fused or not, and of the checkpointed run.
fn load_gradients(m: &Model, law: &dyn Law, c: &[f64], h: &LoadHistory) -> [Vec<f64>; 3] {
    let mat = LawMaterial(law);
    let mut solver = DirectSolver::new(m).unwrap();
    let traj = solver.run_history(&mat, c, h, &opts(true, 0)).unwrap();
    let (dj_dh, dj_df) = costs(traj.steps.len());
    let mut adj = Adjoint::new(m).unwrap();
    let fused = adj
        .gradient_load(&mat, c, &traj, h, &dj_dh, &dj_df)
        .unwrap()
        .dj_dc;
    adj.set_fused(false);
    let general = adj
        .gradient_load(&mat, c, &traj, h, &dj_dh, &dj_df)
        .unwrap()
        .dj_dc;
    adj.set_fused(true);
    let ck_opts = opts(false, 4);
    let ck = solver.run_history(&mat, c, h, &ck_opts).unwrap();
    assert!(ck.checkpoints.len() > 1);
    let replayed = adj
        .gradient_load_replayed(
            &mat,
            c,
            &ck,
            h,
            &dj_dh,
            &dj_df,
            LoadReplay {
                solver: &mut solver,
                opts: &ck_opts,
            },
        )
        .unwrap()
        .dj_dc;
    [fused, general, replayed]
}

#[test]
fn load_control_fused_equals_general() {
    let maxwell = [21000.0, 0.3, 25000.0];
    for (punch, kind) in [
        (cone(), ContactKind::Vertical),
        (Punch::Sphere { radius: 1.0 }, ContactKind::Normal),
    ] {
        let m = small_model(punch, kind);
        for h in histories() {
            for (law, c) in [
                (&Maxwell as &dyn Law, &maxwell[..]),
                (&Elastic, &[21000.0, 0.32][..]),
            ] {
                let [fused, general, replayed] = load_gradients(&m, law, c, &h);
                let r = rel(&general, &fused);
                println!("{kind:?} {}: fused vs general {r:.2e}", law.name());
                assert!(r <= 1e-12, "{fused:?} vs {general:?}: {r:.2e}");
                let r = rel(&fused, &replayed);
                assert!(r <= 1e-10, "replayed {replayed:?} vs {fused:?}: {r:.2e}");
            }
        }
    }
}

#[test]
fn depth_control_fused_equals_general() {
    let m = small_model(cone(), ContactKind::Vertical);
    let sched = Schedule::from_segments(&trapezoid(0.1, 1.0, 1.0, 1.0, 6)).unwrap();
    let c = [21000.0, 0.3, 25000.0];
    let mat = LawMaterial(&Maxwell);
    let mut solver = DirectSolver::new(&m).unwrap();
    let traj = solver.run(&mat, &c, &sched, &opts(true, 0)).unwrap();
    let rho: Vec<f64> = (0..traj.steps.len()).map(|i| 1.0 + i as f64).collect();
    let mut adj = Adjoint::new(&m).unwrap();
    let fused = adj.gradient(&mat, &c, &traj, &rho).unwrap().dj_dc;
    adj.set_fused(false);
    let general = adj.gradient(&mat, &c, &traj, &rho).unwrap().dj_dc;
    let r = rel(&general, &fused);
    assert!(r <= 1e-12, "{fused:?} vs {general:?}: {r:.2e}");
}

#[test]
fn one_and_two_threads_give_the_same_bits() {
    let m = small_model(cone(), ContactKind::Vertical);
    let c = [21000.0, 0.3, 25000.0];
    let h = &histories()[1];
    let on = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| load_gradients(&m, &Maxwell, &c, h))
    };
    let (one, two) = (on(1), on(2));
    for (a, b) in one.iter().zip(&two) {
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(a), bits(b));
    }
}
