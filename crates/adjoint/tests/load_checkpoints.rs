//! Checkpoints under load control: a run of `DirectSolver::run_history` that saves its
//! states every few schedule steps instead of every step's fields, replayed stretch by
//! stretch with its load-controlled segments driven by their force again
//! (`DirectSolver::replay_history`), gives `Adjoint::gradient_load_replayed` equal to the
//! gradient of the fully recorded run (`Adjoint::gradient_load`) to 1e-10 relative (the
//! largest `|dJ/dc_k c_k|`); the checkpointed run's steps are the recorded run's to
//! 1e-12 of the largest depth (each stretch starts from a fresh factorization), and the
//! replay checks its steps against them. Stress-only laws (Maxwell,
//! Norton-Hoff) and materials with internal variables (Prony), vertical and normal
//! contact, a load-hold-unload and a depth-load-hold-depth history, with a cost on the
//! depths and on the depth-controlled steps' forces.

mod common;

use common::small_model;
use indentify_adjoint::{Adjoint, LoadReplay};
use indentify_contact::{ContactKind, DirectSolver, LoadHistory, Model, Punch, SolverOptions};
use indentify_laws::{LawMaterial, Material, Maxwell, NortonHoff, Prony};
use indentify_testkit::{depth, force};

/// The checkpointed gradient against the recorded one; returns the largest relative
/// difference (to the largest `|dJ/dc_k c_k|`).
fn compare(m: &Model, mat: &dyn Material, c: &[f64], h: &LoadHistory, every: usize) -> f64 {
    let recorded = SolverOptions {
        record_fields: true,
        residual_tol: 1e-11,
        ..SolverOptions::default()
    };
    let checkpointed = SolverOptions {
        record_fields: false,
        checkpoint_every: every,
        ..recorded.clone()
    };
    let mut solver = DirectSolver::new(m).unwrap();
    let full = solver.run_history(mat, c, h, &recorded).unwrap();
    let cp = solver.run_history(mat, c, h, &checkpointed).unwrap();
    assert!(cp.fields.is_empty());
    assert!(
        cp.checkpoints.len() > 1,
        "{} checkpoints",
        cp.checkpoints.len()
    );
    // the checkpointed run is the recorded one, step for step (each stretch starts from
    // a fresh factorization: the same steps to round-off)
    assert_eq!(cp.steps.len(), full.steps.len());
    let h_max = full.steps.iter().fold(0.0f64, |m, s| m.max(s.depth.abs()));
    for (a, b) in cp.steps.iter().zip(&full.steps) {
        assert_eq!(a.t.to_bits(), b.t.to_bits());
        assert!(
            (a.depth - b.depth).abs() <= 1e-12 * h_max,
            "depth at t = {}",
            a.t
        );
    }
    // a depth cost on every step and a force cost on the depth-controlled ones
    let n = full.steps.len();
    let dj_dh: Vec<f64> = full.steps.iter().map(|s| s.depth - 0.01).collect();
    let dj_df: Vec<f64> = full.steps.iter().map(|s| 1e-3 * s.force).collect();
    assert_eq!(dj_df.len(), n);
    let mut adj = Adjoint::new(m).unwrap();
    let g_full = adj.gradient_load(mat, c, &full, h, &dj_dh, &dj_df).unwrap();
    let g_cp = adj
        .gradient_load_replayed(
            mat,
            c,
            &cp,
            h,
            &dj_dh,
            &dj_df,
            LoadReplay {
                solver: &mut solver,
                opts: &checkpointed,
            },
        )
        .unwrap();
    let scale = g_full
        .dj_dc
        .iter()
        .zip(c)
        .fold(0.0f64, |s, (g, p)| s.max((g * p).abs()));
    let worst = g_full
        .dj_dc
        .iter()
        .zip(&g_cp.dj_dc)
        .zip(c)
        .map(|((a, b), p)| ((a - b) * p).abs() / scale)
        .fold(0.0f64, f64::max);
    println!(
        "recorded {:?}\ncheckpointed {:?}\nworst {worst:.2e}",
        g_full.dj_dc, g_cp.dj_dc
    );
    worst
}

fn lhu(p: f64, steps: usize) -> LoadHistory {
    LoadHistory::from_segments(&[
        force(1.0, p, steps),
        force(1.0, p, steps),
        force(1.0, 0.4 * p, steps),
    ])
    .unwrap()
}

fn mixed(p: f64, d: f64) -> LoadHistory {
    LoadHistory::from_segments(&[
        depth(1.0, d, 4),
        force(1.0, p, 6),
        force(1.0, p, 4),
        depth(1.0, d, 5),
    ])
    .unwrap()
}

#[test]
fn stress_only_laws_vertical_contact() {
    let m = small_model(
        Punch::Cone {
            half_angle_deg: 68.0,
        },
        ContactKind::Vertical,
    );
    let maxwell = [21000.0, 0.3, 25000.0];
    for h in [lhu(40.0, 6), mixed(40.0, 0.02)] {
        let w = compare(&m, &LawMaterial(&Maxwell), &maxwell, &h, 4);
        assert!(w <= 1e-10, "maxwell {w:.2e}");
    }
    let norton = [1.1e5, 0.3, 1400.0, 5.5, 450.0];
    let w = compare(&m, &LawMaterial(&NortonHoff), &norton, &lhu(40.0, 6), 5);
    assert!(w <= 1e-10, "norton-hoff {w:.2e}");
}

#[test]
fn prony_normal_contact() {
    let m = small_model(Punch::Sphere { radius: 1.0 }, ContactKind::Normal);
    let p = Prony::new(2).unwrap();
    let c = [1e5, 0.3, 0.3, 0.2, 0.2, 2.0];
    for h in [lhu(600.0, 6), mixed(600.0, 0.03)] {
        let w = compare(&m, &p, &c, &h, 3);
        assert!(w <= 1e-10, "prony {w:.2e}");
    }
}
