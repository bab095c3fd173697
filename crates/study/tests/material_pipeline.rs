//! Laws with internal variables (`Plastic`, `Prony`) through the whole study pipeline:
//! `simulate` of the shipped examples, an identification round trip on synthesized data
//! that recovers the parameters it was made with, and the gradient check (adjoint against
//! finite differences of the cost and against the forward sensitivities).

use indentify_study::ConfigSource;
use indentify_study::check::{self, CheckOptions};
use indentify_study::identify::{self, IdentifyOptions};
use indentify_study::simulate::{self, SimulateOptions};

/// A small cone indentation (6 x 6 mesh, 14 steps) of `law`, identifying `params`.
fn small(law: &str, params: &str) -> ConfigSource {
    ConfigSource::Text {
        text: format!(
            "(
    specimen: Cylinder(radius: 10.0, height: 10.0, nr: 6, nz: 6, grading_r: 1.3, grading_z: 1.3),
    punch: Cone(half_angle_deg: 68.0),
    contact: Vertical,
    kinematics: Small,
    law: {law},
    history: (
        segments: [
            (duration: 1.0, depth: 0.1, steps: 6),
            (duration: 1.0, depth: 0.1, steps: 3),
            (duration: 1.0, depth: 0.0, steps: 5),
        ],
    ),
    identify: (params: {{ {params} }}, method: Lm),
)"
        ),
        name: "small".into(),
    }
}

const PLASTIC: &str = "Plastic(E: 20000.0, nu: 0.3, sY: 150.0, hardening: Linear(H: 3000.0))";
const PLASTIC_PARAMS: &str = "\"E\": Free(start: 17000.0), \"nu\": Fixed(value: 0.3), \
     \"sY\": Free(start: 120.0), \"H\": Free(start: 4000.0)";
const PRONY: &str = "Prony(E: 20000.0, nu: 0.3, terms: [(g: 0.6, tau: 0.5)])";
const PRONY_PARAMS: &str = "\"E\": Free(start: 15000.0), \"nu\": Fixed(value: 0.3), \
     \"g1\": Free(start: 0.4, lower: 0.01, upper: 0.95), \
     \"tau1\": Free(start: 1.0, lower: 0.01, upper: 100.0)";

fn example(path: &str) -> ConfigSource {
    ConfigSource::Path(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../..")
            .join(path),
    )
}

/// `simulate` of a shipped example on a coarse mesh: a curve that loads, with the
/// material's name.
fn simulates(path: &str, law: &str, sets: &[&str]) {
    let mut opts = SimulateOptions::new(example(path));
    opts.sets = sets.iter().map(|s| s.to_string()).collect();
    let o = simulate::run(&opts).unwrap();
    assert!(o.failure.is_none(), "{path}: {:?}", o.failure);
    assert_eq!(o.law, law);
    let peak = o.trajectory.forces().into_iter().fold(0.0, f64::max);
    assert!(peak > 0.0 && peak.is_finite(), "{path}: peak {peak}");
}

/// The system shall simulate the shipped Prony and Plastic examples.
#[test]
fn simulate_runs_the_prony_and_plastic_examples() {
    let coarse = ["specimen.nr=6", "specimen.nz=6"];
    simulates(
        "examples/prony-sls.ron",
        "prony",
        &[
            coarse[0],
            coarse[1],
            "history.segments.0.steps=5",
            "history.segments.1.steps=5",
            "history.segments.2.steps=5",
        ],
    );
    simulates("examples/real/anon-plastic.ron", "plastic", &[]);
}

/// Identification from data synthesized with the same law recovers the law's values
/// (no noise: to the optimizer's tolerance) from starts 15-40% away.
fn round_trip(law: &str, params: &str, truth: &[(&str, f64)]) {
    let opts = IdentifyOptions::new(small(law, params));
    let o = identify::run(&opts, &mut ()).unwrap();
    assert!(
        o.result.stop_reason.is_converged(),
        "{law}: {:?}",
        o.result.stop_reason
    );
    eprintln!(
        "{law}: {} iterations, cost {:e} -> {:e}, c = {:?}",
        o.result.iterations, o.result.initial_cost, o.result.cost, o.result.c
    );
    assert!(o.result.iterations > 0 && o.result.cost < 1e-6 * o.result.initial_cost);
    for &(name, want) in truth {
        let k = o.names.iter().position(|n| *n == name).unwrap();
        let got = o.result.c[k];
        assert!(
            ((got - want) / want).abs() < 1e-3,
            "{law}: {name} = {got}, expected {want}"
        );
    }
}

/// The system shall identify J2 plasticity with linear hardening end to end.
#[test]
fn identify_recovers_plastic_linear_hardening() {
    round_trip(
        PLASTIC,
        PLASTIC_PARAMS,
        &[("E", 20000.0), ("sY", 150.0), ("H", 3000.0)],
    );
}

/// The system shall identify a one-term Prony series end to end.
#[test]
fn identify_recovers_a_prony_series() {
    round_trip(
        PRONY,
        PRONY_PARAMS,
        &[("E", 20000.0), ("g1", 0.6), ("tau1", 0.5)],
    );
}

/// The gradient check of `law`: every parameter's adjoint derivative agrees with finite
/// differences of the cost and with the forward sensitivities.
fn gradient_check(law: &str, params: &str, name: &str, n: usize) {
    let r = check::run(&CheckOptions::new(small(law, params))).unwrap();
    assert_eq!(r.law, name);
    assert_eq!(r.checks.len(), n);
    for c in &r.checks {
        eprintln!(
            "{}: adjoint {:e} fd {:e} sensitivity {:e}",
            c.name, c.adjoint, c.fd, c.sensitivity
        );
        assert!(c.adjoint != 0.0, "{}", c.name);
        assert!(
            c.passed,
            "{}: adjoint {} fd {} sensitivity {}",
            c.name, c.adjoint, c.fd, c.sensitivity
        );
    }
}

/// The system shall pass the gradient check for a Plastic configuration.
#[test]
fn gradient_check_passes_for_plastic() {
    gradient_check(PLASTIC, PLASTIC_PARAMS, "plastic", 4);
}

/// The system shall pass the gradient check for a Prony configuration.
#[test]
fn gradient_check_passes_for_prony() {
    gradient_check(PRONY, PRONY_PARAMS, "prony", 4);
}
