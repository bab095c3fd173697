//! Laws with internal variables under load control (docs/theory.md §12-13): `gradient`
//! and `gradient-check` run `Plastic` and `Prony` configurations whose history
//! prescribes the force (they were refused, naming the law), the bordered adjoint
//! through the material's blocks passing against central differences of the command's
//! own depth cost and against the bordered sensitivities; a mixed depth-load-depth
//! history included.

use indentify_study::check::{self, CheckOptions};
use indentify_study::gradient::{self, GradientOptions};
use indentify_study::simulate::{self, SimulateOptions};
use indentify_study::source::ConfigSource;

const PLASTIC: &str = "Plastic(E: 20000.0, nu: 0.3, sY: 150.0, hardening: Power(n: 0.2), \
                       rate: Norton(K: 400.0, m: 4.0))";
const PRONY: &str = "Prony(E: 20000.0, nu: 0.3, terms: [(g: 0.3, tau: 0.3), (g: 0.2, tau: 2.0)])";

fn source(law: &str, segments: &str) -> ConfigSource {
    ConfigSource::Text {
        text: format!(
            "(specimen: Cylinder(radius: 10.0, height: 10.0, nr: 8, nz: 8, grading_r: 1.3, \
             grading_z: 1.3), punch: Cone(half_angle_deg: 68.0), law: {law}, \
             history: (segments: [{segments}]))"
        ),
        name: "load-control-material".into(),
    }
}

/// `gradient-check` on the depth cost passes every parameter of both laws, over a
/// load-hold and a mixed history.
#[test]
fn gradient_check_passes_for_laws_with_internal_variables() {
    for law in [PLASTIC, PRONY] {
        for segments in [
            "(duration: 1.0, force: 60.0, steps: 6), (duration: 1.0, force: 60.0, steps: 6)",
            "(duration: 0.2, depth: 0.01, steps: 2), (duration: 1.0, force: 60.0, steps: 5), \
             (duration: 1.0, force: 60.0, steps: 5), (duration: 0.5, depth: 0.005, steps: 3)",
        ] {
            let r = check::run(&CheckOptions::new(source(law, segments))).unwrap();
            assert!(r.j > 0.0);
            for c in &r.checks {
                println!(
                    "{law} {}: adjoint {:.10e} fd {:.10e} ({:.1e}) sens ({:.1e})",
                    c.name, c.adjoint, c.fd, c.rel_diff_fd, c.rel_diff_sensitivity
                );
                assert!(c.passed, "{law} {}: {:?}", c.name, c.rel_diff_fd);
            }
        }
    }
}

/// `gradient` of a Prony configuration under load control against the data simulated
/// at other parameters: the gradient against central differences of the command's `J`.
#[test]
fn gradient_of_a_prony_depth_cost_matches_central_differences() {
    let segments = "(duration: 1.0, force: 60.0, steps: 6), \
                    (duration: 1.0, force: 60.0, steps: 6)";
    let dir = std::env::temp_dir().join(format!("indentify-load-mat-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let csv = dir.join("curve.csv");
    let mut sim = SimulateOptions::new(source(PRONY, segments));
    sim.out = Some(csv.clone());
    simulate::run(&sim).unwrap();
    let at = |e: f64, g1: f64| -> (f64, Vec<f64>) {
        let mut o = GradientOptions::new(source(PRONY, segments), Some(csv.clone()));
        o.sets = vec![format!("law.E={e}"), format!("law.g1={g1}")];
        let out = gradient::run(&o).unwrap();
        (out.j, out.gradient)
    };
    let (e, g1) = (21000.0, 0.33);
    let (j, g) = at(e, g1);
    assert!(j > 0.0);
    let (de, dg) = (e * 1e-5, g1 * 1e-5);
    let fd_e = (at(e + de, g1).0 - at(e - de, g1).0) / (2.0 * de);
    let fd_g = (at(e, g1 + dg).0 - at(e, g1 - dg).0) / (2.0 * dg);
    for (k, fd) in [(0, fd_e), (2, fd_g)] {
        let r = (g[k] - fd).abs() / fd.abs();
        println!("param {k}: adjoint {} fd {fd} ({r:.2e})", g[k]);
        assert!(r < 1e-5, "param {k}: adjoint {} fd {fd} ({r:.2e})", g[k]);
    }
    std::fs::remove_dir_all(&dir).ok();
}
