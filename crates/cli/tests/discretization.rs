//! `indentify identify` and the discretization error: the `disc. shift` column and the
//! summary line by default, result.json's `discretization` object, and `--no-refine`.

mod common;

use common::*;

fn run(extra: &[&str]) -> (std::process::Output, serde_json::Value, tempfile::TempDir) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("rep").display().to_string();
    let mut args = vec!["identify", "--out", out.as_str()];
    args.extend_from_slice(extra);
    let o = indentify(&coarse(&args));
    assert_ok(&o);
    let text = std::fs::read_to_string(dir.path().join("rep/result.json")).unwrap();
    (o, serde_json::from_str(&text).unwrap(), dir)
}

#[test]
fn identify_shows_the_discretization_shift_by_default() {
    let (o, v, _dir) = run(&[]);
    let text = stdout(&o);
    assert!(text.contains("disc. shift"), "{text}");
    assert!(text.contains("std. dev."), "{text}");
    assert!(
        text.contains(
            "discretization: mesh refined 2x (36 -> 144 elements), steps halved (12 -> 24)"
        ),
        "{text}"
    );
    assert!(text.contains("--no-refine"), "{text}");
    // the exact data of the coarse model: the shift exceeds the round-off deviations
    assert!(
        stderr(&o).contains("discretization moves E by"),
        "{}",
        stderr(&o)
    );
    let d = &v["discretization"];
    assert!(d["rms_rel"].as_f64().unwrap() > 0.0, "{d}");
    assert!(d["shift"]["E"].is_number(), "{d}");
    assert!(d["shift"]["eta"].is_number(), "{d}");
    assert_eq!(d["elements"], serde_json::json!([36, 144]));
}

#[test]
fn no_refine_skips_it() {
    let (o, v, dir) = run(&["--no-refine"]);
    let text = stdout(&o);
    assert!(!text.contains("disc. shift"), "{text}");
    assert!(!text.contains("discretization"), "{text}");
    assert!(v.get("discretization").is_none(), "{v}");
    let md = std::fs::read_to_string(dir.path().join("rep/report.md")).unwrap();
    assert!(!md.contains("Discretization"), "{md}");
}
