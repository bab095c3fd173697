//! End-to-end tests of `indentify gradient` and `indentify gradient-check` on coarse,
//! short runs of the shipped examples (6 x 6 mesh, 4 steps per segment, contact on over
//! load, hold and unload).
//!
//! References: central differences of the command's own `J` (independent of the adjoint),
//! the forward-sensitivity gradient `J^T rho`, and the full-storage adjoint for the
//! checkpointed one. Bad input shall be rejected naming the file, line or field.

mod common;

use std::path::Path;

use common::{assert_ok, assert_rejected, coarse, example, indentify, json, parse_curve, stdout};

/// Writes the coarse R1 curve at the truth (E = 20000, nu = 0.3, eta = 30000) to `path`.
fn r1_curve(path: &Path) {
    let mut args = coarse(&["simulate", &example("r1-maxwell.ron")]);
    args.extend(["--out".to_string(), path.display().to_string()]);
    assert_ok(&indentify(&args));
}

/// `gradient --json` of the coarse R1 against `data`, with extra arguments.
fn gradient_json(data: &Path, extra: &[&str]) -> serde_json::Value {
    let mut args = coarse(&["gradient", &example("r1-maxwell.ron"), "--json"]);
    args.extend(["--data".to_string(), data.display().to_string()]);
    args.extend(extra.iter().map(|s| s.to_string()));
    let o = indentify(&args);
    assert_ok(&o);
    json(&o)
}

/// The system shall print J, dJ/dc per parameter with its unit, and the forward and adjoint
/// wall times with their ratio; at the parameters that made the data, J and dJ/dc vanish.
#[test]
fn gradient_reports_j_gradient_units_and_timings() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("r1.csv");
    r1_curve(&data);
    let mut args = coarse(&["gradient", &example("r1-maxwell.ron")]);
    args.extend(["--data".to_string(), data.display().to_string()]);
    args.extend(["--set".into(), "law.eta=25000".into()]);
    let o = indentify(&args);
    assert_ok(&o);
    let text = stdout(&o);
    for needle in [
        "J = 1/2 sum_i",
        "dJ/dc",
        "N^2/MPa",
        "N^2/(MPa s)",
        "eta",
        "forward",
        "adjoint sweep",
        "adjoint / forward",
        "recorded",
    ] {
        assert!(text.contains(needle), "`{needle}` missing:\n{text}");
    }
    assert!(!text.contains("NaN"), "{text}");

    let at_truth = gradient_json(&data, &[]);
    for key in [
        "law",
        "params",
        "J",
        "gradient",
        "forward_seconds",
        "adjoint_seconds",
        "steps",
        "factorizations",
    ] {
        assert!(at_truth.get(key).is_some(), "key `{key}` in {at_truth}");
    }
    assert_eq!(at_truth["law"], "maxwell");
    assert_eq!(at_truth["steps"], 12);
    assert_eq!(at_truth["params"]["eta"], 30000.0);
    assert_eq!(at_truth["J"], 0.0, "the data are the same solve");
    for k in ["E", "nu", "eta"] {
        assert_eq!(at_truth["gradient"][k], 0.0, "{k}");
    }
}

/// dJ/deta of the command shall agree with central differences of the command's own J to
/// the truncation error of the stencil.
#[test]
fn gradient_matches_central_differences_of_the_reported_cost() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("r1.csv");
    r1_curve(&data);
    let (eta, h) = (25000.0_f64, 25000.0 * 1e-5);
    let at = |v: f64| gradient_json(&data, &["--set", &format!("law.eta={v}")]);
    let g = at(eta)["gradient"]["eta"].as_f64().unwrap();
    let jp = at(eta + h)["J"].as_f64().unwrap();
    let jm = at(eta - h)["J"].as_f64().unwrap();
    let fd = (jp - jm) / (2.0 * h);
    assert!(g != 0.0);
    assert!(
        ((g - fd) / g).abs() < 1e-6,
        "adjoint {g:e}, central differences {fd:e}"
    );
}

/// With --checkpoint, the gradient shall equal the full-storage one to round-off while
/// recording fewer bytes.
#[test]
fn checkpointed_gradient_equals_full_storage_with_less_memory() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("r1.csv");
    r1_curve(&data);
    let full = gradient_json(&data, &["--set", "law.E=15000"]);
    let cp = gradient_json(&data, &["--set", "law.E=15000", "--checkpoint", "3"]);
    for k in ["E", "nu", "eta"] {
        let (a, b) = (
            full["gradient"][k].as_f64().unwrap(),
            cp["gradient"][k].as_f64().unwrap(),
        );
        assert!((a - b).abs() <= 1e-12 * a.abs(), "{k}: {a:e} vs {b:e}");
    }
    assert_eq!(full["J"], cp["J"]);
    assert_eq!(cp["checkpoint_every"], 3);
    assert!(
        cp["recorded_bytes"].as_u64().unwrap() < full["recorded_bytes"].as_u64().unwrap() / 2,
        "{} vs {}",
        cp["recorded_bytes"],
        full["recorded_bytes"]
    );
}

/// Bad data and non-differentiable parameters shall be rejected with the file, line or
/// field, never with a panic or a NaN.
#[test]
fn gradient_rejects_bad_data_and_non_differentiable_points() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let good = d.join("r1.csv");
    r1_curve(&good);
    let rows = parse_curve(&std::fs::read_to_string(&good).unwrap());
    let write = |name: &str, text: &str| {
        let p = d.join(name);
        std::fs::write(&p, text).unwrap();
        p.display().to_string()
    };
    let short: String = std::iter::once("t,h,F,a\n".to_string())
        .chain(
            rows[..8]
                .iter()
                .map(|r| format!("{},{},{},{}\n", r[0], r[1], r[2], r[3])),
        )
        .collect();
    let cases: Vec<(String, &[&str], &str)> = vec![
        (
            write("malformed.csv", "t,h,F,a\n0,0,0,0\n0.25,0.025,abc,0\n"),
            &["malformed.csv:3:", "`F` holds `abc`", "number"],
            "malformed row",
        ),
        (
            write("fields.csv", "t,h,F,a\n0,0,0,0\n0.25,0.025\n"),
            &["fields.csv:3:", "2 fields"],
            "missing fields",
        ),
        (
            write("nocol.csv", "time,h,force\n0,0,0\n3,0,0\n"),
            &["nocol.csv:1:", "no column `t`"],
            "missing column",
        ),
        (
            write("one.csv", "t,F\n0,0\n"),
            &["one.csv", "1 data row", "at least 2"],
            "too few rows",
        ),
        (
            write("order.csv", "t,F\n0,0\n2,1\n1,2\n3,0\n"),
            &["order.csv:4:", "strictly increase"],
            "times going back",
        ),
        (
            write("short.csv", &short),
            &["short.csv", "[0, 1.75] s", "[0, 3] s", "cover"],
            "record too short",
        ),
        (
            d.join("absent.csv").display().to_string(),
            &["absent.csv", "cannot read"],
            "missing file",
        ),
    ];
    for (file, needles, case) in &cases {
        let o = indentify(&coarse(&[
            "gradient",
            &example("r1-maxwell.ron"),
            "--data",
            file,
        ]));
        assert_rejected(&o, needles, case);
        assert!(stdout(&o).is_empty(), "{case}: {}", stdout(&o));
    }
    // Norton-Hoff with m = 1: the pseudo-potential is not twice differentiable
    for extra in [&[][..], &["--json"][..]] {
        let mut args = coarse(&[
            "gradient",
            &example("r2-norton-hoff.ron"),
            "--data",
            &good.display().to_string(),
            "--set",
            "law.m=1",
        ]);
        args.extend(extra.iter().map(|s| s.to_string()));
        let o = indentify(&args);
        assert_rejected(&o, &["law.m = 1", "m > 1", "differentiable"], "m = 1");
        assert!(!stdout(&o).contains("NaN") && !stdout(&o).contains("null"));
    }
    let o = indentify(&coarse(&[
        "gradient",
        &example("r1-maxwell.ron"),
        "--data",
        &good.display().to_string(),
        "--checkpoint",
        "0",
    ]));
    assert_rejected(&o, &["--checkpoint", "0"], "checkpoint 0");
}

/// The system shall pass its own gradient check on Maxwell and Norton-Hoff (every
/// parameter: adjoint vs central FD <= 1e-6, adjoint vs J^T rho <= 1e-8), exit 0, and
/// report one JSON object with every comparison.
#[test]
fn gradient_check_passes_on_maxwell_and_norton_hoff() {
    for (file, n) in [("r1-maxwell.ron", 3), ("r2-norton-hoff.ron", 5)] {
        let o = indentify(&coarse(&["gradient-check", &example(file), "--json"]));
        assert_ok(&o);
        let v = json(&o);
        assert_eq!(v["passed"], true, "{file}: {v}");
        assert_eq!(v["data"], "synthesized");
        let checks = v["checks"].as_array().unwrap();
        assert_eq!(checks.len(), n);
        for c in checks {
            assert!(c["rel_diff_fd"].as_f64().unwrap() < 1e-6, "{file}: {c}");
            assert!(
                c["rel_diff_sensitivity"].as_f64().unwrap() < 1e-8,
                "{file}: {c}"
            );
            assert!(c["adjoint"].as_f64().unwrap() != 0.0, "{file}: {c}");
        }
        // the documented check point: truth x 1.1, nu x 0.97
        let (e, truth) = (
            v["params"]["E"].as_f64().unwrap(),
            v["truth"]["E"].as_f64().unwrap(),
        );
        assert!((e - 1.1 * truth).abs() < 1e-12 * e, "{e} {truth}");
        assert_eq!(v["params"]["nu"], 0.291);
    }
}

/// The text report shall show every gradient and, with --scan, the FD V per parameter.
#[test]
fn gradient_check_text_and_scan() {
    let o = indentify(&coarse(&[
        "gradient-check",
        &example("r1-maxwell.ron"),
        "--scan",
    ]));
    assert_ok(&o);
    let text = stdout(&o);
    for needle in [
        "adjoint dJ/dc",
        "central FD",
        "sensitivities J^T rho",
        "x 1.1, nu x 0.97",
        "1e-2",
        "1e-9",
        "passed",
    ] {
        assert!(text.contains(needle), "`{needle}` missing:\n{text}");
    }
}

/// A tolerance the check cannot meet shall give a non-zero exit naming the parameters,
/// after the report; data given on the command line are compared at the configuration's law.
#[test]
fn gradient_check_fails_above_tolerance_and_uses_given_data() {
    let o = indentify(&coarse(&[
        "gradient-check",
        &example("r1-maxwell.ron"),
        "--tol",
        "1e-300",
    ]));
    assert_rejected(
        &o,
        &["gradient check", "failed", "eta", "--tol"],
        "tol 1e-300",
    );
    assert!(stdout(&o).contains("central FD"));

    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("r1.csv");
    r1_curve(&data);
    let o = indentify(&coarse(&[
        "gradient-check",
        &example("r1-maxwell.ron"),
        "--json",
        "--data",
        &data.display().to_string(),
        "--set",
        "law.E=17000",
    ]));
    assert_ok(&o);
    let v = json(&o);
    assert_eq!(v["params"]["E"], 17000.0);
    assert!(v.get("truth").is_none());
    assert_eq!(v["passed"], true);
    for (bad, needles) in [
        ("--rel-step=0", &["--rel-step", "(0, 1)"][..]),
        ("--tol=-1", &["--tol"][..]),
    ] {
        let o = indentify(&coarse(&[
            "gradient-check",
            &example("r1-maxwell.ron"),
            bad,
        ]));
        assert_rejected(&o, needles, bad);
    }
}
