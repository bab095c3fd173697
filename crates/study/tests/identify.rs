//! The identification pipeline as a library: a dict-like configuration, an observer that
//! sees every iteration, a cancel flag that ends the run after the current iteration with
//! its report written, and error kinds that front ends map onto their own classes.

mod common;

use common::coarse as opts;
use indentify_identify::{IterationRecord, StopReason};
use indentify_study::identify::{self, IdentifyOptions, Observer, RunInfo};
use indentify_study::{ConfigSource, ErrorKind};

/// Counts iterations and raises the cancel flag after the second.
struct StopAfterTwo {
    seen: Vec<usize>,
    cancel: indentify_identify::Cancel,
    started: bool,
}

impl Observer for StopAfterTwo {
    fn started(&mut self, info: &RunInfo) {
        assert_eq!(info.names, ["E", "nu", "eta"]);
        self.started = true;
    }
    fn iteration(&mut self, r: &IterationRecord) {
        self.seen.push(r.iteration);
        if r.iteration == 2 {
            self.cancel.raise();
        }
    }
}

#[test]
fn a_cancelled_run_stops_after_its_iteration_with_the_report_written() {
    let tmp = tempfile::tempdir().unwrap();
    let mut o = opts();
    o.out = Some(tmp.path().to_path_buf());
    let mut obs = StopAfterTwo {
        seen: Vec::new(),
        cancel: o.cancel.clone(),
        started: false,
    };
    let outcome = identify::run(&o, &mut obs).unwrap();
    assert!(obs.started);
    assert_eq!(obs.seen, [0, 1, 2]);
    assert_eq!(outcome.result.stop_reason, StopReason::Interrupted);
    assert!(!outcome.converged());
    let result: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(tmp.path().join("result.json")).unwrap())
            .unwrap();
    assert_eq!(result["stop_reason"], "interrupted");
    assert_eq!(result["converged"], false);
    let history = std::fs::read_to_string(tmp.path().join("history.csv")).unwrap();
    assert_eq!(history.lines().count(), 4, "{history}");
    // and it resumes to convergence
    let mut o2 = opts();
    o2.out = Some(tmp.path().to_path_buf());
    o2.resume = true;
    let done = identify::run(&o2, &mut ()).unwrap();
    assert!(done.converged(), "{}", done.result.stop_reason);
    assert!(done.resumed);
    let e = done.value("E").unwrap();
    assert!((e - 20000.0).abs() < 1e-3 * 20000.0, "E = {e}");
}

#[test]
fn errors_carry_their_kind() {
    let mut o = opts();
    o.sets.push("law.E=-3".into());
    assert_eq!(
        identify::run(&o, &mut ()).unwrap_err().kind(),
        ErrorKind::Config
    );
    let mut o = opts();
    o.data = Some("definitely-missing.csv".into());
    let e = identify::run(&o, &mut ()).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Data);
    assert!(
        e.messages().join(" ").contains("definitely-missing.csv"),
        "{e:?}"
    );
    // a record whose file is missing is a data error too, not a configuration error
    let mut o = IdentifyOptions::new(ConfigSource::Path(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../examples/real/anon-maxwell.ron"),
    ));
    o.sets.push("data.file=nowhere.txt".into());
    assert_eq!(
        identify::run(&o, &mut ()).unwrap_err().kind(),
        ErrorKind::Data
    );
}

#[test]
fn checkpointed_runs_agree_with_recorded_ones() {
    let full = identify::run(&opts(), &mut ()).unwrap();
    let mut o = opts();
    o.checkpoint = Some(3);
    let ck = identify::run(&o, &mut ()).unwrap();
    // a memory budget below the recording checkpoints by itself
    let mut o = opts();
    o.memory_budget = 1000;
    let auto = identify::run(&o, &mut ()).unwrap();
    for r in [&ck, &auto] {
        assert!(r.converged());
        for (a, b) in full.result.params.iter().zip(&r.result.params) {
            assert!(
                (a.value - b.value).abs() <= 1e-6 * a.value.abs(),
                "{}: {} vs {}",
                a.name,
                a.value,
                b.value
            );
        }
    }
    let mut o = opts();
    o.checkpoint = Some(0);
    assert_eq!(
        identify::run(&o, &mut ()).unwrap_err().kind(),
        ErrorKind::Config
    );
}
