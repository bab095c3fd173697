//! The Oliver-Pharr numbers beside a joint FE fit: on `ht-nh-joint.ron` (tests 1-4 of the
//! Anton Paar sphere record, one Norton-Hoff law) every test's record is analysed with the
//! configuration's punch as the tip (sphere R = 10 µm) and the held `nu`, and reported beside
//! the shared fitted `E`: `IdentifyOutcome::tests[k].oliver_pharr`, result.json's
//! `tests[k].oliver_pharr`, each test's page and a table on the index page. Reference: the
//! same test analysed by `indentify analyze` (equal to 1e-12) and the vendor's own `EIT (O&P)`
//! of the file's `_data.TXT` (within 5 %: the vendor uses `epsilon` from `m`, the
//! configuration's analysis the sphere's 0.75).

mod common;

use common::examples;

use indentify_analysis::{AreaFunction, Tip};
use indentify_study::ConfigSource;
use indentify_study::analyze::{self, AnalyzeOptions};
use indentify_study::identify::{self, IdentifyOptions};

#[test]
fn a_joint_fit_reports_each_tests_oliver_pharr() {
    let tmp = tempfile::tempdir().unwrap();
    let mut o = IdentifyOptions::new(ConfigSource::Path(examples().join("real/ht-nh-joint.ron")));
    o.sets = (0..4)
        .map(|k| format!("tests.{k}.data.preprocessing.resample.n=12"))
        .chain(["specimen.elements_in_contact=4".to_string()])
        .collect();
    o.overrides.max_iterations = Some(1);
    o.refine = false;
    o.figures = true;
    o.jobs = Some(2);
    o.out = Some(tmp.path().to_path_buf());
    let outcome = identify::run(&o, &mut ()).unwrap();
    assert!(outcome.oliver_pharr.is_none(), "a joint fit's are per test");
    assert_eq!(outcome.tests.len(), 4);
    let e_fe = outcome.value("E").unwrap();
    // the same numbers as `indentify analyze FILE --tip sphere:10 --nu 0.3`
    let mut a = AnalyzeOptions::new(examples().join("data/anton-paar-sphere-creep/HT_V_100mN.TXT"));
    a.tip = Tip::diamond(AreaFunction::Sphere { radius: 0.01 });
    a.nu = 0.3;
    let r = analyze::run(&a).unwrap();
    assert_eq!(r.tests.len(), 4);
    for (t, direct) in outcome.tests.iter().zip(&r.tests) {
        let b = t.oliver_pharr.as_ref().expect("O&P beside each test");
        let op =
            b.op.as_ref()
                .unwrap_or_else(|| panic!("{}: {:?}", t.name, b.skipped));
        for (ours, theirs) in [
            (op.e, direct.values.e.unwrap()),
            (op.h, direct.values.h.unwrap()),
            (op.s, direct.values.s.unwrap()),
            (op.hc, direct.values.hc.unwrap()),
        ] {
            assert!(
                (ours - theirs).abs() <= 1e-12 * theirs.abs(),
                "{}: {ours} vs {theirs}",
                t.name
            );
        }
        let vendor = direct
            .vendor
            .iter()
            .find(|q| q.name == "EIT (O&P)")
            .expect("the vendor's E_IT")
            .value;
        assert!(
            (op.e * 1e-3 / vendor - 1.0).abs() < 0.05,
            "{}: E_IT {} MPa vs the vendor's {vendor} GPa",
            t.name,
            op.e
        );
        assert_eq!(b.e_fe, Some(e_fe));
        let d = b.e_difference_pct.unwrap();
        assert!((d - 100.0 * (op.e - e_fe) / e_fe).abs() < 1e-9, "{d}");
        assert!(b.tip.contains("sphere"), "{}", b.tip);
    }
    // result.json: each test's `oliver_pharr`, none at the top
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(tmp.path().join("result.json")).unwrap()).unwrap();
    assert!(json.get("oliver_pharr").is_none());
    let tests = json["tests"].as_array().unwrap();
    for (t, fit) in tests.iter().zip(&outcome.tests) {
        let op = fit.oliver_pharr.as_ref().unwrap().op.as_ref().unwrap();
        assert_eq!(t["oliver_pharr"]["E"].as_f64(), Some(op.e), "{t}");
        assert_eq!(t["oliver_pharr"]["E_fe"].as_f64(), Some(e_fe));
    }
    // the index page's table and each test's page
    let index = std::fs::read_to_string(tmp.path().join("report.md")).unwrap();
    assert!(
        index.contains("## Oliver-Pharr beside the FE result"),
        "{index}"
    );
    for t in &outcome.tests {
        assert!(index.contains(&format!("| {} |", t.name)), "{index}");
    }
    for k in 1..=4 {
        let page = std::fs::read_to_string(tmp.path().join(format!("test-{k}/report.md"))).unwrap();
        assert!(
            page.contains("## Oliver-Pharr beside the FE result"),
            "test {k}"
        );
    }
}
