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

/// An undetermined parameter shall show `undetermined` instead of its deviation, no
/// correlation, and a `## Identifiability` section with the reason, what to do, the weakest
/// direction and the singular values; the JSON shall read back.
#[test]
fn undetermined_parameters_are_marked_not_shown_as_numbers() {
    let mut r = common::nano_report();
    r.identifiability = Some(indentify_report::IdentifiabilitySummary {
        names: vec!["E".into(), "eta".into()],
        singular_values: vec![1.6e3, 1.03],
        directions: vec![vec![1.0, 0.0], vec![0.0, 1.0]],
        condition: "2.401e6".into(),
        weakest: Some("eta alone is the least determined".into()),
        undetermined: vec![indentify_report::Undetermined {
            name: "eta".into(),
            reason: "its 2-sigma interval is as wide as its admissible range".into(),
        }],
        advice: "hold it".into(),
    });
    let md = r.to_markdown();
    let row = md.lines().find(|l| l.starts_with("| eta |")).unwrap();
    assert!(row.contains("| undetermined |"), "{row}");
    assert!(row.contains("**undetermined**"), "{row}");
    assert!(!row.contains("400"), "no deviation shown: {row}");
    // E alone is left: no correlation table
    assert!(
        !md.contains("Correlation of the identified parameters"),
        "{md}"
    );
    for needle in [
        "## Identifiability",
        "- **eta**: its 2-sigma interval",
        "What to do: hold it.",
        "Weakest direction: eta alone is the least determined.",
        "condition number of S^T S: 2.401e6",
        "| 2 | 1.030 | 6.438e-4 | +0.000 | +1.000 |",
    ] {
        assert!(md.contains(needle), "`{needle}` missing:\n{md}");
    }
    let back = Report::from_json(&r.to_json().unwrap()).unwrap();
    assert_eq!(back, r);
    // a report without the section reads back as before (older report.json files)
    let mut v: serde_json::Value = serde_json::from_str(&r.to_json().unwrap()).unwrap();
    v.as_object_mut().unwrap().remove("identifiability");
    let old = Report::from_json(&v.to_string()).unwrap();
    assert!(old.identifiability.is_none() && !old.is_undetermined("eta"));
}

/// A report whose residuals are systematic says so at the top, marks its deviations as
/// conditional, and has a `## Model adequacy` section with the statistics; the adequacy
/// reads back from JSON.
#[test]
fn systematic_residuals_are_said_at_the_top() {
    use indentify_report::{Adequacy, Report, Verdict};
    let mut r = common::nano_report();
    let md = r.to_markdown();
    assert!(!md.contains("Model adequacy") && !md.contains("conditional on a law"));
    let c = &r.curves;
    // the law's curve plus a smooth misfit of 10% F_max: systematic however small the noise
    let bent: Vec<f64> = c
        .f_final
        .iter()
        .zip(&c.t)
        .map(|(f, t)| f + 1e-3 * (t / 3.0).sin())
        .collect();
    let a = Adequacy::assess(&c.t, &bent, &c.f_final, 2).unwrap();
    assert_eq!(a.verdict, Verdict::Systematic, "{}", a.message);
    r.adequacy = Some(a);
    let md = r.to_markdown();
    let top: String = md.lines().take(4).collect::<Vec<_>>().join("\n");
    assert!(top.contains("> **Warning:** systematic residuals"), "{top}");
    assert!(md.contains("| parameter | value | ± σ \\* |"), "{md}");
    assert!(md.contains("conditional on a law that fits"));
    assert!(md.contains("## Model adequacy") && md.contains("runs of one sign"));
    let back = Report::from_json(&r.to_json().unwrap()).unwrap();
    assert_eq!(back.adequacy, r.adequacy);
}
