//! Load control in configurations: `history` segments with `force` (N), `simulate`
//! writing t, h, F, a for a mixed history; `gradient` on the depth cost against central
//! differences (the adjoint of the bordered system, docs/theory.md §13); the depth-only
//! commands refusing load-controlled histories with a message naming the field; `gradient-check`
//! passing on the depth cost; bad segments naming theirs.

use indentify_study::gradient::{self, GradientOptions};
use indentify_study::simulate::{self, SimulateOptions};
use indentify_study::source::ConfigSource;

const MODEL: &str = "specimen: Cylinder(radius: 10.0, height: 10.0, nr: 8, nz: 8, grading_r: 1.3, \
                     grading_z: 1.3), punch: Cone(half_angle_deg: 68.0), \
                     law: Maxwell(E: 20000.0, nu: 0.3, eta: 30000.0),";

fn source(segments: &str) -> ConfigSource {
    ConfigSource::Text {
        text: format!("({MODEL} history: (segments: [{segments}]))"),
        name: "load-control".into(),
    }
}

/// Approach in depth control to 0.02 mm, load control to 200 N and a hold, unload in
/// depth control to 0: the curve carries the prescribed forces and the creep depth.
#[test]
fn simulate_writes_a_mixed_load_controlled_history() {
    let segments = "(duration: 0.2, depth: 0.02, steps: 4), \
                    (duration: 1.0, force: 200.0, steps: 10), \
                    (duration: 1.0, force: 200.0, steps: 10), \
                    (duration: 0.5, depth: 0.0, steps: 5)";
    let out = simulate::run(&SimulateOptions::new(source(segments))).unwrap();
    assert!(out.failure.is_none(), "{:?}", out.failure);
    let rows = &out.rows;
    assert_eq!(rows.len(), 30);
    assert!((rows[4].h - 0.02).abs() < 1e-15);
    for r in &rows[14..=24] {
        assert!((r.f - 200.0).abs() < 1e-7, "{}", r.f);
    }
    // Maxwell creeps under the held load
    assert!(
        rows[24].h > rows[14].h * 1.05,
        "{} {}",
        rows[14].h,
        rows[24].h
    );
    assert!(rows[29].h.abs() < 1e-15);
    // the prescribed force carried also where the coarse grid keeps only the axis node
    // in contact (a = 0)
    assert!(rows.iter().all(|r| r.a >= 0.0));
}

/// The commands that drive by depth only (through `Config::prepare`) refuse load
/// control, naming the field and the commands that take it (`identify` takes it:
/// `identify_load.rs`).
#[test]
fn load_control_is_refused_by_depth_only_commands_naming_the_field() {
    let segments =
        "(duration: 0.2, depth: 0.02, steps: 2), (duration: 1.0, force: 100.0, steps: 3)";
    let cfg = source(segments).load(&[]).unwrap();
    let e = cfg.prepare("load-control").map(|_| ()).unwrap_err();
    let m = format!("{e:#}");
    assert!(
        m.contains("history.segments[1].force")
            && m.contains("drives by depth only")
            && m.contains("`identify`"),
        "{m}"
    );
}

/// `gradient` under load control: the depth is the observable; `J` and `dJ/dc` of data
/// simulated at other parameters (`simulate` writes t, h, F, a), the gradient against
/// central differences of the command's own `J`.
#[test]
fn gradient_of_the_depth_cost_matches_central_differences() {
    let segments = "(duration: 1.0, force: 100.0, steps: 6), \
                    (duration: 1.0, force: 100.0, steps: 6)";
    let dir = std::env::temp_dir().join(format!("indentify-load-grad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let csv = dir.join("curve.csv");
    let mut sim = SimulateOptions::new(source(segments));
    sim.out = Some(csv.clone());
    simulate::run(&sim).unwrap();
    let at = |e: f64, eta: f64| -> (f64, Vec<f64>) {
        let mut o = GradientOptions::new(source(segments), Some(csv.clone()));
        o.sets = vec![format!("law.E={e}"), format!("law.eta={eta}")];
        let out = gradient::run(&o).unwrap();
        (out.j, out.gradient)
    };
    let (e, eta) = (21000.0, 27000.0);
    let (j, g) = at(e, eta);
    assert!(j > 0.0);
    let (de, deta) = (e * 1e-5, eta * 1e-5);
    let fd_e = (at(e + de, eta).0 - at(e - de, eta).0) / (2.0 * de);
    let fd_eta = (at(e, eta + deta).0 - at(e, eta - deta).0) / (2.0 * deta);
    for (k, fd) in [(0, fd_e), (2, fd_eta)] {
        let r = (g[k] - fd).abs() / fd.abs();
        assert!(r < 1e-5, "param {k}: adjoint {} fd {fd} ({r:.2e})", g[k]);
    }
    // a curve without a depth column is refused, naming it
    std::fs::write(dir.join("f.csv"), "t,F\n0,0\n2,100\n").unwrap();
    let e = gradient::run(&GradientOptions::new(
        source(segments),
        Some(dir.join("f.csv")),
    ))
    .unwrap_err();
    assert!(format!("{e:#}").contains("no depth column"), "{e:#}");
    std::fs::remove_dir_all(&dir).ok();
}

/// `gradient-check` under load control (depth observable, data synthesized at the
/// configuration's values, checked at the perturbed point): the bordered adjoint against
/// central differences of the check's own depth cost and against `J^T rho` of the
/// bordered sensitivities, every parameter passing at the command's tolerances (1e-6,
/// relative step 1e-5); a mixed depth-load-depth history included.
#[test]
fn gradient_check_passes_under_load_control() {
    use indentify_study::check::{self, CheckOptions};
    for segments in [
        "(duration: 1.0, force: 100.0, steps: 6), (duration: 1.0, force: 100.0, steps: 6)",
        "(duration: 0.2, depth: 0.02, steps: 2), (duration: 1.0, force: 100.0, steps: 5), \
         (duration: 1.0, force: 100.0, steps: 5), (duration: 0.5, depth: 0.01, steps: 3)",
    ] {
        let r = check::run(&CheckOptions::new(source(segments))).unwrap();
        assert!(r.j > 0.0);
        for c in &r.checks {
            println!(
                "{}: adjoint {:.10e} fd {:.10e} ({:.1e}) sens ({:.1e})",
                c.name, c.adjoint, c.fd, c.rel_diff_fd, c.rel_diff_sensitivity
            );
            assert!(c.passed, "{}: {:?}", c.name, c.rel_diff_fd);
        }
    }
}

/// A segment with both or neither of depth and force, or a negative force: the field.
#[test]
fn bad_load_segments_are_refused_naming_the_field() {
    for (seg, want) in [
        (
            "(duration: 1.0, depth: 0.1, force: 10.0, steps: 2)",
            "both depth and force",
        ),
        ("(duration: 1.0, steps: 2)", "neither depth nor force"),
        (
            "(duration: 1.0, force: -3.0, steps: 2)",
            "history.segments[].force",
        ),
    ] {
        let e = simulate::run(&SimulateOptions::new(source(seg))).unwrap_err();
        let m = format!("{e:?}");
        assert!(m.contains(want), "{seg}: {m}");
    }
}

/// `simulate --noise` under load control perturbs the observable (the depth) and leaves
/// the prescribed force as prescribed.
#[test]
fn simulate_noise_goes_on_the_depth_under_load_control() {
    let segments = "(duration: 1.0, force: 100.0, steps: 5), \
                    (duration: 1.0, force: 100.0, steps: 5)";
    let clean = simulate::run(&SimulateOptions::new(source(segments))).unwrap();
    let mut o = SimulateOptions::new(source(segments));
    o.noise = Some((0.05, 3));
    let noisy = simulate::run(&o).unwrap();
    let mut moved = 0;
    for (a, b) in clean.rows.iter().zip(&noisy.rows) {
        assert_eq!(a.f.to_bits(), b.f.to_bits(), "the force is prescribed");
        if a.h != 0.0 {
            let rel = (b.h / a.h - 1.0).abs();
            assert!(rel < 0.05 * 6.0, "{rel}");
            moved += usize::from(rel > 0.0);
        }
    }
    assert!(moved >= 8, "{moved}");
}
