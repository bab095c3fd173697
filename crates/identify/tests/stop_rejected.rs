//! Levenberg-Marquardt's rejected trials stopped early (`LmStrategy::stop_rejected`): a
//! trial's forward runs stop between steps once the cost over the steps run already
//! rejects it. The fit with the stop gives the same parameters, costs, iterations,
//! rejected trials and identifiability, bit for bit, as the fit without it, on a small
//! R2-like problem (Norton-Hoff, cone 68 deg, 8 x 8 Q8, 2% noise, warm starts on), on a
//! two-test joint fit on 1 and on 2 threads, and on a load-controlled Maxwell test (cost
//! on the depth); the stop fires (schedule steps skipped > 0).
//!
//! Reference: the same fit with every trial run in full (the code before the stop). The
//! solver's watch (`DirectSolver::watched`) is checked against the unwatched run: the
//! same steps bit for bit up to the stop, and the next run unchanged.

mod common;

use common::{NH_TRUTH as TRUTH, load_hold_unload, nh_data, nh_lm, schedule_depths};
use indentify_contact::{
    ContactError, DirectSolver, Schedule, SolverOptions, StepRecord, StepWatch, trapezoid,
};
use indentify_identify::{
    ForceRecord, IdentifyConfig, IdentifyResult, Method, ParamSpec, Problem, Test, identify,
    multiplicative_noise,
};
use indentify_laws::{LawMaterial, Maxwell, NortonHoff};
use indentify_testkit::{bits, cone_model as model};

fn schedule(rise: f64) -> Schedule {
    Schedule::from_segments(&trapezoid(0.1, rise, 1.0, 1.0, 8)).unwrap()
}

/// A depth-controlled Norton-Hoff test at the truth with 2% noise (seed `seed`).
fn nh_test(rise: f64, seed: u64) -> Test {
    let (s, rec) = nh_data(rise, seed);
    Test::new(model(), s, &rec, None, SolverOptions::default(), 1.0).unwrap()
}

fn nh_config(stop: bool) -> IdentifyConfig {
    let mut cfg = nh_lm();
    cfg.stop.lm.stop_rejected = stop;
    cfg
}

/// Everything a fit reports but the work counts, bit for bit.
fn assert_same(off: &IdentifyResult, on: &IdentifyResult, label: &str) {
    assert_eq!(bits(&off.c), bits(&on.c), "{label}: parameters");
    assert_eq!(off.cost.to_bits(), on.cost.to_bits(), "{label}: cost");
    assert_eq!(off.iterations, on.iterations, "{label}: iterations");
    assert_eq!(off.rejected_trials, on.rejected_trials, "{label}: rejected");
    assert_eq!(off.forward_solves, on.forward_solves, "{label}: forward");
    assert_eq!(
        off.sensitivity_solves, on.sensitivity_solves,
        "{label}: sensitivities"
    );
    assert_eq!(off.stop_reason, on.stop_reason, "{label}: stop");
    assert_eq!(off.history.len(), on.history.len(), "{label}: history");
    for (a, b) in off.history.iter().zip(&on.history) {
        assert_eq!(bits(&a.params), bits(&b.params), "{label}: iterate");
        assert_eq!(a.cost.to_bits(), b.cost.to_bits(), "{label}: iterate cost");
        assert_eq!(a.grad_norm.to_bits(), b.grad_norm.to_bits(), "{label}");
    }
    assert_eq!(bits(&off.forces), bits(&on.forces), "{label}: forces");
    let sd = |r: &IdentifyResult| r.identifiability.as_ref().map(|i| bits(&i.std_dev));
    assert_eq!(sd(off), sd(on), "{label}: deviations");
}

fn report(label: &str, r: &IdentifyResult) {
    println!(
        "{label}: {} it, {} forward, {} rejected, {} runs stopped, {} schedule steps run, \
         {} skipped, {} Newton iterations ({})",
        r.iterations,
        r.forward_solves,
        r.rejected_trials,
        r.stopped_runs,
        r.schedule_steps,
        r.steps_skipped,
        r.newton_iterations,
        r.stop_reason
    );
}

/// The stop fired (at most one run per test of each rejected trial) and accounts for
/// every step the full fit ran.
fn assert_fired(off: &IdentifyResult, on: &IdentifyResult, tests: usize) {
    assert_eq!(off.stopped_runs, 0);
    assert_eq!(off.steps_skipped, 0);
    assert!(on.rejected_trials > 0, "no rejected trial to stop");
    assert!(on.stopped_runs > 0 && on.stopped_runs <= tests * on.rejected_trials);
    assert!(on.steps_skipped > 0, "no step skipped");
    assert_eq!(
        on.schedule_steps + on.steps_skipped,
        off.schedule_steps,
        "steps run + skipped = the full fit's steps"
    );
}

#[test]
fn single_test_fit_is_bit_identical_with_rejected_trials_stopped() {
    let p = Problem::joint(&NortonHoff, vec![nh_test(1.0, 3)]).unwrap();
    let off = identify(&p, &nh_config(false), &mut |_| {}).unwrap();
    let on = identify(&p, &nh_config(true), &mut |_| {}).unwrap();
    report("off", &off);
    report("on", &on);
    assert_same(&off, &on, "single");
    assert_fired(&off, &on, 1);
    // with the first damping from the step's length (configurations' default)
    let radius = |stop| {
        let mut c = nh_config(stop);
        c.stop.lm.first_radius = Some(1.0);
        c
    };
    let off = identify(&p, &radius(false), &mut |_| {}).unwrap();
    let on = identify(&p, &radius(true), &mut |_| {}).unwrap();
    report("radius off", &off);
    report("radius on", &on);
    assert_same(&off, &on, "radius");
}

#[test]
fn joint_fit_is_bit_identical_on_one_and_two_threads() {
    let mut p = Problem::joint(&NortonHoff, vec![nh_test(1.0, 3), nh_test(0.25, 4)]).unwrap();
    p.set_threads(1).unwrap();
    let off = identify(&p, &nh_config(false), &mut |_| {}).unwrap();
    let on1 = identify(&p, &nh_config(true), &mut |_| {}).unwrap();
    p.set_threads(2).unwrap();
    let on2 = identify(&p, &nh_config(true), &mut |_| {}).unwrap();
    report("joint off", &off);
    report("joint on, 1 thread", &on1);
    report("joint on, 2 threads", &on2);
    assert_same(&off, &on1, "joint 1 thread");
    assert_same(&off, &on2, "joint 2 threads");
    assert_fired(&off, &on1, 2);
    // per-test bounds: what stops does not depend on the threads
    assert_eq!(on1.stopped_runs, on2.stopped_runs);
    assert_eq!(on1.steps_skipped, on2.steps_skipped);
    assert_eq!(on1.schedule_steps, on2.schedule_steps);
    assert_eq!(on1.newton_iterations, on2.newton_iterations);
}

#[test]
fn load_controlled_fit_is_bit_identical_with_rejected_trials_stopped() {
    let h = load_hold_unload();
    let truth = [20000.0, 0.3, 30000.0];
    let traj = DirectSolver::new(&model())
        .unwrap()
        .run_history(
            &LawMaterial(&Maxwell),
            &truth,
            &h,
            &SolverOptions::default(),
        )
        .unwrap();
    let d = multiplicative_noise(&schedule_depths(&traj), 0.01, 7);
    let rec = ForceRecord::new(h.schedule.t.clone(), d).unwrap();
    let test = Test::new_load(model(), h, &rec, None, SolverOptions::default(), 1.0).unwrap();
    let p = Problem::joint(&Maxwell, vec![test]).unwrap();
    let cfg = |stop| {
        let mut cfg = IdentifyConfig::new(vec![
            ParamSpec::free("E", 2000.0, 100.0, 1e6),
            ParamSpec::fixed("nu", 0.3),
            ParamSpec::free("eta", 4e5, 1000.0, 1e8),
        ]);
        cfg.method = Method::LevenbergMarquardt;
        cfg.stop.lm.stop_rejected = stop;
        cfg
    };
    let off = identify(&p, &cfg(false), &mut |_| {}).unwrap();
    let on = identify(&p, &cfg(true), &mut |_| {}).unwrap();
    report("load off", &off);
    report("load on", &on);
    assert_same(&off, &on, "load");
    assert_fired(&off, &on, 1);
}

/// Stops after the `n`-th schedule step and keeps what it saw.
struct After {
    n: usize,
    seen: std::sync::Arc<std::sync::Mutex<Vec<StepRecord>>>,
}

impl StepWatch for After {
    fn stop_after(&mut self, step: &StepRecord) -> bool {
        let mut seen = self.seen.lock().unwrap();
        seen.push(step.clone());
        seen.iter().filter(|s| s.on_schedule).count() >= self.n
    }
}

#[test]
fn a_watched_run_is_the_run_up_to_its_stop_and_leaves_the_next_run_unchanged() {
    let m = model();
    let s = schedule(1.0);
    let opts = SolverOptions::default();
    let mut solver = DirectSolver::new(&m).unwrap();
    solver
        .run(&LawMaterial(&NortonHoff), &TRUTH, &s, &opts)
        .unwrap();
    let seen = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
    let watch = After {
        n: 5,
        seen: seen.clone(),
    };
    let other = [1.2e5, 0.3, 1800.0, 5.0, 450.0];
    let stopped = solver.watched(Box::new(watch), |sv| {
        sv.run(&LawMaterial(&NortonHoff), &other, &s, &opts)
    });
    let again = solver
        .run(&LawMaterial(&NortonHoff), &other, &s, &opts)
        .unwrap();
    match stopped {
        Err(ContactError::Stopped {
            step,
            steps,
            newton_iterations,
            factorizations,
            ..
        }) => {
            assert_eq!(step, 5);
            let seen = seen.lock().unwrap();
            assert_eq!(steps, seen.len());
            // the stopped run's work is reported, not dropped
            let iterations: u64 = seen.iter().map(|r| r.iterations as u64).sum();
            assert_eq!(newton_iterations, iterations);
            assert!(factorizations >= 1, "{factorizations} factorizations");
        }
        other => panic!("not stopped: {other:?}"),
    }
    // the watched steps are the unwatched run's, bit for bit
    let seen = seen.lock().unwrap();
    assert_eq!(seen.as_slice(), &again.steps[..seen.len()]);
    // and a run after a stopped one is the same as after a full one
    let after_full = {
        let mut sv = DirectSolver::new(&m).unwrap();
        sv.run(&LawMaterial(&NortonHoff), &TRUTH, &s, &opts)
            .unwrap();
        sv.run(&LawMaterial(&NortonHoff), &other, &s, &opts)
            .unwrap()
    };
    assert_eq!(again.steps, after_full.steps);
    assert_eq!(
        bits(&again.forces()),
        bits(&after_full.forces()),
        "the next run unchanged"
    );
}
