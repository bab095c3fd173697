//! The forward sensitivities under finite strain with the compact per-point operator
//! `G = P L(F)` (`finite.rs`, the default where `dF_i/dc_k` come from the tangent's rows)
//! against the same pass with `B_L` and `P` formed per point
//! (`Adjoint::set_compact_finite(false)`, the operators before it) and against the
//! Gauss-point pass with its third pass (`set_fused(false)`, the pinned arithmetic of
//! `pinned.rs`, checked against central differences in `gradient_fd*.rs`): every column
//! within 1e-12 of its largest entry, for Norton-Hoff and Maxwell under frictionless and
//! Coulomb contact, every parameter and a subset; the compact pass gives the same bits on
//! one thread and on a 2-thread pool (the parameters' solves in parallel); and two
//! columns against central differences of the direct solver's forces, a reference this
//! code did not produce.

use indentify_adjoint::Adjoint;
use indentify_contact::{
    ContactKind, DirectSolver, Kinematics, Model, Punch, Schedule, SolverOptions, Trajectory,
    trapezoid,
};
use indentify_laws::{Law, LawMaterial, Maxwell, NortonHoff};
use indentify_mesh::CylinderMesher;

fn model(kind: ContactKind) -> Model {
    let mesh = CylinderMesher {
        radius: 4.0,
        height: 4.0,
        nr: 7,
        nz: 7,
        grading_r: 1.45,
        grading_z: 1.45,
    }
    .build()
    .unwrap();
    Model::with_contact(mesh, Punch::Sphere { radius: 1.0 }, kind)
        .unwrap()
        .with_kinematics(Kinematics::Finite)
        .unwrap()
}

fn schedule() -> Schedule {
    Schedule::from_segments(&trapezoid(0.12, 1.0, 1.0, 1.0, 5)).unwrap()
}

fn opts() -> SolverOptions {
    SolverOptions {
        residual_tol: 1e-12,
        ..Default::default()
    }
}

const NH: [f64; 5] = [1e5, 0.3, 1500.0, 5.0, 500.0];
const MAXWELL: [f64; 3] = [2e4, 0.3, 3e4];

fn run(m: &Model, law: &dyn Law, c: &[f64]) -> Trajectory {
    DirectSolver::new(m)
        .unwrap()
        .run(&LawMaterial(law), c, &schedule(), &opts())
        .unwrap()
}

fn pass(
    adj: &mut Adjoint,
    law: &dyn Law,
    c: &[f64],
    t: &Trajectory,
    cols: Option<&[usize]>,
) -> Vec<Vec<f64>> {
    let mat = LawMaterial(law);
    match cols {
        Some(k) => adj.sensitivities_of(&mat, c, t, k).unwrap().df_dc,
        None => adj.sensitivities(&mat, c, t).unwrap().df_dc,
    }
}

/// The largest difference of `a` from `b` over `cols`, relative to each column's largest
/// entry of `b`; skipped columns must be zero in `a`.
fn worst(a: &[Vec<f64>], b: &[Vec<f64>], np: usize, cols: Option<&[usize]>) -> f64 {
    let mut w = 0.0f64;
    for k in 0..np {
        if cols.is_some_and(|c| !c.contains(&k)) {
            assert!(a.iter().all(|r| r[k] == 0.0), "skipped column {k} formed");
            continue;
        }
        let scale = b.iter().fold(0.0f64, |s, r| s.max(r[k].abs()));
        assert!(scale > 0.0, "column {k} is zero everywhere");
        for (x, y) in a.iter().zip(b) {
            w = w.max((x[k] - y[k]).abs() / scale);
        }
    }
    w
}

#[test]
fn compact_operators_equal_b_l_and_p_and_the_third_pass() {
    let friction = ContactKind::normal_with_friction(0.2).unwrap();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    for (name, kind) in [("normal", ContactKind::Normal), ("coulomb", friction)] {
        let m = model(kind);
        for (law, c, cols) in [
            (&NortonHoff as &dyn Law, &NH[..], None),
            (&NortonHoff, &NH[..], Some(&[0usize, 2, 3, 4][..])),
            (&Maxwell, &MAXWELL[..], None),
        ] {
            let t = run(&m, law, c);
            let mut adj = Adjoint::new(&m).unwrap();
            let compact = pass(&mut adj, law, c, &t, cols);
            assert!(adj.last_pass_reaction_rows(), "{name}: no tangent rows");
            assert!(adj.last_pass_compact_finite(), "{name}: not compact");
            adj.set_compact_finite(false);
            let full = pass(&mut adj, law, c, &t, cols);
            assert!(!adj.last_pass_compact_finite());
            adj.set_compact_finite(true);
            // another order of the products: round-off apart, not the same bits
            assert!(compact != full, "{name}: the compact form was not used");
            let w_full = worst(&compact, &full, c.len(), cols);
            adj.set_fused(false);
            let gauss = pass(&mut adj, law, c, &t, cols);
            assert!(!adj.last_pass_compact_finite());
            let w_gauss = worst(&compact, &gauss, c.len(), cols);
            println!(
                "{name} {} {cols:?}: {w_full:.1e} of B_L and P's columns, {w_gauss:.1e} of \
                 the third pass's",
                law.name()
            );
            assert!(
                w_full <= 1e-12 && w_gauss <= 1e-12,
                "{name}: {w_full:.2e} {w_gauss:.2e}"
            );
            // the parameters' solves in parallel: the same bits
            let pooled = pool.install(|| {
                let mut adj = Adjoint::new(&m).unwrap();
                pass(&mut adj, law, c, &t, cols)
            });
            assert!(compact == pooled, "{name}: other bits on 2 threads");
        }
    }
}

/// `dF_i/dE` and `dF_i/dsY` of the compact pass (finite strain, Coulomb friction) against
/// central differences of the direct solver's forces.
#[test]
fn compact_columns_match_central_differences() {
    let m = model(ContactKind::normal_with_friction(0.2).unwrap());
    let t = run(&m, &NortonHoff, &NH);
    let mut adj = Adjoint::new(&m).unwrap();
    let df = pass(&mut adj, &NortonHoff, &NH, &t, Some(&[0, 4]));
    assert!(adj.last_pass_compact_finite());
    for k in [0, 4] {
        let h = 1e-5 * NH[k];
        let forces = |s: f64| {
            let mut c = NH;
            c[k] += s;
            run(&m, &NortonHoff, &c)
                .steps
                .iter()
                .map(|s| s.force)
                .collect::<Vec<_>>()
        };
        let (fp, fm) = (forces(h), forces(-h));
        assert_eq!(fp.len(), df.len(), "the perturbed runs took other steps");
        let scale = df.iter().fold(0.0f64, |s, r| s.max(r[k].abs()));
        assert!(scale > 0.0);
        let mut w = 0.0f64;
        for (i, row) in df.iter().enumerate() {
            let fd = (fp[i] - fm[i]) / (2.0 * h);
            w = w.max((row[k] - fd).abs() / scale);
        }
        println!("column {k}: {w:.2e} of its largest entry");
        assert!(w < 1e-5, "column {k}: {w:.2e}");
    }
}
