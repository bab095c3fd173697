//! `identify` under load control end to end (docs/theory.md §13): the force prescribed, the
//! depth fitted (`J = 1/2 sum (h_i - h_exp,i)^2`).
//!
//! References: the law values that generated the data. Exact synthesized depths: the
//! identified (E, eta) equal them to 1e-6 relative. A noisy round trip (`simulate
//! --noise` writes the curve, `identify --data` reads it): the identified values lie
//! within 2 of the fit's own standard deviations of the truth (one seeded draw). The report
//! files say that the depth is fitted: report.md's fit table, the depth-time figure's
//! axis label, result.json's `observable`, fit.csv's header. A joint fit of a
//! load-controlled and a depth-driven test recovers the exact truth too.
//!
//! ```text
//!   10 x 10 mm cylinder, 8 x 8 Q8 graded 1.3; cone 68 deg; Maxwell E = 20000 MPa,
//!   nu = 0.3 (fixed), eta = 30000 MPa s; force 0 -> 100 N (1 s, 6 steps), hold (1 s, 6)
//! ```

use indentify_study::identify::{self, IdentifyOptions};
use indentify_study::simulate::{self, SimulateOptions};
use indentify_study::source::ConfigSource;

const MODEL: &str = "specimen: Cylinder(radius: 10.0, height: 10.0, nr: 8, nz: 8, grading_r: 1.3, \
                     grading_z: 1.3), punch: Cone(half_angle_deg: 68.0), \
                     law: Maxwell(E: 20000.0, nu: 0.3, eta: 30000.0),";
const LOAD: &str = "(segments: [(duration: 1.0, force: 100.0, steps: 6), \
                    (duration: 1.0, force: 100.0, steps: 6)])";
const ID: &str = "identify: (params: {\"E\": Free(start: 14000.0, lower: 1000.0, upper: 1e6), \
                  \"nu\": Fixed(value: 0.3), \"eta\": Free(start: 50000.0, lower: 1000.0, \
                  upper: 1e7)}, method: Lm, stop: (step_sigma: None))";

fn source(history: &str) -> ConfigSource {
    ConfigSource::Text {
        text: format!("({MODEL} history: {history}, {ID})"),
        name: "load-fit".into(),
    }
}

fn options(src: ConfigSource) -> IdentifyOptions {
    let mut o = IdentifyOptions::new(src);
    o.refine = false;
    o.figures = false;
    o
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

fn temp_dir(what: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("indentify-{what}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Exact synthesized depths under load control: the fit recovers the truth to 1e-6.
#[test]
fn exact_load_controlled_data_are_recovered() {
    let o = identify::run(&options(source(LOAD)), &mut ()).unwrap();
    assert!(o.converged(), "{}", o.result.stop_reason);
    assert_eq!(o.fit.observable, indentify_study::Observable::Depth);
    let (e, eta) = (o.value("E").unwrap(), o.value("eta").unwrap());
    assert!(rel(e, 20000.0) < 1e-6, "E = {e}");
    assert!(rel(eta, 30000.0) < 1e-6, "eta = {eta}");
    // the data are depths (mm) and the prescribed series the force (N)
    assert!(o.fit.f_data.iter().all(|h| (0.0..0.1).contains(h)));
    let f_max = o.fit.h.iter().copied().fold(0.0, f64::max);
    assert!((f_max - 100.0).abs() < 1e-6, "{f_max}");
    assert!(o.data.contains("under load control"), "{}", o.data);
}

/// `simulate --noise` (noise on the depth), then `identify --data`: within 2 sigma.
#[test]
fn noisy_round_trip_lands_within_two_sigma() {
    let dir = temp_dir("load-noisy");
    let csv = dir.join("curve.csv");
    let mut sim = SimulateOptions::new(source(LOAD));
    sim.noise = Some((0.01, 11));
    sim.out = Some(csv.clone());
    simulate::run(&sim).unwrap();
    let mut o = options(source(LOAD));
    o.data = Some(csv);
    let out = identify::run(&o, &mut ()).unwrap();
    assert!(out.converged(), "{}", out.result.stop_reason);
    for (name, truth) in [("E", 20000.0), ("eta", 30000.0)] {
        let v = out.value(name).unwrap();
        let s = out.std_dev(name).expect("a standard deviation");
        assert!(s > 0.0 && s < 0.2 * truth, "{name}: sigma {s}");
        assert!(
            (v - truth).abs() <= 2.0 * s,
            "{name} = {v}, truth {truth}, sigma {s}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The report files of a load-controlled fit say that the depth is fitted.
#[test]
fn report_and_figures_show_the_depth_as_the_observable() {
    let dir = temp_dir("load-report");
    let out_dir = dir.join("report");
    let mut o = options(source(LOAD));
    o.figures = true;
    o.out = Some(out_dir.clone());
    let out = identify::run(&o, &mut ()).unwrap();
    assert!(out.converged());
    let md = std::fs::read_to_string(out_dir.join("report.md")).unwrap();
    for want in [
        "R² of the depth",
        "RMS depth residual",
        "RMS / h_max",
        "| observable | the depth (load control",
        "![depth vs time](depth_time.svg)",
        "![force vs depth](force_depth.svg)",
    ] {
        assert!(md.contains(want), "report.md lacks `{want}`:\n{md}");
    }
    assert!(!md.contains("R² of the force"), "{md}");
    let svg = std::fs::read_to_string(out_dir.join("depth_time.svg")).unwrap();
    assert!(svg.contains("depth h ["), "the depth-time axis");
    assert!(svg.contains("depth vs time"), "the depth-time caption");
    assert!(!out_dir.join("force_time.svg").exists());
    let fd = std::fs::read_to_string(out_dir.join("force_depth.svg")).unwrap();
    assert!(fd.contains("force F [") && fd.contains("depth h ["));
    let json = std::fs::read_to_string(out_dir.join("result.json")).unwrap();
    assert!(json.contains("\"observable\": \"Depth\""), "{json}");
    let report = std::fs::read_to_string(out_dir.join("report.json")).unwrap();
    assert!(report.contains("\"observable\": \"Depth\""));
    let fit = std::fs::read_to_string(out_dir.join("fit.csv")).unwrap();
    assert!(fit.starts_with("t,F,h_data,h_start,h_final\n"), "{fit}");
    // a data row: the force (N) prescribed, the depths (mm)
    let last: Vec<f64> = fit
        .lines()
        .last()
        .unwrap()
        .split(',')
        .map(|x| x.parse().unwrap())
        .collect();
    assert!((last[1] - 100.0).abs() < 1e-6, "{last:?}");
    assert!(last[2] > 0.0 && last[2] < 0.1 && (last[4] - last[2]).abs() < 1e-8);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A joint fit of a load-controlled test and a depth-driven one (exact data): the shared
/// truth recovered, each test's curves with its own observable.
#[test]
fn joint_fit_of_load_and_depth_controlled_tests() {
    let text = format!(
        "({MODEL} tests: [(name: \"load\", history: {LOAD}), (name: \"depth\", history: \
         (segments: [(duration: 0.5, depth: 0.03, steps: 4), (duration: 1.0, depth: 0.03, \
         steps: 4)]))], {ID})"
    );
    let o = identify::run(
        &options(ConfigSource::Text {
            text,
            name: "joint-load".into(),
        }),
        &mut (),
    )
    .unwrap();
    assert!(o.converged(), "{}", o.result.stop_reason);
    assert!(rel(o.value("E").unwrap(), 20000.0) < 1e-6);
    assert!(rel(o.value("eta").unwrap(), 30000.0) < 1e-6);
    use indentify_study::Observable;
    assert_eq!(o.tests[0].fit.observable, Observable::Depth);
    assert_eq!(o.tests[1].fit.observable, Observable::Force);
    // no quality over forces and depths together; each test has its own
    assert!(o.quality.is_none());
    assert!(o.tests.iter().all(|t| t.quality.is_some()));
}

/// `--checkpoint` under load control: the states saved every 3 steps and the gradient
/// replayed stretch by stretch with the force drive (`Adjoint::gradient_load_replayed`)
/// give the fit of the fully recorded run, to 1e-10 relative, with Levenberg-Marquardt
/// (its Jacobian from a recorded rerun) and BFGS (the replayed adjoint's gradient).
#[test]
fn checkpoints_under_load_control_give_the_recorded_fit() {
    for method in ["Lm", "Bfgs"] {
        let text = format!(
            "({MODEL} history: {LOAD}, {})",
            ID.replace("method: Lm", &format!("method: {method}"))
        );
        let src = || ConfigSource::Text {
            text: text.clone(),
            name: "load-fit".into(),
        };
        let plain = identify::run(&options(src()), &mut ()).unwrap();
        let mut o = options(src());
        o.checkpoint = Some(3);
        let cp = identify::run(&o, &mut ()).unwrap();
        assert!(cp.converged(), "{method}: {}", cp.result.stop_reason);
        for name in ["E", "eta"] {
            let (a, b) = (plain.value(name).unwrap(), cp.value(name).unwrap());
            assert!(rel(b, a) <= 1e-10, "{method} {name}: {b} vs {a}");
            assert!(
                rel(b, if name == "E" { 2e4 } else { 3e4 }) < 1e-5,
                "{method} {name} = {b}"
            );
        }
    }
}
