//! Schedules whose steps are solved in sub-steps (`Schedule::with_substeps`, what
//! `data.substeps` of a measured record sets): the forward solve equals the run over a
//! schedule with the sub-steps' times inserted as points, the cost sees the schedule's
//! points only, and the adjoint (which transposes the sub-steps as it transposes the
//! sub-steps of a cut step) stays exact: against central differences of the direct
//! solver's own cost, against `J^T rho`, and replayed from checkpoints.
//!
//! Model: finite strain, frictionless normal contact (what measured data default to),
//! Norton-Hoff with yield, cone and sphere; 4 x 4 mm cylinder, 8 x 8 Q8 graded 1.45;
//! trapezoid 0 -> 0.1 mm -> hold -> 0 in 4 steps per segment, sub-steps 1 to 3 per step.

use indentify_adjoint::Adjoint;
use indentify_adjoint::check::{central_difference, relative_difference};
use indentify_contact::{
    ContactKind, DirectSolver, Kinematics, Model, Punch, Schedule, SolverOptions, trapezoid,
};
use indentify_laws::{Law, NortonHoff};
use indentify_mesh::CylinderMesher;

fn model(punch: Punch) -> Model {
    let mesh = CylinderMesher {
        radius: 4.0,
        height: 4.0,
        nr: 8,
        nz: 8,
        grading_r: 1.45,
        grading_z: 1.45,
    }
    .build()
    .unwrap();
    Model::with_contact(mesh, punch, ContactKind::Normal)
        .unwrap()
        .with_kinematics(Kinematics::Finite)
        .unwrap()
}

/// The trapezoid's 12 steps with uneven sub-steps (more in the loading, none in places).
fn schedule() -> Schedule {
    Schedule::from_segments(&trapezoid(0.1, 1.0, 1.0, 1.0, 4))
        .unwrap()
        .with_substeps(vec![3, 2, 2, 1, 2, 1, 1, 3, 1, 2, 2, 1])
        .unwrap()
}

/// The schedule with every sub-step's end inserted as a point (no sub-steps), and where
/// the original points are in it.
fn inserted(s: &Schedule) -> (Schedule, Vec<usize>) {
    let (mut t, mut d, mut at) = (vec![s.t[0]], vec![s.depth[0]], vec![0]);
    for j in 1..=s.n_steps() {
        for tk in s.step_targets(j) {
            t.push(tk);
            d.push(s.depth_at(tk));
        }
        at.push(t.len() - 1);
    }
    (Schedule::from_record(&t, &d).unwrap(), at)
}

fn opts() -> SolverOptions {
    SolverOptions {
        residual_tol: 1e-12,
        ..Default::default()
    }
}

/// Sub-steps are the inserted points' run: the same forces at the schedule's points
/// (1e-9), as many recorded steps, the schedule's points marked on them.
#[test]
fn substeps_solve_the_schedule_with_the_points_inserted() {
    let law = NortonHoff;
    let c = [1e5, 0.3, 1500.0, 5.0, 500.0];
    for punch in [
        Punch::Cone {
            half_angle_deg: 68.0,
        },
        Punch::Sphere { radius: 1.0 },
    ] {
        let m = model(punch);
        let s = schedule();
        let (fine, at) = inserted(&s);
        let mut solver = DirectSolver::new(&m).unwrap();
        let traj = solver.run(&m, &law, &c, &s, &opts()).unwrap();
        let reference = solver.run(&m, &law, &c, &fine, &opts()).unwrap();
        // one recorded step per sub-step (and per cut, the same in both runs)
        assert!(traj.steps.len() >= s.n_solver_steps());
        assert_eq!(traj.steps.len(), reference.steps.len());
        assert_eq!(s.n_solver_steps(), fine.n_steps());
        assert_eq!(traj.schedule_steps().count(), s.n_steps());
        let (f, f_ref) = (traj.forces(), reference.forces());
        assert_eq!(f.len(), s.t.len());
        let f_max = f.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        for (j, &i) in at.iter().enumerate() {
            assert!(
                (f[j] - f_ref[i]).abs() <= 1e-9 * f_max,
                "point {j}: {} vs {} with the points inserted",
                f[j],
                f_ref[i]
            );
        }
        // and they are not the forces without sub-steps (the test can tell)
        let plain = Schedule {
            substeps: Vec::new(),
            ..s.clone()
        };
        let f_plain = solver.run(&m, &law, &c, &plain, &opts()).unwrap().forces();
        let moved = f
            .iter()
            .zip(&f_plain)
            .fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
        assert!(moved > 1e-4 * f_max, "sub-steps changed nothing: {moved}");
    }
}

/// The adjoint through sub-steps: vs central differences of the cost at the schedule's
/// points (1e-6), vs `J^T rho` (1e-10), recorded vs replayed from checkpoints (1e-10).
#[test]
fn the_adjoint_through_substeps_matches_finite_differences() {
    let law = NortonHoff;
    let truth = [1e5, 0.3, 1500.0, 5.0, 500.0];
    let c = [1.2e5, 0.31, 1300.0, 4.0, 420.0];
    for punch in [
        Punch::Cone {
            half_angle_deg: 68.0,
        },
        Punch::Sphere { radius: 1.0 },
    ] {
        let m = model(punch);
        let s = schedule();
        let opts = opts();
        let mut solver = DirectSolver::new(&m).unwrap();
        let data = solver.run(&m, &law, &truth, &s, &opts).unwrap().forces();
        let mut cost = |p: &[f64]| -> Result<f64, String> {
            let t = solver
                .run(&m, &law, p, &s, &opts)
                .map_err(|e| e.to_string())?;
            Ok(0.5
                * t.forces()
                    .iter()
                    .zip(&data)
                    .map(|(f, d)| (f - d).powi(2))
                    .sum::<f64>())
        };
        let fd: Vec<f64> = (0..5)
            .map(|k| central_difference(&mut cost, &c, k, 1e-5).unwrap())
            .collect();
        let mut solver = DirectSolver::new(&m).unwrap();
        let traj = solver.run(&m, &law, &c, &s, &opts).unwrap();
        assert!(traj.steps.len() >= s.n_solver_steps());
        let rho: Vec<f64> = traj
            .steps
            .iter()
            .map(|st| {
                if st.on_schedule {
                    st.force - data[st.schedule_index]
                } else {
                    0.0
                }
            })
            .collect();
        let mut adj = Adjoint::new(&m).unwrap();
        let g = adj.gradient(&m, &law, &c, &traj, &rho).unwrap();
        let jt = adj
            .sensitivities(&m, &law, &c, &traj)
            .unwrap()
            .transpose_mul(&rho);
        let ck_opts = SolverOptions {
            record_fields: false,
            checkpoint_every: 5,
            ..opts.clone()
        };
        let ck = solver.run(&m, &law, &c, &s, &ck_opts).unwrap();
        let g_ck = adj
            .gradient_replayed(&m, &law, &c, &ck, &rho, &mut solver, &s, &ck_opts)
            .unwrap();
        for k in 0..5 {
            let name = law.params()[k].name;
            let (rf, rs, rc) = (
                relative_difference(g.dj_dc[k], fd[k]),
                relative_difference(g.dj_dc[k], jt[k]),
                relative_difference(g.dj_dc[k], g_ck.dj_dc[k]),
            );
            println!(
                "{name}: adjoint {:.12e} fd {:.12e} | rel fd {rf:.1e} sens {rs:.1e} replay {rc:.1e}",
                g.dj_dc[k], fd[k]
            );
            assert!(rf < 1e-6, "{name}: adjoint {} vs fd {}", g.dj_dc[k], fd[k]);
            assert!(
                rs < 1e-10,
                "{name}: adjoint {} vs J^T rho {}",
                g.dj_dc[k],
                jt[k]
            );
            assert!(rc < 1e-10, "{name}: recorded vs replayed {}", g_ck.dj_dc[k]);
        }
    }
}
