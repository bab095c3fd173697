//! The exact gradient under load control (docs/theory.md §13): over a load-hold-unload
//! history (force segments), the adjoint of the bordered system
//! (`Adjoint::gradient_load`) of the depth cost `J = 1/2 sum (h_i - h_exp,i)^2` against
//! central differences of the direct solver's own load-controlled runs, for vertical and
//! frictionless normal contact and Coulomb friction, small and finite strain, elastic,
//! Maxwell and Norton-Hoff laws; and a mixed history (depth control, then load control).

mod common;

use common::{finite_model, small_model};
use indentify_adjoint::Adjoint;
use indentify_adjoint::check::{central_difference, relative_difference};
use indentify_contact::{
    ContactKind, DirectSolver, HistorySegment, LoadHistory, Model, Punch, SolverOptions,
};
use indentify_laws::{Elastic, Law, LawMaterial, Maxwell, NortonHoff};

fn opts(record: bool) -> SolverOptions {
    SolverOptions {
        record_fields: record,
        residual_tol: 1e-11,
        ..SolverOptions::default()
    }
}

fn force(duration: f64, force: f64, steps: usize) -> HistorySegment {
    HistorySegment {
        duration,
        depth: None,
        force: Some(force),
        steps,
    }
}

fn depth(duration: f64, depth: f64, steps: usize) -> HistorySegment {
    HistorySegment {
        duration,
        depth: Some(depth),
        force: None,
        steps,
    }
}

/// Ramp to `p` N, hold, unload to `0.4 p`, `steps` steps per segment.
fn lhu(p: f64, steps: usize) -> LoadHistory {
    LoadHistory::from_segments(&[
        force(1.0, p, steps),
        force(1.0, p, steps),
        force(1.0, 0.4 * p, steps),
    ])
    .unwrap()
}

/// The depths of the schedule's steps of a load-controlled run.
fn depths(
    solver: &mut DirectSolver,
    law: &dyn Law,
    c: &[f64],
    h: &LoadHistory,
) -> Result<Vec<(f64, f64)>, String> {
    let traj = solver
        .run_history(&LawMaterial(law), c, h, &opts(false))
        .map_err(|e| e.to_string())?;
    Ok(traj.schedule_steps().map(|s| (s.t, s.depth)).collect())
}

/// Adjoint vs central differences of the depth cost at `c` (data simulated at
/// `truth`), for the first `checked` parameters; returns the worst relative difference.
fn check(model: &Model, law: &dyn Law, c: &[f64], truth: &[f64], h: &LoadHistory) -> f64 {
    let mut solver = DirectSolver::new(model).unwrap();
    let data = depths(&mut solver, law, truth, h).unwrap();
    let traj = solver
        .run_history(&LawMaterial(law), c, h, &opts(true))
        .unwrap();
    // dJ/dh_i on the schedule's steps, 0 on sub-steps
    let mut j = 0;
    let mut dj_dh = vec![0.0; traj.steps.len()];
    for (s, d) in traj.steps.iter().zip(dj_dh.iter_mut()) {
        if s.on_schedule {
            assert!((s.t - data[j].0).abs() < 1e-12);
            *d = s.depth - data[j].1;
            j += 1;
        }
    }
    assert_eq!(j, data.len());
    let mut adj = Adjoint::new(model).unwrap();
    let zero = vec![0.0; traj.steps.len()];
    let g = adj
        .gradient_load(&LawMaterial(law), c, &traj, h, &dj_dh, &zero)
        .unwrap();
    let mut cost = |p: &[f64]| -> Result<f64, String> {
        let d = depths(&mut solver, law, p, h)?;
        Ok(0.5
            * d.iter()
                .zip(&data)
                .map(|(a, b)| (a.1 - b.1).powi(2))
                .sum::<f64>())
    };
    let mut worst: f64 = 0.0;
    for k in 0..c.len() {
        let fd = central_difference(&mut cost, c, k, 1e-5).unwrap();
        let r = relative_difference(g.dj_dc[k], fd);
        println!(
            "param {k}: adjoint {:.10e} fd {fd:.10e} rel {r:.2e}",
            g.dj_dc[k]
        );
        worst = worst.max(r);
    }
    worst
}

fn cone() -> Punch {
    Punch::Cone {
        half_angle_deg: 68.0,
    }
}

fn sphere() -> Punch {
    Punch::Sphere { radius: 1.0 }
}

#[test]
fn vertical_small_strain_every_law() {
    let m = small_model(cone(), ContactKind::Vertical);
    let h = lhu(40.0, 6);
    let w = check(&m, &Elastic, &[21000.0, 0.32], &[20000.0, 0.3], &h);
    assert!(w < 1e-5, "elastic {w:.2e}");
    let w = check(
        &m,
        &Maxwell,
        &[21000.0, 0.3, 25000.0],
        &[20000.0, 0.3, 30000.0],
        &h,
    );
    assert!(w < 1e-5, "maxwell {w:.2e}");
    let w = check(
        &m,
        &NortonHoff,
        &[1.1e5, 0.3, 1400.0, 5.5, 450.0],
        &[1e5, 0.3, 1500.0, 5.0, 500.0],
        &h,
    );
    assert!(w < 1e-4, "norton-hoff {w:.2e}");
}

#[test]
fn normal_contact_small_and_finite_strain() {
    let h = lhu(40.0, 6);
    let m = small_model(sphere(), ContactKind::Normal);
    let w = check(
        &m,
        &Maxwell,
        &[21000.0, 0.3, 25000.0],
        &[20000.0, 0.3, 30000.0],
        &h,
    );
    assert!(w < 1e-5, "normal small {w:.2e}");
    let m = finite_model(sphere());
    let w = check(
        &m,
        &Maxwell,
        &[21000.0, 0.3, 25000.0],
        &[20000.0, 0.3, 30000.0],
        &h,
    );
    assert!(w < 1e-5, "normal finite {w:.2e}");
}

#[test]
fn mixed_history_depth_load_depth() {
    let m = small_model(cone(), ContactKind::Vertical);
    let h = LoadHistory::from_segments(&[
        depth(1.0, 0.02, 4),
        force(1.0, 40.0, 6),
        force(1.0, 40.0, 6),
        depth(1.0, 0.02, 5),
    ])
    .unwrap();
    let w = check(
        &m,
        &Maxwell,
        &[21000.0, 0.3, 25000.0],
        &[20000.0, 0.3, 30000.0],
        &h,
    );
    assert!(w < 1e-5, "mixed {w:.2e}");
}

/// Coulomb friction under load control (docs/theory.md §13; the stick/slip cases, laws
/// and kinematics in `gradient_load_friction.rs`): the gradient of the depth cost against
/// central differences, every status of the base run held by the +-h runs there.
#[test]
fn coulomb_friction_matches_central_differences() {
    let kind = ContactKind::normal_with_friction(0.2).unwrap();
    let m = small_model(sphere(), kind);
    let w = check(
        &m,
        &Maxwell,
        &[21000.0, 0.3, 25000.0],
        &[20000.0, 0.3, 30000.0],
        &lhu(300.0, 6),
    );
    assert!(w < 1e-6, "coulomb {w:.2e}");
}

/// The forward sensitivities of the bordered system give the same gradient as its
/// adjoint (`J^T (h - h_exp)`), and their depth rows agree with central differences of
/// the depths.
#[test]
fn sensitivities_agree_with_the_adjoint_and_differences() {
    let m = small_model(cone(), ContactKind::Vertical);
    for h in [
        lhu(40.0, 6),
        LoadHistory::from_segments(&[
            depth(1.0, 0.02, 4),
            force(1.0, 40.0, 6),
            force(1.0, 40.0, 6),
            depth(1.0, 0.02, 5),
        ])
        .unwrap(),
    ] {
        let (law, c) = (&Maxwell, [21000.0, 0.3, 25000.0]);
        let mut solver = DirectSolver::new(&m).unwrap();
        let traj = solver
            .run_history(&LawMaterial(law), &c, &h, &opts(true))
            .unwrap();
        let mut adj = Adjoint::new(&m).unwrap();
        let sens = adj
            .sensitivities_load(&LawMaterial(law), &c, &traj, &h)
            .unwrap();
        let n = traj.steps.len();
        // an arbitrary depth cost: dJ/dU_i = i
        let rho: Vec<f64> = (0..n).map(|i| i as f64).collect();
        let g = adj
            .gradient_load(&LawMaterial(law), &c, &traj, &h, &rho, &vec![0.0; n])
            .unwrap();
        for k in 0..c.len() {
            let jt: f64 = sens.dh_dc.iter().zip(&rho).map(|(r, w)| r[k] * w).sum();
            let r = relative_difference(jt, g.dj_dc[k]);
            assert!(
                r < 1e-8,
                "param {k}: J^T rho {jt} adjoint {} ({r:.2e})",
                g.dj_dc[k]
            );
        }
        // the last schedule step's depth vs central differences
        let last = |p: &[f64]| -> Result<f64, String> {
            Ok(depths(&mut solver, law, p, &h)?.last().unwrap().1)
        };
        let mut last = last;
        for k in 0..c.len() {
            let fd = central_difference(&mut last, &c, k, 1e-5).unwrap();
            let r = relative_difference(sens.dh_dc[n - 1][k], fd);
            assert!(
                r < 1e-5,
                "param {k}: {} vs {fd} ({r:.2e})",
                sens.dh_dc[n - 1][k]
            );
        }
    }
}
