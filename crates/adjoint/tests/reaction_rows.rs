//! The Gauss-point forward sensitivities with `dF_i/dc_k` read from the force dofs' rows
//! of each step's tangent (`K du` there less the right-hand side, the default) against
//! the same pass with the third pass over the Gauss points (`Adjoint::set_fused(false)`,
//! the pinned arithmetic of `pinned.rs`, itself checked against central differences in
//! `gradient_fd*.rs`): every column within 1e-12 of its largest entry, for Norton-Hoff
//! and Maxwell, small strain (vertical, frictionless normal and Coulomb contact, whose
//! sensitivities tie each step to the previous one) and finite strain (frictionless and
//! Coulomb), every parameter and a subset; and two columns against central differences
//! of the direct solver's forces, a reference this code did not produce.

mod common;

use common::{shifted_forces, sphere_model as model, tight_opts as opts, trapezoid5 as schedule};
use indentify_adjoint::Adjoint;
use indentify_contact::{ContactKind, DirectSolver, Kinematics, Model};
use indentify_laws::{Law, LawMaterial, Maxwell, NortonHoff};

const NH: [f64; 5] = [1e5, 0.3, 1500.0, 5.0, 500.0];
const MAXWELL: [f64; 3] = [2e4, 0.3, 3e4];

/// The largest difference between the tangent-row pass and the Gauss-point pass of
/// `columns` (`None`: every parameter), relative to each column's largest entry.
fn worst_difference(m: &Model, law: &dyn Law, c: &[f64], columns: Option<&[usize]>) -> f64 {
    let mat = LawMaterial(law);
    let t = DirectSolver::new(m)
        .unwrap()
        .run(&mat, c, &schedule(), &opts())
        .unwrap();
    let mut adj = Adjoint::new(m).unwrap();
    let pass = |adj: &mut Adjoint| match columns {
        Some(cols) => adj.sensitivities_of(&mat, c, &t, cols).unwrap().df_dc,
        None => adj.sensitivities(&mat, c, &t).unwrap().df_dc,
    };
    let rows = pass(&mut adj);
    assert!(
        adj.last_pass_reaction_rows(),
        "the tangent rows were not used"
    );
    adj.set_fused(false);
    let gauss = pass(&mut adj);
    assert!(!adj.last_pass_reaction_rows());
    let mut worst = 0.0f64;
    for k in 0..c.len() {
        let scale = gauss.iter().fold(0.0f64, |s, r| s.max(r[k].abs()));
        if columns.is_some_and(|cols| !cols.contains(&k)) {
            assert!(
                rows.iter().all(|r| r[k] == 0.0),
                "skipped column {k} formed"
            );
            continue;
        }
        assert!(scale > 0.0, "column {k} is zero everywhere");
        for (i, (a, b)) in rows.iter().zip(&gauss).enumerate() {
            let d = (a[k] - b[k]).abs() / scale;
            assert!(
                d <= 1e-12,
                "step {i} column {k}: {} vs {} ({d:.2e})",
                a[k],
                b[k]
            );
            worst = worst.max(d);
        }
    }
    worst
}

#[test]
fn tangent_rows_equal_the_gauss_point_pass() {
    let friction = ContactKind::normal_with_friction(0.2).unwrap();
    let mut report = Vec::new();
    for (name, kind, kin) in [
        ("vertical", ContactKind::Vertical, Kinematics::Small),
        ("normal", ContactKind::Normal, Kinematics::Small),
        ("coulomb", friction, Kinematics::Small),
        ("finite normal", ContactKind::Normal, Kinematics::Finite),
        ("finite coulomb", friction, Kinematics::Finite),
    ] {
        let m = model(kind, kin);
        let nh = worst_difference(&m, &NortonHoff, &NH, None);
        let nh_free = worst_difference(&m, &NortonHoff, &NH, Some(&[0, 2, 3, 4]));
        report.push(format!("{name}: Norton-Hoff {nh:.1e}, free {nh_free:.1e}"));
        // Maxwell runs all-nodal under small-strain vertical contact (`nodal_sens.rs`)
        if !(kind == ContactKind::Vertical && kin == Kinematics::Small) {
            let mx = worst_difference(&m, &Maxwell, &MAXWELL, None);
            report.push(format!("{name}: Maxwell {mx:.1e}"));
        }
    }
    println!("{}", report.join("\n"));
}

/// `dF_i/dsY` and `dF_i/dm` of the tangent-row pass (finite strain, Coulomb friction)
/// against central differences of the direct solver's forces.
#[test]
fn tangent_rows_match_central_differences() {
    let m = model(
        ContactKind::normal_with_friction(0.2).unwrap(),
        Kinematics::Finite,
    );
    let law = LawMaterial(&NortonHoff);
    let mut adj = Adjoint::new(&m).unwrap();
    let t = DirectSolver::new(&m)
        .unwrap()
        .run(&law, &NH, &schedule(), &opts())
        .unwrap();
    let df = adj.sensitivities_of(&law, &NH, &t, &[3, 4]).unwrap().df_dc;
    assert!(adj.last_pass_reaction_rows());
    for k in [3, 4] {
        let h = 1e-5 * NH[k];
        let forces = |s: f64| shifted_forces(&m, &law, &NH, k, s);
        let (fp, fm) = (forces(h), forces(-h));
        let scale = df.iter().fold(0.0f64, |s, r| s.max(r[k].abs()));
        assert!(scale > 0.0);
        let mut worst = 0.0f64;
        for (i, row) in df.iter().enumerate() {
            let fd = (fp[i] - fm[i]) / (2.0 * h);
            worst = worst.max((row[k] - fd).abs() / scale);
        }
        println!("column {k}: {worst:.2e} of its largest entry");
        assert!(worst < 1e-5, "column {k}: {worst:.2e}");
    }
}
