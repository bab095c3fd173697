//! The refresh policy of the inexact Newton solves (`refresh.rs`, docs/performance.md "The
//! preconditioner refresh policy") on R2's mesh and history (docs/theory.md §11) with
//! rate-independent Voce hardening, the law whose tangent changes most: the adaptive rule
//! falls back less and factorizes less than the legacy one, converges to the same
//! solution (to the solver's tolerance), gives the same bits on 1 and 2 threads and in a
//! replay from a checkpoint, and whatever ran before on the same solver; `Auto` is the
//! legacy rule for Norton-Hoff (its pinned bits) and the adaptive one for Plastic.

use indentify_contact::{
    DirectSolver, Model, Punch, RefreshRule, Schedule, SolverOptions, Trajectory, trapezoid,
};
use indentify_laws::{Hardening, LawMaterial, Material, NortonHoff, Plastic, Prony, Rate};
use indentify_mesh::CylinderMesher;

fn r2_model() -> Model {
    Model::new(
        CylinderMesher::REFERENCE.build().unwrap(),
        Punch::Cone {
            half_angle_deg: 68.0,
        },
    )
    .unwrap()
}

fn schedule() -> Schedule {
    Schedule::from_segments(&trapezoid(0.1, 1.0, 1.0, 1.0, 30)).unwrap()
}

fn voce() -> (Plastic, Vec<f64>) {
    (
        Plastic::new(Hardening::Voce, Rate::Independent),
        vec![1e5, 0.3, 500.0, 300.0, 20.0],
    )
}

fn run(model: &Model, mat: &dyn Material, c: &[f64], rule: RefreshRule) -> Trajectory {
    let mut solver = DirectSolver::new(model).unwrap();
    solver.set_refresh_rule(rule);
    solver
        .run(mat, c, &schedule(), &SolverOptions::default())
        .unwrap()
}

fn bits(t: &Trajectory) -> Vec<u64> {
    t.steps
        .iter()
        .map(|s| s.force.to_bits())
        .chain(t.fields.last().unwrap().u.iter().map(|u| u.to_bits()))
        .collect()
}

/// Adaptive against legacy on Voce: fewer fallbacks and factorizations, the same forces to
/// the solver's tolerance; `Auto` is adaptive for Plastic, legacy for Norton-Hoff.
#[test]
fn adaptive_refresh_falls_back_less_and_converges_to_the_same_forces() {
    let model = r2_model();
    let (mat, c) = voce();
    let legacy = run(&model, &mat, &c, RefreshRule::Legacy);
    let adaptive = run(&model, &mat, &c, RefreshRule::Adaptive);
    let (l, a) = (legacy.timing, adaptive.timing);
    println!(
        "legacy: {} Newton, {} PCG, {} fallbacks, {} factorizations; adaptive: {} Newton, \
         {} PCG, {} fallbacks, {} factorizations",
        legacy.total_iterations(),
        l.pcg_solves,
        l.pcg_fallbacks,
        l.factorizations,
        adaptive.total_iterations(),
        a.pcg_solves,
        a.pcg_fallbacks,
        a.factorizations
    );
    assert!(a.pcg_fallbacks * 2 < l.pcg_fallbacks, "{a:?} against {l:?}");
    assert!(a.factorizations < l.factorizations);
    assert!(a.cg_iterations < l.cg_iterations);
    // the same steps, the same forces to the Newton tolerance (relative residual 1e-10:
    // forces agree far below 1e-6 of the largest)
    let fmax = legacy.steps.iter().map(|s| s.force).fold(0.0, f64::max);
    // (step cuts may differ: the steps of the schedule are compared)
    println!(
        "steps with sub-steps: legacy {}, adaptive {}",
        legacy.steps.len(),
        adaptive.steps.len()
    );
    assert_eq!(
        legacy.schedule_steps().count(),
        adaptive.schedule_steps().count()
    );
    // before the first step either run cut, the same time steps: the same forces to the
    // Newton tolerance; after it, the sub-steps' time discretization differs (a
    // rate-independent path): the difference stays small
    let first_cut = |t: &Trajectory| {
        t.steps
            .iter()
            .position(|s| !s.on_schedule)
            .map_or(usize::MAX, |k| t.steps[k].schedule_index)
    };
    let cut = first_cut(&legacy).min(first_cut(&adaptive));
    let (mut before, mut after) = (0.0f64, 0.0f64);
    for (x, y) in legacy.schedule_steps().zip(adaptive.schedule_steps()) {
        let d = (x.force - y.force).abs() / fmax;
        if x.schedule_index < cut {
            before = before.max(d);
        } else {
            after = after.max(d);
        }
    }
    println!(
        "first cut at schedule step {cut}; largest force difference of the largest force: \
         {before:.2e} before it, {after:.2e} after"
    );
    assert!(before < 1e-8, "{before}");
    assert!(after < 1e-5, "{after}");
    // Auto: adaptive for a material with internal variables ...
    assert_eq!(
        bits(&run(&model, &mat, &c, RefreshRule::Auto)),
        bits(&adaptive)
    );
    // ... and legacy for a stress-only law
    let nh = [1e5, 0.3, 1500.0, 5.0, 500.0];
    let law = LawMaterial(&NortonHoff);
    assert_eq!(
        bits(&run(&model, &law, &nh, RefreshRule::Auto)),
        bits(&run(&model, &law, &nh, RefreshRule::Legacy))
    );
}

/// The adaptive rule reads counts, never clocks: the same bits on 1 and 2 threads, and a
/// replay from a checkpoint repeats the run's steps bit for bit.
#[test]
fn adaptive_refresh_is_reproducible_across_threads_and_replays() {
    let model = r2_model();
    let (mat, c) = voce();
    let pool = |n: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .unwrap()
    };
    let one = pool(1).install(|| run(&model, &mat, &c, RefreshRule::Adaptive));
    let two = pool(2).install(|| run(&model, &mat, &c, RefreshRule::Adaptive));
    assert_eq!(bits(&one), bits(&two));
    let opts = SolverOptions {
        checkpoint_every: 20,
        ..SolverOptions::default()
    };
    let mut solver = DirectSolver::new(&model).unwrap();
    solver.set_refresh_rule(RefreshRule::Adaptive);
    let sched = schedule();
    let full = solver.run(&mat, &c, &sched, &opts).unwrap();
    // every stretch (the unloading's, where the streaks are, included) replayed
    for (k, ck) in full.checkpoints.iter().enumerate() {
        let j_end = full
            .checkpoints
            .get(k + 1)
            .map_or(sched.t.len() - 1, |n| n.schedule_index);
        let replayed = solver.replay(&mat, &c, &sched, &opts, ck, j_end).unwrap();
        let start = ck.steps_done;
        for (a, b) in replayed.steps.iter().zip(&full.steps[start..]) {
            assert_eq!(a.force.to_bits(), b.force.to_bits(), "step at t = {}", a.t);
        }
        assert!(!replayed.steps.is_empty());
    }
}

/// A material's run does not depend on what ran before on the solver: after a linear
/// law's run (Prony: a reusable tangent whose factor the system keeps), Voce gives the
/// bits of a fresh solver (its first solve factorizes instead of preconditioning CG with
/// that factor).
#[test]
fn a_run_does_not_depend_on_an_earlier_linear_run() {
    let model = r2_model();
    let (mat, c) = voce();
    let fresh = run(&model, &mat, &c, RefreshRule::Auto);
    let mut solver = DirectSolver::new(&model).unwrap();
    let prony = Prony::new(1).unwrap();
    solver
        .run(
            &prony,
            &[1e5, 0.3, 0.3, 0.2],
            &schedule(),
            &SolverOptions::default(),
        )
        .unwrap();
    let after = solver
        .run(&mat, &c, &schedule(), &SolverOptions::default())
        .unwrap();
    assert_eq!(bits(&after), bits(&fresh));
    // the same for a stress-only nonlinear law (Norton-Hoff) after a linear one
    let nh = LawMaterial(&NortonHoff);
    let nh_c = [1e5, 0.3, 1500.0, 5.0, 500.0];
    let nh_fresh = run(&model, &nh, &nh_c, RefreshRule::Auto);
    solver
        .run(
            &prony,
            &[1e5, 0.3, 0.3, 0.2],
            &schedule(),
            &SolverOptions::default(),
        )
        .unwrap();
    let nh_after = solver
        .run(&nh, &nh_c, &schedule(), &SolverOptions::default())
        .unwrap();
    assert_eq!(bits(&nh_after), bits(&nh_fresh));
}

/// Load control (R2's load and hold under Norton-Hoff, the force history of the
/// depth-controlled run): with the depth column's CG started from the last iterate's
/// column and the refresh reading the larger of an iterate's two solves, the
/// load-controlled run still returns to the depth-controlled depths to the solver's
/// tolerance.
#[test]
fn load_control_returns_to_the_depth_controlled_depths() {
    use indentify_contact::{LoadHistory, Segment};
    let model = r2_model();
    let seg = |depth| Segment {
        duration: 1.0,
        depth,
        steps: 30,
    };
    let sched = Schedule::from_segments(&[seg(0.1), seg(0.1)]).unwrap();
    let law = LawMaterial(&NortonHoff);
    let nh = [1e5, 0.3, 1500.0, 5.0, 500.0];
    let mut solver = DirectSolver::new(&model).unwrap();
    let opts = SolverOptions::default();
    let by_depth = solver.run(&law, &nh, &sched, &opts).unwrap();
    let history = LoadHistory::from_force_record(&sched.t, &by_depth.forces()).unwrap();
    let by_force = solver.run_history(&law, &nh, &history, &opts).unwrap();
    let tm = by_force.timing;
    println!(
        "load control: {} Newton iterations, {} PCG solves, {} CG iterations, {} fallbacks, \
         {} factorizations",
        by_force.total_iterations(),
        tm.pcg_solves,
        tm.cg_iterations,
        tm.pcg_fallbacks,
        tm.factorizations
    );
    let worst = by_depth
        .schedule_steps()
        .zip(by_force.schedule_steps())
        .map(|(a, b)| (a.depth - b.depth).abs() / 0.1)
        .fold(0.0, f64::max);
    println!("largest depth difference {worst:.2e} of the largest depth");
    assert!(worst < 1e-6, "{worst}");
}
