//! The adjoint of depth control through the instrument's frame replayed from checkpoints
//! (`Adjoint::gradient_compliant_replayed`; docs/theory.md §13.7): a run of
//! `DirectSolver::run_compliant` kept as checkpoints only (every 4 schedule steps, no
//! fields), each stretch replayed with the frame's drive (`DirectSolver::replay_compliant`)
//! and swept backward, gives the gradient of the run recorded with every field
//! (`Adjoint::gradient_compliant`, itself checked against central differences in
//! `gradient_compliant.rs` and `compliant_frame.rs`): the law's entries, `dJ/dCf`,
//! `dJ/dvd`, `dJ/dh0` and every `dJ/dH_i` within 1e-12 of the largest, for Maxwell under
//! the cone (vertical contact, where the recorded sweep may take the all-nodal path and the
//! replayed one the per-point pass), Maxwell under the sphere with Coulomb friction
//! (mu 0.2: the first step's ties read the initial displacement, which the replayed sweep
//! takes from the first stretch), J2 power + Norton with friction (internal variables
//! replayed) and Maxwell under finite strain. A run with neither fields nor checkpoints,
//! and a replaying solver on another model, are refused.

mod common;

use common::{finite_model, small_model};
use indentify_adjoint::{Adjoint, AdjointError, FrameGradient, LoadReplay};
use indentify_contact::{ContactKind, DirectSolver, Frame, Model, Schedule, SolverOptions};
use indentify_laws::{Hardening, LawMaterial, Material, Maxwell, Plastic, Rate};
use indentify_testkit::{cone68 as cone, depth_lhu, sphere1 as sphere, weights};

fn opts(record: bool, every: usize) -> SolverOptions {
    SolverOptions {
        record_fields: record,
        checkpoint_every: every,
        residual_tol: 1e-12,
        ..SolverOptions::default()
    }
}

/// Machine depth: ramp to `h` mm, hold, unload to `0.6 h`, `steps` steps per segment.
fn lhu(h: f64, steps: usize) -> Schedule {
    depth_lhu(h, 0.6 * h, steps)
}

const R1: [f64; 3] = [20000.0, 0.3, 30000.0];
const MAXWELL_SPHERE: [f64; 3] = [1e5, 0.3, 2e5];
const POWER_NORTON: [f64; 6] = [1e5, 0.3, 500.0, 0.2, 1500.0, 5.0];

/// The largest difference between the replayed and the recorded gradient, relative to the
/// largest entry of each part (law, frame, `dJ/dH`).
fn worst(a: &FrameGradient, b: &FrameGradient) -> f64 {
    let part = |x: &[f64], y: &[f64]| {
        assert_eq!(x.len(), y.len());
        let scale = y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(scale > 0.0);
        x.iter()
            .zip(y)
            .fold(0.0f64, |m, (p, q)| m.max((p - q).abs() / scale))
    };
    part(&a.dj_dc, &b.dj_dc)
        .max(part(&a.dj_dframe, &b.dj_dframe))
        .max(part(&a.dj_dh, &b.dj_dh))
}

/// The recorded and the replayed gradient of one case; returns the worst difference.
fn case(name: &str, m: &Model, mat: &dyn Material, c: &[f64], fr: &Frame, s: &Schedule) -> f64 {
    let mut solver = DirectSolver::new(m).unwrap();
    let recorded = solver.run_compliant(mat, c, s, fr, &opts(true, 0)).unwrap();
    let ck = opts(false, 4);
    let stored = solver.run_compliant(mat, c, s, fr, &ck).unwrap();
    assert!(stored.fields.is_empty(), "{name}");
    assert!(stored.checkpoints.len() > 2, "{name}");
    assert_eq!(stored.steps.len(), recorded.steps.len(), "{name}");
    let w = weights(recorded.steps.len());
    let mut adj = Adjoint::new(m).unwrap();
    let g1 = adj
        .gradient_compliant(mat, c, &recorded, (s, fr), &w)
        .unwrap();
    // without fields the plain sweep refuses the run, naming what is missing
    assert!(matches!(
        adj.gradient_compliant(mat, c, &stored, (s, fr), &w),
        Err(AdjointError::NotRecorded { .. })
    ));
    let g2 = adj
        .gradient_compliant_replayed(
            mat,
            c,
            &stored,
            (s, fr),
            &w,
            LoadReplay {
                solver: &mut solver,
                opts: &ck,
            },
        )
        .unwrap();
    // a recorded run takes the plain sweep through the replayed entry point
    let g3 = adj
        .gradient_compliant_replayed(
            mat,
            c,
            &recorded,
            (s, fr),
            &w,
            LoadReplay {
                solver: &mut solver,
                opts: &ck,
            },
        )
        .unwrap();
    assert_eq!(g3.dj_dc, g1.dj_dc, "{name}");
    let d = worst(&g2, &g1);
    println!(
        "{name}: {} steps, {} stretches replayed; dJ/dc {:?} dJ/dframe {:?}; replayed vs \
         recorded {d:.2e} of the largest",
        recorded.steps.len(),
        stored.checkpoints.len(),
        g1.dj_dc,
        g1.dj_dframe
    );
    d
}

fn frame(cf: f64) -> Frame {
    Frame {
        compliance: cf,
        drift: 1e-3,
        offset: 1e-3,
    }
}

/// A case: its name, model, material, parameters, frame and machine-depth schedule.
type Case<'a> = (&'a str, Model, &'a dyn Material, &'a [f64], Frame, Schedule);

#[test]
fn replayed_compliant_gradient_equals_the_recorded_one() {
    let mx = LawMaterial(&Maxwell);
    let pl = Plastic::new(Hardening::Power, Rate::Norton);
    let mu = |m: f64| ContactKind::normal_with_friction(m).unwrap();
    let cases: [Case; 4] = [
        (
            "Maxwell cone vertical",
            small_model(cone(), ContactKind::Vertical),
            &mx,
            &R1,
            Frame {
                compliance: 1e-4,
                drift: 2e-3,
                offset: -2e-3,
            },
            lhu(0.06, 6),
        ),
        (
            "Maxwell sphere mu 0.2",
            small_model(sphere(), mu(0.2)),
            &mx,
            &MAXWELL_SPHERE,
            frame(1.5e-5),
            lhu(0.04, 6),
        ),
        (
            "J2 power + Norton sphere mu 0.2",
            small_model(sphere(), mu(0.2)),
            &pl,
            &POWER_NORTON,
            frame(1.5e-5),
            lhu(0.04, 6),
        ),
        (
            "Maxwell sphere finite strain",
            finite_model(sphere()),
            &mx,
            &MAXWELL_SPHERE,
            frame(1.5e-5),
            lhu(0.04, 6),
        ),
    ];
    for (name, m, mat, c, fr, s) in &cases {
        let d = case(name, m, *mat, c, fr, s);
        assert!(d <= 1e-12, "{name}: {d:e}");
    }
}

/// A run with neither fields nor a checkpoint at its start, and a replaying solver built
/// on another model, are refused with the reason.
#[test]
fn replayed_compliant_gradient_refuses_what_it_cannot_replay() {
    let m = small_model(cone(), ContactKind::Vertical);
    let other = small_model(cone(), ContactKind::Vertical);
    let (s, fr, mat) = (lhu(0.06, 4), frame(1e-4), LawMaterial(&Maxwell));
    let mut solver = DirectSolver::new(&m).unwrap();
    let bare = solver
        .run_compliant(&mat, &R1, &s, &fr, &opts(false, 0))
        .unwrap();
    assert!(bare.fields.is_empty() && bare.checkpoints.is_empty());
    let w = weights(bare.steps.len());
    let mut adj = Adjoint::new(&m).unwrap();
    let ck = opts(false, 4);
    let e = adj
        .gradient_compliant_replayed(
            &mat,
            &R1,
            &bare,
            (&s, &fr),
            &w,
            LoadReplay {
                solver: &mut solver,
                opts: &ck,
            },
        )
        .unwrap_err();
    assert!(matches!(e, AdjointError::NotRecorded { .. }), "{e}");
    let stored = solver.run_compliant(&mat, &R1, &s, &fr, &ck).unwrap();
    let mut elsewhere = DirectSolver::new(&other).unwrap();
    let e = adj
        .gradient_compliant_replayed(
            &mat,
            &R1,
            &stored,
            (&s, &fr),
            &w,
            LoadReplay {
                solver: &mut elsewhere,
                opts: &ck,
            },
        )
        .unwrap_err();
    assert!(
        matches!(&e, AdjointError::Replay(m) if m.contains("another model")),
        "{e}"
    );
}
