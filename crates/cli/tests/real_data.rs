//! End-to-end runs on real instrument records (examples/real, data in examples/data with
//! their licences): identification from the measured depth and force, the report and its
//! figures, and bad data sections rejected with messages that name the field and the file.

mod common;

use common::{assert_ok, assert_rejected, example, examples, indentify, stderr, stdout};

#[test]
fn maxwell_on_the_anton_paar_berkovich_record_identifies_and_reports() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let o = indentify(&[
        "identify",
        &example("real/anon-maxwell.ron"),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_ok(&o);
    let text = common::stdout(&o);
    assert!(text.contains("fit: R^2 = "), "{text}");
    // the Oliver-Pharr numbers of the same test beside the FE result
    assert!(
        text.contains("Oliver-Pharr of the same test (tip: ideal Berkovich")
            && text.contains("E_IT vs the fitted E = "),
        "{text}"
    );
    for f in [
        "report.md",
        "report.json",
        "result.json",
        "history.csv",
        "fit.csv",
        "force_depth.svg",
        "force_depth.png",
        "force_time.svg",
        "force_time.png",
        "convergence.svg",
        "convergence.png",
    ] {
        let p = out.join(f);
        assert!(
            p.metadata().map(|m| m.len() > 100).unwrap_or(false),
            "{f} missing or empty"
        );
    }
    let png = std::fs::read(out.join("force_depth.png")).unwrap();
    assert_eq!(&png[1..4], b"PNG");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    // a Maxwell fit of a polymer-like record: E of the order of the vendor's E_IT
    // (2.5 GPa by Oliver-Pharr), a fair but imperfect fit (Maxwell has no plasticity)
    let e = report["parameters"][0]["value"].as_f64().unwrap();
    assert!((1000.0..4000.0).contains(&e), "E = {e} MPa");
    let r2 = report["fit"]["r2"].as_f64().unwrap();
    assert!(r2 > 0.95 && r2 < 1.0, "R^2 = {r2}");
    let steps: Vec<&str> = report["preprocessing"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["name"].as_str().unwrap())
        .collect();
    assert!(
        steps.contains(&"zero point") || steps.contains(&"zero_point"),
        "{steps:?}"
    );
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(
        md.contains("anonNI.TXT") && md.contains("force_depth.svg"),
        "{md}"
    );
    // the fit is at the record's resampled times: 60 points from the contact on
    let fit = std::fs::read_to_string(out.join("fit.csv")).unwrap();
    assert_eq!(fit.lines().count(), 1 + 60);
}

#[test]
fn simulate_runs_the_measured_depth_history() {
    let dir = tempfile::tempdir().unwrap();
    let curve = dir.path().join("curve.csv");
    let o = indentify(&[
        "simulate",
        &example("real/ht-nh.ron"),
        "--out",
        curve.to_str().unwrap(),
        "--set",
        "data.preprocessing.resample.n=12",
    ]);
    assert_ok(&o);
    let rows = common::parse_curve(&std::fs::read_to_string(&curve).unwrap());
    assert_eq!(rows.len(), 12);
    // a 10 um sphere pressed about 0.55 um into a metal: tens of mN at the peak
    let f_max = rows.iter().map(|r| r[2]).fold(0.0, f64::max);
    assert!((0.01..1.0).contains(&f_max), "F_max = {f_max} N");
    assert!(stderr(&o).contains("automatic cylinder"), "{}", stderr(&o));
}

#[test]
fn bad_data_sections_are_rejected_naming_what_is_wrong() {
    let dir = tempfile::tempdir().unwrap();
    let base = std::fs::read_to_string(examples().join("real/ht-nh.ron")).unwrap();
    let data = examples().join("data").display().to_string();
    let base = base.replace("../data", &data);
    let cases: [(&str, &str, &str, &[&str]); 5] = [
        (
            "missing file",
            "HT_V_100mN.TXT\"",
            "nope.TXT\"",
            &["cannot read the data file", "nope.TXT"],
        ),
        (
            "test out of range",
            "test: 1,",
            "test: 7,",
            &["HT_V_100mN.TXT", "4"],
        ),
        (
            "test zero",
            "test: 1,",
            "test: 0,",
            &["data.test", "from 1"],
        ),
        (
            "history and data",
            "    data: (",
            "    history: (segments: [(duration: 1.0, depth: 0.001, steps: 2)]),\n    data: (",
            &["both `history` and `data`"],
        ),
        (
            "unknown preprocessing field",
            "resample: (n: 60)",
            "resampel: (n: 60)",
            &["resampel", "data.preprocessing"],
        ),
    ];
    for (k, (case, from, to, needles)) in cases.iter().enumerate() {
        assert!(base.contains(from), "{case}: `{from}` not in the example");
        let p = dir.path().join(format!("bad{k}.ron"));
        std::fs::write(&p, base.replacen(from, to, 1)).unwrap();
        let o = indentify(&["check", p.to_str().unwrap()]);
        assert_rejected(&o, needles, case);
    }
    // a record without contact: a flat force
    let flat = dir.path().join("flat.csv");
    let mut text = String::from("Time (s),Depth (nm),Load (mN)\n");
    for i in 0..50 {
        text.push_str(&format!("{},{},0.0\n", i as f64 * 0.1, i as f64));
    }
    std::fs::write(&flat, text).unwrap();
    let cfg = base
        .replace(
            &format!("{data}/anton-paar-sphere-creep/HT_V_100mN.TXT"),
            flat.to_str().unwrap(),
        )
        .replace("test: 1,", "");
    let p = dir.path().join("flat.ron");
    std::fs::write(&p, cfg).unwrap();
    let o = indentify(&["check", p.to_str().unwrap()]);
    assert_rejected(&o, &["flat.csv"], "no contact");
}

#[test]
fn gradients_on_a_measured_history_match_finite_differences() {
    // the measured depth of the Berkovich record (20 points), the automatic mesh, contact
    // on and off: adjoint vs central differences and vs forward sensitivities
    let o = indentify(&[
        "gradient-check",
        &example("real/anon-nh.ron"),
        "--set",
        "data.preprocessing.resample.n=20",
        "--json",
    ]);
    assert_ok(&o);
    let v: serde_json::Value = serde_json::from_str(&common::stdout(&o)).unwrap();
    assert_eq!(v["passed"], true, "{v}");
    // and `gradient` takes the data from the configuration's data section
    let o = indentify(&[
        "gradient",
        &example("real/anon-maxwell.ron"),
        "--set",
        "data.preprocessing.resample.n=20",
        "--json",
    ]);
    assert_ok(&o);
    let v: serde_json::Value = serde_json::from_str(&common::stdout(&o)).unwrap();
    assert!(v["J"].as_f64().unwrap() > 0.0, "{v}");
    assert!(v["data"].as_str().unwrap().contains("anonNI.TXT"), "{v}");
}

#[test]
fn old_configs_repeated_times_and_unitless_columns_get_precise_messages() {
    let dir = tempfile::tempdir().unwrap();
    // the specimen as written before Cylinder/Auto existed
    let old = std::fs::read_to_string(examples().join("r0-elastic.ron"))
        .unwrap()
        .replace("specimen: Cylinder(", "specimen: (");
    let p = dir.path().join("old.ron");
    std::fs::write(&p, old).unwrap();
    let o = indentify(&["check", p.to_str().unwrap()]);
    assert_rejected(&o, &["hint", "specimen: Cylinder("], "old specimen");
    // repeated times without resampling: the points and what to do
    let csv = dir.path().join("dup.csv");
    std::fs::write(
        &csv,
        "Time (s),Depth (nm),Load (mN)\n0,0,0\n1,100,1\n1,110,1.2\n2,200,4\n3,200,3.9\n4,100,0.5\n",
    )
    .unwrap();
    let cfg = |file: &str, pre: &str| {
        format!(
            "(specimen: Auto(), punch: Berkovich(), law: Maxwell(E: 2000.0, nu: 0.3, eta: 1e5), \
             data: (file: {file:?}, preprocessing: ({pre})))"
        )
    };
    let p = dir.path().join("dup.ron");
    std::fs::write(&p, cfg(csv.to_str().unwrap(), "zero_point: None")).unwrap();
    let o = indentify(&["check", p.to_str().unwrap()]);
    assert_rejected(
        &o,
        &["dup.csv", "points 1 and 2", "resample"],
        "repeated times",
    );
    // a table without units whose numbers are nm and mN: accepted, with a warning
    let csv = dir.path().join("nounits.csv");
    std::fs::write(
        &csv,
        "t,h,F\n0,0,0\n1,100,1\n2,200,4\n3,200,3.9\n4,100,0.5\n",
    )
    .unwrap();
    let p = dir.path().join("nounits.ron");
    std::fs::write(&p, cfg(csv.to_str().unwrap(), "zero_point: None")).unwrap();
    let o = indentify(&["check", p.to_str().unwrap()]);
    assert_ok(&o);
    assert!(
        stderr(&o).contains("warning") && stderr(&o).contains("Depth (nm)"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn init_with_data_writes_a_valid_template_for_the_record() {
    let dir = tempfile::tempdir().unwrap();
    let file = examples()
        .join("data/anton-paar-unht-berkovich/anonNI.TXT")
        .display()
        .to_string();
    for law in ["maxwell", "norton-hoff"] {
        let o = indentify(&["init", law, "--data", &file]);
        assert_ok(&o);
        let text = common::stdout(&o);
        assert!(
            text.contains("data: (") && !text.contains("history:"),
            "{text}"
        );
        assert!(text.contains("specimen: Auto(") && text.contains("punch: Berkovich"));
        let p = dir.path().join(format!("{law}.ron"));
        std::fs::write(&p, &text).unwrap();
        // the template writes the sub-steps of measured data out; the record's 60 points
        // are the fitted ones, each step solved in 2 sub-steps (docs/discretization.md)
        assert!(text.contains("substeps: 2,"), "{text}");
        let o = indentify(&["check", p.to_str().unwrap()]);
        assert_ok(&o);
        assert!(
            stderr(&o).contains("1000 samples -> 60 points")
                && stderr(&o).contains("59 steps (2 sub-steps per step: 118 solver steps)"),
            "{}",
            stderr(&o)
        );
    }
}

/// `init --data` on every shipped record: the file is read (a missing one is an error, a
/// multi-test file gets its test), the template passes `check`, and a short identification
/// runs on it.
#[test]
fn init_templates_of_every_shipped_record_check_and_identify() {
    let dir = tempfile::tempdir().unwrap();
    let data = examples().join("data");
    let records = [
        ("anton-paar-unht-berkovich/anonNI.TXT", None, None),
        (
            "anton-paar-sphere-creep/HT_V_100mN.TXT",
            Some("3"),
            Some("sphere:0.01"),
        ),
        ("hysitron/Exp-50mN_0000.hld", None, None),
        ("hysitron/RobinSteel0000LC.txt", None, None),
    ];
    for (k, (rel, test, tip)) in records.iter().enumerate() {
        let file = data.join(rel).display().to_string();
        let mut args = vec!["init", "maxwell", "--data", &file];
        if let Some(t) = test {
            args.extend(["--test", t]);
        }
        if let Some(t) = tip {
            args.extend(["--tip", t]);
        }
        let o = indentify(&args);
        assert_ok(&o);
        let text = stdout(&o);
        if let Some(t) = test {
            assert!(text.contains(&format!("test: {t}")), "{text}");
            assert!(text.contains("holds 4 tests"), "{text}");
            assert!(text.contains("Sphere(radius: 0.01)"), "{text}");
        } else {
            assert!(text.contains("Berkovich, assumed"), "{text}");
        }
        assert!(text.contains("relative_decrease_tol: 0.0001"), "{text}");
        let p = dir.path().join(format!("t{k}.ron"));
        std::fs::write(&p, &text).unwrap();
        let p = p.display().to_string();
        assert_ok(&indentify(&["-q", "check", &p]));
        let out = dir.path().join(format!("out{k}")).display().to_string();
        let o = indentify(&[
            "-q",
            "identify",
            &p,
            "--out",
            &out,
            "--max-iter",
            "2",
            "--set",
            "data.preprocessing.resample.n=15",
        ]);
        // two iterations need not converge, but the run and its report must complete
        assert!(!stderr(&o).contains("panicked"), "{}", stderr(&o));
        assert!(
            dir.path().join(format!("out{k}/result.json")).is_file(),
            "{rel}: {}",
            stderr(&o)
        );
    }
    let o = indentify(&["init", "maxwell", "--data", "no-such-file.txt"]);
    assert_rejected(&o, &["no-such-file.txt"], "missing file");
    let anon = data
        .join("anton-paar-unht-berkovich/anonNI.TXT")
        .display()
        .to_string();
    let o = indentify(&["init", "maxwell", "--data", &anon, "--test", "2"]);
    assert_rejected(&o, &["--test 2 is not a test", "holds 1 test"], "bad test");
    let o = indentify(&["init", "maxwell", "--data", &anon, "--tip", "pyramid"]);
    assert_rejected(&o, &["--tip `pyramid`", "sphere:R"], "bad tip");
}

/// `init --data FILE --out elsewhere/CONFIG` names the record relative to the
/// configuration's folder: the configuration checks from any working folder (the record is
/// found), and the path written is the relative one, not the one given.
#[test]
fn init_out_writes_the_data_path_relative_to_the_configuration() {
    let dir = tempfile::tempdir().unwrap();
    let file = examples()
        .join("data/anton-paar-unht-berkovich/anonNI.TXT")
        .display()
        .to_string();
    let config = dir.path().join("configs/nested/my.ron");
    std::fs::create_dir_all(config.parent().unwrap()).unwrap();
    let o = indentify(&[
        "init",
        "maxwell",
        "--data",
        &file,
        "--out",
        config.to_str().unwrap(),
    ]);
    assert_ok(&o);
    assert!(stdout(&o).is_empty(), "{}", stdout(&o));
    let text = std::fs::read_to_string(&config).unwrap();
    assert!(!text.contains(&file), "{text}");
    assert!(
        text.contains("anton-paar-unht-berkovich") && text.contains("file: \"../../"),
        "{text}"
    );
    // from another working folder: the record is found from the configuration's folder
    let o = common::indentify_in(dir.path(), &["check", config.to_str().unwrap()]);
    assert_ok(&o);
    assert!(
        stderr(&o).contains("1000 samples -> 60 points"),
        "{}",
        stderr(&o)
    );
    // a folder that does not exist: refused, naming it
    let missing = dir.path().join("no/such/folder/my.ron");
    let o = indentify(&[
        "init",
        "maxwell",
        "--data",
        &file,
        "--out",
        missing.to_str().unwrap(),
    ]);
    assert_rejected(&o, &["no/such/folder"], "missing --out folder");
}

/// `check` of a joint configuration (examples/r2-multi-rate.ron) prepares every test, prints
/// one summary per test, and its resolved output (with `tests`) checks again.
#[test]
fn check_accepts_a_joint_configuration() {
    let o = indentify(&["check", &example("r2-multi-rate.ron")]);
    assert_ok(&o);
    let err = stderr(&o);
    for label in ["load 0.1 s", "load 1 s", "load 10 s"] {
        assert!(
            err.contains(&format!("[{label}]: valid; law norton-hoff")),
            "{err}"
        );
    }
    let text = stdout(&o);
    assert!(text.contains("tests: ["), "{text}");
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("resolved.ron");
    std::fs::write(&p, &text).unwrap();
    let again = indentify(&["check", p.to_str().unwrap()]);
    assert_ok(&again);
    let strip = |t: &str| {
        t.lines()
            .filter(|l| !l.starts_with("// Resolved from"))
            .collect::<Vec<_>>()
            .join("\n")
    };
    assert_eq!(strip(&stdout(&again)), strip(&text));
}
