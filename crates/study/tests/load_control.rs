//! Load control in configurations: `history` segments with `force` (N), `simulate`
//! writing t, h, F, a for a mixed history; `identify` and `gradient-check` refusing
//! load-controlled histories and `data.drive: Force` with a message naming the field
//! (their gradient needs the adjoint of the bordered system, docs/theory.md §13); bad
//! segments naming theirs.

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

/// `gradient-check` (and `identify`, through the same preparation) refuses load control,
/// naming the field.
#[test]
fn load_control_is_refused_by_the_gradient_naming_the_field() {
    let segments =
        "(duration: 0.2, depth: 0.02, steps: 2), (duration: 1.0, force: 100.0, steps: 3)";
    let e = gradient::run(&GradientOptions::new(source(segments), None)).unwrap_err();
    let m = format!("{e:#}");
    assert!(
        m.contains("history.segments[1].force") && m.contains("`simulate` only"),
        "{m}"
    );
    let data = ConfigSource::Text {
        text: format!("({MODEL} data: (file: \"missing.csv\", drive: Force))"),
        name: "load-control-data".into(),
    };
    let e = gradient::run(&GradientOptions::new(data, None)).unwrap_err();
    let m = format!("{e:#}");
    assert!(
        m.contains("data.drive: Force") && m.contains("adjoint"),
        "{m}"
    );
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
