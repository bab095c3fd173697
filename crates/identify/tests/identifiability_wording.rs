//! The identifiability's reasons name what the data observe: a parameter without effect is
//! "no effect on the force" under depth control, "no effect on the depth under load
//! control" under load control (the depth is the observable there, docs/theory.md §13),
//! and names both for a joint fit of mixed drives.
//!
//! The parameter without effect is real, not a made-up column: a Norton-Hoff solid whose
//! yield stress (1e7 MPa) is never reached flows nowhere, so its `K` changes neither the
//! force of a depth-controlled test nor the depth of a load-controlled one (its
//! sensitivity is exactly 0), while `E` does.

use indentify_contact::{
    DirectSolver, HistorySegment, LoadHistory, Model, Schedule, Segment, SolverOptions,
};
use indentify_identify::{
    ForceRecord, IdentifyConfig, Method, Observed, ParamSpec, Problem, Test, identify,
};
use indentify_laws::{LawMaterial, NortonHoff};
use indentify_testkit::{cone68, cylinder};

/// E, nu, K, m, sY: sY beyond any stress of the run.
const TRUTH: [f64; 5] = [20000.0, 0.3, 1500.0, 5.0, 1e7];

fn model() -> Model {
    Model::new(cylinder(4.0, 6, 1.45), cone68()).unwrap()
}

fn opts() -> SolverOptions {
    SolverOptions {
        residual_tol: 1e-11,
        ..SolverOptions::default()
    }
}

fn load_history() -> LoadHistory {
    let seg = |force| HistorySegment {
        duration: 1.0,
        depth: None,
        force: Some(force),
        steps: 4,
    };
    LoadHistory::from_segments(&[seg(60.0), seg(60.0)]).unwrap()
}

fn depth_schedule() -> Schedule {
    let seg = |depth| Segment {
        duration: 1.0,
        depth,
        steps: 4,
    };
    Schedule::from_segments(&[seg(0.02), seg(0.02)]).unwrap()
}

/// A load-controlled test with the truth's exact depths.
fn load_test() -> Test {
    let h = load_history();
    let traj = DirectSolver::new(&model())
        .unwrap()
        .run_history(&LawMaterial(&NortonHoff), &TRUTH, &h, &opts())
        .unwrap();
    let depths: Vec<f64> = std::iter::once(0.0)
        .chain(traj.schedule_steps().map(|s| s.depth))
        .collect();
    let record = ForceRecord::new(h.schedule.t.clone(), depths).unwrap();
    Test::new_load(model(), h, &record, None, opts(), 1.0).unwrap()
}

/// A depth-controlled test with the truth's exact forces.
fn depth_test() -> Test {
    let s = depth_schedule();
    let traj = DirectSolver::new(&model())
        .unwrap()
        .run(&LawMaterial(&NortonHoff), &TRUTH, &s, &opts())
        .unwrap();
    let record = ForceRecord::new(s.t.clone(), traj.forces()).unwrap();
    Test::new(model(), s, &record, None, opts(), 1.0).unwrap()
}

/// The reason `identify` gives for `K` (free with `E`, from the truth, LM).
fn reason_for_k(p: &Problem) -> String {
    let mut cfg = IdentifyConfig::new(vec![
        ParamSpec::free("E", TRUTH[0], 1000.0, 1e6),
        ParamSpec::fixed("nu", TRUTH[1]),
        ParamSpec::free("K", TRUTH[2], 10.0, 1e5),
        ParamSpec::fixed("m", TRUTH[3]),
        ParamSpec::fixed("sY", TRUTH[4]),
    ]);
    cfg.method = Method::LevenbergMarquardt;
    cfg.stop.max_iterations = 2;
    let r = identify(p, &cfg, &mut |_| {}).unwrap();
    let id = r.identifiability.expect("an identifiability summary");
    assert!(!id.undetermined.contains(&"E"), "{:?}", id.reasons);
    let k = id
        .undetermined
        .iter()
        .position(|n| *n == "K")
        .unwrap_or_else(|| panic!("K undetermined: {:?} {:?}", id.undetermined, id.reasons));
    id.reasons[k].clone()
}

#[test]
fn no_effect_names_the_depth_under_load_control() {
    let p = Problem::joint(&NortonHoff, vec![load_test()]).unwrap();
    assert_eq!(p.observed(), Observed::Depth);
    let reason = reason_for_k(&p);
    assert!(
        reason.starts_with("no effect on the depth under load control (sensitivity"),
        "{reason}"
    );
    assert!(!reason.contains("force"), "{reason}");
}

#[test]
fn no_effect_names_the_force_under_depth_control_and_both_for_mixed_drives() {
    let p = Problem::joint(&NortonHoff, vec![depth_test()]).unwrap();
    assert_eq!(p.observed(), Observed::Force);
    let reason = reason_for_k(&p);
    assert!(
        reason.starts_with("no effect on the force (sensitivity"),
        "{reason}"
    );
    let p = Problem::joint(&NortonHoff, vec![depth_test(), load_test()]).unwrap();
    assert_eq!(p.observed(), Observed::ForceAndDepth);
    let reason = reason_for_k(&p);
    assert!(
        reason.starts_with(
            "no effect on the force (depth control) or the depth (load control) (sensitivity"
        ),
        "{reason}"
    );
}
