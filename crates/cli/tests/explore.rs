//! End-to-end checks of `indentify map` and `identify --starts/--profiles` on a coarse R1:
//! the files they write and the refusals of bad input before any solve.

mod common;

use common::{example, indentify, stderr};

const COARSE: [&str; 10] = [
    "--set",
    "specimen.nr=6",
    "--set",
    "specimen.nz=6",
    "--set",
    "history.segments.0.steps=4",
    "--set",
    "history.segments.1.steps=4",
    "--set",
    "history.segments.2.steps=4",
];

/// `map` shall write the grid as CSV (grid^2 lines and a header), its JSON and the contour
/// figure as SVG and PNG.
#[test]
fn map_writes_csv_json_and_figures() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("m");
    let mut args = vec![
        "map".to_string(),
        example("r1-maxwell.ron"),
        "--pair".into(),
        "E,eta".into(),
        "--grid".into(),
        "3".into(),
        "--through".into(),
        "law".into(),
        "--out".into(),
        out.display().to_string(),
    ];
    args.extend(COARSE.iter().map(|s| s.to_string()));
    let o = indentify(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let csv = std::fs::read_to_string(out.join("map.csv")).unwrap();
    assert_eq!(csv.lines().count(), 10, "{csv}");
    assert!(
        std::fs::read_to_string(out.join("map.svg"))
            .unwrap()
            .contains("<svg")
    );
    assert_eq!(&std::fs::read(out.join("map.png")).unwrap()[1..4], b"PNG");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("map.json")).unwrap()).unwrap();
    assert_eq!(json["through"], "law");
}

/// Bad input shall be refused with a message naming the option, and nothing written.
#[test]
fn bad_map_and_starts_input_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("bad").display().to_string();
    let r1 = example("r1-maxwell.ron");
    for (args, expect) in [
        (
            vec!["map", &r1, "--pair", "E,nu", "--out", &out],
            "`nu` is held",
        ),
        (
            vec!["map", &r1, "--pair", "E,q", "--out", &out],
            "no parameter `q`",
        ),
        (vec!["map", &r1, "--pair", "E,E", "--out", &out], "twice"),
        (
            vec!["map", &r1, "--pair", "E,eta", "--grid", "2", "--out", &out],
            "[3, 401]",
        ),
        (
            vec!["identify", &r1, "--starts", "0", "--out", &out],
            "--starts",
        ),
        (
            vec!["identify", &r1, "--seed", "3", "--out", &out],
            "--seed needs",
        ),
    ] {
        let o = indentify(&args);
        let e = stderr(&o);
        assert!(!o.status.success() && e.contains(expect), "{args:?}: {e}");
        assert!(!e.contains("panicked"), "{e}");
    }
    assert!(!dir.path().join("bad").join("history.csv").exists());
}

/// `identify --starts 3 --profiles` shall report the minima and the intervals on the
/// console, in report.md and result.json, and draw one profile per free parameter.
#[test]
fn starts_and_profiles_reach_every_output() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("r");
    let mut args = vec![
        "identify".to_string(),
        example("r1-maxwell.ron"),
        "--noise".into(),
        "0.02".into(),
        "--starts".into(),
        "3".into(),
        "--seed".into(),
        "2".into(),
        "--profiles".into(),
        "--no-refine".into(),
        "--out".into(),
        out.display().to_string(),
    ];
    args.extend(COARSE.iter().map(|s| s.to_string()));
    let o = indentify(&args);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stdout.contains("multi-start: 3 starts") && stdout.contains("95% lower"),
        "{stdout}"
    );
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(md.contains("## Multi-start") && md.contains("## Profile likelihood"));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("result.json")).unwrap()).unwrap();
    assert_eq!(json["multistart"]["runs"].as_array().unwrap().len(), 3);
    assert_eq!(json["profiles"].as_array().unwrap().len(), 2);
    for p in ["E", "eta"] {
        assert!(out.join(format!("profile_{p}.svg")).exists());
        assert!(out.join(format!("profile_{p}.png")).exists());
    }
}
