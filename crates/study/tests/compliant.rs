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
