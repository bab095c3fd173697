//! Exact properties of the discrete direct problem (P) with viscous laws: time scaling,
//! stress scaling (checked by finite differences on the solver), the Norton-Hoff law at
//! m = 1 without yield being Maxwell's, withdrawal past the loss of contact, and a run
//! repeated bit for bit by the same or a fresh solver.
//!
//! References: the paper's discrete scheme (§2.2, eqs. 41-46; docs/theory.md §1). With
//! backward Euler, step i solves `S (sigma_i - sigma_i-1) + dt_i g(sigma_i, c) = B (u_i -
//! u_i-1)` with contact on the depth `U_i`. Hence, exactly (up to the solver's tolerance):
//!
//! ```text
//!   time scaling    t -> s t, eta -> s eta (Maxwell), K -> s^(1/m) K (Norton-Hoff):
//!                   dt g is unchanged, so every F_i is unchanged;
//!   stress scaling  E, eta (and K, sY) -> s (E, eta, K, sY): every stress is multiplied by
//!                   s at the same displacements and active sets, so F_i(s c) = s F_i(c)
//!                   and, at s = 1 (Euler's identity for homogeneous functions),
//!                   E dF_i/dE + eta dF_i/deta = F_i   (+ K dF/dK + sY dF/dsY for Norton-Hoff);
//!   m = 1, sY = 0   g = x n = (s_eq/K) 3 s/(2 s_eq) = 3 s/(2K) = P sigma/eta with
//!                   eta = 2K/3: Norton-Hoff is Maxwell, step by step, for the whole
//!                   indentation.
//! ```
//!
//! The stress-scaling identity is checked here by central finite differences on the
//! direct solver, independently of the adjoint-based check in
//! crates/adjoint/tests/identities.rs.
//!
//! Goal: time scaling and the m = 1 identity to 1e-10 and 1e-9 of the peak force, the
//! homogeneity `F(s c) = s F(c)` to 1e-10, Euler's identity to 1e-6 at the best
//! finite-difference step; F = 0 (not an error) once the punch is withdrawn above the
//! surface.
//!
//! ```text
//!          cone 68 deg, trapezoid 0.1 mm (load / hold / unload), 10 steps per segment
//!                  \    /
//!   z = 0  o-o-oo\oo/oo-o--o----o         top: contact candidates
//!          |oooooooooo   graded 1.45      (the properties are exact on any mesh:
//!   axis   |o o o  o   o      o   |        a coarse one keeps the tests fast)
//!   z = -4 +----------------------+ r = 4 mm
//!          bottom: u_z = 0
//! ```
//!
//! Parameters: Maxwell R1 (E = 20000 MPa, nu = 0.3, eta = 30000 MPa s); Norton-Hoff R2
//! (E = 1e5 MPa, nu = 0.3, K = 1500 MPa s^(1/m), m = 5, sY = 500 MPa); 4 x 4 mm cylinder,
//! 10 x 10 Q8 graded 1.45, residual tolerance 1e-12.

use indentify_contact::{
    DirectSolver, Model, Punch, Schedule, Segment, SolverOptions, Trajectory, trapezoid,
};
use indentify_laws::{Law, Maxwell, NortonHoff};
use indentify_mesh::CylinderMesher;

/// R1's Maxwell parameters `[E, nu, eta]`.
const MAXWELL: [f64; 3] = [20000.0, 0.3, 30000.0];
/// R2's Norton-Hoff parameters `[E, nu, K, m, sY]`.
const NORTON_HOFF: [f64; 5] = [1e5, 0.3, 1500.0, 5.0, 500.0];
/// Maximum depth (mm).
const H_MAX: f64 = 0.1;

fn model() -> Model {
    let mesh = CylinderMesher {
        radius: 4.0,
        height: 4.0,
        nr: 10,
        nz: 10,
        grading_r: 1.45,
        grading_z: 1.45,
    }
    .build()
    .expect("valid mesh");
    Model::new(
        mesh,
        Punch::Cone {
            half_angle_deg: 68.0,
        },
    )
    .expect("valid model")
}

fn options() -> SolverOptions {
    SolverOptions {
        residual_tol: 1e-12,
        record_fields: false,
        ..SolverOptions::default()
    }
}

/// The trapezoid with all durations multiplied by `s`.
fn trapezoid_scaled(s: f64, steps: usize) -> Schedule {
    Schedule::from_segments(&trapezoid(H_MAX, s, s, s, steps)).expect("valid schedule")
}

/// Runs `law` with `c` on the shared model.
fn run(model: &Model, law: &dyn Law, c: &[f64], schedule: &Schedule) -> Trajectory {
    DirectSolver::new(model)
        .expect("symbolic analysis")
        .run(&indentify_laws::LawMaterial(law), c, schedule, &options())
        .expect("run converges")
}

/// `max_i |a_i - b_i| / max_i |b_i|` over the schedule forces.
fn force_difference(a: &Trajectory, b: &Trajectory) -> f64 {
    let (fa, fb) = (a.forces(), b.forces());
    assert_eq!(fa.len(), fb.len());
    let f_max = fb.iter().fold(0.0_f64, |m, f| m.max(f.abs()));
    fa.iter()
        .zip(&fb)
        .map(|(x, y)| (x - y).abs() / f_max)
        .fold(0.0, f64::max)
}

/// Active sets at the schedule times.
fn active_sets(t: &Trajectory) -> Vec<Vec<u32>> {
    t.schedule_steps().map(|s| s.active.clone()).collect()
}

/// The solver shall repeat a run bit for bit: the same solver run twice (its cached
/// element matrices and factorizations from the first run notwithstanding) and a fresh
/// solver give identical forces, active sets and fields, for a law solved by exact
/// (Maxwell: affine updates, capacitance solves) and by inexact Newton (Norton-Hoff:
/// CG preconditioned with earlier factorizations). The adjoint's replays rely on it.
#[test]
fn runs_repeat_bit_for_bit() {
    let model = model();
    let schedule = trapezoid_scaled(1.0, 10);
    let opts = SolverOptions {
        record_fields: true,
        ..options()
    };
    for (law, c) in [
        (&Maxwell as &dyn Law, &MAXWELL[..]),
        (&NortonHoff, &NORTON_HOFF[..]),
    ] {
        let mut solver = DirectSolver::new(&model).expect("symbolic analysis");
        let first = solver
            .run(&indentify_laws::LawMaterial(law), c, &schedule, &opts)
            .expect("run");
        let again = solver
            .run(&indentify_laws::LawMaterial(law), c, &schedule, &opts)
            .expect("run");
        let fresh = DirectSolver::new(&model)
            .expect("symbolic analysis")
            .run(&indentify_laws::LawMaterial(law), c, &schedule, &opts)
            .expect("run");
        for other in [&again, &fresh] {
            assert_eq!(first.forces(), other.forces(), "{}", law.name());
            assert_eq!(active_sets(&first), active_sets(other), "{}", law.name());
            assert_eq!(first.fields, other.fields, "{}", law.name());
        }
        if law.name() == "norton-hoff" {
            assert!(first.timing.cg_iterations > 0, "inexact solves were used");
            assert!(first.timing.factorizations < first.total_iterations() as usize);
        }
    }
}

/// The solver shall give the same forces and active sets when all durations and eta are
/// multiplied by the same factor (Maxwell), or the durations by s and K by s^(1/m)
/// (Norton-Hoff), to 1e-10 of the peak force.
#[test]
fn time_scaling_leaves_the_forces_unchanged() {
    let model = model();
    let base = trapezoid_scaled(1.0, 10);
    let f_mx = run(&model, &Maxwell, &MAXWELL, &base);
    let f_nh = run(&model, &NortonHoff, &NORTON_HOFF, &base);
    for s in [7.3, 0.043] {
        let schedule = trapezoid_scaled(s, 10);
        let [e, nu, eta] = MAXWELL;
        let mx = run(&model, &Maxwell, &[e, nu, s * eta], &schedule);
        let [e, nu, k, m, sy] = NORTON_HOFF;
        let nh = run(
            &model,
            &NortonHoff,
            &[e, nu, s.powf(1.0 / m) * k, m, sy],
            &schedule,
        );
        let (d_mx, d_nh) = (force_difference(&mx, &f_mx), force_difference(&nh, &f_nh));
        println!(
            "time scaling by {s}: max |dF| / F_max = {d_mx:.1e} (Maxwell), {d_nh:.1e} (Norton-Hoff)"
        );
        assert!(d_mx < 1e-10, "Maxwell, s = {s}: {d_mx:e}");
        assert!(d_nh < 1e-10, "Norton-Hoff, s = {s}: {d_nh:e}");
        assert_eq!(active_sets(&mx), active_sets(&f_mx), "Maxwell, s = {s}");
        assert_eq!(active_sets(&nh), active_sets(&f_nh), "Norton-Hoff, s = {s}");
    }
}

/// Stress-like parameters of each law: Maxwell E, eta; Norton-Hoff E, K, sY.
const MAXWELL_STRESS_LIKE: [usize; 2] = [0, 2];
const NORTON_HOFF_STRESS_LIKE: [usize; 3] = [0, 2, 4];

/// `max_i |sum_k c_k dF_i/dc_k - F_i| / F_max`, the derivatives by central differences
/// of relative step `delta` (`c_k dF/dc_k = (F(c_k (1+delta)) - F(c_k (1-delta))) / (2
/// delta)`); also whether every perturbed run kept the active sets of the base run.
fn euler_identity_error(
    model: &Model,
    law: &dyn Law,
    c: &[f64],
    stress_like: &[usize],
    schedule: &Schedule,
    base: &Trajectory,
    delta: f64,
) -> (f64, bool) {
    let f = base.forces();
    let f_max = f.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    let mut lhs = vec![0.0; f.len()];
    let mut same_sets = true;
    for &k in stress_like {
        let mut runs = [1.0 + delta, 1.0 - delta].map(|factor| {
            let mut cp = c.to_vec();
            cp[k] *= factor;
            run(model, law, &cp, schedule)
        });
        for r in &mut runs {
            same_sets &= active_sets(r) == active_sets(base);
        }
        let (fp, fm) = (runs[0].forces(), runs[1].forces());
        for i in 0..f.len() {
            lhs[i] += (fp[i] - fm[i]) / (2.0 * delta);
        }
    }
    let err = lhs
        .iter()
        .zip(&f)
        .map(|(l, x)| (l - x).abs() / f_max)
        .fold(0.0, f64::max);
    (err, same_sets)
}

/// Checks the homogeneity `F(s c) = s F(c)` (1e-10) and Euler's identity by central
/// differences (1e-6 at the best step) for `law` on the trapezoid.
fn check_stress_scaling(law: &dyn Law, c: &[f64], stress_like: &[usize]) {
    let model = model();
    let schedule = trapezoid_scaled(1.0, 10);
    let base = run(&model, law, c, &schedule);
    // homogeneity of degree 1
    let s = 3.7;
    let mut cs = c.to_vec();
    for &k in stress_like {
        cs[k] *= s;
    }
    let scaled = run(&model, law, &cs, &schedule);
    let f_max = base.forces().iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    let homogeneity = base
        .forces()
        .iter()
        .zip(scaled.forces())
        .map(|(f, fs)| (fs - s * f).abs() / (s * f_max))
        .fold(0.0, f64::max);
    assert!(homogeneity < 1e-10, "{}: {homogeneity:e}", law.name());
    assert_eq!(active_sets(&scaled), active_sets(&base), "{}", law.name());
    // Euler's identity by central differences: truncation ~ delta^2, noise ~ eps/delta
    let mut best = f64::INFINITY;
    let mut line = String::new();
    for delta in [1e-3, 1e-4, 1e-5, 1e-6] {
        let (err, same_sets) =
            euler_identity_error(&model, law, c, stress_like, &schedule, &base, delta);
        let note = if same_sets { "" } else { " (sets changed)" };
        line += &format!(" {delta:.0e}: {err:.1e}{note}");
        best = best.min(err);
    }
    println!(
        "{}: |F(s c) - s F(c)| / (s F_max) = {homogeneity:.1e}; Euler identity by FD, relative step:{line}",
        law.name()
    );
    assert!(best < 1e-6, "{}: best FD error {best:e}", law.name());
}

/// The solver shall satisfy, for Maxwell, the stress scaling `F_i(s E, nu, s eta) = s
/// F_i(E, nu, eta)` to 1e-10 and Euler's identity `E dF/dE + eta dF/deta = F` with the
/// derivatives by central finite differences on the solver, to 1e-6 of the peak force at
/// the best step.
#[test]
fn maxwell_stress_scaling_holds_by_finite_differences() {
    check_stress_scaling(&Maxwell, &MAXWELL, &MAXWELL_STRESS_LIKE);
}

/// The solver shall satisfy, for Norton-Hoff, the stress scaling of (E, K, sY) to 1e-10
/// and Euler's identity `E dF/dE + K dF/dK + sY dF/dsY = F` by central finite differences
/// on the solver, to 1e-6 of the peak force at the best step.
#[test]
fn norton_hoff_stress_scaling_holds_by_finite_differences() {
    check_stress_scaling(&NortonHoff, &NORTON_HOFF, &NORTON_HOFF_STRESS_LIKE);
}

/// The solver shall give, with Norton-Hoff at m = 1 and sY = 0, the same forces and active
/// sets as Maxwell with eta = 2K/3 over R1's whole indentation history, to 1e-9 of the
/// peak force.
#[test]
fn norton_hoff_with_m_one_is_maxwell() {
    let model = model();
    let schedule = trapezoid_scaled(1.0, 30);
    let [e, nu, eta] = MAXWELL;
    let mx = run(&model, &Maxwell, &MAXWELL, &schedule);
    let nh = run(
        &model,
        &NortonHoff,
        &[e, nu, 1.5 * eta, 1.0, 0.0],
        &schedule,
    );
    let d = force_difference(&nh, &mx);
    println!(
        "Norton-Hoff (m = 1, sY = 0, K = 3 eta/2) vs Maxwell: max |dF| / F_max = {d:.1e} over {} steps",
        schedule.n_steps()
    );
    assert!(d < 1e-9, "{d:e}");
    assert_eq!(active_sets(&nh), active_sets(&mx));
}

/// The solver shall withdraw the punch past the loss of contact without error for the
/// viscous laws, with zero force and no active node once the punch is above the surface
/// and no tensile force at any time.
#[test]
fn withdrawing_past_contact_loss_gives_zero_force() {
    let model = model();
    let schedule = Schedule::from_segments(&[
        Segment {
            duration: 1.0,
            depth: H_MAX,
            steps: 10,
        },
        Segment {
            duration: 1.0,
            depth: -0.05,
            steps: 10,
        },
    ])
    .expect("valid schedule");
    let cases: [(&dyn Law, &[f64]); 2] = [(&Maxwell, &MAXWELL), (&NortonHoff, &NORTON_HOFF)];
    for (law, c) in cases {
        let traj = run(&model, law, c, &schedule);
        assert_eq!(traj.schedule_steps().count(), 20, "{}", law.name());
        let mut lifted = 0;
        let mut lost_at = None;
        for s in traj.schedule_steps() {
            assert!(
                s.force >= 0.0,
                "{}: tensile force at t = {}",
                law.name(),
                s.t
            );
            if s.active.is_empty() {
                lost_at.get_or_insert(s.depth);
            }
            if s.depth < 0.0 {
                lifted += 1;
                assert_eq!(s.force, 0.0, "{}: depth {}", law.name(), s.depth);
                assert!(
                    s.active.is_empty(),
                    "{}: depth {}: {:?}",
                    law.name(),
                    s.depth,
                    s.active
                );
            }
        }
        assert!(lifted >= 3);
        println!(
            "{}: contact lost at depth {:.3} mm on the way out; F = 0 over the {lifted} steps above the surface",
            law.name(),
            lost_at.expect("contact lost")
        );
    }
}
