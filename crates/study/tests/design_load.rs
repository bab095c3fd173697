//! `indentify_study::design` with load-controlled candidates: histories that prescribe the
//! force (a ramp to a hold load, the hold), the depth the observable, under a stated depth
//! noise; mixed with depth-controlled candidates and tests.
//!
//! References the design code did not produce: for an elastic law (small strain, rigid
//! frictionless punch) the depth under a prescribed force depends on `F / E` only, so the
//! deviation of `ln E` has a closed form in `d_i = dh_i/d ln E`, taken here by central
//! differences of plain `simulate` runs at `E e^(+-delta)` (not the design's sensitivities):
//! `s / sqrt(sum d^2)` for an absolute depth noise `s`, `f sqrt(sum h^2 d^2) / sum d^2` for
//! a relative one. A depth-controlled test has `dF/d ln E = F` exactly; a candidate of one
//! of each, with explicit weights, has `Var(ln E) = B / A^2`, `A = sum w_i d_i^2`,
//! `B = sum w_i^2 s_i^2 d_i^2` over both tests' rows, each row with its own noise.
//! And a Maxwell solid creeping under a held load: a candidate with a long hold determines
//! the viscosity better than one without, at the same number of points.

use indentify_study::design::{self, DesignOptions};
use indentify_study::simulate::{self, SimulateOptions};
use indentify_study::{ConfigSource, ErrorKind};

const MESH: &str =
    "specimen: Cylinder(radius: 10.0, height: 10.0, nr: 6, nz: 6, grading_r: 1.3, grading_z: 1.3),
     punch: Cone(half_angle_deg: 68.0),";
const ELASTIC: &str = "Elastic(E: 20000.0, nu: 0.3)";
const ELASTIC_ID: &str =
    "params: {\"E\": Free(lower: 1000.0, upper: 1e6), \"nu\": Fixed(value: 0.3)}";
const MAXWELL: &str = "Maxwell(E: 20000.0, nu: 0.3, eta: 30000.0)";
const MAXWELL_ID: &str = "params: {\"E\": Free(lower: 1000.0, upper: 1e6), \"nu\": Fixed(value: 0.3), \
                          \"eta\": Free(lower: 1000.0, upper: 1e7)}, method: Lm";

/// A load-controlled history: the force ramped to `force` N in `load` s (`n_load` steps),
/// then held `hold` s (`n_hold` steps; no hold with `n_hold = 0`).
fn load_history(load: f64, force: f64, n_load: usize, hold: f64, n_hold: usize) -> String {
    let mut s = format!("(duration: {load}, force: {force}, steps: {n_load})");
    if n_hold > 0 {
        s.push_str(&format!(
            ", (duration: {hold}, force: {force}, steps: {n_hold})"
        ));
    }
    format!("history: (segments: [{s}])")
}

/// A depth-controlled history: the depth ramped to `depth` mm in 1 s (4 steps).
fn depth_history(depth: f64) -> String {
    format!("history: (segments: [(duration: 1.0, depth: {depth}, steps: 4)])")
}

/// A configuration with a design section: `noise` the whole `noise: ...` (and
/// `depth_noise: ...`) text, each candidate its tests' inner texts.
fn text(law: &str, identify: &str, noise: &str, candidates: &[(&str, Vec<String>)]) -> String {
    let cands: Vec<String> = candidates
        .iter()
        .map(|(name, tests)| {
            let t: Vec<String> = tests.iter().map(|h| format!("({h})")).collect();
            format!("(name: \"{name}\", tests: [{}])", t.join(", "))
        })
        .collect();
    format!(
        "({MESH} law: {law}, {}, identify: ({identify}), design: ({noise}, candidates: [{}]))",
        depth_history(0.1),
        cands.join(", ")
    )
}

fn source(t: String) -> ConfigSource {
    ConfigSource::Text {
        text: t,
        name: "design-load-test".into(),
    }
}

/// The rows (t, h, F) of a plain simulation of `history` with `law`.
fn simulate_rows(law: &str, history: &str) -> Vec<(f64, f64)> {
    let mut o = SimulateOptions::new(source(format!("({MESH} law: {law}, {history})")));
    o.out = None;
    simulate::run(&o)
        .unwrap()
        .rows
        .iter()
        .map(|r| (r.h, r.f))
        .collect()
}

/// Central differences `dh_i / d ln E` of the depths of a load-controlled elastic run, and
/// the depths at the nominal E.
fn depth_derivatives(history: &str) -> (Vec<f64>, Vec<f64>) {
    let delta: f64 = 1e-4;
    let at = |e: f64| -> Vec<f64> {
        simulate_rows(&format!("Elastic(E: {e:.17e}, nu: 0.3)"), history)
            .iter()
            .map(|r| r.0)
            .collect()
    };
    let (hp, hm) = (at(20000.0 * delta.exp()), at(20000.0 * (-delta).exp()));
    let h = at(20000.0);
    let d = hp
        .iter()
        .zip(&hm)
        .map(|(a, b)| (a - b) / (2.0 * delta))
        .collect();
    (h, d)
}

/// Elastic, E alone, load control: the design's deviation of ln E equals the closed form
/// in the finite-difference depth derivatives, under an absolute and a relative depth
/// noise (to 1e-6; measured 2e-9), and
/// `ln det I = -2 ln sigma`.
#[test]
fn load_controlled_elastic_deviation_matches_the_closed_form() {
    let hist = load_history(1.0, 300.0, 6, 0.0, 0);
    let (h, d) = depth_derivatives(&hist);
    // the depth falls as E rises: h = g^-1(F / E)
    assert!(d[1..].iter().all(|&x| x < 0.0), "{d:?}");
    let s2: f64 = d.iter().map(|x| x * x).sum();
    let cands = vec![("ramp to 300 N", vec![hist.clone()])];
    for (noise, want) in [
        (
            "noise: Absolute(0.5), depth_noise: Absolute(1e-4)",
            1e-4 / s2.sqrt(),
        ),
        (
            "noise: Relative(0.02)",
            0.02 * h
                .iter()
                .zip(&d)
                .map(|(h, d)| (h * d).powi(2))
                .sum::<f64>()
                .sqrt()
                / s2,
        ),
        (
            "noise: Absolute(0.5), depth_noise: Relative(0.02)",
            0.02 * h
                .iter()
                .zip(&d)
                .map(|(h, d)| (h * d).powi(2))
                .sum::<f64>()
                .sqrt()
                / s2,
        ),
    ] {
        let dsg = design::run(&DesignOptions::new(source(text(
            ELASTIC, ELASTIC_ID, noise, &cands,
        ))))
        .unwrap();
        println!("{}", dsg.summary());
        let c = &dsg.candidates[0];
        assert_eq!(c.load_controlled, vec![true]);
        let got = c.params[0].rel_std_dev;
        println!("{noise}: design {got}, closed form {want}");
        assert!((got - want).abs() <= 1e-6 * want, "{got} vs {want}");
        assert!((c.log_det + 2.0 * got.ln()).abs() < 1e-6, "{}", c.log_det);
        assert!(dsg.depth_noise.is_some(), "the depth noise is named");
        assert!(
            dsg.summary()
                .contains("on the depth (load-controlled tests)"),
            "{}",
            dsg.summary()
        );
    }
}

/// A candidate of one depth-controlled and one load-controlled test, explicit weights,
/// each row under its own noise (force rows 0.5 N, depth rows 1e-4 mm): the deviation of
/// ln E is `sqrt(B) / A` over both tests' rows; the list also holds each test alone, and
/// with weights at the inverse noise variances (`1/s^2`) the pair ranks first (more
/// information than either).
#[test]
fn mixed_depth_and_load_candidates_combine_each_rows_noise() {
    let (w_f, w_h) = (4.0, 1e8);
    let (s_f, s_h) = (0.5, 1e-4);
    let load = load_history(1.0, 300.0, 6, 0.0, 0);
    let depth = depth_history(0.08);
    let forces: Vec<f64> = simulate_rows(ELASTIC, &depth).iter().map(|r| r.1).collect();
    let (_, d) = depth_derivatives(&load);
    let sum_f2: f64 = forces.iter().map(|f| f * f).sum();
    let sum_d2: f64 = d.iter().map(|x| x * x).sum();
    let a = w_f * sum_f2 + w_h * sum_d2;
    let b = w_f * w_f * s_f * s_f * sum_f2 + w_h * w_h * s_h * s_h * sum_d2;
    let want_mixed = b.sqrt() / a;
    let want_depth = s_f / sum_f2.sqrt();
    let want_load = s_h / sum_d2.sqrt();
    let cands = vec![
        ("depth-controlled", vec![format!("{depth}, weight: {w_f}")]),
        ("load-controlled", vec![format!("{load}, weight: {w_h}")]),
        (
            "both",
            vec![
                format!("{depth}, weight: {w_f}"),
                format!("{load}, weight: {w_h}"),
            ],
        ),
    ];
    let dsg = design::run(&DesignOptions::new(source(text(
        ELASTIC,
        ELASTIC_ID,
        &format!("noise: Absolute({s_f}), depth_noise: Absolute({s_h})"),
        &cands,
    ))))
    .unwrap();
    println!("{}", dsg.summary());
    println!("{}", dsg.markdown());
    for (k, want) in [(0, want_depth), (1, want_load), (2, want_mixed)] {
        let got = dsg.candidates[k].params[0].rel_std_dev;
        println!(
            "{}: design {got}, closed form {want}",
            dsg.candidates[k].name
        );
        assert!((got - want).abs() <= 1e-6 * want, "{got} vs {want}");
    }
    assert_eq!(dsg.candidates[2].load_controlled, vec![false, true]);
    assert_eq!(dsg.rank_d[0], 2, "the pair carries the most information");
    assert!(
        dsg.markdown()
            .contains("(load control: the depth observed)")
    );
}

/// Maxwell under a held load: at the same number of points (16), the ramp with a 10 s
/// hold determines eta better than the ramp alone and than a 1 s hold, and ranks first by
/// both criteria; E and eta are determined by each.
#[test]
fn a_long_hold_ranks_above_no_hold_for_the_viscosity() {
    let cands = vec![
        (
            "ramp 1 s, no hold",
            vec![load_history(1.0, 300.0, 16, 0.0, 0)],
        ),
        (
            "ramp 1 s, hold 1 s",
            vec![load_history(1.0, 300.0, 8, 1.0, 8)],
        ),
        (
            "ramp 1 s, hold 10 s",
            vec![load_history(1.0, 300.0, 8, 10.0, 8)],
        ),
    ];
    let dsg = design::run(&DesignOptions::new(source(text(
        MAXWELL,
        MAXWELL_ID,
        "noise: Relative(0.01)",
        &cands,
    ))))
    .unwrap();
    println!("{}", dsg.summary());
    let eta = |k: usize| {
        dsg.candidates[k]
            .params
            .iter()
            .find(|p| p.name == "eta")
            .unwrap()
            .rel_std_dev
    };
    println!("sigma(eta)/eta: {} / {} / {}", eta(0), eta(1), eta(2));
    assert!(eta(2) < eta(1) && eta(1) < eta(0), "{dsg:?}");
    assert_eq!(dsg.rank_d[0], 2);
    assert_eq!(dsg.rank_worst[0], 2);
    for c in &dsg.candidates {
        // the same points for each (16 steps and the start)
        assert_eq!(c.n_data, dsg.candidates[0].n_data, "{}", c.name);
        assert!(
            c.undetermined.is_empty(),
            "{}: {:?}",
            c.name,
            c.undetermined
        );
    }
}

/// Bad load-controlled candidates are refused before any solve, naming the candidate and
/// the field: a negative hold force, a zero hold time, an absolute force noise without a
/// depth noise, a depth noise that is not a stated level > 0.
#[test]
fn bad_load_candidates_are_refused_naming_the_field() {
    let err = |t: String| {
        let e = design::run(&DesignOptions::new(source(t))).unwrap_err();
        let text = e.messages().join(": ");
        assert_eq!(e.kind(), ErrorKind::Config, "{text}");
        println!("{text}");
        text
    };
    let good = load_history(1.0, 300.0, 4, 1.0, 4);
    let one = |hist: String| vec![("ok", vec![depth_history(0.1)]), ("bad", vec![hist])];
    // a negative hold force
    let e = err(text(
        MAXWELL,
        MAXWELL_ID,
        "noise: Relative(0.01)",
        &one(load_history(1.0, 300.0, 4, 1.0, 4).replacen("force: 300", "force: -300", 2)),
    ));
    assert!(
        e.contains("history.segments[].force") && e.contains("-300") && e.contains("candidates[1]"),
        "{e}"
    );
    // a zero hold time
    let e = err(text(
        MAXWELL,
        MAXWELL_ID,
        "noise: Relative(0.01)",
        &one(load_history(1.0, 300.0, 4, 0.0, 4)),
    ));
    assert!(
        e.contains("history.segments[].duration") && e.contains("candidates[1]"),
        "{e}"
    );
    // an absolute force noise says nothing of the depth
    let e = err(text(
        MAXWELL,
        MAXWELL_ID,
        "noise: Absolute(0.5)",
        &one(good.clone()),
    ));
    assert!(
        e.contains("design.depth_noise") && e.contains("candidates[1].tests[0]"),
        "{e}"
    );
    for bad in [
        "Relative(0.0)",
        "Absolute(-1e-5)",
        "Residual",
        "RelativeEstimated",
    ] {
        let e = err(text(
            MAXWELL,
            MAXWELL_ID,
            &format!("noise: Relative(0.01), depth_noise: {bad}"),
            &one(good.clone()),
        ));
        assert!(e.contains("design.depth_noise"), "{bad}: {e}");
    }
}
