//! Laws with internal variables under load control (docs/theory.md §12-13): the adjoint
//! of the bordered system swept through the material's blocks
//! (`Adjoint::gradient_load` with a `Material`, regime held) against central
//! differences of the direct solver's own load-controlled runs, over a sphere
//! load-hold-unload with frictionless normal contact, small and finite strain: J2 with
//! power-law hardening and Norton overstress, rate-independent J2 with linear hardening
//! and a two-term Prony solid, and a mixed depth/load/depth history; the forward
//! sensitivities (`sensitivities_load`) give the adjoint's gradient and their depth rows
//! agree with differences; a Prony solid with Coulomb friction.

mod common;

use common::{finite_model, small_model};
use indentify_adjoint::Adjoint;
use indentify_adjoint::check::{central_difference, relative_difference};
use indentify_contact::{ContactKind, DirectSolver, LoadHistory, Model, SolverOptions, Trajectory};
use indentify_laws::{Hardening, Material, Plastic, Prony, Rate};
use indentify_testkit::{depth, force, force_lhu as lhu, recording, sphere1 as sphere, weights};

fn opts(record: bool) -> SolverOptions {
    recording(record, 1e-12)
}

fn run(solver: &mut DirectSolver, mat: &dyn Material, c: &[f64], h: &LoadHistory) -> Trajectory {
    solver.run_history(mat, c, h, &opts(true)).unwrap()
}

/// Adjoint vs central differences of the depth cost `J = sum w_i U_i` (the depth is the
/// observable, as in a load-controlled fit: `dJ/dF = 0`) and vs the forward
/// sensitivities; returns the worst difference relative to the largest `|dJ/dc_k c_k|`.
fn check(m: &Model, mat: &dyn Material, c: &[f64], h: &LoadHistory, h_rel: f64) -> f64 {
    let mut solver = DirectSolver::new(m).unwrap();
    let traj = run(&mut solver, mat, c, h);
    let n = traj.steps.len();
    let w = weights(n);
    let mut adj = Adjoint::new(m).unwrap();
    let g = adj
        .gradient_load(mat, c, &traj, h, &w, &vec![0.0; n])
        .unwrap();
    let big = g
        .dj_dc
        .iter()
        .zip(c)
        .fold(0.0f64, |a, (g, c)| a.max((g * c).abs()));
    assert!(
        big > 0.0,
        "{}: a zero gradient cannot be checked",
        mat.name()
    );
    // the forward sensitivities give the same gradient
    let sens = adj.sensitivities_load(mat, c, &traj, h).unwrap();
    for k in 0..c.len() {
        let jt: f64 = (0..n).map(|i| w[i] * sens.dh_dc[i][k]).sum();
        let d = (jt - g.dj_dc[k]).abs() * c[k].abs() / big;
        assert!(
            d < 1e-9,
            "{} {k}: J^T w {jt} vs adjoint {} ({d:.2e})",
            mat.name(),
            g.dj_dc[k]
        );
    }
    let mut worst: f64 = 0.0;
    for k in 0..c.len() {
        let fd = central_difference(
            |p: &[f64]| -> Result<f64, String> {
                let t = solver
                    .run_history(mat, p, h, &opts(false))
                    .map_err(|e| e.to_string())?;
                assert_eq!(t.steps.len(), n, "a cut changed the steps");
                Ok(t.steps.iter().zip(&w).map(|(s, w)| w * s.depth).sum())
            },
            c,
            k,
            h_rel,
        )
        .unwrap();
        let rel = (fd - g.dj_dc[k]).abs() * c[k].abs() / big;
        println!(
            "{} {}: adjoint {:.10e}, fd {fd:.10e}, rel {rel:.2e} (plain {:.2e})",
            mat.name(),
            mat.params()[k].name,
            g.dj_dc[k],
            relative_difference(g.dj_dc[k], fd)
        );
        worst = worst.max(rel);
    }
    worst
}

const POWER_NORTON: [f64; 6] = [1e5, 0.3, 500.0, 0.2, 1500.0, 5.0];
const LINEAR: [f64; 4] = [1e5, 0.3, 500.0, 2000.0];
const PRONY: [f64; 6] = [1e5, 0.3, 0.3, 0.2, 0.2, 2.0];

#[test]
fn plastic_power_norton_small_and_finite_strain() {
    let pl = Plastic::new(Hardening::Power, Rate::Norton);
    let h = lhu(600.0, 6);
    let m = small_model(sphere(), ContactKind::Normal);
    let w = check(&m, &pl, &POWER_NORTON, &h, 1e-6);
    assert!(w < 1e-6, "small strain {w:.2e}");
    let m = finite_model(sphere());
    let w = check(&m, &pl, &POWER_NORTON, &h, 1e-6);
    assert!(w < 1e-6, "finite strain {w:.2e}");
}

/// Rate independent: the elastic/plastic partition held, FD steps small enough not to
/// flip a point.
#[test]
fn plastic_linear_rate_independent_small_and_finite_strain() {
    let pl = Plastic::new(Hardening::Linear, Rate::Independent);
    let h = lhu(600.0, 6);
    let m = small_model(sphere(), ContactKind::Normal);
    let w = check(&m, &pl, &LINEAR, &h, 1e-6);
    assert!(w < 1e-5, "small strain {w:.2e}");
    let m = finite_model(sphere());
    let w = check(&m, &pl, &LINEAR, &h, 1e-6);
    assert!(w < 1e-5, "finite strain {w:.2e}");
}

/// Two-term Prony solid: the hold creeps.
#[test]
fn prony_two_terms_small_and_finite_strain() {
    let p = Prony::new(2).unwrap();
    let h = lhu(600.0, 6);
    let m = small_model(sphere(), ContactKind::Normal);
    let mut solver = DirectSolver::new(&m).unwrap();
    let t = run(&mut solver, &p, &PRONY, &h);
    let hold: Vec<f64> = t
        .steps
        .iter()
        .filter(|s| s.t > 1.0 + 1e-9 && s.t <= 2.0 + 1e-9)
        .map(|s| s.depth)
        .collect();
    assert!(
        hold.last().unwrap() > &(hold[0] * 1.01),
        "the hold creeps: {hold:?}"
    );
    let w = check(&m, &p, &PRONY, &h, 1e-6);
    assert!(w < 1e-6, "small strain {w:.2e}");
    let m = finite_model(sphere());
    let w = check(&m, &p, &PRONY, &h, 1e-6);
    assert!(w < 1e-6, "finite strain {w:.2e}");
}

/// Depth control, then load control (from the depth-controlled step's force), then
/// depth control again (from the load-controlled step's depth).
#[test]
fn mixed_history_with_internal_variables() {
    let m = small_model(sphere(), ContactKind::Normal);
    let h = LoadHistory::from_segments(&[
        depth(1.0, 0.03, 4),
        force(1.0, 600.0, 6),
        force(1.0, 600.0, 4),
        depth(1.0, 0.03, 5),
    ])
    .unwrap();
    let p = Prony::new(2).unwrap();
    let w = check(&m, &p, &PRONY, &h, 1e-6);
    assert!(w < 1e-6, "prony {w:.2e}");
    let pl = Plastic::new(Hardening::Power, Rate::Norton);
    let w = check(&m, &pl, &POWER_NORTON, &h, 1e-6);
    assert!(w < 1e-6, "plastic {w:.2e}");
}

/// Coulomb friction under load control (docs/theory.md §13; more cases in
/// `gradient_load_friction.rs`): a two-term Prony solid's gradient against central
/// differences and the sensitivities.
#[test]
fn coulomb_friction_prony() {
    let kind = ContactKind::normal_with_friction(0.2).unwrap();
    let m = small_model(sphere(), kind);
    let p = Prony::new(2).unwrap();
    let w = check(&m, &p, &PRONY, &lhu(1500.0, 6), 1e-6);
    assert!(w < 1e-6, "prony with friction {w:.2e}");
}
