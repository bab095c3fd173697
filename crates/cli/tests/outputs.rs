//! Outputs are never lost: a refused identification writes nothing and leaves the earlier
//! report whole, a folder holding another run is refused unless --resume or --force, and
//! `simulate --out` replaces its file atomically.

mod common;

use common::*;

fn dir_listing(dir: &std::path::Path) -> Vec<(String, Vec<u8>)> {
    let mut v: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file())
        .map(|p| {
            (
                p.file_name().unwrap().to_string_lossy().into_owned(),
                std::fs::read(&p).unwrap(),
            )
        })
        .collect();
    v.sort();
    v
}

#[test]
fn a_refused_or_competing_run_never_touches_an_earlier_report() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let out_s = out.display().to_string();
    let r1 = example("r1-maxwell.ron");
    let first = indentify(&coarse(&[
        "-q",
        "identify",
        &r1,
        "--out",
        &out_s,
        "--max-iter",
        "2",
    ]));
    // two iterations do not converge: exit 1, but the report is complete
    assert!(!first.status.success());
    let before = dir_listing(&out);
    let names: Vec<&str> = before.iter().map(|(n, _)| n.as_str()).collect();
    for f in ["result.json", "history.csv", "fit.csv"] {
        assert!(names.contains(&f), "{names:?}");
    }
    assert!(before.iter().all(|(_, b)| !b.is_empty()));
    // refused for bad input: nothing written
    let bad = indentify(&coarse(&[
        "identify", &r1, "--out", &out_s, "--force", "--set", "law.E=-1",
    ]));
    assert_rejected(&bad, &["law.E"], "bad law");
    assert_eq!(dir_listing(&out), before);
    let bad = indentify(&coarse(&[
        "identify",
        &r1,
        "--out",
        &out_s,
        "--force",
        "--data",
        "no-such.csv",
    ]));
    assert_rejected(&bad, &["no-such.csv"], "missing data");
    assert_eq!(dir_listing(&out), before);
    // another run into the folder is refused and says how to go on
    let again = indentify(&coarse(&["identify", &r1, "--out", &out_s]));
    assert_rejected(
        &again,
        &["holds another run", "--resume", "--force"],
        "occupied",
    );
    assert_eq!(dir_listing(&out), before);
    // --force replaces it with a complete report
    let forced = indentify(&coarse(&[
        "-q", "identify", &r1, "--out", &out_s, "--force",
    ]));
    assert_ok(&forced);
    assert_ne!(dir_listing(&out), before);
    // no temporary file is left behind
    assert!(
        dir_listing(&out).iter().all(|(n, _)| !n.contains(".tmp-")),
        "{:?}",
        dir_listing(&out).iter().map(|x| &x.0).collect::<Vec<_>>()
    );
}

#[test]
fn simulate_out_is_replaced_whole_or_kept() {
    let tmp = tempfile::tempdir().unwrap();
    let curve = tmp.path().join("curve.csv");
    let c = curve.display().to_string();
    let r0 = example("r0-elastic.ron");
    assert_ok(&indentify(&coarse(&["-q", "simulate", &r0, "--out", &c])));
    let before = std::fs::read(&curve).unwrap();
    // refused: the earlier curve is kept as it was
    let bad = indentify(&coarse(&[
        "simulate",
        &r0,
        "--out",
        &c,
        "--set",
        "law.nu=0.7",
    ]));
    assert_rejected(&bad, &["law.nu"], "bad nu");
    assert_eq!(std::fs::read(&curve).unwrap(), before);
    let bad = indentify(&coarse(&["simulate", &r0, "--out", "/no/such/dir/c.csv"]));
    assert_rejected(&bad, &["does not exist"], "bad folder");
}

#[test]
fn a_negative_noise_is_read_as_a_value_and_refused_with_its_range() {
    let r0 = example("r0-elastic.ron");
    let o = indentify(&["simulate", &r0, "--noise", "-1"]);
    assert_rejected(&o, &["--noise -1 is not allowed", "[0, 1)"], "simulate");
    let o = indentify(&["identify", "--noise", "-0.5", "--out", "/nonexistent/x"]);
    assert_rejected(&o, &["--noise -0.5 is not allowed"], "identify");
}

/// Text of `dir/name`, or `None` when it cannot be read.
fn read(dir: &std::path::Path, name: &str) -> Option<String> {
    std::fs::read_to_string(dir.join(name)).ok()
}

#[test]
fn a_forced_run_killed_mid_run_leaves_the_earlier_run_whole_or_the_new_one_marked() {
    use std::process::{Command, Stdio};
    use std::time::{Duration, Instant};
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let out_s = out.display().to_string();
    let r1 = example("r1-maxwell.ron");
    // the earlier run: two iterations, a complete report
    let first = indentify(&coarse(&[
        "-q",
        "identify",
        &r1,
        "--out",
        &out_s,
        "--max-iter",
        "2",
    ]));
    assert!(!first.status.success(), "{}", stderr(&first));
    let before = dir_listing(&out);
    let history_before = read(&out, "history.csv").unwrap();
    // the new run (R1's own 20 x 20 mesh: about 16 iterations of a few tenths of a second
    // each), killed (SIGKILL) once its first iteration is in its history
    let new_run = |flag: &str| {
        vec![
            "-q".to_string(),
            "identify".into(),
            r1.clone(),
            "--out".into(),
            out_s.clone(),
            flag.into(),
            "--method".into(),
            "bfgs".into(),
            "--no-refine".into(),
        ]
    };
    let mut child = Command::new(env!("CARGO_BIN_EXE_indentify"))
        .args(new_run("--force"))
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let deadline = Instant::now() + Duration::from_secs(600);
    let mut finished = false;
    loop {
        let h = read(&out, "history.csv").unwrap_or_default();
        if h != history_before && h.lines().any(|l| l.starts_with("1,")) {
            break;
        }
        if child.try_wait().unwrap().is_some() {
            finished = true;
            break;
        }
        assert!(
            Instant::now() < deadline,
            "no iteration of the new run after 600 s"
        );
        std::thread::sleep(Duration::from_millis(2));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let marked = out.join("RUN-IN-PROGRESS.txt").is_file();
    let history = read(&out, "history.csv").unwrap_or_default();
    let names: Vec<String> = dir_listing(&out).into_iter().map(|(n, _)| n).collect();
    eprintln!(
        "killed {} the new run's end",
        if marked { "before" } else { "after" }
    );
    if marked {
        // the new run's partial output, marked; the earlier run whole beside it
        assert!(!finished);
        assert_ne!(history, history_before);
        assert_eq!(dir_listing(&out.join(".replaced")), before, "{names:?}");
        for (name, bytes) in &before {
            if let Ok(now) = std::fs::read(out.join(name)) {
                assert_ne!(
                    &now, bytes,
                    "`{name}` is the earlier run's in a new run's folder"
                );
            }
        }
        let mark = read(&out, "RUN-IN-PROGRESS.txt").unwrap();
        assert!(
            mark.contains("partial") && mark.contains(".replaced"),
            "{mark}"
        );
        // --resume continues the new run to its end: the mark and the earlier run go
        let resumed = indentify(&new_run("--resume"));
        assert_ok(&resumed);
        assert!(!out.join("RUN-IN-PROGRESS.txt").exists());
        assert!(!out.join(".replaced").exists());
    } else {
        // no mark: one whole run (the earlier one, or the new one finished before the kill)
        let result = read(&out, "result.json").unwrap();
        if history == history_before {
            assert_eq!(dir_listing(&out), before);
        } else {
            let r: serde_json::Value = serde_json::from_str(&result).unwrap();
            assert_ne!(result, read_before(&before, "result.json"), "{names:?}");
            let lines = history.lines().count() - 1;
            assert!(r.to_string().contains("\"iterations\""), "{r}");
            assert!(lines >= 2, "{history}");
            assert!(!out.join(".replaced").exists());
        }
    }
}

fn read_before(before: &[(String, Vec<u8>)], name: &str) -> String {
    before
        .iter()
        .find(|(n, _)| n == name)
        .map(|(_, b)| String::from_utf8_lossy(b).into_owned())
        .unwrap_or_default()
}
