//! The Oliver-Pharr numbers of the same test beside the FE result of `identify`: on the
//! shipped Anton Paar Berkovich record (`anon-maxwell.ron`), result.json's `oliver_pharr`
//! carries E_IT, H_IT, S, h_c and the tip, equal to `indentify analyze`'s of that test and
//! near the vendor's own O&P values in the file's header (H 134.71 MPa, E 2.5187 GPa with
//! beta 1.034); report.md has the section; a record without unloading is skipped with the
//! reason.

mod common;

use common::examples;

use indentify_analysis::Tip;
use indentify_study::ConfigSource;
use indentify_study::analyze::{self, AnalyzeOptions};
use indentify_study::identify::{self, IdentifyOptions};

#[test]
fn identify_reports_oliver_pharr_beside_the_fe_result() {
    let tmp = tempfile::tempdir().unwrap();
    let mut o = IdentifyOptions::new(ConfigSource::Path(examples().join("real/anon-maxwell.ron")));
    o.sets = vec![
        "data.preprocessing.resample.n=16".into(),
        "specimen.elements_in_contact=4".into(),
    ];
    o.overrides.max_iterations = Some(2);
    o.refine = false;
    o.figures = true;
    o.out = Some(tmp.path().to_path_buf());
    let outcome = identify::run(&o, &mut ()).unwrap();
    let b = outcome.oliver_pharr.as_ref().expect("O&P beside the fit");
    let op = b.op.as_ref().expect("an analysed unloading");
    // the same numbers as `indentify analyze FILE --tip berkovich --nu 0.3`
    let mut a = AnalyzeOptions::new(examples().join("data/anton-paar-unht-berkovich/anonNI.TXT"));
    a.tip = Tip::berkovich();
    a.nu = 0.3;
    let r = analyze::run(&a).unwrap();
    let t = &r.tests[0];
    for (ours, theirs) in [
        (op.e, t.values.e.unwrap()),
        (op.h, t.values.h.unwrap()),
        (op.s, t.values.s.unwrap()),
        (op.hc, t.values.hc.unwrap()),
    ] {
        assert!(
            (ours - theirs).abs() <= 1e-12 * theirs.abs(),
            "{ours} vs {theirs}"
        );
    }
    // the vendor's header values (their epsilon from m and beta 1.034; ours 0.75 and 1):
    // H within 5 %, E within 6 % (beta alone moves E by 3 %)
    assert!((op.h / 134.71 - 1.0).abs() < 0.05, "H = {} MPa", op.h);
    assert!((op.e / 2518.7 - 1.0).abs() < 0.06, "E = {} MPa", op.e);
    // the difference is the stated one, against the fitted E
    let e_fe = outcome.value("E").unwrap();
    assert_eq!(b.e_fe, Some(e_fe));
    let d = b.e_difference_pct.unwrap();
    assert!((d - 100.0 * (op.e - e_fe) / e_fe).abs() < 1e-9, "{d}");
    assert!(b.tip.contains("Berkovich"), "{}", b.tip);
    // result.json and report.md carry it
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(tmp.path().join("result.json")).unwrap())
            .unwrap();
    let j = &json["oliver_pharr"];
    for key in [
        "E",
        "H",
        "Er",
        "S",
        "hc",
        "hmax",
        "Fmax",
        "tip",
        "E_fe",
        "E_difference_pct",
    ] {
        assert!(!j[key].is_null(), "oliver_pharr.{key} missing: {j}");
    }
    assert_eq!(j["E"].as_f64(), Some(op.e));
    assert!(j["why_they_differ"].as_str().unwrap().contains("pile-up"));
    let md = std::fs::read_to_string(tmp.path().join("report.md")).unwrap();
    assert!(md.contains("## Oliver-Pharr beside the FE result"), "{md}");
    assert!(md.contains(&indentify_study::format::sig(op.e, 4)), "{md}");
    // and the console lines
    let lines = indentify_study::op_beside::lines(b);
    assert!(lines.contains("E_IT vs the fitted E"), "{lines}");
}

#[test]
fn a_record_without_unloading_is_skipped_with_the_reason() {
    // a loading only: F = k h^2
    let n = 50;
    let t: Vec<f64> = (0..n).map(|i| i as f64).collect();
    let h: Vec<f64> = t.iter().map(|x| 1e-5 * x).collect();
    let f: Vec<f64> = h.iter().map(|x| 1e3 * x * x).collect();
    let r = indentify_records::Record {
        name: "loading.csv".into(),
        t,
        h,
        f,
        segment: None,
        meta: Default::default(),
    };
    let b = indentify_study::op_beside::compare(
        &r,
        &indentify_contact::Punch::Berkovich { tip_radius: None },
        None,
        Some(1000.0),
        0.3,
    );
    assert!(b.op.is_none());
    assert_eq!(b.e_difference_pct, None);
    let why = b.skipped.as_deref().unwrap();
    assert!(why.contains("loading.csv"), "{why}");
    assert!(
        indentify_study::op_beside::lines(&b).contains("not analysed"),
        "{}",
        indentify_study::op_beside::lines(&b)
    );
    let json = serde_json::to_value(&b).unwrap();
    assert!(json["skipped"].is_string());
}
