//! End-to-end tests of `indentify identify` and of the seeded noise of `simulate`: the
//! embedded default (R1 of docs/theory.md §11 from the paper's first start), the report files,
//! the history written line by line and resumed, the command-line settings, and bad input.
//!
//! Reference: the truth that generated the synthetic data, E = 20000 MPa, eta = 30000 MPa s
//! (nu = 0.3 held); exact data give J = 0 there, so the identified values shall match it.
//!
//! ```text
//!      cone 68 deg, depth 0 -> 0.1 mm (1 s) -> hold (1 s) -> 0 (1 s)
//!        \   /
//!   z=0 --\-/--------------  top: contact candidates
//!        |                |  10 x 10 mm cylinder, 20 x 20 Q8 graded 1.3 (default run);
//!  axis  |                |  6 x 6 Q8 and 4 steps per segment (the other tests)
//!  u_r=0 |                |
//!        +----------------+  bottom: u_z = 0
//! ```

mod common;

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use common::{
    assert_ok, assert_rejected, coarse, example, indentify, indentify_in, parse_curve, stderr,
    stdout,
};

fn read_json(path: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(path)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    serde_json::from_str(&text).unwrap()
}

/// `(name, value, rel_error)` of every parameter of a result.json.
fn params(v: &serde_json::Value) -> Vec<(String, f64, Option<f64>)> {
    v["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| {
            (
                p["name"].as_str().unwrap().to_string(),
                p["value"].as_f64().unwrap(),
                p["rel_error"].as_f64(),
            )
        })
        .collect()
}

/// History lines (header excluded), each checked to have every column.
fn history_lines(path: &Path) -> Vec<Vec<f64>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = lines.next().expect("a header line");
    assert_eq!(
        header,
        "iteration,E,nu,eta,J,grad_norm,forward_solves,adjoint_solves,sensitivity_solves,seconds"
    );
    lines
        .map(|l| {
            let v: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
            assert_eq!(v.len(), 10, "complete line: {l}");
            v
        })
        .collect()
}

/// The README's main command: with no arguments at all, `indentify identify` shall identify
/// R1's (E, eta) from (4000, 70000) within 1e-3 of the truth (measured: ~1e-11), print the
/// table with the truth, and write out/result.json, out/history.csv and out/fit.csv.
#[test]
fn default_identify_recovers_r1_from_the_paper_start() {
    let dir = tempfile::tempdir().unwrap();
    let no_args: [&str; 1] = ["identify"];
    let o = indentify_in(dir.path(), &no_args);
    assert_ok(&o);
    let table = stdout(&o);
    for needle in [
        "identified maxwell parameters",
        "converged",
        "truth",
        "E ",
        "eta",
        "(held)",
        "out/result.json",
    ] {
        assert!(table.contains(needle), "`{needle}` missing:\n{table}");
    }
    assert!(
        stderr(&o).contains("iter"),
        "progress lines:\n{}",
        stderr(&o)
    );
    let out = dir.path().join("out");
    let v = read_json(&out.join("result.json"));
    assert_eq!(v["converged"], true, "{v}");
    assert_eq!(v["law"], "maxwell");
    let p = params(&v);
    assert_eq!(p[0].0, "E");
    assert!((p[0].1 - 20000.0).abs() < 1e-3 * 20000.0, "{p:?}");
    assert_eq!((p[1].0.as_str(), p[1].1), ("nu", 0.3));
    assert!((p[2].1 - 30000.0).abs() < 1e-3 * 30000.0, "{p:?}");
    let starts: Vec<f64> = v["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .map(|q| q["start"].as_f64().unwrap())
        .collect();
    assert_eq!(starts, [4000.0, 0.3, 70000.0]);
    let hist = history_lines(&out.join("history.csv"));
    assert_eq!(hist.len() as u64, v["iterations"].as_u64().unwrap() + 1);
    assert_eq!(hist[0][1], 4000.0);
    let fit = std::fs::read_to_string(out.join("fit.csv")).unwrap();
    assert!(fit.starts_with("t,h,F_data,F_start,F_final\n"));
    assert_eq!(fit.lines().count(), 92, "91 schedule times + header");
}

/// The report shall carry everything the issue asks for, and fit.csv the data, start and
/// final curves at the schedule times.
#[test]
fn result_json_and_fit_csv_hold_the_whole_report() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("rep");
    let o = indentify(&coarse(&[
        "identify",
        &example("r1-maxwell.ron"),
        "--out",
        &out.display().to_string(),
        "--quiet",
    ]));
    assert_ok(&o);
    assert!(stderr(&o).is_empty(), "--quiet: {}", stderr(&o));
    let v = read_json(&out.join("result.json"));
    for key in [
        "law",
        "method",
        "parameters",
        "J",
        "J_start",
        "iterations",
        "forward_solves",
        "adjoint_solves",
        "stop_reason",
        "seconds",
        "identifiability",
    ] {
        assert!(v.get(key).is_some(), "`{key}` in {v}");
    }
    for q in v["parameters"].as_array().unwrap() {
        for key in ["name", "unit", "start", "value", "bound_hit", "truth"] {
            assert!(q.get(key).is_some(), "`{key}` in {q}");
        }
    }
    assert_eq!(v["parameters"][2]["unit"], "MPa s");
    assert!(v["J"].as_f64().unwrap() < 1e-10 * v["J_start"].as_f64().unwrap());
    assert!(v["forward_solves"].as_u64().unwrap() >= v["iterations"].as_u64().unwrap());
    for (name, value, rel) in params(&v) {
        if name != "nu" {
            assert!(rel.unwrap() < 1e-6, "{name} = {value}");
        }
    }
    let corr = &v["identifiability"]["correlation"];
    assert_eq!(corr.as_array().unwrap().len(), 2);

    let fit = std::fs::read_to_string(out.join("fit.csv")).unwrap();
    let rows: Vec<Vec<f64>> = fit
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 13);
    let peak = rows.iter().map(|r| r[2]).fold(0.0, f64::max);
    assert!(peak > 0.0);
    for r in &rows {
        assert!(
            (r[4] - r[2]).abs() < 1e-6 * peak,
            "final curve on the data: {r:?}"
        );
    }
    assert!(
        rows.iter().any(|r| (r[3] - r[2]).abs() > 0.1 * peak),
        "the start's curve is off"
    );
}

/// The history shall be written line by line: after --max-iter 2 (a non-zero exit, the
/// result so far written) it holds iterations 0, 1, 2; --resume continues from the last
/// line without repeating it, to the truth.
#[test]
fn history_is_written_per_iteration_and_resumes() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("h");
    let run = |extra: &[&str]| {
        let mut args = coarse(&[
            "identify",
            &example("r1-maxwell.ron"),
            "--out",
            &out.display().to_string(),
        ]);
        args.extend(extra.iter().map(|s| s.to_string()));
        indentify(&args)
    };
    let o = run(&["--max-iter", "2"]);
    assert_rejected(
        &o,
        &[
            "did not converge",
            "iteration limit",
            "history.csv",
            "--resume",
        ],
        "--max-iter 2",
    );
    let h = history_lines(&out.join("history.csv"));
    assert_eq!(h.iter().map(|l| l[0]).collect::<Vec<_>>(), [0.0, 1.0, 2.0]);
    assert!(h[2][4] < h[0][4], "J decreases");
    assert!(h[2][6] >= 3.0, "cumulative forward solves");
    let v = read_json(&out.join("result.json"));
    assert_eq!(v["converged"], false);
    assert_eq!(v["iterations"], 2);

    let o = run(&["--resume"]);
    assert_ok(&o);
    let h2 = history_lines(&out.join("history.csv"));
    assert_eq!(&h2[..3], &h[..], "resume keeps the old lines");
    for (i, l) in h2.iter().enumerate() {
        assert_eq!(l[0], i as f64, "iterations follow each other");
    }
    assert!(h2[3][6] > h[2][6], "solve counts continue");
    let v = read_json(&out.join("result.json"));
    assert_eq!(v["resumed"], true);
    let p = params(&v);
    assert!((p[0].1 / 20000.0 - 1.0).abs() < 1e-6 && (p[2].1 / 30000.0 - 1.0).abs() < 1e-6);
}

/// An interrupted run shall lose nothing: lines on disk while the process runs are
/// complete, and they stay after a kill.
#[test]
fn a_killed_run_keeps_complete_history_lines() {
    let dir = tempfile::tempdir().unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_indentify"))
        .current_dir(dir.path())
        .args(["identify", "--quiet"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let path = dir.path().join("out/history.csv");
    let start = Instant::now();
    let mut seen = 0;
    while start.elapsed() < Duration::from_secs(120) {
        if let Ok(text) = std::fs::read_to_string(&path) {
            seen = text.lines().count().saturating_sub(1);
            if seen >= 2 {
                break;
            }
        }
        if child.try_wait().unwrap().is_some() {
            break;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let _ = child.kill();
    let _ = child.wait();
    assert!(seen >= 2, "history lines appeared while running: {seen}");
    let lines = history_lines(&path);
    assert!(lines.len() >= 2);
    assert_eq!(lines[0][0], 0.0);
}

/// --free, --fixed, --start and --method shall override the configuration's section.
#[test]
fn command_line_settings_override_the_section() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("s");
    let o = indentify(&coarse(&[
        "identify",
        &example("r1-maxwell.ron"),
        "--out",
        &out.display().to_string(),
        "--free",
        "E",
        "--fixed",
        "eta=30000",
        "--start",
        "E=8000",
        "--method",
        "lbfgsb",
        "-q",
    ]));
    assert_ok(&o);
    let v = read_json(&out.join("result.json"));
    assert_eq!(v["method"], "lbfgsb");
    let q = v["parameters"].as_array().unwrap();
    assert_eq!(
        (q[0]["free"].as_bool(), q[0]["start"].as_f64()),
        (Some(true), Some(8000.0))
    );
    assert_eq!(
        (q[2]["free"].as_bool(), q[2]["value"].as_f64()),
        (Some(false), Some(30000.0))
    );
    assert!(
        (q[0]["value"].as_f64().unwrap() / 20000.0 - 1.0).abs() < 1e-6,
        "{v}"
    );
    assert_eq!(
        v["identifiability"]["names"].as_array().unwrap().len(),
        1,
        "one free parameter"
    );
}

/// Bad input shall fail before any solve with a message naming the parameter, field, flag
/// or file, a non-zero exit and no panic.
#[test]
fn bad_identify_inputs_are_rejected_clearly() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let one_row = d.join("one.csv");
    std::fs::write(&one_row, "t,h,F,a\n0,0,0,0\n").unwrap();
    let short = d.join("short.csv");
    std::fs::write(&short, "t,F\n0,0\n1,5\n").unwrap();
    let r1 = example("r1-maxwell.ron");
    let bad_section = d.join("bad-section.ron");
    let text = std::fs::read_to_string(common::examples().join("r1-maxwell.ron")).unwrap();
    std::fs::write(
        &bad_section,
        text.replacen("start: 4000.0", "strt: 4000.0", 1),
    )
    .unwrap();
    let (one_row, short, bad_section) = (
        one_row.display().to_string(),
        short.display().to_string(),
        bad_section.display().to_string(),
    );
    let cases: Vec<(Vec<&str>, &[&str], &str)> = vec![
        (
            vec!["--start", "E=100"],
            &["`E`", "100", "outside its bounds", "[1000, 1000000]"],
            "start outside the bounds",
        ),
        (
            vec!["--set", "identify.params.E.lower=2000000"],
            &["`E`", "exclude each other", "identify.params.E"],
            "bounds that exclude each other",
        ),
        (
            vec!["--fixed", "nu="],
            &["--fixed nu=", "no value"],
            "fixed without value",
        ),
        (
            vec!["--start", "nu=0.2"],
            &["`nu` is held fixed", "E, eta"],
            "start of a held parameter",
        ),
        (
            vec!["--free", "E,G"],
            &["no parameter `G`", "E, nu, eta"],
            "unknown parameter",
        ),
        (
            vec!["--free", "E", "--fixed", "E"],
            &["both in --free and in --fixed"],
            "free and fixed",
        ),
        (
            vec!["--data", one_row.as_str()],
            &["one.csv", "1 data row", "at least 2"],
            "too few points",
        ),
        (
            vec!["--data", short.as_str()],
            &["short.csv", "[0, 1] s", "[0, 3] s"],
            "data too short",
        ),
        (
            vec!["--noise", "1.5"],
            &["--noise 1.5", "[0, 1)"],
            "noise amplitude",
        ),
        (
            vec!["--set", "identify.memory=0"],
            &["identify.memory", "[1, 100]"],
            "memory",
        ),
        (
            vec!["--resume"],
            &["cannot resume", "history.csv"],
            "nothing to resume",
        ),
    ];
    for (i, (extra, needles, case)) in cases.iter().enumerate() {
        let out = d.join(format!("out{i}"));
        let out = out.display().to_string();
        let mut args = coarse(&["identify", &r1, "--out", &out]);
        args.extend(extra.iter().map(|s| s.to_string()));
        let o = indentify(&args);
        assert_rejected(&o, needles, case);
    }
    let o = indentify(&coarse(&[
        "identify",
        &bad_section,
        "--out",
        &d.join("x").display().to_string(),
    ]));
    assert_rejected(
        &o,
        &["bad-section.ron:", "strt", "identify.params"],
        "unknown field",
    );
}

/// An optimizer that stalls shall end with a non-zero exit and a message saying so, the
/// history so far and the result kept on disk.
#[test]
fn a_stalled_optimizer_fails_and_keeps_the_history() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("stall");
    let o = indentify(&coarse(&[
        "identify",
        &example("r1-maxwell.ron"),
        "--out",
        &out.display().to_string(),
        "--set",
        "identify.stop.max_line_search_evaluations=1",
    ]));
    assert_rejected(&o, &["did not converge", "stalled", "history.csv"], "stall");
    assert!(!history_lines(&out.join("history.csv")).is_empty());
    let v = read_json(&out.join("result.json"));
    assert_eq!(v["converged"], false);
    assert!(v["stop_reason"].as_str().unwrap().contains("stalled"));
}

/// `simulate --noise A --seed N` shall perturb F by F (1 + A xi) with the identify crate's
/// SplitMix64 draws, reproducibly; `identify --data` on that curve shall equal `identify
/// --noise A --seed N` (the same draws on the same schedule), the paper's Table II set-up.
#[test]
fn seeded_noise_is_reproducible_and_shared_with_identify() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let sim = |extra: &[&str]| {
        let mut args = coarse(&["simulate", &example("r1-maxwell.ron")]);
        args.extend(extra.iter().map(|s| s.to_string()));
        let o = indentify(&args);
        assert_ok(&o);
        (parse_curve(&stdout(&o)), stdout(&o), stderr(&o))
    };
    let (exact, _, _) = sim(&[]);
    let (noisy, text, err) = sim(&["--noise", "0.1", "--seed", "7"]);
    let (_, again, _) = sim(&["--noise", "0.1", "--seed", "7"]);
    let (other, _, _) = sim(&["--noise", "0.1", "--seed", "8"]);
    assert_eq!(text, again, "same seed, same curve");
    assert!(err.contains("seed 7"), "{err}");
    let forces: Vec<f64> = exact.iter().map(|r| r[2]).collect();
    let expected = indentify_study::multiplicative_noise(&forces, 0.1, 7);
    for ((n, e), x) in noisy.iter().zip(&expected).zip(&exact) {
        assert_eq!(n[2], *e);
        assert!((n[2] - x[2]).abs() <= 0.1 * x[2].abs());
        assert_eq!((n[0], n[1], n[3]), (x[0], x[1], x[3]), "only F changes");
    }
    assert!(noisy.iter().zip(&other).any(|(a, b)| a[2] != b[2]));

    let csv = d.join("noisy.csv");
    std::fs::write(&csv, &text).unwrap();
    let ident = |out: &str, extra: &[&str]| {
        let out = d.join(out);
        let mut args = coarse(&[
            "identify",
            &example("r1-maxwell.ron"),
            "--out",
            &out.display().to_string(),
            "-q",
        ]);
        args.extend(extra.iter().map(|s| s.to_string()));
        assert_ok(&indentify(&args));
        read_json(&out.join("result.json"))
    };
    let from_file = ident("a", &["--data", &csv.display().to_string()]);
    let synthesized = ident("b", &["--noise", "0.1", "--seed", "7"]);
    assert_eq!(params(&from_file), {
        let mut p = params(&synthesized);
        for q in &mut p {
            q.2 = None; // a file has no known truth
        }
        p
    });
    assert_eq!(synthesized["noise"]["seed"], 7);
    let e = params(&synthesized)[0].2.unwrap();
    assert!(e > 1e-6 && e < 0.1, "noise moves the optimum a little: {e}");

    let o = indentify(&coarse(&[
        "simulate",
        &example("r1-maxwell.ron"),
        "--seed",
        "3",
    ]));
    assert_rejected(&o, &["--noise"], "seed without noise");
    let o = indentify(&coarse(&[
        "simulate",
        &example("r1-maxwell.ron"),
        "--noise=-0.1",
    ]));
    assert_rejected(&o, &["--noise", "[0, 1)"], "negative noise");
}

/// Runs one of the issue's two false convergences and checks the honest outcome: either the
/// truth within 1% (every free parameter) and exit 0, or exit 3 with the parameters the
/// data do not determine listed in result.json (`undetermined`), marked in the table, a
/// reason for each and what to do; never "converged" far from the truth.
fn honest_stop(config: &str, method: &str, start: &str, truth: &[(&str, f64)]) -> Vec<String> {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let o = indentify(&[
        "identify",
        &example(config),
        "--method",
        method,
        "--start",
        start,
        "--no-refine",
        "--out",
        out.to_str().unwrap(),
    ]);
    let v = read_json(&out.join("result.json"));
    let at_truth = truth.iter().all(|(name, t)| {
        params(&v)
            .iter()
            .any(|(n, value, _)| n == name && ((value - t) / t).abs() < 0.01)
    });
    if at_truth {
        assert_ok(&o);
        assert_eq!(v["converged"], true, "{v}");
        return Vec::new();
    }
    assert_eq!(o.status.code(), Some(3), "{}\n{}", stdout(&o), stderr(&o));
    assert_eq!(v["converged"], false, "{v}");
    let undetermined: Vec<String> = v["undetermined"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n.as_str().unwrap().to_string())
        .collect();
    assert!(!undetermined.is_empty(), "{v}");
    let reasons = &v["identifiability"]["undetermined_reasons"];
    let table = stdout(&o);
    for n in &undetermined {
        assert!(reasons[n].as_str().is_some_and(|r| !r.is_empty()), "{v}");
        // the table's deviation column says so instead of a number
        let row = table
            .lines()
            .find(|l| l.trim_start().starts_with(&format!("{n} ")))
            .unwrap_or_else(|| panic!("no row for {n}:\n{table}"));
        assert!(row.trim_end().ends_with("undetermined"), "{row}");
    }
    assert!(stderr(&o).contains("What to do"), "{}", stderr(&o));
    assert!(table.contains("NOT converged:"), "{table}");
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(
        md.contains("## Identifiability") && md.contains("**undetermined**"),
        "{md}"
    );
    // the determined parameters' deviations are conditional on the undetermined ones held:
    // the console, result.json and report.md say so
    assert!(table.contains("conditional on"), "{table}");
    assert!(v["caveats"].to_string().contains("conditional on"), "{v}");
    assert!(md.contains("conditional"), "{md}");
    undetermined
}

/// A false convergence once seen: R2 with BFGS from (E, K, m, sY) = (30000, 20000,
/// 15, 2000), where the material stays elastic: K, m and sY have no effect there. It used
/// to print "converged" with R^2 0.73 and `unidentifiable: []`; now K, m and sY are
/// undetermined and the exit status is 3 (measured: E 28162, 6 iterations, ~7 s).
#[test]
fn r2_from_an_elastic_start_does_not_claim_convergence() {
    let u = honest_stop(
        "r2-norton-hoff.ron",
        "bfgs",
        "E=30000,K=20000,m=15,sY=2000",
        &[("E", 1e5), ("K", 1500.0), ("m", 5.0), ("sY", 500.0)],
    );
    for n in ["K", "m", "sY"] {
        assert!(u.iter().any(|x| x == n), "{u:?}");
    }
}

/// A second false convergence once seen: R1 with L-BFGS from (E, eta) = (20000, 1000)
/// jumps eta to its upper bound 1e7, where dJ/deta vanishes; it used to exit 0 with E 29%
/// off. Now eta is undetermined at that bound and the exit status is 3.
#[test]
fn r1_with_eta_at_its_upper_bound_does_not_claim_convergence() {
    let u = honest_stop(
        "r1-maxwell.ron",
        "lbfgs",
        "E=20000,eta=1000",
        &[("E", 20000.0), ("eta", 30000.0)],
    );
    assert_eq!(u, vec!["eta".to_string()]);
}
