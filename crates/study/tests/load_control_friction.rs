//! Coulomb friction under load control (docs/theory.md §13): `gradient-check` of a
//! configuration whose history prescribes the force and whose contact has friction
//! (it was refused with the reason): the bordered adjoint passing against central
//! differences of the command's own depth cost (with every contact and stick/slip status
//! of the +-h runs equal to the base run's) and against the bordered sensitivities, for
//! a stress-only law and a law with internal variables, over a load-hold-unload and a
//! mixed depth-load-depth history.

use indentify_study::check::{self, CheckOptions};
use indentify_study::source::ConfigSource;

const MAXWELL: &str = "Maxwell(E: 20000.0, nu: 0.3, eta: 30000.0)";
const PRONY: &str = "Prony(E: 20000.0, nu: 0.3, terms: [(g: 0.3, tau: 0.3), (g: 0.2, tau: 2.0)])";

fn source(law: &str, mu: f64, segments: &str) -> ConfigSource {
    ConfigSource::Text {
        text: format!(
            "(specimen: Cylinder(radius: 4.0, height: 4.0, nr: 8, nz: 8, grading_r: 1.45, \
             grading_z: 1.45), punch: Sphere(radius: 1.0), contact: Normal(friction: {mu}), \
             law: {law}, history: (segments: [{segments}]))"
        ),
        name: "load-control-friction".into(),
    }
}

#[test]
fn gradient_check_passes_with_coulomb_friction_under_load_control() {
    for (law, mu) in [(MAXWELL, 0.2), (PRONY, 0.1)] {
        for segments in [
            "(duration: 1.0, force: 60.0, steps: 6), (duration: 1.0, force: 60.0, steps: 6), \
             (duration: 1.0, force: 24.0, steps: 6)",
            "(duration: 0.2, depth: 0.01, steps: 2), (duration: 1.0, force: 60.0, steps: 5), \
             (duration: 1.0, force: 60.0, steps: 5), (duration: 0.5, depth: 0.01, steps: 3)",
        ] {
            let r = check::run(&CheckOptions::new(source(law, mu, segments))).unwrap();
            assert!(r.j > 0.0);
            for c in &r.checks {
                println!(
                    "{law} mu {mu} {}: adjoint {:.10e} fd {:.10e} ({:.1e}) sens ({:.1e}) \
                     statuses held {:?}",
                    c.name, c.adjoint, c.fd, c.rel_diff_fd, c.rel_diff_sensitivity, c.statuses_held
                );
                assert_eq!(c.statuses_held, Some(true), "{law} {}", c.name);
                assert!(c.passed, "{law} {}: {:?}", c.name, c.rel_diff_fd);
            }
        }
    }
}
