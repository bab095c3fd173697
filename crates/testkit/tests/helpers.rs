//! The test support builds exactly what the tests wrote out before: the test cylinder of
//! the mesher's own fields, the segments, the bit and relative comparisons, the root.

use indentify_contact::{Punch, Schedule, Segment};
use indentify_mesh::CylinderMesher;
use indentify_testkit::*;

#[test]
fn the_helpers_build_what_the_tests_wrote_out() {
    let m = small_cylinder();
    let by_hand = CylinderMesher {
        radius: 4.0,
        height: 4.0,
        nr: 8,
        nz: 8,
        grading_r: 1.45,
        grading_z: 1.45,
    }
    .build()
    .unwrap();
    assert_eq!(m.nodes, by_hand.nodes);
    assert_eq!(m.elements, by_hand.elements);
    assert_eq!(
        bits(&[1.0, -0.0]),
        vec![1.0f64.to_bits(), (-0.0f64).to_bits()]
    );
    assert_eq!(rel_to_largest(&[2.0, -4.0], &[2.0, -3.0]), 0.25);
    let f = force(1.0, 60.0, 6);
    assert_eq!((f.depth, f.force, f.steps), (None, Some(60.0), 6));
    assert!(workspace_root().join("crates/testkit/src/lib.rs").is_file());
    let d = depth(1.0, 0.02, 4);
    assert_eq!((d.depth, d.force, d.steps), (Some(0.02), None, 4));
    // the machine-depth and force histories, segment by segment
    let seg = |depth, steps| Segment {
        duration: 1.0,
        depth,
        steps,
    };
    let s = depth_lhu(0.06, 0.6 * 0.06, 8);
    let by_hand =
        Schedule::from_segments(&[seg(0.06, 8), seg(0.06, 8), seg(0.6 * 0.06, 8)]).unwrap();
    assert_eq!(
        (bits(&s.t), bits(&s.depth)),
        (bits(&by_hand.t), bits(&by_hand.depth))
    );
    let h = force_lhu(60.0, 6);
    assert_eq!(h.schedule.t.len(), 19);
    assert_eq!(h.schedule.t.last().copied(), Some(3.0));
    // the weights 1 + 0.37 ((7 i) mod 5) and the cone of the small model
    assert_eq!(weights(3), vec![1.0, 1.0 + 0.37 * 2.0, 1.0 + 0.37 * 4.0]);
    let Punch::Cone { half_angle_deg } = cone68() else {
        panic!("not a cone")
    };
    assert_eq!(half_angle_deg, 68.0);
    assert_eq!(cylinder_rz(2.0, 3, 2, 1.3).elements.len(), 6);
}
