//! The Gauss-point sensitivity pass solves the parameters' systems of a step in one pass
//! over the factor (`SparseCholesky::solve_multi_with`, docs/performance.md): every column
//! is the same bits as with the parameters solved one after the other
//! (`Adjoint::set_multi_solve(false)`, the pass as it was), for Norton-Hoff under vertical
//! contact, frictionless normal contact (frames), Coulomb friction (ties to the previous
//! step, slipping rows' Woodbury correction), finite strain, every parameter or a subset,
//! on one thread and on a pool of two.

mod common;

use common::sphere_model as model;
use indentify_adjoint::Adjoint;
use indentify_contact::{
    ContactKind, DirectSolver, Kinematics, Model, Schedule, SolverOptions, trapezoid,
};
use indentify_laws::{LawMaterial, NortonHoff};

const NH: [f64; 5] = [1e5, 0.3, 1500.0, 5.0, 500.0];

fn bits(rows: &[Vec<f64>]) -> Vec<Vec<u64>> {
    rows.iter()
        .map(|r| r.iter().map(|v| v.to_bits()).collect())
        .collect()
}

/// The columns of `columns` (every parameter for `None`) with the parameters solved
/// together and one after the other, on this thread and on a pool of two threads.
fn same_bits(m: &Model, columns: Option<&[usize]>) {
    let mat = LawMaterial(&NortonHoff);
    let schedule = Schedule::from_segments(&trapezoid(0.1, 1.0, 1.0, 1.0, 5)).unwrap();
    let opts = SolverOptions {
        residual_tol: 1e-12,
        ..Default::default()
    };
    let t = DirectSolver::new(m)
        .unwrap()
        .run(&mat, &NH, &schedule, &opts)
        .unwrap();
    let pass = |multi: bool| {
        let mut adj = Adjoint::new(m).unwrap();
        adj.set_multi_solve(multi);
        let s = match columns {
            None => adj.sensitivities(&mat, &NH, &t),
            Some(cols) => adj.sensitivities_of(&mat, &NH, &t, cols),
        }
        .unwrap();
        assert_eq!(adj.last_pass_multi_solve(), multi, "the path asked for");
        s.df_dc
    };
    let one = pass(false);
    let together = pass(true);
    assert_eq!(bits(&one), bits(&together));
    // the columns compared are not trivially zero
    let n_nonzero = (0..NH.len())
        .filter(|&k| one.iter().any(|r| r[k] != 0.0))
        .count();
    assert!(n_nonzero >= columns.map_or(NH.len() - 1, |c| c.len()));
    // on a pool's worker the parameters' right-hand sides and remainders run in parallel
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    let (one2, together2) = pool.install(|| (pass(false), pass(true)));
    assert_eq!(bits(&one), bits(&one2));
    assert_eq!(bits(&one), bits(&together2));
}

#[test]
fn vertical_contact_columns_are_the_same_bits() {
    let m = model(ContactKind::Vertical, Kinematics::Small);
    same_bits(&m, Some(&[0, 2, 3, 4]));
    same_bits(&m, Some(&[4, 0]));
}

#[test]
fn normal_contact_columns_are_the_same_bits() {
    let m = model(ContactKind::Normal, Kinematics::Small);
    same_bits(&m, None);
}

#[test]
fn friction_columns_are_the_same_bits() {
    let m = model(
        ContactKind::normal_with_friction(0.2).unwrap(),
        Kinematics::Small,
    );
    same_bits(&m, Some(&[0, 2, 3, 4]));
}

#[test]
fn finite_strain_columns_are_the_same_bits() {
    let m = model(ContactKind::Normal, Kinematics::Finite);
    same_bits(&m, Some(&[0, 2, 3, 4]));
}
