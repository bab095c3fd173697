//! End-to-end check of `indentify design` on a coarse R1 (Maxwell) configuration with two
//! candidates: the table printed, design.json and design.md written, and bad input (no
//! `design` section, a noise level <= 0) refused before any solve with nothing written.

mod common;

use common::{assert_ok, assert_rejected, indentify, stdout};

const CONFIG: &str = r#"(
    specimen: Cylinder(radius: 10.0, height: 10.0, nr: 6, nz: 6, grading_r: 1.3, grading_z: 1.3),
    punch: Cone(half_angle_deg: 68.0),
    law: Maxwell(E: 20000.0, nu: 0.3, eta: 30000.0),
    history: (segments: [(duration: 1.0, depth: 0.1, steps: 4), (duration: 1.0, depth: 0.1, steps: 4)]),
    identify: (params: {"E": Free(lower: 1000.0, upper: 1e6), "nu": Fixed(value: 0.3), "eta": Free(lower: 1000.0, upper: 1e7)}),
    design: (
        noise: Relative(0.01),
        candidates: [
            (name: "no hold", tests: [(history: (segments: [(duration: 1.0, depth: 0.1, steps: 4)]))]),
            (name: "load and hold", tests: [(history: (segments: [(duration: 1.0, depth: 0.1, steps: 4), (duration: 1.0, depth: 0.1, steps: 4)]))]),
        ],
    ),
)"#;

/// `design` shall print the ranked table and write design.json (both candidates, their
/// deviations and ranks) and design.md.
#[test]
fn design_prints_the_table_and_writes_json_and_markdown() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("d.ron");
    std::fs::write(&cfg, CONFIG).unwrap();
    let out = dir.path().join("out");
    let o = indentify(&[
        "design".to_string(),
        cfg.display().to_string(),
        "--out".into(),
        out.display().to_string(),
        "--jobs".into(),
        "2".into(),
    ]);
    assert_ok(&o);
    let text = stdout(&o);
    println!("{text}");
    assert!(
        text.contains("| rank (D) |") && text.contains("load and hold"),
        "{text}"
    );
    assert!(
        text.contains("noise: multiplicative noise, standard deviation 1.00% of F"),
        "{text}"
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("design.json")).unwrap()).unwrap();
    let cands = json["candidates"].as_array().unwrap();
    assert_eq!(cands.len(), 2);
    assert_eq!(cands[1]["name"], "load and hold");
    assert!(cands[1]["params"][1]["rel_std_dev"].as_f64().unwrap() > 0.0);
    assert_eq!(json["rank_d"].as_array().unwrap().len(), 2);
    let md = std::fs::read_to_string(out.join("design.md")).unwrap();
    assert!(md.starts_with("# Test design"), "{md}");
}

/// A configuration without `design` and a noise level of 0 shall be refused, naming the
/// section or field, and nothing written.
#[test]
fn bad_design_input_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let no_design = dir.path().join("n.ron");
    let text = CONFIG.split("    design:").next().unwrap().to_string() + ")";
    std::fs::write(&no_design, text).unwrap();
    let o = indentify(&[
        "design".to_string(),
        no_design.display().to_string(),
        "--out".into(),
        out.display().to_string(),
    ]);
    assert_rejected(&o, &["no `design` section"], "no design section");
    let zero = dir.path().join("z.ron");
    std::fs::write(&zero, CONFIG.replace("Relative(0.01)", "Relative(0.0)")).unwrap();
    let o = indentify(&[
        "design".to_string(),
        zero.display().to_string(),
        "--out".into(),
        out.display().to_string(),
    ]);
    assert_rejected(&o, &["design.noise", "> 0"], "noise 0");
    assert!(!out.exists());
}
