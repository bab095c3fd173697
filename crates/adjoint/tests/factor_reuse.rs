//! The forward's factorization handed to the adjoint (`Adjoint::take_factor`,
//! `crates/adjoint/src/reuse.rs`): the gradients and sensitivities of a run equal those of
//! a fresh workspace (asserted 1e-12 of the largest component, and under load control
//! bit for bit: the same `K`, factor and columns) while the
//! sweep factorizes once less; histories whose step length changes mid-run (the sweep
//! must refactorize for the earlier segments), a solver whose last run had other
//! parameters (its factor is stale and must not be used), load control, depth control
//! and the frame's compliant drive, vertical and normal contact; the same bits on one and
//! two threads; and the solver's next run, given the sweep's last factor back, repeats
//! its trajectory bit for bit with one factorization less.

mod common;

use common::small_model;
use indentify_adjoint::{Adjoint, Gradient, LoadReplay};
use indentify_contact::{
    ContactKind, DirectSolver, Frame, LoadHistory, Model, Punch, Schedule, SolverOptions,
    Trajectory, trapezoid,
};
use indentify_laws::{Elastic, Law, LawMaterial, Maxwell};
use indentify_testkit::{bits, cone68 as cone, depth, force, rel_to_largest as rel};

fn opts() -> SolverOptions {
    SolverOptions {
        record_fields: true,
        residual_tol: 1e-11,
        ..SolverOptions::default()
    }
}

/// Load-hold-unload with the step length changing at every segment (1/6, 1/2, 1/5 s:
/// three tangents, three factorizations in a fresh sweep), and depth-load-hold-depth.
fn histories() -> [LoadHistory; 2] {
    [
        LoadHistory::from_segments(&[
            force(1.0, 40.0, 6),
            force(2.0, 40.0, 4),
            force(1.0, 16.0, 5),
        ])
        .unwrap(),
        LoadHistory::from_segments(&[
            depth(1.0, 0.02, 4),
            force(1.0, 40.0, 6),
            force(3.0, 40.0, 6),
            depth(1.0, 0.02, 5),
        ])
        .unwrap(),
    ]
}

/// The largest difference relative to the largest `|g_k|`.
fn costs(n: usize) -> (Vec<f64>, Vec<f64>) {
    let dj_dh = (0..n).map(|i| 1.0 + (i % 5) as f64).collect();
    let dj_df = (0..n).map(|i| 1e-3 * (1.0 + (i % 3) as f64)).collect();
    (dj_dh, dj_df)
}

/// The fresh and the reused `gradient_load` of `h` at `c`, the reused one after the solver
/// ran `last` (the parameters of its last run: `c` itself, or others whose factor is
/// stale), and whether the solver's run with the sweep's factor handed back repeated the
/// trajectory's bits with one factorization less.
fn load_pair(
    m: &Model,
    law: &dyn Law,
    c: &[f64],
    last: &[f64],
    h: &LoadHistory,
) -> (Gradient, Gradient, bool) {
    let mat = LawMaterial(law);
    let mut solver = DirectSolver::new(m).unwrap();
    let traj = solver.run_history(&mat, c, h, &opts()).unwrap();
    let (dj_dh, dj_df) = costs(traj.steps.len());
    let fresh = Adjoint::new(m)
        .unwrap()
        .gradient_load(&mat, c, &traj, h, &dj_dh, &dj_df)
        .unwrap();
    if last != c {
        solver.run_history(&mat, last, h, &opts()).unwrap();
    }
    let mut adj = Adjoint::new(m).unwrap();
    assert!(adj.take_factor(&mut solver));
    let reused = adj
        .gradient_load(&mat, c, &traj, h, &dj_dh, &dj_df)
        .unwrap();
    // handed back, the sweep's last factor (the first segment's key) serves the solver's
    // next run at `c` for its first segment: one factorization less, the same bits
    assert!(adj.take_factor(&mut solver));
    let again = solver.run_history(&mat, c, h, &opts()).unwrap();
    let fewer = again.timing.factorizations + 1 == traj.timing.factorizations;
    (fresh, reused, fewer && same_run(&traj, &again))
}

fn same_run(a: &Trajectory, b: &Trajectory) -> bool {
    let da: Vec<f64> = a.steps.iter().flat_map(|s| [s.depth, s.force]).collect();
    let db: Vec<f64> = b.steps.iter().flat_map(|s| [s.depth, s.force]).collect();
    bits(&da) == bits(&db)
        && a.fields.len() == b.fields.len()
        && a.fields
            .iter()
            .zip(&b.fields)
            .all(|(x, y)| bits(&x.u) == bits(&y.u))
}

#[test]
fn load_control_reuses_the_forward_factor_and_refactorizes_mid_run() {
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
                let (fresh, reused, repeated) = load_pair(&m, law, c, c, &h);
                let r = rel(&fresh.dj_dc, &reused.dj_dc);
                println!(
                    "{kind:?} {}: reused vs fresh {r:.2e}, factorizations {} -> {}",
                    law.name(),
                    fresh.factorizations,
                    reused.factorizations
                );
                assert!(
                    r <= 1e-12,
                    "{:?} vs {:?}: {r:.2e}",
                    reused.dj_dc,
                    fresh.dj_dc
                );
                // the same K, factor and columns: the same bits
                assert_eq!(bits(&reused.dj_dc), bits(&fresh.dj_dc));
                // the segments' step lengths differ: the fresh sweep factorizes once per
                // tangent, the reused one skips the last only (a reuse of a stale factor
                // for the earlier segments would change the gradient above)
                assert!(fresh.factorizations >= 2, "{}", fresh.factorizations);
                assert_eq!(reused.factorizations + 1, fresh.factorizations);
                assert!(repeated, "the run after the exchange changed its bits");
            }
        }
    }
}

#[test]
fn a_factor_of_other_parameters_is_not_used() {
    let m = small_model(cone(), ContactKind::Vertical);
    let c = [21000.0, 0.3, 25000.0];
    // the last run's parameters: eta alone differs (the tangent, not the elasticity)
    let other = [21000.0, 0.3, 26000.0];
    for h in histories() {
        let (fresh, reused, repeated) = load_pair(&m, &Maxwell, &c, &other, &h);
        let r = rel(&fresh.dj_dc, &reused.dj_dc);
        assert!(
            r <= 1e-12,
            "{:?} vs {:?}: {r:.2e}",
            reused.dj_dc,
            fresh.dj_dc
        );
        assert_eq!(reused.factorizations, fresh.factorizations);
        assert!(repeated);
    }
}

#[test]
fn depth_control_compliant_and_sensitivities_equal_the_fresh_ones() {
    let m = small_model(cone(), ContactKind::Vertical);
    let c = [21000.0, 0.3, 25000.0];
    let mat = LawMaterial(&Maxwell);
    // a trapezoid's load and hold in 6 steps each, its unload in 6 over another length
    let mut segs = trapezoid(0.1, 1.0, 2.0, 1.0, 6);
    segs[1].steps = 4;
    let sched = Schedule::from_segments(&segs).unwrap();
    let mut solver = DirectSolver::new(&m).unwrap();
    let traj = solver.run(&mat, &c, &sched, &opts()).unwrap();
    let rho: Vec<f64> = (0..traj.steps.len()).map(|i| 1.0 + i as f64).collect();
    let fresh = Adjoint::new(&m)
        .unwrap()
        .gradient(&mat, &c, &traj, &rho)
        .unwrap();
    let mut adj = Adjoint::new(&m).unwrap();
    assert!(adj.take_factor(&mut solver));
    let reused = adj.gradient(&mat, &c, &traj, &rho).unwrap();
    assert!(rel(&fresh.dj_dc, &reused.dj_dc) <= 1e-12);
    assert_eq!(reused.factorizations + 1, fresh.factorizations);
    // the next pass starts fresh again
    let after = adj.gradient(&mat, &c, &traj, &rho).unwrap();
    assert_eq!(bits(&after.dj_dc), bits(&fresh.dj_dc));
    assert_eq!(after.factorizations, fresh.factorizations);

    // through the frame
    let frame = Frame {
        compliance: 1e-4,
        ..Frame::default()
    };
    let traj = solver
        .run_compliant(&mat, &c, &sched, &frame, &opts())
        .unwrap();
    let rho: Vec<f64> = traj.steps.iter().map(|s| s.force).collect();
    let fresh = Adjoint::new(&m)
        .unwrap()
        .gradient_compliant(&mat, &c, &traj, (&sched, &frame), &rho)
        .unwrap();
    assert!(adj.take_factor(&mut solver));
    let reused = adj
        .gradient_compliant(&mat, &c, &traj, (&sched, &frame), &rho)
        .unwrap();
    let r = rel(&fresh.dj_dc, &reused.dj_dc);
    assert!(r <= 1e-12, "compliant: {r:.2e}");
    assert!(rel(&fresh.dj_dframe, &reused.dj_dframe) <= 1e-12);
    assert_eq!(reused.factorizations + 1, fresh.factorizations);

    // the load-controlled forward sensitivities
    let h = &histories()[0];
    let traj = solver.run_history(&mat, &c, h, &opts()).unwrap();
    let fresh = Adjoint::new(&m)
        .unwrap()
        .sensitivities_load(&mat, &c, &traj, h)
        .unwrap();
    assert!(adj.take_factor(&mut solver));
    let reused = adj.sensitivities_load(&mat, &c, &traj, h).unwrap();
    for (a, b) in fresh.dh_dc.iter().zip(&reused.dh_dc) {
        assert!(rel(a, b) <= 1e-12, "{a:?} vs {b:?}");
    }
}

#[test]
fn checkpointed_runs_replayed_with_the_forward_factor() {
    // the replaying solver runs beside the sweep: it holds the adjoint's old factor
    // after the exchange, and its stretches must still repeat the recorded steps
    let m = small_model(cone(), ContactKind::Vertical);
    let c = [21000.0, 0.3, 25000.0];
    let mat = LawMaterial(&Maxwell);
    let ck_opts = SolverOptions {
        record_fields: false,
        checkpoint_every: 4,
        ..opts()
    };
    for h in histories() {
        let mut solver = DirectSolver::new(&m).unwrap();
        let ck = solver.run_history(&mat, &c, &h, &ck_opts).unwrap();
        assert!(ck.checkpoints.len() > 1);
        let (dj_dh, dj_df) = costs(ck.steps.len());
        let sweep = |adj: &mut Adjoint, solver: &mut DirectSolver| {
            adj.gradient_load_replayed(
                &mat,
                &c,
                &ck,
                &h,
                &dj_dh,
                &dj_df,
                LoadReplay {
                    solver,
                    opts: &ck_opts,
                },
            )
            .unwrap()
        };
        let fresh = sweep(&mut Adjoint::new(&m).unwrap(), &mut solver);
        solver.run_history(&mat, &c, &h, &ck_opts).unwrap();
        let mut adj = Adjoint::new(&m).unwrap();
        assert!(adj.take_factor(&mut solver));
        let reused = sweep(&mut adj, &mut solver);
        let r = rel(&fresh.dj_dc, &reused.dj_dc);
        println!(
            "replayed: reused vs fresh {r:.2e}, factorizations {} -> {}",
            fresh.factorizations, reused.factorizations
        );
        assert!(
            r <= 1e-12,
            "{:?} vs {:?}: {r:.2e}",
            reused.dj_dc,
            fresh.dj_dc
        );
        assert_eq!(reused.factorizations + 1, fresh.factorizations);
    }
}

#[test]
fn a_solver_of_another_model_is_refused() {
    let m = small_model(cone(), ContactKind::Vertical);
    let other = small_model(cone(), ContactKind::Vertical);
    let mut solver = DirectSolver::new(&other).unwrap();
    let mut adj = Adjoint::new(&m).unwrap();
    assert!(!adj.take_factor(&mut solver));
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
            .install(|| load_pair(&m, &Maxwell, &c, &c, h))
    };
    let (one, two) = (on(1), on(2));
    assert_eq!(bits(&one.1.dj_dc), bits(&two.1.dj_dc));
    assert_eq!(bits(&one.0.dj_dc), bits(&two.0.dj_dc));
}
