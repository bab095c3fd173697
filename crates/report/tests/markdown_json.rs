//! Markdown snapshot and JSON round trip of small fixed reports.

mod common;

use indentify_report::Report;

/// The Markdown of a nano-indentation report shall show parameters in their own units
/// (GPa), forces in mN, and every section.
#[test]
fn nano_report_markdown_snapshot() {
    let md = common::nano_report().to_markdown();
    insta::assert_snapshot!(md);
}

/// A macroscopic test shall read in N, not mN.
#[test]
fn macro_report_reads_in_newton() {
    let md = common::macro_report().to_markdown();
    assert!(md.contains("| RMS force residual |"));
    let rms_line = md
        .lines()
        .find(|l| l.starts_with("| RMS force residual"))
        .unwrap();
    assert!(rms_line.ends_with(" N |"), "{rms_line}");
    let r = common::macro_report();
    assert_eq!(r.curves.depth_unit.label, "mm");
    assert_eq!(r.curves.force_unit.label, "N");
}

/// The JSON shall be one object that reads back to the same report.
#[test]
fn json_round_trip_keeps_key_fields() {
    let r = common::nano_report();
    let json = r.to_json().unwrap();
    assert!(json.trim_start().starts_with('{'));
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert_eq!(v["law"], "maxwell");
    assert_eq!(v["parameters"][0]["name"], "E");
    assert_eq!(v["parameters"][2]["at_bound"], "upper");
    assert_eq!(v["curves"]["force_unit"]["label"], "mN");
    let back = Report::from_json(&json).unwrap();
    assert_eq!(back, r);
}

/// A long history shall show its first and last ten iterations and mark the gap.
#[test]
fn long_history_is_elided_in_the_middle() {
    let mut r = common::nano_report();
    let rec = r.history[0].clone();
    r.history = (0..40)
        .map(|k| indentify_report::IterationRecord {
            iteration: k,
            ..rec.clone()
        })
        .collect();
    let md = r.to_markdown();
    let row = |k: usize| format!("\n| {k} | ");
    assert!(md.contains(&row(9)) && md.contains(&row(30)) && md.contains(&row(39)));
    assert!(!md.contains(&row(10)) && !md.contains(&row(29)));
    assert!(md.contains("\n| … |"));
}
