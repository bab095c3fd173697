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
use indentify_contact::{ContactKind, DirectSolver, LoadHistory, Model, SolverOptions};
use indentify_laws::{Elastic, Law, LawMaterial, Material, Maxwell, NortonHoff, Prony};
use indentify_testkit::{
    cone68 as cone, depth, force, force_lhu as lhu, recording, sphere1 as sphere,
};

fn opts(record: bool) -> SolverOptions {
    recording(record, 1e-11)
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

/// A cost on the forces of the depth-controlled steps of a mixed history (depth, load,
/// hold, depth: the last segment starts from the depth the load reached, so its forces
/// depend on the parameters through it as well), with a cost on the depths beside it:
/// the adjoint against the forward sensitivities (`J^T w`, every depth-controlled step
/// one at a time and all together, 1e-8) and against central differences of the direct
/// solver's own runs (1e-6, the differences' own accuracy), for Maxwell, Norton-Hoff and
/// a two-term Prony solid, under vertical contact (cone) and normal contact (sphere).
#[test]
fn force_cost_on_depth_steps_after_a_load_segment() {
    for (punch, kind) in [
        (cone(), ContactKind::Vertical),
        (sphere(), ContactKind::Normal),
    ] {
        force_cost_after_load(&small_model(punch, kind));
    }
}

fn force_cost_after_load(m: &Model) {
    let h = LoadHistory::from_segments(&[
        depth(1.0, 0.02, 4),
        force(1.0, 40.0, 6),
        force(1.0, 40.0, 6),
        depth(1.0, 0.005, 5),
    ])
    .unwrap();
    let (maxwell, norton) = (LawMaterial(&Maxwell), LawMaterial(&NortonHoff));
    let prony = Prony::new(2).unwrap();
    let cases: [(&dyn Material, Vec<f64>); 3] = [
        (&maxwell, vec![21000.0, 0.3, 25000.0]),
        (&norton, vec![1.1e5, 0.3, 1400.0, 5.5, 450.0]),
        (&prony, vec![2.1e4, 0.3, 0.3, 0.2, 0.2, 2.0]),
    ];
    for (law, c) in cases {
        let mut solver = DirectSolver::new(m).unwrap();
        let traj = solver.run_history(law, &c, &h, &opts(true)).unwrap();
        let n = traj.steps.len();
        let mut adj = Adjoint::new(m).unwrap();
        let sens = adj.sensitivities_load(law, &c, &traj, &h).unwrap();
        let depth_step: Vec<bool> = traj.steps.iter().map(|s| s.t <= 1.0 || s.t > 3.0).collect();
        let scale = |g: &[f64]| {
            g.iter()
                .zip(&c)
                .fold(0.0f64, |m, (g, c)| m.max((g * c).abs()))
        };
        // each depth-controlled step alone, then all with weights and a depth cost
        let mut cases: Vec<(Vec<f64>, Vec<f64>)> = (0..n)
            .filter(|&i| depth_step[i])
            .map(|i| {
                let mut f = vec![0.0; n];
                f[i] = 1.0;
                (vec![0.0; n], f)
            })
            .collect();
        let dj_df: Vec<f64> = (0..n)
            .map(|i| if depth_step[i] { 1.0 + i as f64 } else { 0.0 })
            .collect();
        let dj_dh: Vec<f64> = (0..n).map(|i| 100.0 * (i % 4) as f64).collect();
        cases.push((dj_dh.clone(), dj_df.clone()));
        for (dh, df) in &cases {
            let g = adj.gradient_load(law, &c, &traj, &h, dh, df).unwrap().dj_dc;
            let jt: Vec<f64> = (0..c.len())
                .map(|k| {
                    (0..n)
                        .map(|i| sens.df_dc[i][k] * df[i] + sens.dh_dc[i][k] * dh[i])
                        .sum()
                })
                .collect();
            // (steps out of contact: both zero)
            let s = scale(&jt).max(f64::MIN_POSITIVE);
            for k in 0..c.len() {
                let r = (g[k] - jt[k]).abs() * c[k].abs() / s;
                assert!(
                    r < 1e-8,
                    "{} param {k}: adjoint {} J^T w {} ({r:.2e})",
                    law.name(),
                    g[k],
                    jt[k]
                );
            }
        }
        // central differences of J = sum w_F F_i + sum w_h U_i
        let g = adj
            .gradient_load(law, &c, &traj, &h, &dj_dh, &dj_df)
            .unwrap()
            .dj_dc;
        let mut cost = |p: &[f64]| -> Result<f64, String> {
            let t = solver
                .run_history(law, p, &h, &opts(false))
                .map_err(|e| e.to_string())?;
            if t.steps.len() != n {
                return Err("another number of steps".into());
            }
            Ok(t.steps
                .iter()
                .enumerate()
                .map(|(i, s)| dj_df[i] * s.force + dj_dh[i] * s.depth)
                .sum())
        };
        let s = scale(&g);
        for k in 0..c.len() {
            let fd = central_difference(&mut cost, &c, k, 1e-6).unwrap();
            let r = (g[k] - fd).abs() * c[k].abs() / s;
            println!(
                "{} param {k}: adjoint {:.10e} fd {fd:.10e} ({r:.2e})",
                law.name(),
                g[k]
            );
            assert!(
                r < 1e-6,
                "{} param {k}: adjoint {} fd {fd} ({r:.2e})",
                law.name(),
                g[k]
            );
        }
    }
}
