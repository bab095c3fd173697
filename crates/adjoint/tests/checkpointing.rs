//! Checkpointed adjoint: storing the solver state every few steps and replaying segments
//! in the backward sweep gives the same gradient as storing every step, with less memory.
//!
//! The same adjoint computation repeats bit for bit on one `Adjoint` whatever ran before.
//!
//! Reference: the full-storage adjoint (itself checked against finite differences in
//! gradient_fd.rs). Norton-Hoff on a 10 x 10 graded cylinder, cone 68 deg, trapezoid with
//! 8 steps per segment (the first unloading step of the perturbed run is cut).

use indentify_adjoint::check::relative_difference;
use indentify_adjoint::{Adjoint, Replay};
use indentify_contact::{DirectSolver, Model, Punch, Schedule, SolverOptions, trapezoid};
use indentify_laws::{Law, Maxwell, NortonHoff};
use indentify_testkit::cylinder;

fn check(law: &dyn Law, c: &[f64], every: usize) {
    let mesh = cylinder(4.0, 10, 1.45);
    let model = Model::new(
        mesh,
        Punch::Cone {
            half_angle_deg: 68.0,
        },
    )
    .unwrap();
    let sched = Schedule::from_segments(&trapezoid(0.1, 1.0, 1.0, 1.0, 8)).unwrap();
    let full_opts = SolverOptions::default();
    let mut solver = DirectSolver::new(&model).unwrap();
    let full = solver
        .run(&indentify_laws::LawMaterial(law), c, &sched, &full_opts)
        .unwrap();
    let cp_opts = SolverOptions {
        record_fields: false,
        checkpoint_every: every,
        ..Default::default()
    };
    let light = solver
        .run(&indentify_laws::LawMaterial(law), c, &sched, &cp_opts)
        .unwrap();
    // the same forward run: a checkpoint restarts the inexact solves' preconditioner with
    // a fresh factorization (so that replays repeat the checkpointed run bit for bit),
    // which moves the converged iterates by round-off only
    let (fl, ff) = (light.forces(), full.forces());
    assert_eq!(fl.len(), ff.len());
    let fmax = ff.iter().fold(0.0f64, |m, f| m.max(f.abs()));
    for (a, b) in fl.iter().zip(&ff) {
        assert!((a - b).abs() <= 1e-11 * fmax, "forces {a} vs {b}");
    }
    let active = |t: &indentify_contact::Trajectory| -> Vec<Vec<u32>> {
        t.steps.iter().map(|s| s.active.clone()).collect()
    };
    assert_eq!(active(&light), active(&full), "same steps and active sets");
    assert!(light.fields.is_empty() && light.checkpoints.len() == sched.n_steps().div_ceil(every));
    let rho: Vec<f64> = full
        .steps
        .iter()
        .map(|s| {
            if s.on_schedule {
                0.1 * s.force + 1.0
            } else {
                0.0
            }
        })
        .collect();
    let mut adj = Adjoint::new(&model).unwrap();
    let g_full = adj
        .gradient(&indentify_laws::LawMaterial(law), c, &full, &rho)
        .unwrap();
    let g_cp = adj
        .gradient_replayed(
            &indentify_laws::LawMaterial(law),
            c,
            &light,
            &rho,
            Replay {
                solver: &mut solver,
                schedule: &sched,
                opts: &cp_opts,
            },
        )
        .unwrap();
    println!(
        "{}: full {} bytes, checkpointed {} bytes; gradients {:?} vs {:?}",
        law.name(),
        full.recorded_bytes(),
        light.recorded_bytes(),
        g_full.dj_dc,
        g_cp.dj_dc
    );
    assert!(light.recorded_bytes() * 3 < full.recorded_bytes());
    for (a, b) in g_full.dj_dc.iter().zip(&g_cp.dj_dc) {
        assert!(relative_difference(*a, *b) < 1e-12, "{a} vs {b}");
    } // the adjoint's assembly restarts from a full sum at every sweep: the same gradient,
    // and the same sensitivities, bit for bit after other computations
    let again = adj
        .gradient(&indentify_laws::LawMaterial(law), c, &full, &rho)
        .unwrap();
    assert_eq!(
        again.dj_dc, g_full.dj_dc,
        "gradient repeats after a replayed sweep"
    );
    let s1 = adj
        .sensitivities(&indentify_laws::LawMaterial(law), c, &full)
        .unwrap();
    let s2 = adj
        .sensitivities(&indentify_laws::LawMaterial(law), c, &full)
        .unwrap();
    assert_eq!(s1.df_dc, s2.df_dc, "sensitivities repeat");
}

/// Checkpointed and full-storage adjoint gradients shall agree to round-off for a
/// nonlinear law with step cuts.
#[test]
fn checkpointed_gradient_equals_full_storage_norton_hoff() {
    check(&NortonHoff, &[1.2e5, 0.31, 1300.0, 4.0, 420.0], 5);
}

/// The same for a linear viscoelastic law whose factorizations are cached.
#[test]
fn checkpointed_gradient_equals_full_storage_maxwell() {
    check(&Maxwell, &[15000.0, 0.28, 45000.0], 7);
}
