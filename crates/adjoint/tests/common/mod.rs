//! The whole-history gradient check shared by the adjoint's test files: the adjoint
//! against central differences of the direct solver's own cost, against the forward
//! sensitivities (`J^T rho`), and the checkpointed adjoint against the recorded one.

use indentify_adjoint::Adjoint;
use indentify_adjoint::check::{central_difference, relative_difference};
use indentify_contact::{DirectSolver, Model, Schedule, SolverOptions, trapezoid};
use indentify_laws::Law;

/// On `model`, the trapezoid 0 -> 0.1 mm -> hold -> 0 in `steps` steps per segment with
/// the data simulated at `truth`: adjoint vs central differences (1e-6), vs `J^T rho`
/// (`sens_tol`), and the checkpointed adjoint vs the recorded one (1e-10) at `c`, for the
/// first `checked` parameters (a parameter on its bound, sY = 0, has no central
/// difference); the contact zone must grow and be lost. Returns the worst relative
/// differences (fd, sensitivities).
#[allow(clippy::too_many_arguments)]
pub fn whole_history_check(
    model: &Model,
    law: &dyn Law,
    truth: &[f64],
    c: &[f64],
    checked: usize,
    steps: usize,
    sens_tol: f64,
) -> (f64, f64) {
    let sched = Schedule::from_segments(&trapezoid(0.1, 1.0, 1.0, 1.0, steps)).unwrap();
    let opts = SolverOptions {
        residual_tol: 1e-12,
        ..Default::default()
    };
    let mut solver = DirectSolver::new(model).unwrap();
    let data: Vec<f64> = solver
        .run(model, law, truth, &sched, &opts)
        .unwrap()
        .forces();
    let mut cost = |p: &[f64]| -> Result<f64, String> {
        let t = solver
            .run(model, law, p, &sched, &opts)
            .map_err(|e| e.to_string())?;
        Ok(0.5
            * t.forces()
                .iter()
                .zip(&data)
                .map(|(f, d)| (f - d).powi(2))
                .sum::<f64>())
    };
    let fd: Vec<f64> = (0..checked)
        .map(|k| central_difference(&mut cost, c, k, 1e-5).unwrap())
        .collect();
    let mut solver = DirectSolver::new(model).unwrap();
    let traj = solver.run(model, law, c, &sched, &opts).unwrap();
    // the contact zone grows, holds and is lost
    let sizes: Vec<usize> = traj.steps.iter().map(|s| s.active.len()).collect();
    let most = *sizes.iter().max().unwrap();
    assert!(most >= 3 && *sizes.last().unwrap() < most, "{sizes:?}");
    let rho: Vec<f64> = traj
        .steps
        .iter()
        .map(|s| {
            if s.on_schedule {
                s.force - data[s.schedule_index]
            } else {
                0.0
            }
        })
        .collect();
    let mut adj = Adjoint::new(model).unwrap();
    let g = adj.gradient(model, law, c, &traj, &rho).unwrap();
    let sens = adj.sensitivities(model, law, c, &traj).unwrap();
    let jt = sens.transpose_mul(&rho);
    // the same gradient from a checkpointed run replayed segment by segment
    let ck_opts = SolverOptions {
        record_fields: false,
        checkpoint_every: 5,
        ..opts.clone()
    };
    let ck = solver.run(model, law, c, &sched, &ck_opts).unwrap();
    let g_ck = adj
        .gradient_replayed(model, law, c, &ck, &rho, &mut solver, &sched, &ck_opts)
        .unwrap();
    let (mut worst_fd, mut worst_sens) = (0.0f64, 0.0f64);
    for k in 0..checked {
        let name = law.params()[k].name;
        let (rf, rs) = (
            relative_difference(g.dj_dc[k], fd[k]),
            relative_difference(g.dj_dc[k], jt[k]),
        );
        println!(
            "{} {name}: adjoint={:.12e} fd={:.12e} sens={:.12e} | rel fd {rf:.1e} sens {rs:.1e}",
            law.name(),
            g.dj_dc[k],
            fd[k],
            jt[k],
        );
        assert!(rf < 1e-6, "{name}: adjoint {} vs fd {}", g.dj_dc[k], fd[k]);
        assert!(
            rs < sens_tol,
            "{name}: adjoint {} vs J^T rho {}",
            g.dj_dc[k],
            jt[k]
        );
        assert!(
            relative_difference(g.dj_dc[k], g_ck.dj_dc[k]) < 1e-10,
            "{name}: recorded {} vs replayed {}",
            g.dj_dc[k],
            g_ck.dj_dc[k]
        );
        worst_fd = worst_fd.max(rf);
        worst_sens = worst_sens.max(rs);
    }
    (worst_fd, worst_sens)
}
