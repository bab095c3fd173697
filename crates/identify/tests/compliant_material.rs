//! Instrument parameters of depth-controlled tests with a law that has internal variables
//! (docs/theory.md §13.7): J2 plasticity with power hardening and Norton overstress driven
//! through the frame's spring. The forward sensitivities through the frame exist for it
//! now, so Levenberg-Marquardt fits `Cf` with the law (it was refused with the reason).
//!
//! References this code did not produce: central differences of the `Evaluator`'s own cost
//! (law and frame parameters), the adjoint gradient against `J^T r` of the compliant
//! sensitivity rows (one more route to the same number), the evaluator with checkpointed
//! runs against the one recording every field (to round-off), and the truth that generated
//! synthetic noisy forces (`Cf` recovered within its standard deviation's bound).
//!
//! ```text
//!      sphere R = 1 mm, frictionless normal contact; machine depth 0 -> 0.04 mm (1 s) ->
//!      hold (1 s) -> 0.024 mm (1 s); 4 x 4 mm cylinder, 8 x 8 Q8 graded 1.45;
//!      J2 E = 1e5 MPa, nu = 0.3, sY = 500 MPa, n = 0.2, K = 1500 MPa s^(1/m), m = 5
//! ```

mod common;

use common::{
    assert_within_two_sigma, cost_difference, depth_lhu as lhu, frame_forces, jt_r,
    tight_opts as opts,
};
use indentify_contact::{ContactKind, Frame, Model, Punch, Schedule, SolverOptions};
use indentify_identify::{
    Evaluator, ForceRecord, IdentifyConfig, Instrument, Method, ParamSpec, Problem, Scaling, Test,
    identify,
};
use indentify_laws::{Hardening, Material, Plastic, Rate};
use indentify_testkit::small_cylinder;
use std::sync::Arc;

const TRUTH: [f64; 6] = [1e5, 0.3, 500.0, 0.2, 1500.0, 5.0];

fn model() -> Model {
    Model::with_contact(
        small_cylinder(),
        Punch::Sphere { radius: 1.0 },
        ContactKind::Normal,
    )
    .unwrap()
}

fn plastic() -> Plastic {
    Plastic::new(Hardening::Power, Rate::Norton)
}

fn material() -> Arc<dyn Material> {
    Arc::new(plastic())
}

/// The forces a compliant run at `c` through `frame` gives at the schedule times, with
/// uniform noise of half-width `noise` (N, seed `seed`; none at the initial state).
fn measured(c: &[f64], schedule: &Schedule, frame: &Frame, noise: f64, seed: u64) -> ForceRecord {
    frame_forces(&model(), &plastic(), c, schedule, frame, noise, seed)
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / a.abs().max(b.abs()).max(1e-300)
}

fn all() -> Instrument {
    Instrument {
        compliance: true,
        drift: true,
        offset: true,
    }
}

/// The problem of one test with data from the truth through `(1e-4, 1e-3, 2e-3)`.
fn problem(opts: SolverOptions) -> Problem {
    let schedule = lhu(0.04, 6);
    let truth_frame = Frame {
        compliance: 1e-5,
        drift: 1e-3,
        offset: 2e-3,
    };
    let record = measured(&TRUTH, &schedule, &truth_frame, 0.0, 1);
    let test = Test::new(model(), schedule, &record, None, opts, 1.0).unwrap();
    Problem::joint_instrumented(material(), all(), vec![test]).unwrap()
}

const AT: [f64; 9] = [8e4, 0.3, 600.0, 0.25, 1200.0, 5.0, 1.5e-5, -1e-3, 1e-3];

/// Through the `Evaluator`: the compliant adjoint's gradient with respect to every law
/// parameter and `Cf`, `vd`, `h0` against central differences of its own cost (1e-6), and
/// `J^T r` of the compliant sensitivity rows (a material with internal variables) against
/// the adjoint (1e-12).
#[test]
fn plastic_gradient_and_jacobian_through_the_frame_match_differences() {
    let p = problem(opts());
    let names: Vec<_> = p.law.params().iter().map(|i| i.name).collect();
    assert_eq!(names, ["E", "nu", "sY", "n", "K", "m", "Cf", "vd", "h0"]);
    let mut ev = Evaluator::new(&p).unwrap();
    let c = AT;
    let (j0, g) = ev.cost_and_gradient(&c).unwrap();
    assert!(j0 > 0.0);
    let f_sim = ev.forces(&c).unwrap();
    let jac = ev.jacobian(&c).unwrap();
    let (mut worst_fd, mut worst_jt) = (0.0f64, 0.0f64);
    for k in 0..c.len() {
        let step = 1e-5 * c[k].abs();
        let fd = cost_difference(&mut ev, &c, k, step);
        let jt_r = jt_r(&p, &jac, &f_sim, k);
        println!(
            "dJ/d{}: adjoint {:.12e}, FD {fd:.12e} (rel {:.1e}), J^T r {jt_r:.12e} (rel {:.1e})",
            names[k],
            g[k],
            rel(g[k], fd),
            rel(jt_r, g[k])
        );
        worst_fd = worst_fd.max(rel(g[k], fd));
        worst_jt = worst_jt.max(rel(jt_r, g[k]));
    }
    assert!(worst_fd < 1e-6, "adjoint vs FD {worst_fd:.2e}");
    assert!(worst_jt <= 1e-12, "J^T r vs adjoint {worst_jt:.2e}");
}

/// Runs recorded with checkpoints only: the evaluator's gradient replays the run's
/// stretches one at a time (`Adjoint::gradient_compliant_replayed`), its sensitivities run
/// the test with fields again (without checkpoints, whose stretches each start from a
/// fresh factorization: the same steps to round-off, not bit for bit; the replay of a
/// checkpointed compliant run itself is bit for bit,
/// `crates/adjoint/tests/compliant_frame.rs`), so the cost, the gradient and the Jacobian
/// equal those of runs recording every field to round-off (1e-10 of each entry's scale).
#[test]
fn checkpointed_runs_give_the_recorded_values() {
    let recorded = problem(SolverOptions {
        record_fields: true,
        ..opts()
    });
    let checkpointed = problem(SolverOptions {
        record_fields: false,
        checkpoint_every: 4,
        ..opts()
    });
    let mut a = Evaluator::new(&recorded).unwrap();
    let mut b = Evaluator::new(&checkpointed).unwrap();
    let (ja, ga) = a.cost_and_gradient(&AT).unwrap();
    let (jb, gb) = b.cost_and_gradient(&AT).unwrap();
    let mut worst = rel(ja, jb);
    for (x, y) in ga.iter().zip(&gb) {
        worst = worst.max(rel(*x, *y));
    }
    let (ra, rb) = (a.jacobian(&AT).unwrap(), b.jacobian(&AT).unwrap());
    assert_eq!(ra.len(), rb.len());
    let nc = AT.len();
    for k in 0..nc {
        let big = ra.iter().fold(0.0f64, |m, r| m.max(r[k].abs()));
        for (x, y) in ra.iter().zip(&rb) {
            worst = worst.max((x[k] - y[k]).abs() / big.max(1e-300));
        }
    }
    println!("checkpointed vs recorded: worst relative difference {worst:.1e}");
    assert!(worst <= 1e-10, "{worst:.2e}");
}

/// Synthetic depth-controlled data through a frame (Cf = 1e-5 mm/N), forces with seeded
/// uniform noise (half-width 0.3% of the peak force): LM fits E, sY and Cf (the other law
/// parameters held at the truth) and recovers Cf within its standard deviation's bound
/// (2 sigma asserted; the draw's multiple printed).
#[test]
fn lm_fit_with_a_plastic_law_recovers_the_compliance() {
    let schedule = lhu(0.04, 8);
    let cf = 1e-5;
    let frame = Frame {
        compliance: cf,
        ..Frame::default()
    };
    let clean = measured(&TRUTH, &schedule, &frame, 0.0, 1);
    let f_max = clean.force.iter().copied().fold(0.0, f64::max);
    let noise = 3e-3 * f_max;
    let record = measured(&TRUTH, &schedule, &frame, noise, 21);
    let test = Test::new(model(), schedule, &record, None, opts(), 1.0).unwrap();
    let instrument = Instrument {
        compliance: true,
        ..Instrument::default()
    };
    let p = Problem::joint_instrumented(material(), instrument, vec![test]).unwrap();
    let mut cfg = IdentifyConfig::new(vec![
        ParamSpec::free("E", 7e4, 1e4, 1e6),
        ParamSpec::fixed("nu", 0.3),
        ParamSpec::free("sY", 700.0, 50.0, 5000.0),
        ParamSpec::fixed("n", 0.2),
        ParamSpec::fixed("K", 1500.0),
        ParamSpec::fixed("m", 5.0),
        ParamSpec::free("Cf", 0.0, 0.0, 1.0).with_scaling(Scaling::Linear),
    ]);
    cfg.method = Method::LevenbergMarquardt;
    let r = identify(&p, &cfg, &mut |_| {}).unwrap();
    let id = r.identifiability.as_ref().unwrap();
    println!(
        "plastic fit through the frame: {:?}, {}, {} iterations, std dev {:?}, undetermined \
         {:?}, sigma_hat {:.3e} N (noise {:.3e})",
        r.c,
        r.stop_reason,
        r.iterations,
        id.std_dev,
        id.undetermined,
        id.sigma2.sqrt(),
        noise / 3f64.sqrt()
    );
    assert!(r.stop_reason.is_converged(), "{}", r.stop_reason);
    assert!(id.undetermined.is_empty(), "{:?}", id.undetermined);
    let truth = [TRUTH[0], TRUTH[2], cf];
    assert_within_two_sigma(id, &r.c, &[0, 2, 6], &truth);
    // the compliance is resolved: its deviation is a small part of its value
    assert!(id.std_dev[2] < 0.5 * cf, "sigma(Cf) = {}", id.std_dev[2]);
}
