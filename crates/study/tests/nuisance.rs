//! Instrument parameters in `identify` end to end (docs/theory.md §13.6, docs/cli.md
//! "Instrument parameters"): the frame compliance `Cf`, the drift rate `vd` and the depth
//! offset `h0` (one per test of a joint configuration, `h0[1]`, `h0[2]`, ...) named in
//! `identify.params` or `--free`, fitted beside the law's under load control.
//!
//! References: the values that generated the data. `simulate` writes a load-controlled
//! curve at the law values; the test adds a known drift `vd (t - t0)` and offset `h0` to
//! its depth column; the fit recovers E, eta, vd and h0 (exact data: to 1e-5 relative,
//! 1e-9 mm absolute for the offset). A joint fit of two such curves with different offsets
//! recovers each test's `h0[k]`. Refusals name the field or the test.
//!
//! ```text
//!   10 x 10 mm cylinder, 8 x 8 Q8 graded 1.3; cone 68 deg; Maxwell E = 20000 MPa,
//!   nu = 0.3 (fixed), eta = 30000 MPa s; force 0 -> P (1 s, 6 steps), hold (1 s, 6)
//! ```

use std::path::{Path, PathBuf};

use indentify_study::identify::{self, IdentifyOptions};
use indentify_study::simulate::{self, SimulateOptions};
use indentify_study::source::ConfigSource;

const MODEL: &str = "specimen: Cylinder(radius: 10.0, height: 10.0, nr: 8, nz: 8, grading_r: 1.3, \
                     grading_z: 1.3), punch: Cone(half_angle_deg: 68.0), \
                     law: Maxwell(E: 20000.0, nu: 0.3, eta: 30000.0),";
const LAW_ID: &str = "\"E\": Free(start: 14000.0, lower: 1000.0, upper: 1e6), \"nu\": \
                      Fixed(value: 0.3), \"eta\": Free(start: 50000.0, lower: 1000.0, upper: \
                      1e7)";

fn load(p: f64) -> String {
    format!(
        "(segments: [(duration: 1.0, force: {p}, steps: 6), (duration: 1.0, force: {p}, \
         steps: 6)])"
    )
}

fn id(extra: &str) -> String {
    format!("identify: (params: {{{LAW_ID}{extra}}}, method: Lm, stop: (step_sigma: None))")
}

fn text(name: &str, text: String) -> ConfigSource {
    ConfigSource::Text {
        text,
        name: name.into(),
    }
}

fn options(src: ConfigSource) -> IdentifyOptions {
    let mut o = IdentifyOptions::new(src);
    o.refine = false;
    o.figures = false;
    o
}

fn temp_dir(what: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("indentify-{what}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// `simulate` of a load-controlled configuration at force `p`, its depth column shifted
/// by `vd (t - t0) + h0`, written to `path`.
fn curve_with_instrument(p: f64, vd: f64, h0: f64, path: &Path) {
    let src = text("sim", format!("({MODEL} history: {})", load(p)));
    let mut sim = SimulateOptions::new(src);
    sim.out = Some(path.to_path_buf());
    simulate::run(&sim).unwrap();
    let csv = std::fs::read_to_string(path).unwrap();
    let mut lines = csv.lines();
    let header = lines.next().unwrap();
    let cols: Vec<&str> = header.split(',').collect();
    let (it, ih) = (
        cols.iter().position(|c| *c == "t").unwrap(),
        cols.iter().position(|c| *c == "h").unwrap(),
    );
    let mut out = format!("{header}\n");
    let mut t0 = None;
    for l in lines {
        let mut v: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
        let t = v[it];
        let t0 = *t0.get_or_insert(t);
        v[ih] += vd * (t - t0) + h0;
        let row: Vec<String> = v.iter().map(|x| format!("{x:e}")).collect();
        out.push_str(&row.join(","));
        out.push('\n');
    }
    std::fs::write(path, out).unwrap();
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// A drift and an offset added to exact load-controlled depths: `vd` and `h0` free beside
/// E and eta, all recovered; the result names them with their units; the report, its
/// figures and the discretization check run with them.
#[test]
fn drift_and_offset_are_recovered_with_the_law() {
    let dir = temp_dir("nuisance-one");
    let csv = dir.join("curve.csv");
    let (vd, h0) = (4e-4, -3e-4);
    curve_with_instrument(100.0, vd, h0, &csv);
    let cfg = format!(
        "({MODEL} history: {}, {})",
        load(100.0),
        id(", \"vd\": Free(start: 0.0), \"h0\": Free(start: 0.0)")
    );
    let mut o = options(text("drift", cfg));
    o.data = Some(csv);
    o.out = Some(dir.join("out"));
    o.figures = true;
    // the discretization check runs the instrumented law on the refined model too
    o.refine = true;
    let out = identify::run(&o, &mut ()).unwrap();
    println!(
        "E {:?} eta {:?} vd {:?} h0 {:?}, {}",
        out.value("E"),
        out.value("eta"),
        out.value("vd"),
        out.value("h0"),
        out.result.stop_reason
    );
    assert!(out.converged(), "{}", out.result.stop_reason);
    assert!(rel(out.value("E").unwrap(), 20000.0) < 1e-5);
    assert!(rel(out.value("eta").unwrap(), 30000.0) < 1e-5);
    assert!(rel(out.value("vd").unwrap(), vd) < 1e-5);
    assert!((out.value("h0").unwrap() - h0).abs() < 1e-9);
    let json = std::fs::read_to_string(dir.join("out").join("result.json")).unwrap();
    for want in ["\"vd\"", "\"mm/s\"", "\"h0\""] {
        assert!(json.contains(want), "result.json lacks {want}");
    }
    let md = std::fs::read_to_string(dir.join("out").join("report.md")).unwrap();
    assert!(md.contains("vd") && md.contains("mm/s"), "{md}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Two tests with different offsets, a shared law: `h0` frees every test's offset
/// (`h0[1]`, `h0[2]`), each recovered; `--free` names them too.
#[test]
fn joint_fit_recovers_each_tests_offset() {
    let dir = temp_dir("nuisance-joint");
    let (a, b) = (dir.join("a.csv"), dir.join("b.csv"));
    curve_with_instrument(100.0, 0.0, 2e-4, &a);
    curve_with_instrument(60.0, 0.0, -1e-4, &b);
    let cfg = format!(
        "({MODEL} contact: Vertical, kinematics: Small, tests: [(name: \"100N\", data: (file: {:?}, drive: Force, \
         preprocessing: (zero_point: None))), (name: \"60N\", data: (file: {:?}, drive: \
         Force, preprocessing: (zero_point: None)))], {})",
        a.display().to_string(),
        b.display().to_string(),
        id("")
    );
    let mut o = options(text("joint-h0", cfg));
    o.overrides.free = Some(vec!["E".into(), "eta".into(), "h0".into()]);
    let out = match identify::run(&o, &mut ()) {
        Ok(o) => o,
        Err(e) => panic!("{e:#}"),
    };
    println!(
        "E {:?} eta {:?} h0[1] {:?} h0[2] {:?}",
        out.value("E"),
        out.value("eta"),
        out.value("h0[1]"),
        out.value("h0[2]")
    );
    assert!(out.converged(), "{}", out.result.stop_reason);
    assert!(rel(out.value("E").unwrap(), 20000.0) < 1e-5);
    assert!((out.value("h0[1]").unwrap() - 2e-4).abs() < 1e-9);
    assert!((out.value("h0[2]").unwrap() + 1e-4).abs() < 1e-9);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Bad input names the field or the test: a negative lower bound of Cf, an offset of a
/// test the configuration lacks. (A depth-driven test with instrument parameters runs
/// through the frame: `tests/compliant.rs`.)
#[test]
fn refusals_name_the_field_or_the_test() {
    let cfg = format!(
        "({MODEL} history: {}, {})",
        load(100.0),
        id(", \"Cf\": Free(start: 0.0, lower: -1e-3, upper: 1e-3)")
    );
    let e = identify::run(&options(text("neg-cf", cfg)), &mut ()).unwrap_err();
    let m = format!("{e:?}");
    assert!(
        m.contains("identify.params.Cf") && m.contains("[0, inf)"),
        "{m}"
    );

    let cfg = format!(
        "({MODEL} tests: [(name: \"a\", history: {}), (name: \"b\", history: {})], {})",
        load(100.0),
        load(60.0),
        id(", \"h0[3]\": Free(start: 0.0)")
    );
    let e = identify::run(&options(text("h0-3", cfg)), &mut ()).unwrap_err();
    let m = format!("{e:?}");
    assert!(m.contains("h0[3]") && m.contains("h0[1], h0[2]"), "{m}");

    let cfg = format!(
        "({MODEL} history: {}, {})",
        load(100.0),
        id(", \"vd\": Free(start: NaN)")
    );
    let m = match identify::run(&options(text("nan-vd", cfg)), &mut ()) {
        Ok(_) => panic!("a NaN start is refused"),
        Err(e) => format!("{e:?}"),
    };
    assert!(m.contains("vd"), "{m}");
}

/// `gradient-check` of a load-controlled configuration naming Cf, vd and h0: the
/// instrument's parameters are checked with the law's (adjoint vs central differences of
/// the cost the fit minimizes, and vs the sensitivities), all passing.
#[test]
fn gradient_check_covers_the_instrument_parameters() {
    use indentify_study::check::{self, CheckOptions};
    let unload = "(segments: [(duration: 1.0, force: 100.0, steps: 6), (duration: 1.0, force: \
                  100.0, steps: 6), (duration: 1.0, force: 40.0, steps: 6)])";
    let cfg = format!(
        "({MODEL} history: {unload}, {})",
        id(", \"Cf\": Free(start: 0.0), \"vd\": Free(start: 0.0), \"h0\": Free(start: 0.0)")
    );
    let report = match check::run(&CheckOptions::new(text("check-inst", cfg))) {
        Ok(r) => r,
        Err(e) => panic!("{e:?}"),
    };
    for c in &report.checks {
        println!(
            "{}: adjoint {:.6e} fd {:.6e} (rel {:.1e}) sens rel {:.1e}",
            c.name, c.adjoint, c.fd, c.rel_diff_fd, c.rel_diff_sensitivity
        );
    }
    let names: Vec<&str> = report.checks.iter().map(|c| c.name).collect();
    assert_eq!(names, ["E", "nu", "eta", "Cf", "vd", "h0"]);
    assert!(report.passed, "{:?}", report.failures);
    assert!(report.checks[3..].iter().all(|c| c.adjoint != 0.0));
}
