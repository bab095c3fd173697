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
