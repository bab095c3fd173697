//! The batch runner end to end on a small synthetic two-phase map: both phases recovered,
//! reruns skip finished indents, a bad indent fails alone, shards merged equal one run
//! bit for bit whatever the number of workers, and a folder of another batch is refused.

use std::path::Path;

use indentify_study::batch::{self, BatchOptions, Shard, State};
use indentify_study::synthetic::{MapOptions, PHASE_A, PHASE_B, make_map};

/// results.csv without the wall-time column (the only one that may differ between runs).
fn results_without_seconds(dir: &Path) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(dir.join("results.csv")).unwrap();
    let mut rows: Vec<Vec<String>> = text
        .lines()
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    let k = rows[0].iter().position(|c| c == "seconds").unwrap();
    for r in &mut rows {
        r.remove(k);
    }
    rows
}

#[test]
fn a_map_is_identified_sharded_merged_and_rerun() {
    let tmp = tempfile::tempdir().unwrap();
    let map = make_map(
        &tmp.path().join("map"),
        &MapOptions {
            n: 3,
            spacing: 0.1,
            noise: 0.01,
            seed: 7,
            coarse: true,
        },
    )
    .unwrap();
    assert_eq!(map.indents.iter().filter(|i| i.3 == 'B').count(), 1);

    // one run on two workers
    let whole = tmp.path().join("whole");
    let mut opts = BatchOptions::new(map.manifest.clone(), whole.clone());
    opts.config = Some(map.base.clone());
    opts.jobs = 2;
    let s = batch::run(&opts, &()).unwrap();
    assert_eq!((s.total, s.ran, s.skipped), (9, 9, 0));
    assert_eq!(s.counts.get("converged"), Some(&9), "{:?}", s.counts);
    for (id, _, _, phase) in &map.indents {
        let st = batch::read_status(&whole, id).unwrap();
        assert_eq!(st.state, State::Converged, "{id}: {}", st.message);
        let (e, eta) = if *phase == 'A' { PHASE_A } else { PHASE_B };
        let rel = |v: f64, t: f64| ((v - t) / t).abs();
        assert!(rel(st.values[0], e) < 0.03, "{id} E = {}", st.values[0]);
        assert!(rel(st.values[2], eta) < 0.06, "{id} eta = {}", st.values[2]);
        assert!(st.std_dev[0].is_some_and(|s| s > 0.0));
    }
    for f in [
        "E_map.svg",
        "E_map.png",
        "eta_hist.svg",
        "R2_map.png",
        "E_std_map.svg",
        "eta_std_map.png",
    ] {
        assert!(whole.join("maps").join(f).is_file(), "{f}");
    }
    // positions in mm on both axes; each indent's adequacy in results.csv
    let svg = std::fs::read_to_string(whole.join("maps/E_std_map.svg")).unwrap();
    assert!(svg.contains("σ of E (MPa)") && svg.contains("x [mm]"));
    let csv = std::fs::read_to_string(whole.join("results.csv")).unwrap();
    assert!(csv.lines().next().unwrap().ends_with(",adequacy"), "{csv}");
    let svg = std::fs::read_to_string(whole.join("maps/eta_map.svg")).unwrap();
    assert!(
        svg.contains("eta (MPa s)"),
        "the map's title names the unit"
    );

    // a rerun skips every finished indent and rebuilds the same results
    let before = results_without_seconds(&whole);
    let s = batch::run(&opts, &()).unwrap();
    assert_eq!((s.ran, s.skipped), (0, 9));
    assert_eq!(results_without_seconds(&whole), before);

    // two shards on one worker each, then merge: the same numbers to the bit
    let sharded = tmp.path().join("sharded");
    for k in 1..=2 {
        let mut o = BatchOptions::new(map.manifest.clone(), sharded.clone());
        o.config = Some(map.base.clone());
        o.jobs = 1;
        o.shard = Some(Shard { index: k, count: 2 });
        let s = batch::run(&o, &()).unwrap();
        assert_eq!(s.in_shard, if k == 1 { 5 } else { 4 });
        assert_eq!(s.missing.len(), if k == 1 { 4 } else { 0 });
    }
    let merged = batch::merge(&sharded).unwrap();
    assert!(merged.missing.is_empty());
    assert_eq!(results_without_seconds(&sharded), before);

    // another manifest into the same folder is refused, and nothing there is touched
    let other = tmp.path().join("other.csv");
    std::fs::write(&other, "id,data\nq,map/records/p00_00.csv\n").unwrap();
    let mut o = BatchOptions::new(other, whole.clone());
    o.config = Some(map.base.clone());
    let e = batch::run(&o, &()).unwrap_err().to_string();
    assert!(e.contains("holds another batch"), "{e}");
    assert_eq!(results_without_seconds(&whole), before);
}

#[test]
fn a_bad_indent_fails_alone_and_is_retried_on_request() {
    let tmp = tempfile::tempdir().unwrap();
    let map = make_map(
        &tmp.path().join("map"),
        &MapOptions {
            n: 1,
            spacing: 0.1,
            noise: 0.0,
            seed: 1,
            coarse: true,
        },
    )
    .unwrap();
    let manifest = tmp.path().join("map/two.csv");
    std::fs::write(
        &manifest,
        "id,data,law.E\nok,records/p00_00.csv,\nmissing,records/nothing.csv,\n",
    )
    .unwrap();
    let out = tmp.path().join("out");
    let mut opts = BatchOptions::new(manifest, out.clone());
    opts.config = Some(map.base.clone());
    opts.jobs = 2;
    let s = batch::run(&opts, &()).unwrap();
    assert_eq!(s.counts.get("converged"), Some(&1), "{:?}", s.counts);
    assert_eq!(s.counts.get("failed"), Some(&1), "{:?}", s.counts);
    let missing = batch::read_status(&out, "missing").unwrap();
    assert_eq!(missing.error_kind.as_deref(), Some("data"));
    assert!(
        missing.message.contains("nothing.csv"),
        "{}",
        missing.message
    );
    // a law column out of range is refused before anything runs (batch_law_columns.rs)
    let csv = std::fs::read_to_string(out.join("results.csv")).unwrap();
    assert!(csv.contains("nothing.csv"), "{csv}");
    // a plain rerun leaves failures alone; --retry-failed redoes them (and they fail again)
    let s = batch::run(&opts, &()).unwrap();
    assert_eq!(s.ran, 0);
    opts.retry_failed = true;
    let s = batch::run(&opts, &()).unwrap();
    assert_eq!((s.ran, s.skipped), (1, 1));
}
