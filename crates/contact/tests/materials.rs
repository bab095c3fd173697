//! The solver with materials that carry internal variables (`Material` without a
//! stress-only `Law`): J2 plasticity with Norton overstress and no hardening is the
//! Norton-Hoff law of R2 (docs/theory.md §11) in force; a rate-independent law holds its
//! force while the depth is held and leaves a residual imprint; the internal variables
//! are recorded, checkpointed and replayed bit for bit; a failed local update cuts the
//! step and says where; under finite strain the same Norton-Hoff agreement holds.

mod common;

use common::testkit::cylinder;
use indentify_contact::{
    ContactError, ContactKind, DirectSolver, Kinematics, Model, Punch, Schedule, SolverOptions,
    trapezoid,
};
use indentify_laws::law::LocalFailure;
use indentify_laws::material::{InternalInfo, MaterialUpdate, Step};
use indentify_laws::{
    Hardening, LawMaterial, Material, NortonHoff, ParamInfo, Plastic, Prony, Rate, Regime, Vec4,
};
use indentify_mesh::CylinderMesher;

fn model(kind: ContactKind) -> Model {
    let mesh = cylinder(4.0, 14, 1.3);
    Model::with_contact(
        mesh,
        Punch::Cone {
            half_angle_deg: 68.0,
        },
        kind,
    )
    .unwrap()
}

fn schedule(steps: usize) -> Schedule {
    Schedule::from_segments(&trapezoid(0.1, 1.0, 1.0, 1.0, steps)).unwrap()
}

/// R2's Norton-Hoff parameters `[E, nu, K, m, sY]`.
const R2: [f64; 5] = [1e5, 0.3, 1500.0, 5.0, 500.0];

/// `Plastic(Linear(H: 0), Norton(K, m))` solves the same scalar equation as Norton-Hoff
/// at every Gauss point: the forces of R2's load-hold-unload agree within 1e-8 relative
/// (of the peak force) under vertical and under frictionless normal contact.
#[test]
fn norton_plastic_without_hardening_is_norton_hoff() {
    let pl = Plastic::new(Hardening::Linear, Rate::Norton);
    let c_pl = [R2[0], R2[1], R2[4], 0.0, R2[2], R2[3]];
    for kind in [ContactKind::Vertical, ContactKind::Normal] {
        let m = model(kind);
        let mut solver = DirectSolver::new(&m).unwrap();
        let opts = SolverOptions::default();
        let nh = solver
            .run(&LawMaterial(&NortonHoff), &R2, &schedule(10), &opts)
            .unwrap();
        let got = solver.run(&pl, &c_pl, &schedule(10), &opts).unwrap();
        let (fa, fb) = (nh.forces(), got.forces());
        assert_eq!(fa.len(), fb.len());
        let peak = fa.iter().fold(0.0f64, |s, f| s.max(f.abs()));
        assert!(peak > 0.0);
        let worst = fa
            .iter()
            .zip(&fb)
            .map(|(a, b)| (a - b).abs() / peak)
            .fold(0.0, f64::max);
        println!("{kind:?}: peak {peak:.6e} N, worst relative difference {worst:.2e}");
        assert!(worst < 1e-8, "{kind:?}: {worst:e}");
        // the plastic law records p at every Gauss point; the law none
        let last = got.fields.last().unwrap();
        assert_eq!(last.alpha.len(), m.disc.n_qp());
        assert!(last.alpha.iter().all(|&p| p >= 0.0) && last.alpha.iter().any(|&p| p > 0.0));
        assert!(nh.fields.last().unwrap().alpha.is_empty());
    }
}

/// Rate-independent J2 with linear hardening under depth control: while the depth is
/// held nothing moves (the force of every hold step equals the peak's to 1e-10), the
/// unloaded surface keeps a plastic imprint (the force reaches zero before the depth
/// does), and points are recorded on both branches.
#[test]
fn rate_independent_plasticity_holds_and_leaves_an_imprint() {
    let pl = Plastic::new(Hardening::Linear, Rate::Independent);
    let c = [1e5, 0.3, 500.0, 2000.0];
    let m = model(ContactKind::Normal);
    let mut solver = DirectSolver::new(&m).unwrap();
    let t = solver
        .run(&pl, &c, &schedule(10), &SolverOptions::default())
        .unwrap();
    let f = t.forces();
    let peak = f[10];
    for (i, fi) in f.iter().enumerate().take(21).skip(10) {
        assert!(
            (fi - peak).abs() <= 1e-10 * peak,
            "hold step {i}: {fi} vs {peak}"
        );
    }
    // the imprint: the punch leaves the surface before the depth returns to 0
    let leaves = t
        .schedule_steps()
        .position(|s| s.active.is_empty() && s.t > 2.0)
        .expect("the punch leaves the surface while unloading");
    let rec = t.schedule_steps().nth(leaves).unwrap();
    println!(
        "contact lost at depth {:.4} mm (peak force {peak:.4} N)",
        rec.depth
    );
    assert!(rec.depth > 0.01, "{}", rec.depth);
    let at_peak = &t.fields[10];
    assert!(at_peak.regime.contains(&Regime::Plastic));
    assert!(at_peak.regime.contains(&Regime::Elastic));
}

/// A run saved at checkpoints replays its internal variables bit for bit (a Norton
/// plastic law's `p`, a two-term Prony solid's viscous strains).
#[test]
fn checkpoints_replay_internal_variables() {
    let pl = Plastic::new(Hardening::Power, Rate::Norton);
    let prony = Prony::new(2).unwrap();
    let nh = LawMaterial(&NortonHoff);
    let cases: [(&dyn Material, Vec<f64>); 3] = [
        (&nh, R2.to_vec()),
        (&pl, vec![1e5, 0.3, 500.0, 0.2, 1500.0, 5.0]),
        (&prony, vec![1e5, 0.3, 0.3, 0.2, 0.2, 2.0]),
    ];
    let m = model(ContactKind::Normal);
    let mut solver = DirectSolver::new(&m).unwrap();
    let s = schedule(6);
    for (mat, c) in cases {
        let full = solver.run(mat, &c, &s, &SolverOptions::default()).unwrap();
        // a run with checkpoints starts each stretch from a fresh factorization: the same
        // forces as the plain run to round-off, and its replays repeat it bit for bit
        let opts = SolverOptions {
            checkpoint_every: 5,
            ..Default::default()
        };
        let ck = solver.run(mat, &c, &s, &opts).unwrap();
        let peak = full.forces().iter().fold(0.0f64, |a, f| a.max(f.abs()));
        for (a, b) in full.forces().iter().zip(ck.forces()) {
            assert!((a - b).abs() <= 1e-10 * peak, "{}: {a} vs {b}", mat.name());
        }
        assert!(ck.checkpoints.len() >= 4);
        // (up to the next checkpoint, as the adjoint replays)
        let (cp, next) = (&ck.checkpoints[2], ck.checkpoints[3].schedule_index);
        let seg = solver.replay(mat, &c, &s, &opts, cp, next).unwrap();
        assert!(seg.fields.len() > 3);
        for (k, f) in seg.fields.iter().enumerate() {
            let g = &ck.fields[cp.steps_done + k];
            assert_eq!(f.u, g.u, "{} field {k}", mat.name());
            assert_eq!(f.alpha, g.alpha, "{} field {k}", mat.name());
            assert_eq!(f.regime, g.regime);
        }
        let n = mat.n_internal();
        assert_eq!(full.fields.last().unwrap().alpha.len(), n * m.disc.n_qp());
        if n == 0 {
            continue;
        }
        assert!(
            full.fields[12].alpha.iter().any(|&a| a != 0.0),
            "{}",
            mat.name()
        );
    }
}

/// A plastic law whose local update refuses every step longer than `max_dt` (s).
#[derive(Debug)]
struct Fussy {
    inner: Plastic,
    max_dt: f64,
}

impl Material for Fussy {
    fn name(&self) -> &'static str {
        "fussy"
    }
    fn params(&self) -> &[ParamInfo] {
        self.inner.params()
    }
    fn internal(&self) -> &[InternalInfo] {
        self.inner.internal()
    }
    fn residual(&self, c: &[f64], step: &Step<'_>, r: &mut [f64]) {
        self.inner.residual(c, step, r)
    }
    fn jac_state(&self, c: &[f64], step: &Step<'_>, out: &mut [f64]) {
        self.inner.jac_state(c, step, out)
    }
    fn jac_previous(&self, c: &[f64], step: &Step<'_>, out: &mut [f64]) {
        self.inner.jac_previous(c, step, out)
    }
    fn jac_params(&self, c: &[f64], step: &Step<'_>, out: &mut [f64]) {
        self.inner.jac_params(c, step, out)
    }
    fn update(
        &self,
        c: &[f64],
        y0: &[f64],
        deps: &Vec4,
        dt: f64,
        y1: &mut [f64],
    ) -> Result<MaterialUpdate, LocalFailure> {
        if dt > self.max_dt && deps.max_abs() > 0.0 {
            return Err(LocalFailure {
                reason: format!("step {dt} s too long"),
                suggested_dt_factor: 0.5,
            });
        }
        self.inner.update(c, y0, deps, dt, y1)
    }
}

/// A local update that fails cuts the step (the run then converges in sub-steps); with no
/// cuts allowed the run fails naming the Gauss point and element, and keeps its converged
/// part.
#[test]
fn failed_local_update_cuts_the_step_and_says_where() {
    let fussy = Fussy {
        inner: Plastic::new(Hardening::Linear, Rate::Independent),
        max_dt: 0.06,
    };
    let c = [1e5, 0.3, 500.0, 2000.0];
    let m = model(ContactKind::Vertical);
    let mut solver = DirectSolver::new(&m).unwrap();
    let t = solver
        .run(&fussy, &c, &schedule(10), &SolverOptions::default())
        .unwrap();
    assert!(t.steps.iter().any(|s| !s.on_schedule));
    assert_eq!(t.forces().len(), 31);
    let opts = SolverOptions {
        max_cuts: 0,
        ..Default::default()
    };
    match solver.run(&fussy, &c, &schedule(10), &opts) {
        Err(ContactError::StepFailed {
            reason, partial, ..
        }) => {
            println!("{reason}");
            assert!(reason.contains("Gauss point") && reason.contains("element"));
            assert!(reason.contains("too long"), "{reason}");
            assert!(partial.steps.is_empty() || partial.steps.iter().all(|s| s.force.is_finite()));
        }
        other => panic!("expected a step failure, got {other:?}"),
    }
}

/// Under finite strain (Hencky space) too, `Plastic(Linear(H: 0), Norton(K, m))` is
/// R2's Norton-Hoff in force (1e-8 relative of the peak), frictionless and with
/// Coulomb friction (mu = 0.15), and records `p`.
#[test]
fn finite_strain_norton_plastic_is_norton_hoff() {
    let pl = Plastic::new(Hardening::Linear, Rate::Norton);
    let c_pl = [R2[0], R2[1], R2[4], 0.0, R2[2], R2[3]];
    for kind in [
        ContactKind::Normal,
        ContactKind::normal_with_friction(0.15).unwrap(),
    ] {
        let m = model(kind).with_kinematics(Kinematics::Finite).unwrap();
        let mut solver = DirectSolver::new(&m).unwrap();
        let opts = SolverOptions::default();
        let nh = solver
            .run(&LawMaterial(&NortonHoff), &R2, &schedule(8), &opts)
            .unwrap();
        let got = solver.run(&pl, &c_pl, &schedule(8), &opts).unwrap();
        let (fa, fb) = (nh.forces(), got.forces());
        let peak = fa.iter().fold(0.0f64, |s, f| s.max(f.abs()));
        let worst = fa
            .iter()
            .zip(&fb)
            .map(|(a, b)| (a - b).abs() / peak)
            .fold(0.0, f64::max);
        println!("finite {kind:?}: peak {peak:.6e} N, worst relative difference {worst:.2e}");
        assert!(worst < 1e-8, "{kind:?}: {worst:e}");
        assert!(got.fields.last().unwrap().alpha.iter().any(|&p| p > 0.0));
    }
}

/// Rate-independent J2 (linear hardening) on R2's mesh and history (docs/theory.md §11:
/// the reference mesh, cone 68 deg, trapezoid of 30 steps per segment): Newton reaches
/// every schedule step without a cut. Before the backtracking of a material whose
/// residual switches branches, the full update across an elastic/plastic switch cycled
/// at a relative residual of 1 until the iteration limit (100 steps, 10 of them from
/// cuts, 334 factorizations for 90 schedule steps).
#[test]
fn rate_independent_plasticity_needs_no_step_cuts_on_r2() {
    let mesh = CylinderMesher::REFERENCE.build().unwrap();
    let m = Model::with_contact(
        mesh,
        Punch::Cone {
            half_angle_deg: 68.0,
        },
        ContactKind::Vertical,
    )
    .unwrap();
    let schedule = Schedule::from_segments(&trapezoid(0.1, 1.0, 1.0, 1.0, 30)).unwrap();
    let j2 = Plastic::new(Hardening::Linear, Rate::Independent);
    let mut solver = DirectSolver::new(&m).unwrap();
    let traj = solver
        .run(
            &j2,
            &[1e5, 0.3, 500.0, 1000.0],
            &schedule,
            &SolverOptions::default(),
        )
        .unwrap();
    println!(
        "{} steps, {} iterations, {}",
        traj.steps.len(),
        traj.total_iterations(),
        traj.timing
    );
    assert_eq!(traj.steps.len(), 90, "a step was cut");
    assert!(traj.steps.iter().all(|s| s.iterations <= 20));
    // the run is plastic: a residual imprint after unloading
    let last = traj.fields.last().unwrap();
    assert!(last.alpha.iter().any(|&p| p > 0.0));
}
