//! Instrument parameters of a depth-driven configuration (docs/theory.md §13.7,
//! docs/cli.md "Instrument parameters"): `Cf`, `vd` and `h0` named for a test whose
//! history prescribes the depth are no longer refused; the punch is driven through the
//! frame's spring (the recorded depth is the machine's) and the force stays the
//! observable. Reference: `gradient-check`'s central differences of the pipeline's own
//! cost, and its forward sensitivities.
//!
//! ```text
//!   10 x 10 mm cylinder, 8 x 8 Q8 graded 1.3; cone 68 deg; Maxwell E = 20000 MPa,
//!   nu = 0.3, eta = 30000 MPa s; depth 0 -> 0.05 mm (1 s, 6 steps), hold (1 s, 6),
//!   unload to 0.03 mm (1 s, 6)
//! ```

use indentify_study::check::{self, CheckOptions};
use indentify_study::source::ConfigSource;

const MODEL: &str = "specimen: Cylinder(radius: 10.0, height: 10.0, nr: 8, nz: 8, grading_r: 1.3, \
                     grading_z: 1.3), punch: Cone(half_angle_deg: 68.0), \
                     law: Maxwell(E: 20000.0, nu: 0.3, eta: 30000.0),";
const LAW_ID: &str = "\"E\": Free(start: 14000.0, lower: 1000.0, upper: 1e6), \"nu\": \
                      Fixed(value: 0.3), \"eta\": Free(start: 50000.0, lower: 1000.0, upper: \
                      1e7)";

#[test]
fn gradient_check_covers_the_instrument_parameters_under_depth_control() {
    let history = "(segments: [(duration: 1.0, depth: 0.05, steps: 6), (duration: 1.0, depth: \
                   0.05, steps: 6), (duration: 1.0, depth: 0.03, steps: 6)])";
    let cfg = format!(
        "({MODEL} history: {history}, identify: (params: {{{LAW_ID}, \"Cf\": Free(start: \
         0.0), \"vd\": Free(start: 0.0), \"h0\": Free(start: 0.0)}}, method: Lm))"
    );
    let src = ConfigSource::Text {
        text: cfg,
        name: "check-depth-inst".into(),
    };
    let report = match check::run(&CheckOptions::new(src)) {
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

/// A sphere on a 4 x 4 mm cylinder (8 x 8 Q8 graded 1.45), depth 0 -> 0.04 mm (1 s, 6
/// steps), hold (1 s, 6), unload to 0.024 mm (1 s, 6), with `law` and `contact`, every
/// instrument parameter named, LM (whose forward sensitivities `gradient-check` compares).
fn sphere_config(law: &str, contact: &str, law_id: &str) -> ConfigSource {
    let history = "(segments: [(duration: 1.0, depth: 0.04, steps: 6), (duration: 1.0, depth: \
                   0.04, steps: 6), (duration: 1.0, depth: 0.024, steps: 6)])";
    ConfigSource::Text {
        text: format!(
            "(specimen: Cylinder(radius: 4.0, height: 4.0, nr: 8, nz: 8, grading_r: 1.45, \
             grading_z: 1.45), punch: Sphere(radius: 1.0), contact: {contact}, law: {law}, \
             history: {history}, identify: (params: {{{law_id}, \"Cf\": Free(start: 0.0), \
             \"vd\": Free(start: 0.0), \"h0\": Free(start: 0.0)}}, method: Lm))"
        ),
        name: "check-frame".into(),
    }
}

/// Runs `gradient-check` on `src` with the relative step `rel_step` and asserts every
/// parameter passes (adjoint against central differences and against the forward
/// sensitivities through the frame); with `friction`, that every stencil's runs held the
/// check point's contact sets and stick/slip statuses.
fn passes(src: ConfigSource, rel_step: f64, friction: bool, expected: &[&str]) {
    let opts = CheckOptions {
        rel_step,
        ..CheckOptions::new(src)
    };
    let report = match check::run(&opts) {
        Ok(r) => r,
        Err(e) => panic!("{e:?}"),
    };
    for c in &report.checks {
        println!(
            "{}: adjoint {:.6e} fd {:.6e} (rel {:.1e}) sens rel {:.1e} statuses held {:?}",
            c.name, c.adjoint, c.fd, c.rel_diff_fd, c.rel_diff_sensitivity, c.statuses_held
        );
    }
    let names: Vec<&str> = report.checks.iter().map(|c| c.name).collect();
    assert_eq!(names, expected);
    // with friction every stencil held the check point's contact sets and statuses
    if friction {
        assert!(report.checks.iter().all(|c| c.statuses_held == Some(true)));
    } else {
        assert!(report.checks.iter().all(|c| c.statuses_held.is_none()));
    }
    assert!(report.passed, "{:?}", report.failures);
    let n = expected.len();
    assert!(report.checks[n - 3..].iter().all(|c| c.adjoint != 0.0));
}

/// A law with internal variables (J2, power hardening, Norton overstress) through the
/// frame: its forward sensitivities exist now (LM was refused with the reason), and
/// `gradient-check` compares them and the adjoint with central differences. The relative
/// step is 1e-4: at the default 1e-5 the drift's stencil at its nominal scale (1e-11
/// mm/s, a depth change of 3e-11 mm) left its difference at 1.0e-6 of the adjoint, the
/// check's tolerance, while the adjoint and the sensitivities agreed to 1.5e-15.
#[test]
fn gradient_check_covers_a_plastic_law_through_the_frame() {
    let law = "Plastic(E: 1e5, nu: 0.3, sY: 500.0, hardening: Power(n: 0.2), rate: \
               Norton(K: 1500.0, m: 5.0))";
    let id = "\"E\": Free(start: 8e4, lower: 1e4, upper: 1e6), \"sY\": Free(start: 600.0, \
              lower: 50.0, upper: 5000.0)";
    passes(
        sphere_config(law, "Normal", id),
        1e-4,
        false,
        &["E", "nu", "sY", "n", "K", "m", "Cf", "vd", "h0"],
    );
}

/// Coulomb friction through the frame (it was refused with the reason): Maxwell, mu 0.2.
#[test]
fn gradient_check_covers_coulomb_friction_through_the_frame() {
    let law = "Maxwell(E: 1e5, nu: 0.3, eta: 2e5)";
    let id = "\"E\": Free(start: 8e4, lower: 1e4, upper: 1e6), \"eta\": Free(start: 3e5, \
              lower: 1e3, upper: 1e7)";
    passes(
        sphere_config(law, "Normal(friction: 0.2)", id),
        1e-5,
        true,
        &["E", "nu", "eta", "Cf", "vd", "h0"],
    );
}
