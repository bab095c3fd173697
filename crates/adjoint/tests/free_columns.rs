//! The forward sensitivities of a subset of the parameters (`Adjoint::sensitivities_of`,
//! what an identification asks for its free parameters) against those of every parameter
//! (`Adjoint::sensitivities`, checked against central differences in `gradient_fd*.rs`):
//! the columns formed are the same bits, the others exactly zero, for a stress-only law
//! (Norton-Hoff, small and finite strain, frictionless and with Coulomb friction, whose
//! sensitivities tie each step to the previous one) and a law with internal variables
//! (J2 with power hardening and Norton overstress, the block recursion). One column is
//! also checked against central differences of the forces directly.

mod common;

use common::{shifted_forces, sphere_model as model, tight_opts as opts, trapezoid5 as schedule};
use indentify_adjoint::{Adjoint, AdjointError};
use indentify_contact::{ContactKind, DirectSolver, Kinematics, Model};
use indentify_laws::{Hardening, LawMaterial, Material, NortonHoff, Plastic, Rate};

/// Runs `mat` at `c` on `m`, then compares the sensitivities of `columns` with every
/// parameter's; returns the full sensitivities' rows.
fn same_bits(m: &Model, mat: &dyn Material, c: &[f64], columns: &[usize]) -> Vec<Vec<f64>> {
    let t = DirectSolver::new(m)
        .unwrap()
        .run(mat, c, &schedule(), &opts())
        .unwrap();
    let mut adj = Adjoint::new(m).unwrap();
    let full = adj.sensitivities(mat, c, &t).unwrap();
    let part = adj.sensitivities_of(mat, c, &t, columns).unwrap();
    // and the full pass again after a partial one: the workspace keeps no mask
    let again = adj.sensitivities(mat, c, &t).unwrap();
    assert_eq!(full.df_dc, again.df_dc);
    assert_eq!(full.df_dc.len(), part.df_dc.len());
    let mut nonzero = vec![false; c.len()];
    for (i, (a, b)) in full.df_dc.iter().zip(&part.df_dc).enumerate() {
        for k in 0..c.len() {
            if columns.contains(&k) {
                assert_eq!(
                    a[k].to_bits(),
                    b[k].to_bits(),
                    "step {i} column {k}: {} vs {}",
                    a[k],
                    b[k]
                );
                nonzero[k] |= a[k] != 0.0;
            } else {
                assert_eq!(b[k], 0.0, "step {i}: skipped column {k} was formed");
            }
        }
    }
    // the columns compared are not trivially zero
    for &k in columns {
        assert!(nonzero[k], "column {k} is zero everywhere");
    }
    full.df_dc
}

const NH: [f64; 5] = [1e5, 0.3, 1500.0, 5.0, 500.0];
const FREE_NH: [usize; 4] = [0, 2, 3, 4];

#[test]
fn norton_hoff_small_strain_free_columns_are_the_same_bits() {
    let m = model(ContactKind::Normal, Kinematics::Small);
    same_bits(&m, &LawMaterial(&NortonHoff), &NH, &FREE_NH);
    // any subset, in any order
    same_bits(&m, &LawMaterial(&NortonHoff), &NH, &[4, 0]);
}

#[test]
fn norton_hoff_finite_strain_free_columns_are_the_same_bits() {
    let m = model(ContactKind::Normal, Kinematics::Finite);
    same_bits(&m, &LawMaterial(&NortonHoff), &NH, &FREE_NH);
}

#[test]
fn norton_hoff_with_friction_free_columns_are_the_same_bits() {
    let m = model(
        ContactKind::normal_with_friction(0.2).unwrap(),
        Kinematics::Small,
    );
    same_bits(&m, &LawMaterial(&NortonHoff), &NH, &FREE_NH);
}

#[test]
fn plastic_free_columns_are_the_same_bits() {
    let m = model(ContactKind::Normal, Kinematics::Small);
    let pl = Plastic::new(Hardening::Power, Rate::Norton);
    // E, nu, sY, n, K, m: nu and n fixed
    same_bits(&m, &pl, &[1e5, 0.3, 500.0, 0.2, 1500.0, 5.0], &[0, 2, 4, 5]);
}

/// The reference this code did not produce: `dF_i/dsY` of the partial pass against
/// central differences of the direct solver's forces.
#[test]
fn free_column_matches_central_differences() {
    let m = model(ContactKind::Normal, Kinematics::Small);
    let law = LawMaterial(&NortonHoff);
    let df = {
        let t = DirectSolver::new(&m)
            .unwrap()
            .run(&law, &NH, &schedule(), &opts())
            .unwrap();
        Adjoint::new(&m)
            .unwrap()
            .sensitivities_of(&law, &NH, &t, &[4])
            .unwrap()
            .df_dc
    };
    let h = 1e-5 * NH[4];
    let forces = |s: f64| shifted_forces(&m, &law, &NH, 4, s);
    let (fp, fm) = (forces(h), forces(-h));
    let scale = df.iter().map(|r| r[4].abs()).fold(0.0, f64::max);
    assert!(scale > 0.0);
    for (i, row) in df.iter().enumerate() {
        let fd = (fp[i] - fm[i]) / (2.0 * h);
        assert!(
            (row[4] - fd).abs() <= 1e-5 * scale,
            "step {i}: {} vs {fd}",
            row[4]
        );
    }
}

#[test]
fn a_column_beyond_the_parameters_is_refused() {
    let m = model(ContactKind::Normal, Kinematics::Small);
    let law = LawMaterial(&NortonHoff);
    let t = DirectSolver::new(&m)
        .unwrap()
        .run(&law, &NH, &schedule(), &opts())
        .unwrap();
    let e = Adjoint::new(&m)
        .unwrap()
        .sensitivities_of(&law, &NH, &t, &[0, 5])
        .unwrap_err();
    assert!(
        matches!(
            e,
            AdjointError::Length {
                expected: 5,
                got: 6
            }
        ),
        "{e}"
    );
}
