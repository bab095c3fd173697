//! Depth control through the frame's spring against a closed form
//! (docs/validation-load-control.md §10): an elastic cone on a half-space in series with
//! a frame of compliance `Cf`, driven by the machine depth `H = h + Cf F`. With Sneddon's
//! `F = k h^2`, `k = (2/pi) tan(alpha) E*`, the series spring solves in closed form:
//!
//! ```text
//!   Cf k h^2 + h - H = 0   ->   h = (sqrt(1 + 4 Cf k H) - 1) / (2 Cf k),   F = k h^2
//! ```
//!
//! The machine depth ramps to `H = 0.1 + Cf k 0.01` mm (the punch then reaches 0.1 mm)
//! in 10 steps.

mod common;

use common::*;
use indentify_contact::{DirectSolver, Frame, Model, Punch, Schedule, Segment};
use indentify_laws::{Elastic, LawMaterial};

/// R0's cone on R0's near field prolonged to 48.5 mm, with `Cf = 1e-4` mm/N (the frame
/// takes a quarter of the machine depth): every step's punch depth within 1% and force
/// within 2% of the series spring's closed form; the frame's share is checked not to be
/// negligible.
#[test]
fn cone_through_the_frame_matches_sneddon_in_series() {
    let es = e_star(E, NU);
    let k = sneddon_cone_force(1.0, ALPHA_DEG, es);
    let cf = 1e-4;
    let h_machine = H_MAX + cf * k * H_MAX * H_MAX;
    let model = Model::new(
        extended_cylinder(10.0, 20, 1.3, 6),
        Punch::Cone {
            half_angle_deg: ALPHA_DEG,
        },
    )
    .expect("valid model");
    let mut solver = DirectSolver::new(&model).expect("symbolic analysis");
    let schedule = Schedule::from_segments(&[Segment {
        duration: 1.0,
        depth: h_machine,
        steps: 10,
    }])
    .expect("valid schedule");
    let frame = Frame {
        compliance: cf,
        ..Frame::default()
    };
    let t = solver
        .run_compliant(
            &LawMaterial(&Elastic),
            &[E, NU],
            &schedule,
            &frame,
            &options(),
        )
        .expect("compliant run converges");
    assert!(
        cf * k * H_MAX * H_MAX > 0.2 * h_machine,
        "the frame's share {}",
        cf * k * H_MAX * H_MAX / h_machine
    );
    for s in &t.steps {
        let big_h = schedule.depth_at(s.t);
        let h_ref = ((1.0 + 4.0 * cf * k * big_h).sqrt() - 1.0) / (2.0 * cf * k);
        let f_ref = k * h_ref * h_ref;
        assert!(rel(s.depth, h_ref).abs() < 0.01, "{} {h_ref}", s.depth);
        assert!(rel(s.force, f_ref).abs() < 0.02, "{} {f_ref}", s.force);
    }
    let last = t.steps.last().expect("steps");
    println!(
        "cone through Cf = {cf} mm/N: H = {h_machine:.6} mm -> h = {:.6} mm ({:+.3}%), F = \
         {:.3} N vs {:.3} N ({:+.3}%)",
        last.depth,
        100.0 * rel(last.depth, H_MAX),
        last.force,
        k * H_MAX * H_MAX,
        100.0 * rel(last.force, k * H_MAX * H_MAX)
    );
}
