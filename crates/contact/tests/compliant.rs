//! Depth control through the instrument's frame (`DirectSolver::run_compliant`;
//! docs/theory.md §13.7, docs/validation-load-control.md §10): a schedule of machine
//! depths `h_meas = h + Cf F + vd (t - t0) + h0` drives the punch through the frame's
//! spring. Checked here: `Cf = 0` gives the depth-controlled run's bits; every step meets
//! `h + Cf F = H` to solver tolerance; the punch depths the compliant run reached, at the
//! times of every step it took, drive a plain depth-controlled run back to the same
//! forces (a different statement of the same discrete problem) for every law and both
//! contact kinds and kinematics; a bad frame names its field.

mod common;

use common::model_2mm_kin as model;
use common::testkit::{cone68 as cone, depth_lhu};
use indentify_contact::{
    ContactError, ContactKind, DirectSolver, Frame, Kinematics, Model, Punch, Schedule,
    SolverOptions, Trajectory,
};
use indentify_laws::{Elastic, Law, LawMaterial, Maxwell, NortonHoff};

fn sphere() -> Punch {
    Punch::Sphere { radius: 0.5 }
}

/// Machine depth: ramp to 0.06 mm, hold, unload to 0.03 mm, 8 steps each.
fn schedule() -> Schedule {
    depth_lhu(0.06, 0.03, 8)
}

fn opts() -> SolverOptions {
    SolverOptions {
        record_fields: true,
        ..SolverOptions::default()
    }
}

const R0: [f64; 2] = [20000.0, 0.3];
const R1: [f64; 3] = [20000.0, 0.3, 30000.0];
const R2: [f64; 5] = [1e5, 0.3, 1500.0, 5.0, 500.0];

fn laws() -> [(&'static dyn Law, &'static [f64]); 3] {
    [(&Elastic, &R0), (&Maxwell, &R1), (&NortonHoff, &R2)]
}

/// A frame whose spring takes about a fifth of the machine depth at R0's peak force on
/// the cone (F ~ 78 N through the frame), with a drift and an offset.
const FRAME: Frame = Frame {
    compliance: 1.5e-4,
    drift: 2e-3,
    offset: -1e-3,
};

/// The largest `|h + Cf F + vd (t - t0) + h0 - h_meas(t)|` over the steps (mm).
fn spring_residual(traj: &Trajectory, schedule: &Schedule, frame: &Frame) -> f64 {
    traj.steps
        .iter()
        .map(|s| {
            let meas = s.depth
                + frame.compliance * s.force
                + frame.drift * (s.t - schedule.t[0])
                + frame.offset;
            (meas - schedule.depth_at(s.t)).abs()
        })
        .fold(0.0, f64::max)
}

/// The compliant run, then the depth-controlled run of the punch depths it reached at
/// the times of every step it took: returns the compliant run, the spring's residual
/// relative to the peak machine depth and the largest force difference relative to the
/// peak force.
fn round_trip(model: &Model, law: &dyn Law, c: &[f64], frame: &Frame) -> (Trajectory, f64, f64) {
    let mut solver = DirectSolver::new(model).unwrap();
    let sch = schedule();
    let by_spring = solver
        .run_compliant(&LawMaterial(law), c, &sch, frame, &opts())
        .unwrap();
    let h_max = 0.06;
    let spring = spring_residual(&by_spring, &sch, frame) / h_max;
    let t: Vec<f64> = std::iter::once(sch.t[0])
        .chain(by_spring.steps.iter().map(|s| s.t))
        .collect();
    let h: Vec<f64> = std::iter::once(frame.prescribed(&sch, sch.t[0]))
        .chain(by_spring.steps.iter().map(|s| s.depth))
        .collect();
    let by_depth = solver
        .run(
            &LawMaterial(law),
            c,
            &Schedule::from_record(&t, &h).unwrap(),
            &opts(),
        )
        .unwrap();
    assert_eq!(by_depth.steps.len(), by_spring.steps.len());
    let f_max = by_spring.steps.iter().map(|s| s.force).fold(0.0, f64::max);
    let worst = by_spring
        .steps
        .iter()
        .zip(&by_depth.steps)
        .map(|(a, b)| (a.force - b.force).abs() / f_max)
        .fold(0.0, f64::max);
    (by_spring, spring, worst)
}

/// `Cf = 0` (and no drift or offset) is plain depth control: the same bits, every law.
#[test]
fn zero_compliance_gives_the_depth_controlled_bits() {
    let m = model(cone(), ContactKind::Vertical, Kinematics::Small);
    for (law, c) in laws() {
        // each run on a fresh solver
        let a = DirectSolver::new(&m)
            .unwrap()
            .run(&LawMaterial(law), c, &schedule(), &opts())
            .unwrap();
        let b = DirectSolver::new(&m)
            .unwrap()
            .run_compliant(
                &LawMaterial(law),
                c,
                &schedule(),
                &Frame::default(),
                &opts(),
            )
            .unwrap();
        assert_eq!(a.steps, b.steps, "{}", law.name());
        assert!(a.fields == b.fields, "{}", law.name());
    }
}

/// Vertical contact, small strain, every law: the spring holds to solver tolerance and
/// the depths reached drive the depth-controlled run back to the same forces.
#[test]
fn compliant_run_meets_the_spring_and_drives_back_to_its_forces_vertical() {
    let m = model(cone(), ContactKind::Vertical, Kinematics::Small);
    for (law, c) in laws() {
        let (t, spring, worst) = round_trip(&m, law, c, &FRAME);
        let last = t.steps.iter().map(|s| s.force).fold(0.0, f64::max);
        println!(
            "{}: spring residual {spring:.2e} h_max, max |dF|/F_max = {worst:.2e}, F_max = \
             {last:.3} N, {} Newton iterations",
            law.name(),
            t.total_iterations()
        );
        assert!(spring < 1e-8, "{}: {spring:e}", law.name());
        assert!(worst < 1e-7, "{}: {worst:e}", law.name());
        // the frame took a real share of the machine depth
        assert!(FRAME.compliance * last > 0.15 * 0.06, "{last}");
    }
}

/// Frictionless normal contact on a sphere, small and finite strain.
#[test]
fn compliant_run_meets_the_spring_and_drives_back_to_its_forces_normal() {
    for kin in [Kinematics::Small, Kinematics::Finite] {
        let m = model(sphere(), ContactKind::Normal, kin);
        for (law, c) in [(&Elastic as &dyn Law, &R0[..]), (&Maxwell, &R1[..])] {
            let frame = Frame {
                compliance: 5e-5,
                ..FRAME
            };
            let (_, spring, worst) = round_trip(&m, law, c, &frame);
            println!(
                "{kin:?} {}: spring residual {spring:.2e} h_max, max |dF|/F_max = {worst:.2e}",
                law.name()
            );
            assert!(spring < 1e-8, "{kin:?} {}: {spring:e}", law.name());
            assert!(worst < 1e-7, "{kin:?} {}: {worst:e}", law.name());
        }
    }
}

/// A negative or non-finite compliance, a non-finite drift or offset: refused naming the
/// field.
#[test]
fn bad_frames_name_their_field() {
    let m = model(cone(), ContactKind::Vertical, Kinematics::Small);
    let mut solver = DirectSolver::new(&m).unwrap();
    for (frame, field) in [
        (
            Frame {
                compliance: -1e-4,
                ..FRAME
            },
            "frame.compliance",
        ),
        (
            Frame {
                compliance: f64::NAN,
                ..FRAME
            },
            "frame.compliance",
        ),
        (
            Frame {
                drift: f64::INFINITY,
                ..FRAME
            },
            "frame.drift",
        ),
        (
            Frame {
                offset: f64::NAN,
                ..FRAME
            },
            "frame.offset",
        ),
    ] {
        match solver.run_compliant(&LawMaterial(&Elastic), &R0, &schedule(), &frame, &opts()) {
            Err(ContactError::Input { field: f, .. }) => assert_eq!(f, field),
            other => panic!("{field}: {other:?}"),
        }
    }
}
