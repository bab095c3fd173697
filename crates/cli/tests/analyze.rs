//! `indentify analyze` and `indentify calibrate` end to end: the table, `--json` with the
//! per-test keys, the tip file round trip, and bad arguments named.

mod common;

use common::{assert_ok, example, indentify, stderr, stdout};

#[test]
fn analyze_prints_the_table_and_the_json() {
    let f = example("data/anton-paar-sphere-creep/HT_V_100mN.TXT");
    let o = indentify(&["analyze", &f, "--tip", "sphere:10", "--epsilon", "m"]);
    assert_ok(&o);
    let t = stdout(&o);
    assert!(t.contains("HT_V_100mN_1") && t.contains("97.21"), "{t}");
    let o = indentify(&["analyze", &f, "--tip", "sphere:10", "--test", "2", "--json"]);
    assert_ok(&o);
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let t = &v["tests"][0];
    for k in ["E", "H", "Er", "S", "hc", "hmax", "Fmax"] {
        assert!(t[k].as_f64().is_some(), "{k}: {t}");
    }
    assert_eq!(v["tip"]["modulus"].as_f64(), Some(1_141_000.0));
}

#[test]
fn calibrate_writes_a_tip_file_that_analyze_reads() {
    let dir = tempfile::tempdir().unwrap();
    let tip = dir.path().join("tip.ron");
    let fs = example("data/kla-fused-silica/FusedSilica.xlsx");
    let o = indentify(&[
        "calibrate",
        &fs,
        "--modulus",
        "72",
        "--nu",
        "0.179",
        "--out",
        tip.to_str().unwrap(),
    ]);
    assert_ok(&o);
    assert!(stdout(&o).contains("frame compliance"), "{}", stdout(&o));
    let out = dir.path().join("out");
    let o = indentify(&[
        "analyze",
        &fs,
        "--tip-file",
        tip.to_str().unwrap(),
        "--nu",
        "0.179",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_ok(&o);
    assert!(out.join("analysis.json").is_file() && out.join("analysis.csv").is_file());
}

#[test]
fn bad_arguments_are_named() {
    let f = example("data/anton-paar-sphere-creep/HT_V_100mN.TXT");
    let o = indentify(&["analyze", &f, "--tip", "pyramid"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("pyramid"), "{}", stderr(&o));
    let o = indentify(&["analyze", &f, "--fit-range", "0.9,0.5"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("fit_range"), "{}", stderr(&o));
}
