//! Instrument parameters of depth-controlled tests (docs/theory.md §13.7): the recorded
//! depth is the machine's, `h + Cf F + vd (t - t0) + h0`, so the punch is driven through
//! the frame's spring and the force stays the observable
//! ([`Problem::joint_instrumented`] with a depth-controlled [`Test`]).
//!
//! References this code did not produce: central differences of the `Evaluator`'s own
//! cost (the compliant adjoint, law and frame parameters together), `J^T r` of the
//! compliant sensitivities (the same gradient), the truth that generated synthetic
//! noisy forces (`Cf` and `h0` recovered within 2 standard deviations), and the exact
//! collinearity of a flat punch on an elastic solid with the frame's spring in series
//! (`F = H / (1 / (2 a E*) + Cf)`: only the combination is seen).
//!
//! ```text
//!      cone 68 deg, machine depth 0 -> 0.06 mm (1 s) -> hold (1 s) -> 0.036 mm (1 s),
//!      6 steps/segment; 4 x 4 mm cylinder, 8 x 8 Q8 graded 1.45, vertical contact;
//!      Maxwell E = 20000 MPa, nu = 0.3 (fixed), eta = 30000 MPa s
//! ```

mod common;

use common::{
    assert_gradient_entry, assert_within_two_sigma, cost_difference, depth_lhu as lhu,
    frame_forces, jt_r, tight_opts as opts,
};
use indentify_contact::{Frame, Model, Punch};
use indentify_identify::{
    Evaluator, IdentifyConfig, IdentifyError, Instrument, Method, ParamSpec, Problem, Scaling,
    Test, identify,
};
use indentify_laws::{Elastic, LawMaterial, Maxwell};
use indentify_testkit::{cone68 as cone, small_cylinder};

const TRUTH: [f64; 3] = [20000.0, 0.3, 30000.0];

fn model(punch: Punch) -> Model {
    Model::new(small_cylinder(), punch).unwrap()
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(1e-300)
}

/// Through the `Evaluator`: the compliant adjoint's gradient with respect to E, eta, Cf,
/// vd and h0 against central differences of its own cost (1e-6), and `J^T r` of the
/// compliant sensitivity rows against the adjoint (1e-8).
#[test]
fn gradient_and_jacobian_of_a_depth_controlled_test_match_differences() {
    let m = model(cone());
    let schedule = lhu(0.06, 6);
    let truth_frame = Frame {
        compliance: 1e-4,
        drift: 1e-3,
        offset: 2e-3,
    };
    let record = frame_forces(
        &m,
        &LawMaterial(&Maxwell),
        &TRUTH,
        &schedule,
        &truth_frame,
        0.0,
        1,
    );
    let test = Test::new(m, schedule, &record, None, opts(), 1.0).unwrap();
    let all = Instrument {
        compliance: true,
        drift: true,
        offset: true,
    };
    let p = Problem::joint_instrumented(&Maxwell, all, vec![test]).unwrap();
    let names: Vec<_> = p.law.params().iter().map(|i| i.name).collect();
    assert_eq!(names, ["E", "nu", "eta", "Cf", "vd", "h0"]);
    let mut ev = Evaluator::new(&p).unwrap();
    let c = [15000.0, 0.3, 45000.0, 1.5e-4, -1e-3, 1e-3];
    let (j0, g) = ev.cost_and_gradient(&c).unwrap();
    assert!(j0 > 0.0);
    let f_sim = ev.forces(&c).unwrap();
    let jac = ev.jacobian(&c).unwrap();
    for (k, step) in [
        (0usize, 1e-5 * c[0]),
        (2, 1e-5 * c[2]),
        (3, 1e-5 * c[3]),
        (4, 1e-5 * c[4].abs()),
        (5, 1e-5 * c[5]),
    ] {
        let fd = cost_difference(&mut ev, &c, k, step);
        let jt = jt_r(&p, &jac, &f_sim, k);
        assert_gradient_entry("", names[k], g[k], fd, jt, rel);
    }
}

/// Synthetic depth-controlled data through a frame (Cf = 1e-4 mm/N, h0 = 2 um), forces
/// with seeded uniform noise (half-width 0.3% of the peak force): LM recovers E, eta, Cf
/// and h0 within 2 of the identifiability's standard deviations of the truth.
#[test]
fn fit_recovers_compliance_and_offset_within_two_sigma() {
    let m = model(cone());
    let schedule = lhu(0.06, 10);
    let (cf, h0) = (1e-4, 2e-3);
    let frame = Frame {
        compliance: cf,
        drift: 0.0,
        offset: h0,
    };
    let clean = frame_forces(
        &m,
        &LawMaterial(&Maxwell),
        &TRUTH,
        &schedule,
        &frame,
        0.0,
        1,
    );
    let f_max = clean.force.iter().copied().fold(0.0, f64::max);
    let noise = 3e-3 * f_max;
    let record = frame_forces(
        &m,
        &LawMaterial(&Maxwell),
        &TRUTH,
        &schedule,
        &frame,
        noise,
        21,
    );
    let test = Test::new(m, schedule, &record, None, opts(), 1.0).unwrap();
    let instrument = Instrument {
        compliance: true,
        drift: false,
        offset: true,
    };
    let p = Problem::joint_instrumented(&Maxwell, instrument, vec![test]).unwrap();
    let mut cfg = IdentifyConfig::new(vec![
        ParamSpec::free("E", 12000.0, 1000.0, 1e6),
        ParamSpec::fixed("nu", 0.3),
        ParamSpec::free("eta", 60000.0, 1000.0, 1e7),
        ParamSpec::free("Cf", 0.0, 0.0, 1.0).with_scaling(Scaling::Linear),
        ParamSpec::free("h0", 0.0, -1.0, 1.0).with_scaling(Scaling::Linear),
    ]);
    cfg.method = Method::LevenbergMarquardt;
    let r = identify(&p, &cfg, &mut |_| {}).unwrap();
    let id = r.identifiability.as_ref().unwrap();
    println!(
        "depth-controlled fit through the frame: {:?}, {}, std dev {:?}, undetermined {:?}, \
         sigma_hat {:.3e} N (noise {:.3e})",
        r.c,
        r.stop_reason,
        id.std_dev,
        id.undetermined,
        id.sigma2.sqrt(),
        noise / 3f64.sqrt()
    );
    assert!(r.stop_reason.is_converged(), "{}", r.stop_reason);
    assert!(id.undetermined.is_empty(), "{:?}", id.undetermined);
    let truth = [TRUTH[0], TRUTH[2], cf, h0];
    assert_within_two_sigma(id, &r.c, &[0, 2, 3, 4], &truth);
    // the compliance is resolved: its deviation is a small part of its value
    assert!(id.std_dev[2] < 0.5 * cf, "sigma(Cf) = {}", id.std_dev[2]);
}

/// A flat punch (radius 0.5 mm) on an elastic solid through the frame is a series
/// spring: `F = H / (1 / (2 a E*) + Cf)`, so the forces see only that combination of E
/// and Cf. Fitting both, the identifiability reports them undetermined (or correlated to
/// -1 within round-off).
#[test]
fn compliance_and_modulus_of_a_flat_punch_are_not_separable_under_depth_control() {
    let m = model(Punch::Flat { radius: 0.5 });
    let schedule = lhu(0.01, 6);
    let frame = Frame {
        compliance: 1e-5,
        ..Frame::default()
    };
    let record = frame_forces(
        &m,
        &LawMaterial(&Elastic),
        &[20000.0, 0.3],
        &schedule,
        &frame,
        0.0,
        1,
    );
    let test = Test::new(m, schedule, &record, None, opts(), 1.0).unwrap();
    let instrument = Instrument {
        compliance: true,
        ..Instrument::default()
    };
    let p = Problem::joint_instrumented(&Elastic, instrument, vec![test]).unwrap();
    let mut cfg = IdentifyConfig::new(vec![
        ParamSpec::free("E", 15000.0, 1000.0, 1e6),
        ParamSpec::fixed("nu", 0.3),
        ParamSpec::free("Cf", 5e-6, 0.0, 1.0).with_scaling(Scaling::Linear),
    ]);
    cfg.method = Method::LevenbergMarquardt;
    cfg.stop.max_iterations = 30;
    let r = match identify(&p, &cfg, &mut |_| {}) {
        Ok(r) => r,
        Err(IdentifyError::Stalled { .. }) => return, // a flat valley may also stall
        Err(e) => panic!("{e}"),
    };
    let id = r.identifiability.as_ref().unwrap();
    println!(
        "flat punch under depth control: {:?}, {}, corr {:?}, undetermined {:?}, reasons {:?}",
        r.c, r.stop_reason, id.correlation, id.undetermined, id.reasons
    );
    let corr = id.correlation[0][1];
    assert!(
        !id.undetermined.is_empty() || corr.abs() > 0.999,
        "E and Cf shall be confounded: corr {corr}, undetermined {:?}",
        id.undetermined
    );
}
