//! The whole-history gradient check shared by the adjoint's test files: the adjoint
//! against central differences of the direct solver's own cost, against the forward
//! sensitivities (`J^T rho`), and the checkpointed adjoint against the recorded one;
//! with Coulomb friction, the same with the finite-difference rule that every step's
//! contact set and stick/slip statuses of the +-h runs equal the base run's.

use indentify_adjoint::check::{central_difference, relative_difference};
use indentify_adjoint::{Adjoint, Gradient, Replay};
use indentify_contact::{
    ContactKind, DirectSolver, Kinematics, Model, Punch, Schedule, SolverOptions, Trajectory,
    trapezoid,
};
use indentify_laws::{Law, Material};
use indentify_testkit::{small_cylinder, weights};

/// The gradient of the run of `solver` with `ck_opts` (checkpointed), replayed segment by
/// segment from its checkpoints.
#[allow(dead_code)]
pub fn checkpointed_gradient(
    adj: &mut Adjoint,
    solver: &mut DirectSolver,
    law: &dyn Law,
    c: &[f64],
    sched: &Schedule,
    ck_opts: &SolverOptions,
    rho: &[f64],
) -> Gradient {
    let ck = solver
        .run(&indentify_laws::LawMaterial(law), c, sched, ck_opts)
        .unwrap();
    adj.gradient_replayed(
        &indentify_laws::LawMaterial(law),
        c,
        &ck,
        rho,
        Replay {
            solver,
            schedule: sched,
            opts: ck_opts,
        },
    )
    .unwrap()
}

/// The finite-strain test model: a 4 x 4 mm cylinder, 8 x 8 Q8 graded 1.45 towards the
/// axis and the top, frictionless normal contact with `punch`, `Kinematics::Finite`.
#[allow(dead_code)]
pub fn finite_model(punch: Punch) -> Model {
    finite_model_with_friction(punch, 0.0)
}

/// [`finite_model`] with Coulomb friction `mu` (frictionless `Normal` for `mu = 0`).
#[allow(dead_code)]
pub fn finite_model_with_friction(punch: Punch, mu: f64) -> Model {
    let kind = ContactKind::normal_with_friction(mu).unwrap();
    small_model(punch, kind)
        .with_kinematics(Kinematics::Finite)
        .unwrap()
}

/// The test cylinder (4 x 4 mm, 8 x 8 Q8 graded 1.45 towards the axis and the top) under
/// `punch` with contact `kind`, small strain.
#[allow(dead_code)]
pub fn small_model(punch: Punch, kind: ContactKind) -> Model {
    let mesh = small_cylinder();
    Model::with_contact(mesh, punch, kind).unwrap()
}

/// The test cylinder under the 1 mm sphere with contact `kind` and kinematics `kin`.
#[allow(dead_code)]
pub fn sphere_model(kind: ContactKind, kin: Kinematics) -> Model {
    Model::with_contact(small_cylinder(), Punch::Sphere { radius: 1.0 }, kind)
        .unwrap()
        .with_kinematics(kin)
        .unwrap()
}

/// The trapezoid 0 -> 0.1 mm -> hold -> 0, 1 s and 5 steps per segment.
#[allow(dead_code)]
pub fn trapezoid5() -> Schedule {
    Schedule::from_segments(&trapezoid(0.1, 1.0, 1.0, 1.0, 5)).unwrap()
}

/// Newton to a residual of 1e-12, the other solver options at their defaults.
#[allow(dead_code)]
pub fn tight_opts() -> SolverOptions {
    SolverOptions {
        residual_tol: 1e-12,
        ..Default::default()
    }
}

/// The forces of every step of `mat` at `c` with `c[k]` shifted by `s`, on `m` over
/// [`trapezoid5`] with [`tight_opts`]: one side of a central difference of the forces.
#[allow(dead_code)]
pub fn shifted_forces(m: &Model, mat: &dyn Material, c: &[f64], k: usize, s: f64) -> Vec<f64> {
    let mut c = c.to_vec();
    c[k] += s;
    DirectSolver::new(m)
        .unwrap()
        .run(mat, &c, &trapezoid5(), &tight_opts())
        .unwrap()
        .steps
        .iter()
        .map(|s| s.force)
        .collect()
}

/// `J = sum_i w_i F_i` of a run that must have `n` steps (a cut would change them), with
/// the weights of `indentify_testkit::weights`.
#[allow(dead_code)]
pub fn weighted_forces(t: &Trajectory, n: usize) -> f64 {
    assert_eq!(t.steps.len(), n, "a cut changed the steps");
    t.steps
        .iter()
        .zip(weights(n))
        .map(|(s, w)| w * s.force)
        .sum()
}

/// On `model`, the trapezoid 0 -> 0.1 mm -> hold -> 0 in `steps` steps per segment with
/// the data simulated at `truth`: adjoint vs central differences (1e-6), vs `J^T rho`
/// (`sens_tol`), and the checkpointed adjoint vs the recorded one (1e-10) at `c`, for the
/// first `checked` parameters (a parameter on its bound, sY = 0, has no central
/// difference); the contact zone must grow and be lost. Returns the worst relative
/// differences (fd, sensitivities).
#[allow(dead_code)]
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
    whole_history_check_on(model, law, truth, c, checked, &sched, sens_tol)
}

/// [`whole_history_check`] over any schedule `sched` (which must load into contact and
/// release it), e.g. one whose steps are solved in sub-steps.
#[allow(dead_code)]
pub fn whole_history_check_on(
    model: &Model,
    law: &dyn Law,
    truth: &[f64],
    c: &[f64],
    checked: usize,
    sched: &Schedule,
    sens_tol: f64,
) -> (f64, f64) {
    let sched = sched.clone();
    let opts = SolverOptions {
        residual_tol: 1e-12,
        ..Default::default()
    };
    let mut solver = DirectSolver::new(model).unwrap();
    let data: Vec<f64> = solver
        .run(&indentify_laws::LawMaterial(law), truth, &sched, &opts)
        .unwrap()
        .forces();
    let mut cost = |p: &[f64]| -> Result<f64, String> {
        let t = solver
            .run(&indentify_laws::LawMaterial(law), p, &sched, &opts)
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
    let traj = solver
        .run(&indentify_laws::LawMaterial(law), c, &sched, &opts)
        .unwrap();
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
    let g = adj
        .gradient(&indentify_laws::LawMaterial(law), c, &traj, &rho)
        .unwrap();
    let sens = adj
        .sensitivities(&indentify_laws::LawMaterial(law), c, &traj)
        .unwrap();
    let jt = sens.transpose_mul(&rho);
    // the same gradient from a checkpointed run replayed segment by segment
    let ck_opts = SolverOptions {
        record_fields: false,
        checkpoint_every: 5,
        ..opts.clone()
    };
    let g_ck = checkpointed_gradient(&mut adj, &mut solver, law, c, &sched, &ck_opts, &rho);
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

/// Each step's active set and stick/slip statuses.
#[allow(dead_code)]
pub type Statuses = Vec<(Vec<u32>, Vec<i8>)>;

#[allow(dead_code)]
pub fn statuses(traj: &Trajectory) -> Statuses {
    traj.steps
        .iter()
        .map(|s| (s.active.clone(), s.slip.clone()))
        .collect()
}

/// Worst relative differences of one case: adjoint vs finite differences, vs `J^T rho`.
/// and the sticking and slipping node-steps (off the axis) of the base run.
#[allow(dead_code)]
#[derive(Default)]
pub struct Outcome {
    pub fd: f64,
    pub sens: f64,
    pub stick: usize,
    pub slip: usize,
}

impl Outcome {
    #[allow(dead_code)]
    pub fn add(&mut self, o: Outcome) {
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
    #[allow(dead_code)]
    pub fn assert_stick_and_slip(&self) {
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

/// With friction, on `model`: the trapezoid 0 -> 0.1 mm -> hold -> 0.02 mm in `steps`
/// steps per segment with the data simulated at `truth`; adjoint vs central differences
/// (1e-6), vs J^T rho (1e-10), and the checkpointed adjoint vs the recorded one (1e-10),
/// for the first `checked` parameters (a parameter on its bound, sY = 0, has no central
/// difference); the +-h runs must have the base run's active sets and statuses at every
/// step (the step size is the largest of 1e-5, 1e-6, 1e-7 relative for which they do).
#[allow(dead_code)]
pub fn friction_history_check(
    model: &Model,
    law: &dyn Law,
    truth: &[f64],
    c: &[f64],
    checked: usize,
    steps: usize,
) -> Outcome {
    // unloading stops at 0.02 mm: at zero depth the axis node's contact is borderline
    // (zero reaction), and its status flips under any perturbation
    let mut segments = trapezoid(0.1, 1.0, 1.0, 1.0, steps);
    segments[2].depth = 0.02;
    let sched = Schedule::from_segments(&segments).unwrap();
    let opts = SolverOptions {
        residual_tol: 1e-12,
        ..Default::default()
    };
    let mut solver = DirectSolver::new(model).unwrap();
    let data: Vec<f64> = solver
        .run(&indentify_laws::LawMaterial(law), truth, &sched, &opts)
        .unwrap()
        .forces();
    let traj = solver
        .run(&indentify_laws::LawMaterial(law), c, &sched, &opts)
        .unwrap();
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
                solver
                    .run(&indentify_laws::LawMaterial(law), &p, &sched, &opts)
                    .unwrap()
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
    let mut adj = Adjoint::new(model).unwrap();
    let g = adj
        .gradient(&indentify_laws::LawMaterial(law), c, &traj, &rho)
        .unwrap();
    let sens = adj
        .sensitivities(&indentify_laws::LawMaterial(law), c, &traj)
        .unwrap();
    let jt = sens.transpose_mul(&rho);
    // the same gradient from a checkpointed run replayed segment by segment
    let ck_opts = SolverOptions {
        record_fields: false,
        checkpoint_every: 5,
        ..opts.clone()
    };
    let g_ck = checkpointed_gradient(&mut adj, &mut solver, law, c, &sched, &ck_opts, &rho);
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

/// A law's friction gradient check: its truth and start, how many parameters have central
/// differences, and its two (punch, mu) runs (a cone of 68 degrees, a sphere of 1 mm).
#[allow(dead_code)]
#[derive(Clone, Copy, Debug)]
pub enum FrictionCase {
    /// Elastic, cone mu = 0.1, sphere mu = 0.2: stick points make even elasticity history
    /// dependent.
    Elastic,
    /// Maxwell, cone mu = 0.2, sphere mu = 0.1.
    Maxwell,
    /// Norton-Hoff with yield (sY > 0), cone mu = 0.1, sphere mu = 0.2.
    NortonHoffYield,
    /// Norton-Hoff without yield (sY = 0; on its bound, no central difference), cone and
    /// sphere mu = 0.2 (with 0.1 on the sphere nearly every node slips).
    NortonHoffNoYield,
}

/// [`friction_history_check`] of `case` on the models `model(punch, mu)` in `steps` steps
/// per segment, both runs, with stick and slip node-steps asserted over the two.
#[allow(dead_code)]
pub fn friction_law_check(
    case: FrictionCase,
    model: impl Fn(indentify_contact::Punch, f64) -> Model,
    steps: usize,
) {
    use indentify_contact::Punch;
    use indentify_laws::{Elastic, Maxwell, NortonHoff};
    let cone = || Punch::Cone {
        half_angle_deg: 68.0,
    };
    let sphere = || Punch::Sphere { radius: 1.0 };
    let nh_truth = |sy: f64| vec![1e5, 0.3, 1500.0, 5.0, sy];
    let nh_start = |sy: f64| vec![1.2e5, 0.31, 1300.0, 4.0, sy];
    let (law, truth, start, checked, runs): (&dyn Law, Vec<f64>, Vec<f64>, usize, _) = match case {
        FrictionCase::Elastic => (
            &Elastic,
            vec![20000.0, 0.3],
            vec![17000.0, 0.27],
            2,
            [(cone(), 0.1), (sphere(), 0.2)],
        ),
        FrictionCase::Maxwell => (
            &Maxwell,
            vec![20000.0, 0.3, 30000.0],
            vec![15000.0, 0.28, 45000.0],
            3,
            [(cone(), 0.2), (sphere(), 0.1)],
        ),
        FrictionCase::NortonHoffYield => (
            &NortonHoff,
            nh_truth(500.0),
            nh_start(420.0),
            5,
            [(cone(), 0.1), (sphere(), 0.2)],
        ),
        FrictionCase::NortonHoffNoYield => (
            &NortonHoff,
            nh_truth(0.0),
            nh_start(0.0),
            4,
            [(cone(), 0.2), (sphere(), 0.2)],
        ),
    };
    let mut all = Outcome::default();
    for (punch, mu) in runs {
        all.add(friction_history_check(
            &model(punch, mu),
            law,
            &truth,
            &start,
            checked,
            steps,
        ));
    }
    all.assert_stick_and_slip();
}

/// A Prony solid of one to three terms and its parameters: `E = 1e5` MPa, `nu = 0.3` and
/// the terms `(g, tau)` `(0.3, 0.2 s)`, `(0.2, 2 s)`, `(0.1, 0.05 s)` (the bench's
/// parameters on R2 and a fast third term).
#[allow(dead_code)]
pub fn prony(n: usize) -> (indentify_laws::Prony, Vec<f64>) {
    let terms = [(0.3, 0.2), (0.2, 2.0), (0.1, 0.05)];
    let mut c = vec![1e5, 0.3];
    for &(g, tau) in &terms[..n] {
        c.extend([g, tau]);
    }
    (indentify_laws::Prony::new(n).unwrap(), c)
}

/// The largest difference between two tables of columns (`[row][column]`), each
/// relative to the column's largest entry in `a` (a column zero in `a` must be zero in
/// `b`: its largest entry in `b` counts).
#[allow(dead_code)]
pub fn column_rel(a: &[Vec<f64>], b: &[Vec<f64>]) -> f64 {
    let np = a.first().map_or(0, Vec::len);
    (0..np).fold(0.0f64, |m, k| {
        let scale = a.iter().fold(0.0f64, |s, r| s.max(r[k].abs()));
        if scale == 0.0 {
            return m.max(b.iter().fold(0.0f64, |s, r| s.max(r[k].abs())));
        }
        a.iter()
            .zip(b)
            .fold(m, |m, (x, y)| m.max((x[k] - y[k]).abs() / scale))
    })
}
