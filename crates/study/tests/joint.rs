//! Joint fits through the study pipeline: `examples/r2-multi-rate.ron` on a coarse mesh
//! (three tests, a few Levenberg-Marquardt iterations), its per-test fit quality, result.json
//! and fit.csv, the one-test commands' `--test` choice, and the refusals of bad `tests`
//! lists naming the field.
//!
//! Reference: the truth that synthesized the data (the coarse fit must move towards it) and
//! the one-test configuration the `tests` entry stands for.

use std::path::PathBuf;

use indentify_study::identify::{self, IdentifyOptions};
use indentify_study::simulate::{self, SimulateOptions};
use indentify_study::{ConfigSource, ErrorKind};

fn example() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples/r2-multi-rate.ron")
}

/// The example on a 6 x 6 mesh with 4 + 2 + 2 steps per test.
fn coarse() -> Vec<String> {
    let mut sets: Vec<String> = ["specimen.nr=6", "specimen.nz=6"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    for k in 0..3 {
        for (s, n) in [(0, 4), (1, 2), (2, 2)] {
            sets.push(format!("tests.{k}.history.segments.{s}.steps={n}"));
        }
    }
    sets
}

/// The system shall fit the three tests of the multi-rate example jointly, report each
/// test's R² and weight (the default 1/(n F_max^2)), and write result.json with a `tests`
/// list and fit.csv with a `test` column; three LM iterations shall bring every parameter
/// closer to the truth than the start.
#[test]
fn multi_rate_example_fits_jointly_on_a_coarse_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let mut o = IdentifyOptions::new(ConfigSource::Path(example()));
    o.sets = coarse();
    o.out = Some(dir.path().to_path_buf());
    o.refine = false;
    o.figures = false;
    o.jobs = Some(2);
    o.overrides.max_iterations = Some(3);
    let out = identify::run(&o, &mut ()).unwrap();
    assert_eq!(out.tests.len(), 3);
    let truth = out.truth.clone().unwrap();
    for (k, p) in out.result.params.iter().enumerate() {
        if p.free {
            let (e0, e1) = ((p.start - truth[k]).abs(), (p.value - truth[k]).abs());
            println!(
                "{}: start {} -> {} (truth {})",
                p.name, p.start, p.value, truth[k]
            );
            assert!(e1 < e0, "{} moved away from the truth", p.name);
        }
    }
    let mut n = 0;
    for t in &out.tests {
        let q = t.quality.as_ref().unwrap();
        println!("{}: R2 {} weight {} wJ {}", t.name, q.r2, t.weight, t.cost);
        assert!(q.r2 > 0.9 && q.r2 <= 1.0);
        assert!(t.default_weight);
        let f_max = t.fit.f_data.iter().fold(0.0_f64, |m, f| m.max(f.abs()));
        let expect = 1.0 / (t.fit.t.len() as f64 * f_max * f_max);
        assert!((t.weight - expect).abs() <= 1e-12 * expect);
        n += t.fit.t.len();
    }
    // the joint cost is the sum of the tests' weighted costs
    let sum: f64 = out.tests.iter().map(|t| t.cost).sum();
    assert!((sum - out.result.cost).abs() <= 1e-12 * out.result.cost);
    assert_eq!(out.fit.t.len(), n);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("result.json")).unwrap())
            .unwrap();
    let tests = json["tests"].as_array().unwrap();
    assert_eq!(tests.len(), 3);
    assert_eq!(tests[1]["name"], "load 1 s");
    assert!(tests[2]["fit_quality"]["r2"].as_f64().unwrap() > 0.9);
    let fit = std::fs::read_to_string(dir.path().join("fit.csv")).unwrap();
    assert!(fit.starts_with("test,t,h,F_data,F_start,F_final\n"));
    assert_eq!(fit.lines().count(), n + 1);
    assert!(fit.lines().last().unwrap().starts_with("3,"));
}

fn config_error(text: &str) -> String {
    let o = IdentifyOptions::new(ConfigSource::Text {
        text: text.to_string(),
        name: "bad.ron".into(),
    });
    let e = identify::run(&o, &mut ()).unwrap_err();
    let all = e.messages().join(": ");
    assert_eq!(e.kind(), ErrorKind::Config, "{all}");
    all
}

const HEAD: &str = "specimen: Cylinder(radius: 4.0, height: 4.0, nr: 4, nz: 4, grading_r: 1.3, \
                    grading_z: 1.3), punch: Cone(half_angle_deg: 68.0), \
                    law: Maxwell(E: 20000.0, nu: 0.3, eta: 30000.0),";
const HIST: &str = "history: (segments: [(duration: 1.0, depth: 0.1, steps: 2)])";

/// Bad `tests` lists shall be refused before any solve, naming the field and what is
/// allowed: an empty list, a weight <= 0 or not finite, `tests` with a top-level history
/// (ambiguous), a test without a history or data.
#[test]
fn bad_tests_lists_are_refused_naming_the_field() {
    let e = config_error(&format!("({HEAD} tests: [])"));
    assert!(e.contains("`tests` is empty"), "{e}");
    for w in ["0.0", "-1.0", "inf"] {
        let e = config_error(&format!(
            "({HEAD} tests: [({HIST}), ({HIST}, weight: {w})])"
        ));
        assert!(e.contains("tests[1].weight") && e.contains("> 0"), "{e}");
    }
    let e = config_error(&format!("({HEAD} {HIST}, tests: [({HIST})])"));
    assert!(e.contains("ambiguous") && e.contains("history"), "{e}");
    let e = config_error(&format!("({HEAD} tests: [({HIST}), ()])"));
    assert!(e.contains("tests[1]") && e.contains("neither"), "{e}");
    // an invalid field inside a test is reported with the test
    let e = config_error(&format!(
        "({HEAD} tests: [(history: (segments: [(duration: -1.0, depth: 0.1, steps: 2)]))])"
    ));
    assert!(e.contains("tests[0]"), "{e}");
}

/// `simulate` on a joint configuration shall ask for `--test K` (naming the range), and
/// with it simulate that test as the one-test configuration it stands for.
#[test]
fn simulate_runs_one_test_of_a_joint_configuration() {
    let text = format!(
        "({HEAD} tests: [({HIST}), (history: (segments: [(duration: 2.0, depth: 0.05, \
         steps: 3)]), punch: Cone(half_angle_deg: 70.3))])"
    );
    let src = ConfigSource::Text {
        text: text.clone(),
        name: "joint.ron".into(),
    };
    let e = simulate::run(&SimulateOptions::new(src.clone())).unwrap_err();
    let all = e.messages().join(": ");
    assert!(all.contains("--test K (1 to 2)"), "{all}");
    let mut o = SimulateOptions::new(src);
    o.test = Some(3);
    let all = simulate::run(&o).unwrap_err().messages().join(": ");
    assert!(all.contains("numbered 1 to 2"), "{all}");
    o.test = Some(2);
    let joint = simulate::run(&o).unwrap();
    let single = simulate::run(&SimulateOptions::new(ConfigSource::Text {
        text: "(specimen: Cylinder(radius: 4.0, height: 4.0, nr: 4, nz: 4, grading_r: 1.3, \
             grading_z: 1.3), punch: Cone(half_angle_deg: 70.3), law: Maxwell(E: 20000.0, \
             nu: 0.3, eta: 30000.0), history: (segments: [(duration: 2.0, depth: 0.05, \
             steps: 3)]))"
            .to_string(),
        name: "single.ron".into(),
    }))
    .unwrap();
    assert_eq!(joint.rows.len(), 4);
    assert_eq!(
        joint.rows.iter().map(|r| r.f.to_bits()).collect::<Vec<_>>(),
        single
            .rows
            .iter()
            .map(|r| r.f.to_bits())
            .collect::<Vec<_>>()
    );
}

/// The noise of the tests of a joint fit shall be independent draws: no draw of one test's
/// stream appears among another's (with the old `seed + k * 0x9E3779B97F4A7C15`, test k's
/// draws were test 0's shifted by k points, since SplitMix64 advances by that constant).
#[test]
fn tests_of_a_joint_fit_get_unrelated_noise_streams() {
    use indentify_identify::multiplicative_noise;
    let ones = vec![1.0; 300];
    for seed in [1u64, 2, 3, 17, 1 << 40] {
        assert_eq!(identify::test_seed(seed, 0), seed);
        let streams: Vec<Vec<u64>> = (0..4)
            .map(|k| {
                multiplicative_noise(&ones, 0.02, identify::test_seed(seed, k))
                    .iter()
                    .map(|v| v.to_bits())
                    .collect()
            })
            .collect();
        for a in 0..4 {
            for b in a + 1..4 {
                let shared = streams[a].iter().filter(|x| streams[b].contains(x)).count();
                assert_eq!(
                    shared, 0,
                    "seed {seed}: tests {a} and {b} share {shared} draws"
                );
            }
        }
    }
}
