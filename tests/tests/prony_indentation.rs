//! A Prony solid with one term (the standard linear solid) indented by a cone under depth
//! control against the exact solution of the time-discrete problem: Lee & Radok's
//! correspondence applied to the backward-Euler operator (docs/validation-laws.md,
//! "Prony under a cone"), the same construction as the Maxwell reference of
//! docs/validation-viscous.md §1-§3.
//!
//! ```text
//!   G(s) = G0 (s + (1-g) lambda) / (s + lambda),  lambda = 1/tau,  K(s) = K
//!   E*(s) = 4 G(s) (3K + G(s)) / (3K + 4 G(s))
//!   Psi(t) = A0 + A1 exp(-lambda t) + A2 exp(-mu t)                (E*(s) = s Psi_bar(s))
//!     A0 = 4 Ginf (3K + Ginf) / (3K + 4 Ginf),   Ginf = G0 (1 - g)
//!     A1 = G0 g
//!     A2 = 4 G0 N (3K D + G0 N) / (D (3K + 4 G0) s)  at s = -mu,  N = s + (1-g) lambda,  D = s + lambda
//!     mu = lambda (3K + 4 G0 (1-g)) / (3K + 4 G0)
//!   cone, contact growing or held:  F(t_n) = (2 tan(alpha)/pi) sum_j Psi_BE(n, j) (h_j^2 - h_{j-1}^2)
//! ```
//!
//! The law steps each branch by backward Euler, so with a constant step the discrete
//! operator is `E*(s)` with `s -> (1 - z^-1)/dt`, and its partial fractions are the
//! terms above each stepped by backward Euler (`Relaxation::backward_euler`): the
//! reference holds no time-discretization error. The elastic error of the mesh is divided
//! out as for Maxwell (an elastic run `[E, nu]`, the instantaneous response).

mod viscous;

use std::f64::consts::PI;

use indentify_contact::{
    DirectSolver, Model, Punch, Schedule, SolverOptions, StepRecord, Trajectory, trapezoid,
};
use indentify_laws::{Elastic, LawMaterial, Material, Prony};
use indentify_mesh::CylinderMesher;
use viscous::*;

/// The Prony term: `g` and `tau` (s).
const G1: f64 = 0.6;
const TAU1: f64 = 0.8;

/// The relaxation function of `E*` of a one-term Prony solid (module docs).
fn sls_indentation(e: f64, nu: f64, g: f64, tau: f64) -> Relaxation {
    let (g0, k) = shear_bulk(e, nu);
    let lambda = 1.0 / tau;
    let ginf = g0 * (1.0 - g);
    let a0 = 4.0 * ginf * (3.0 * k + ginf) / (3.0 * k + 4.0 * ginf);
    let a1 = g0 * g;
    let mu = lambda * (3.0 * k + 4.0 * g0 * (1.0 - g)) / (3.0 * k + 4.0 * g0);
    let s = -mu;
    let (n, d) = (s + (1.0 - g) * lambda, s + lambda);
    let a2 = 4.0 * g0 * n * (3.0 * k * d + g0 * n) / (d * (3.0 * k + 4.0 * g0) * s);
    Relaxation {
        terms: vec![(a0, 0.0), (a1, lambda), (a2, mu)],
    }
}

/// `E*(s)` of the one-term Prony solid in the Laplace domain, from `G(s)` directly.
fn sls_modulus_laplace(e: f64, nu: f64, g: f64, tau: f64, s: f64) -> f64 {
    let (g0, k) = shear_bulk(e, nu);
    let gs = g0 * ((1.0 - g) + g * s / (s + 1.0 / tau));
    4.0 * gs * (3.0 * k + gs) / (3.0 * k + 4.0 * gs)
}

/// The partial fractions invert the Laplace-domain modulus: `s Psi_bar(s) = E*(s)` to
/// 1e-13 over six decades of `s`, and `Psi(0) = E/(1 - nu^2)` (instantaneous), `Psi(inf)`
/// the relaxed modulus.
#[test]
fn sls_relaxation_function_inverts_the_laplace_modulus() {
    let psi = sls_indentation(E, NU, G1, TAU1);
    for k in -3..=3 {
        let s = 10f64.powi(k);
        let got = s * psi.laplace(s);
        let want = sls_modulus_laplace(E, NU, G1, TAU1, s);
        assert!(rel(got, want).abs() < 1e-13, "s = {s}: {got} vs {want}");
    }
    assert!(rel(psi.at(0.0), e_star(E, NU)).abs() < 1e-13);
    let (g0, k) = shear_bulk(E, NU);
    let ginf = g0 * (1.0 - G1);
    let relaxed = 4.0 * ginf * (3.0 * k + ginf) / (3.0 * k + 4.0 * ginf);
    assert!(rel(psi.at(1e6), relaxed).abs() < 1e-13);
}

fn run(mat: &dyn Material, c: &[f64], schedule: &Schedule, model: &Model) -> Trajectory {
    let mut solver = DirectSolver::new(model).unwrap();
    let opts = SolverOptions {
        record_fields: false,
        ..Default::default()
    };
    let t = solver.run(mat, c, schedule, &opts).unwrap();
    assert!(t.steps.iter().all(|s| s.on_schedule), "cut steps");
    t
}

fn at(traj: &Trajectory, n: usize) -> &StepRecord {
    &traj.steps[n - 1]
}

/// The solver's force of a one-term Prony solid under a cone (R1's mesh and trapezoid,
/// vertical contact) follows the backward-Euler Lee-Radok force within 2% from
/// `h >= h_max/3` to the end of the hold, after the elastic normalization at `h_max`
/// (within 0.5% with the elastic ratio at the same depth), and relaxes by more than 25%
/// during the hold (the check is not of an elastic response).
#[test]
fn sls_cone_follows_backward_euler_lee_radok() {
    let mesh = CylinderMesher {
        radius: 10.0,
        height: 10.0,
        nr: 20,
        nz: 20,
        grading_r: 1.3,
        grading_z: 1.3,
    }
    .build()
    .unwrap();
    let model = Model::new(
        mesh,
        Punch::Cone {
            half_angle_deg: ALPHA_DEG,
        },
    )
    .unwrap();
    let schedule = Schedule::from_segments(&trapezoid(H_MAX, 1.0, 1.0, 1.0, 30)).unwrap();
    let prony = Prony::new(1).unwrap();
    let visco = run(&prony, &[E, NU, G1, TAU1], &schedule, &model);
    let elastic = run(&LawMaterial(&Elastic), &[E, NU], &schedule, &model);
    let sneddon = |h: f64| 2.0 / PI * ALPHA_DEG.to_radians().tan() * e_star(E, NU) * h * h;
    let rho = at(&elastic, 30).force / sneddon(H_MAX);
    let psi = sls_indentation(E, NU, G1, TAU1);
    let reference = Hereditary {
        psi: &psi,
        t: &schedule.t,
        h: &schedule.depth,
        time: Time::BackwardEuler,
    };
    let (mut worst, mut worst_local) = (0.0f64, 0.0f64);
    for n in 1..=60 {
        let s = at(&visco, n);
        let (f_ref, _, t1) = reference.cone(n, ALPHA_DEG);
        assert_eq!(t1, schedule.t[n.min(30)], "Lee-Radok regime at step {n}");
        if s.depth >= H_MAX / 3.0 - 1e-12 {
            let e = rel(s.force, rho * f_ref);
            let el = at(&elastic, n.min(30));
            let local = el.force / sneddon(el.depth);
            let e_local = rel(s.force, local * f_ref);
            worst = worst.max(e.abs());
            worst_local = worst_local.max(e_local.abs());
            assert!(
                e.abs() < 0.02,
                "step {n}: F = {} vs {}",
                s.force,
                rho * f_ref
            );
            assert!(e_local.abs() < 0.005, "step {n}: {e_local}");
        }
    }
    let relaxed = 1.0 - at(&visco, 60).force / at(&visco, 30).force;
    println!(
        "SLS cone load+hold: rho = {rho:.5}; worst |F / (rho F_LR) - 1| = {:.3}%, same depth \
         {:.3}%; hold relaxation {:.1}%",
        100.0 * worst,
        100.0 * worst_local,
        100.0 * relaxed
    );
    assert!(relaxed > 0.25, "{relaxed}");
}
