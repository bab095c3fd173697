//! `identify --checkpoint` of a depth-driven test through the instrument's frame
//! (docs/theory.md §13.7, docs/cli.md "Instrument parameters"): with `Cf` free beside the
//! law's E and eta and BFGS (the adjoint gradient), a run kept as checkpoints only has
//! its gradient swept from replayed stretches (`Adjoint::gradient_compliant_replayed`), and
//! the fit lands where the fit recording every field lands: the same iterations, the
//! same cost and values to 1e-8 relative (the checkpointed stretches each start from a
//! fresh factorization: the same steps to round-off). Reference: the truth that generated
//! the exact synthetic forces (E = 20000 MPa, eta = 30000 MPa s, `Cf` = 0), recovered to
//! 1e-4 relative, `Cf` below 1e-9 mm/N from a start of 2e-5 mm/N. (The fit recording
//! every field ran the same before the replayed sweep existed, when a checkpointed run
//! was recorded again with fields: this test checks the front end's path, the sweep
//! itself is checked in `crates/adjoint/tests/compliant_replayed.rs`.)
//!
//! ```text
//!   10 x 10 mm cylinder, 8 x 8 Q8 graded 1.3; cone 68 deg; Maxwell; depth 0 -> 0.05 mm
//!   (1 s, 6 steps), hold (1 s, 6), unload to 0.03 mm (1 s, 6)
//! ```

use indentify_study::identify::{self, IdentifyOptions};
use indentify_study::source::ConfigSource;

fn options(checkpoint: Option<usize>) -> IdentifyOptions {
    let text = "(specimen: Cylinder(radius: 10.0, height: 10.0, nr: 8, nz: 8, grading_r: 1.3, \
                grading_z: 1.3), punch: Cone(half_angle_deg: 68.0), \
                law: Maxwell(E: 20000.0, nu: 0.3, eta: 30000.0), \
                history: (segments: [(duration: 1.0, depth: 0.05, steps: 6), (duration: 1.0, \
                depth: 0.05, steps: 6), (duration: 1.0, depth: 0.03, steps: 6)]), \
                identify: (params: {\"E\": Free(start: 16000.0, lower: 1000.0, upper: 1e6), \
                \"nu\": Fixed(value: 0.3), \"eta\": Free(start: 40000.0, lower: 1000.0, \
                upper: 1e7), \"Cf\": Free(start: 2e-5)}, method: Bfgs))";
    let mut o = IdentifyOptions::new(ConfigSource::Text {
        text: text.into(),
        name: "compliant-checkpoint".into(),
    });
    o.refine = false;
    o.figures = false;
    o.checkpoint = checkpoint;
    o
}

#[test]
fn checkpointed_compliant_fit_lands_where_the_recorded_one_does() {
    let full = identify::run(&options(None), &mut ()).unwrap();
    let ck = identify::run(&options(Some(3)), &mut ()).unwrap();
    for (name, o) in [("recorded", &full), ("checkpointed", &ck)] {
        println!(
            "{name}: {} after {} iterations, {} adjoint solves: J = {:e}, E = {:?}, eta = {:?}, \
             Cf = {:?}",
            o.result.stop_reason,
            o.result.iterations,
            o.result.adjoint_solves,
            o.result.cost,
            o.value("E"),
            o.value("eta"),
            o.value("Cf")
        );
        assert!(o.converged(), "{name}: {}", o.result.stop_reason);
        assert!(
            o.result.adjoint_solves > 0,
            "{name}: the adjoint gradient ran"
        );
        assert!(
            (o.value("E").unwrap() / 20000.0 - 1.0).abs() < 1e-4,
            "{name}"
        );
        assert!(
            (o.value("eta").unwrap() / 30000.0 - 1.0).abs() < 1e-4,
            "{name}"
        );
        assert!(o.value("Cf").unwrap().abs() < 1e-9, "{name}");
    }
    assert_eq!(full.result.iterations, ck.result.iterations);
    for name in ["E", "eta"] {
        let (a, b) = (full.value(name).unwrap(), ck.value(name).unwrap());
        assert!((a - b).abs() <= 1e-8 * a.abs(), "{name}: {a} vs {b}");
    }
    let (a, b) = (full.value("Cf").unwrap(), ck.value("Cf").unwrap());
    assert!((a - b).abs() <= 1e-8 * 2e-5, "Cf: {a} vs {b}");
}
