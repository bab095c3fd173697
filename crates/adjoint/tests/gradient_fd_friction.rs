//! Adjoint gradients and forward sensitivities with Coulomb friction
//! (`ContactKind::NormalFriction`: sticking nodes tied to the previous step's stick
//! point, slipping rows unsymmetric) against central finite differences of the
//! whole-history cost, over load-hold-unload histories with the contact zone growing and
//! shrinking and both sticking and slipping node-steps, for elastic, Maxwell and
//! Norton-Hoff (sY = 0 and > 0), cone and sphere, mu = 0.1 and 0.2.
//!
//! The rule for finite differences with friction: the cost is differentiable only where
//! no step's contact set or stick/slip partition changes under the perturbation. Every
//! check compares each step's active set and statuses of the +h and -h runs with the base
//! run and asserts that they match (the step size is chosen among 1e-5, 1e-6, 1e-7
//! relative, the largest for which they do); a check across a status flip would not be
//! meaningful.
//!
//! Mesh: 4 x 4 mm cylinder, 10 x 10 Q8 graded 1.45 towards axis and top; 0 -> 0.1 mm ->
//! hold -> 0.02 mm, 1 s and 8 steps per segment (as `gradient_fd_normal.rs`, whose
//! unloading to 0 ends with the axis node borderline: with friction its status flips
//! under any perturbation of nu).

use indentify_adjoint::Adjoint;
use indentify_adjoint::check::relative_difference;
use indentify_contact::{
    ContactKind, DirectSolver, Model, Punch, Schedule, SolverOptions, Trajectory, trapezoid,
};
use indentify_laws::{Elastic, Law, Maxwell, NortonHoff};
use indentify_mesh::CylinderMesher;

fn model(punch: Punch, mu: f64) -> Model {
    let mesh = CylinderMesher {
        radius: 4.0,
        height: 4.0,
        nr: 10,
        nz: 10,
        grading_r: 1.45,
        grading_z: 1.45,
    }
    .build()
    .unwrap();
    let kind = ContactKind::normal_with_friction(mu).unwrap();
    Model::with_contact(mesh, punch, kind).unwrap()
}

fn cone() -> Punch {
    Punch::Cone {
        half_angle_deg: 68.0,
    }
}

fn sphere() -> Punch {
    Punch::Sphere { radius: 1.0 }
}

/// Each step's active set and stick/slip statuses.
type Statuses = Vec<(Vec<u32>, Vec<i8>)>;

fn statuses(traj: &Trajectory) -> Statuses {
    traj.steps
        .iter()
        .map(|s| (s.active.clone(), s.slip.clone()))
        .collect()
}

/// Worst relative differences of one case: adjoint vs finite differences, vs `J^T rho`.
/// and the sticking and slipping node-steps (off the axis) of the base run.
#[derive(Default)]
struct Outcome {
    fd: f64,
    sens: f64,
    stick: usize,
    slip: usize,
}

impl Outcome {
    fn add(&mut self, o: Outcome) {
        println!(
            "worst: fd {:.1e}, sens {:.1e}; stick {}, slip {} node-steps",
            o.fd, o.sens, o.stick, o.slip
        );
        self.fd = self.fd.max(o.fd);
        self.sens = self.sens.max(o.sens);
        self.stick += o.stick;
        self.slip += o.slip;
    }

    /// Both statuses were exercised.
    fn assert_stick_and_slip(&self) {
        println!(
            "all cases: worst fd {:.1e}, sens {:.1e}; stick {}, slip {} node-steps",
            self.fd, self.sens, self.stick, self.slip
        );
        assert!(
            self.stick >= 10 && self.slip >= 10,
            "stick {}, slip {} node-steps",
            self.stick,
            self.slip
        );
    }
}

/// Adjoint vs central differences (1e-6), vs J^T rho (1e-10), and the checkpointed
/// adjoint vs the recorded one (1e-10), for the first `checked` parameters (a parameter
/// on its bound, sY = 0, has no central difference); the +-h runs must have the base
/// run's active sets and statuses at every step.
fn check_gradient(
    punch: Punch,
    mu: f64,
    law: &dyn Law,
    truth: &[f64],
    c: &[f64],
    checked: usize,
) -> Outcome {
    let model = model(punch, mu);
    // unloading stops at 0.02 mm: at zero depth the axis node's contact is borderline
    // (zero reaction), and its status flips under any perturbation
    let mut segments = trapezoid(0.1, 1.0, 1.0, 1.0, 8);
    segments[2].depth = 0.02;
    let sched = Schedule::from_segments(&segments).unwrap();
    let opts = SolverOptions {
        residual_tol: 1e-12,
        ..Default::default()
    };
    let mut solver = DirectSolver::new(&model).unwrap();
    let data: Vec<f64> = solver
        .run(&model, law, truth, &sched, &opts)
        .unwrap()
        .forces();
    let traj = solver.run(&model, law, c, &sched, &opts).unwrap();
    let base = statuses(&traj);
    // the contact zone grows, holds and is lost; sticking and slipping node-steps
    let sizes: Vec<usize> = traj.steps.iter().map(|s| s.active.len()).collect();
    let most = *sizes.iter().max().unwrap();
    assert!(most >= 3 && *sizes.last().unwrap() < most, "{sizes:?}");
    let (mut stick, mut slip) = (0, 0);
    for s in &traj.steps {
        for (&k, &st) in s.active.iter().zip(&s.slip) {
            if model.candidate_r(k as usize) > 0.0 {
                if st == 0 {
                    stick += 1;
                } else {
                    slip += 1;
                }
            }
        }
    }
    let cost_of = |t: &Trajectory| -> f64 {
        0.5 * t
            .forces()
            .iter()
            .zip(&data)
            .map(|(f, d)| (f - d).powi(2))
            .sum::<f64>()
    };
    // central differences with the statuses of the base run held
    let mut fd = Vec::new();
    for k in 0..checked {
        let mut found = None;
        for h_rel in [1e-5, 1e-6, 1e-7] {
            let h = if c[k] == 0.0 {
                h_rel
            } else {
                h_rel * c[k].abs()
            };
            let mut run = |x: f64| {
                let mut p = c.to_vec();
                p[k] = x;
                solver.run(&model, law, &p, &sched, &opts).unwrap()
            };
            let (tp, tm) = (run(c[k] + h), run(c[k] - h));
            if statuses(&tp) == base && statuses(&tm) == base {
                found = Some(((cost_of(&tp) - cost_of(&tm)) / (2.0 * h), h_rel));
                break;
            }
            for (name, t) in [("+h", &tp), ("-h", &tm)] {
                let st = statuses(t);
                if st.len() != base.len() {
                    println!("  {name}: {} steps, base {}", st.len(), base.len());
                }
                for (i, (a, b)) in st.iter().zip(&base).enumerate() {
                    if a != b {
                        println!("  {name}: step {i}: {a:?} vs base {b:?}");
                    }
                }
            }
            println!("parameter {k}: h = {h_rel:e} flips a status; trying a smaller one");
        }
        let (d, h_rel) = found.expect("no step size keeps every status of the base run");
        println!("parameter {k}: h = {h_rel:e} keeps every status");
        fd.push(d);
    }
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
    let mut adj = Adjoint::new(&model).unwrap();
    let g = adj.gradient(&model, law, c, &traj, &rho).unwrap();
    let sens = adj.sensitivities(&model, law, c, &traj).unwrap();
    let jt = sens.transpose_mul(&rho);
    // the same gradient from a checkpointed run replayed segment by segment
    let ck_opts = SolverOptions {
        record_fields: false,
        checkpoint_every: 5,
        ..opts.clone()
    };
    let ck = solver.run(&model, law, c, &sched, &ck_opts).unwrap();
    let g_ck = adj
        .gradient_replayed(&model, law, c, &ck, &rho, &mut solver, &sched, &ck_opts)
        .unwrap();
    let mut out = Outcome {
        stick,
        slip,
        ..Outcome::default()
    };
    println!("stick {stick}, slip {slip} node-steps; active per step {sizes:?}");
    for k in 0..checked {
        let name = law.params()[k].name;
        let (rf, rs) = (
            relative_difference(g.dj_dc[k], fd[k]),
            relative_difference(g.dj_dc[k], jt[k]),
        );
        println!(
            "{name}: adjoint={:.12e} fd={:.12e} sens={:.12e} | rel fd {rf:.1e} sens {rs:.1e}",
            g.dj_dc[k], fd[k], jt[k],
        );
        assert!(rf < 1e-6, "{name}: {rf:e} vs finite differences");
        assert!(rs < 1e-10, "{name}: {rs:e} vs the sensitivities");
        assert!(
            relative_difference(g.dj_dc[k], g_ck.dj_dc[k]) < 1e-10,
            "{name}"
        );
        out.fd = out.fd.max(rf);
        out.sens = out.sens.max(rs);
    }
    out
}

/// The adjoint shall differentiate an elastic cost with friction (cone mu = 0.1, sphere
/// mu = 0.2): stick points make even elasticity history dependent.
#[test]
fn elastic_with_friction() {
    let mut all = Outcome::default();
    let (t, c) = ([20000.0, 0.3], [17000.0, 0.27]);
    for (punch, mu) in [(cone(), 0.1), (sphere(), 0.2)] {
        all.add(check_gradient(punch, mu, &Elastic, &t, &c, 2));
    }
    all.assert_stick_and_slip();
}

/// The adjoint shall differentiate a Maxwell cost with friction (cone mu = 0.2, sphere
/// mu = 0.1).
#[test]
fn maxwell_with_friction() {
    let mut all = Outcome::default();
    let (t, c) = ([20000.0, 0.3, 30000.0], [15000.0, 0.28, 45000.0]);
    for (punch, mu) in [(cone(), 0.2), (sphere(), 0.1)] {
        all.add(check_gradient(punch, mu, &Maxwell, &t, &c, 3));
    }
    all.assert_stick_and_slip();
}

/// The adjoint shall differentiate a Norton-Hoff cost with yield (sY > 0) with friction
/// (cone mu = 0.1, sphere mu = 0.2).
#[test]
fn norton_hoff_with_yield_with_friction() {
    let mut all = Outcome::default();
    let t = [1e5, 0.3, 1500.0, 5.0, 500.0];
    let c = [1.2e5, 0.31, 1300.0, 4.0, 420.0];
    for (punch, mu) in [(cone(), 0.1), (sphere(), 0.2)] {
        all.add(check_gradient(punch, mu, &NortonHoff, &t, &c, 5));
    }
    all.assert_stick_and_slip();
}

/// The adjoint shall differentiate a Norton-Hoff cost without yield (sY = 0) with
/// friction (cone and sphere, mu = 0.2: with 0.1 on the sphere nearly every node slips).
#[test]
fn norton_hoff_without_yield_with_friction() {
    let mut all = Outcome::default();
    let t = [1e5, 0.3, 1500.0, 5.0, 0.0];
    let c = [1.2e5, 0.31, 1300.0, 4.0, 0.0];
    for (punch, mu) in [(cone(), 0.2), (sphere(), 0.2)] {
        all.add(check_gradient(punch, mu, &NortonHoff, &t, &c, 4));
    }
    all.assert_stick_and_slip();
}
