//! Checkpointed identifications with laws that carry internal variables (J2 plasticity with
//! a Norton rate, a two-term Prony series): the checkpoints keep each Gauss point's internal
//! variables, so a fit replayed stretch by stretch takes the recorded run's path, iteration
//! by iteration, to the same parameters.

mod common;

use common::example;

use indentify_study::ConfigSource;
use indentify_study::identify::{self, IdentifyOptions};

fn options(config: &str, sets: &[&str], starts: &[(&str, f64)]) -> IdentifyOptions {
    let mut o = IdentifyOptions::new(ConfigSource::Path(example(config)));
    o.sets = sets.iter().map(|s| s.to_string()).collect();
    o.overrides.starts = starts.iter().map(|(n, v)| (n.to_string(), *v)).collect();
    o.overrides.max_iterations = Some(4);
    o
}

fn same_fit(o: IdentifyOptions) {
    let full = identify::run(&o, &mut ()).unwrap();
    let mut ck = o;
    ck.checkpoint = Some(3);
    let replayed = identify::run(&ck, &mut ()).unwrap();
    assert!(full.result.iterations >= 2, "the fit moves");
    assert_eq!(full.result.iterations, replayed.result.iterations);
    for (a, b) in full.result.params.iter().zip(&replayed.result.params) {
        assert!(
            (a.value - b.value).abs() <= 1e-9 * a.value.abs(),
            "{}: recorded {} vs checkpointed {}",
            a.name,
            a.value,
            b.value
        );
    }
}

#[test]
fn a_plastic_norton_fit_checkpointed_equals_the_recorded_one() {
    same_fit(options(
        "plastic-power-design.ron",
        &[
            "specimen.nr=6",
            "specimen.nz=6",
            "history.segments.0.steps=6",
            "history.segments.1.steps=4",
            "history.segments.2.steps=4",
        ],
        &[("sY", 300.0), ("K", 300.0)],
    ));
}

const PRONY2: &str = r#"(
    specimen: Cylinder(radius: 10.0, height: 10.0, nr: 6, nz: 6, grading_r: 1.3, grading_z: 1.3),
    punch: Cone(half_angle_deg: 68.0),
    contact: Vertical,
    kinematics: Small,
    law: Prony(E: 20000.0, nu: 0.3, terms: [(g: 0.3, tau: 0.2), (g: 0.3, tau: 2.0)]),
    history: (
        segments: [
            (duration: 1.0, depth: 0.1, steps: 6),
            (duration: 2.0, depth: 0.1, steps: 6),
            (duration: 1.0, depth: 0.0, steps: 4),
        ],
    ),
    identify: (
        params: {
            "E": Free(start: 18000.0, lower: 1000.0, upper: 1e6),
            "nu": Fixed(value: 0.3),
            "g1": Free(start: 0.4, lower: 0.01, upper: 0.6),
            "tau1": Fixed(value: 0.2),
            "g2": Free(start: 0.2, lower: 0.01, upper: 0.6),
            "tau2": Fixed(value: 2.0),
        },
        method: Lm,
    ),
)"#;

#[test]
fn a_two_term_prony_fit_checkpointed_equals_the_recorded_one() {
    let mut o = IdentifyOptions::new(ConfigSource::Text {
        text: PRONY2.to_string(),
        name: "prony2".to_string(),
    });
    o.overrides.max_iterations = Some(4);
    same_fit(o);
}
