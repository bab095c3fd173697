//! What a user sees on the edges: a negative count named with its range, a refused run
//! that leaves no folder behind, `simulate --out` given a folder refused before the solve,
//! each test of a joint configuration with its own noise, a force implausible for its tip
//! and depth warned about, a batch without positions saying why it draws no map, and a
//! Ctrl-C during the discretization check skipping it and saying so.

mod common;

use common::*;

#[test]
fn a_negative_count_names_its_option_and_range() {
    for (args, flag) in [
        (vec!["identify", "--max-iter", "-1"], "--max-iter"),
        (vec!["identify", "--noise", "0.1", "--seed", "-3"], "--seed"),
        (
            vec!["batch", "m.csv", "--out", "o", "--max-iter", "-2"],
            "--max-iter",
        ),
        (vec!["simulate", "--noise", "0.1", "--seed", "-1"], "--seed"),
    ] {
        let o = indentify(&args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(!err.contains("unexpected argument"), "{args:?}: {err}");
        assert!(
            err.contains(flag) && err.contains(">= 0"),
            "{args:?}: {err}"
        );
    }
}

#[test]
fn a_run_refused_for_its_data_leaves_no_empty_folder() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("new/report");
    let o = indentify(&coarse(&[
        "identify",
        &example("r1-maxwell.ron"),
        "--data",
        "no-such.csv",
        "--out",
        &out.display().to_string(),
    ]));
    assert_rejected(&o, &["no-such.csv"], "missing data");
    assert!(
        !tmp.path().join("new").exists(),
        "a refused run made its folder"
    );
    // an --out below a file is refused before any solve
    let file = tmp.path().join("file");
    std::fs::write(&file, "x").unwrap();
    let o = indentify(&coarse(&[
        "identify",
        &example("r1-maxwell.ron"),
        "--out",
        &file.join("r").display().to_string(),
    ]));
    assert_rejected(&o, &["is a file"], "out below a file");
}

#[test]
fn simulate_out_a_folder_is_refused_before_the_solve() {
    let tmp = tempfile::tempdir().unwrap();
    let o = indentify(&[
        "simulate",
        &example("r1-maxwell.ron"),
        "--out",
        &tmp.path().display().to_string(),
    ]);
    assert_rejected(&o, &["is a folder", "curve.csv"], "a folder");
}

/// `F_noisy / F - 1` of a simulated test with and without noise.
fn relative_noise(test: &str) -> Vec<f64> {
    let r2 = example("r2-multi-rate.ron");
    let run = |noise: bool| {
        let mut args = vec![
            "-q",
            "simulate",
            &r2,
            "--test",
            test,
            "--set",
            "specimen.nr=4",
            "--set",
            "specimen.nz=4",
        ];
        if noise {
            args.extend(["--noise", "0.05", "--seed", "7"]);
        }
        let o = indentify(&args);
        assert_ok(&o);
        parse_curve(&stdout(&o))
    };
    let (clean, noisy) = (run(false), run(true));
    clean
        .iter()
        .zip(&noisy)
        .filter(|(c, _)| c[2].abs() > 0.0)
        .map(|(c, n)| n[2] / c[2] - 1.0)
        .collect()
}

#[test]
fn simulate_draws_each_tests_own_noise_as_identify_does() {
    let (one, two) = (relative_noise("1"), relative_noise("2"));
    assert_eq!(one.len(), two.len());
    assert!(one.iter().all(|r| r.abs() <= 0.05 + 1e-12));
    let same = one
        .iter()
        .zip(&two)
        .filter(|(a, b)| (*a - *b).abs() < 1e-12)
        .count();
    assert!(
        same < 3,
        "tests 1 and 2 share {same} of {} draws",
        one.len()
    );
}

#[test]
fn a_force_implausible_for_the_tip_and_depth_is_warned_about() {
    let tmp = tempfile::tempdir().unwrap();
    // a 2 um Berkovich indent whose force column says kN: 11 kN on a few square um
    let mut text = String::from("Time (s),Depth (um),Fn (kN)\n");
    for i in 0..=20 {
        let t = f64::from(i);
        let x = if i <= 10 { t / 10.0 } else { (20.0 - t) / 10.0 };
        text.push_str(&format!("{t},{},{}\n", 2.0 * x, 11.0 * x * x));
    }
    let data = tmp.path().join("kn.csv");
    std::fs::write(&data, text).unwrap();
    let init = indentify(&["init", "elastic", "--data", &data.display().to_string()]);
    assert_ok(&init);
    let cfg = tmp.path().join("kn.ron");
    std::fs::write(&cfg, stdout(&init)).unwrap();
    let o = indentify(&["check", &cfg.display().to_string()]);
    let err = stderr(&o);
    assert!(!err.contains("panicked"), "{err}");
    assert!(
        err.contains("mean pressure") && err.contains("harder than") && err.contains("Fn (mN)"),
        "{err}"
    );
}

#[test]
fn a_batch_without_positions_says_why_it_draws_no_map() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let sim = indentify(&coarse(&[
        "-q",
        "simulate",
        &example("r1-maxwell.ron"),
        "--out",
        &d.join("c.csv").display().to_string(),
    ]));
    assert_ok(&sim);
    // a coarse mesh and few steps through the manifest's configuration columns
    std::fs::write(
        d.join("m.csv"),
        "id,data,x,specimen.nr,specimen.nz,history.segments.0.steps,history.segments.1.steps,\
         history.segments.2.steps\na,c.csv,0.1,6,6,4,4,4\n",
    )
    .unwrap();
    let args = [
        "batch".to_string(),
        d.join("m.csv").display().to_string(),
        "--out".into(),
        d.join("out").display().to_string(),
        "--config".into(),
        example("r1-maxwell.ron"),
    ];
    let o = indentify(&args);
    let out = stdout(&o);
    assert!(
        out.contains("no maps are drawn") && out.contains("no `y` column"),
        "{out}\n{}",
        stderr(&o)
    );
}

#[test]
fn batch_slurm_validates_every_indent_before_writing_a_job_array() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(d.join("c.csv"), "t,F\n0,0\n1,1\n2,0\n").unwrap();
    let r1 = example("r1-maxwell.ron");
    for (manifest, needles) in [
        (
            "id,data,law.foo\na,c.csv,1\n",
            vec!["m.csv:2", "`a`", "foo"],
        ),
        (
            "id,data,law.E\na,c.csv,1000\nb,c.csv,-5\n",
            vec!["m.csv:3", "`b`", "law.E"],
        ),
        (
            "id,test\na,2\n",
            vec!["m.csv:2", "`test` column (2)", "no `data` section"],
        ),
    ] {
        std::fs::write(d.join("m.csv"), manifest).unwrap();
        let out = d.join("run");
        let o = indentify(&[
            "batch",
            "slurm",
            &d.join("m.csv").display().to_string(),
            "--config",
            &r1,
            "--out",
            &out.display().to_string(),
            "--array",
            "2",
        ]);
        assert_rejected(&o, &needles, manifest);
        assert!(!out.join("batch.sbatch").exists(), "{manifest}");
    }
}

#[test]
fn ctrl_c_during_the_discretization_check_skips_it_says_so_and_exits_130() {
    use std::io::{BufRead, BufReader, Read};
    use std::process::{Command, Stdio};
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    // R1 on its own 20 x 20 mesh: the check re-runs it on 40 x 40 (about a second)
    let mut child = Command::new(env!("CARGO_BIN_EXE_indentify"))
        .args([
            "identify",
            &example("r1-maxwell.ron"),
            "--out",
            &out.display().to_string(),
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut err = BufReader::new(child.stderr.take().unwrap());
    let mut seen = String::new();
    let mut line = String::new();
    while err.read_line(&mut line).unwrap() > 0 {
        seen.push_str(&line);
        if line.contains("discretization check:") {
            let kill = Command::new("kill")
                .args(["-INT", &child.id().to_string()])
                .status()
                .unwrap();
            assert!(kill.success());
            break;
        }
        line.clear();
    }
    err.read_to_string(&mut seen).unwrap();
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(130), "{seen}");
    assert!(
        seen.contains("the discretization check was skipped"),
        "{seen}"
    );
    let result = std::fs::read_to_string(out.join("result.json")).unwrap();
    assert!(
        result.contains("discretization check was skipped"),
        "{result}"
    );
    assert!(!out.join("RUN-IN-PROGRESS.txt").exists());
}
