//! Lamé's thick-walled cylinder under internal pressure, axisymmetric, plane strain.
//!
//! Reference: G. Lamé, *Leçons sur la théorie mathématique de l'élasticité des corps
//! solides* (1852); Timoshenko & Goodier, *Theory of Elasticity*, 3rd ed. (1970), ch. 4
//! (thick-walled cylinder); Barber, *Elasticity* (thick cylinder under internal
//! pressure). With `k = p a^2 / (b^2 - a^2)`:
//!
//! ```text
//!   sigma_rr = k (1 - b^2/r^2)     sigma_tt = k (1 + b^2/r^2)     sigma_zz = 2 nu k
//!   u_r      = (1 + nu) k / E ((1 - 2 nu) r + b^2/r)                u_z = 0
//! ```
//!
//! Goal: the `fe` crate (B operator with hoop row, full-circle weights, assembly,
//! elimination of the u_z = 0 supports, Cholesky) converges to the closed form — nodal
//! `u_r` at order 3 or better (4 is observed: nodal superconvergence), Gauss-point
//! stresses at order 2 in the element size — and the pressure's consistent nodal forces sum to `2 pi a H p`.
//!
//! ```text
//!        z = 0   u_z = 0 (top)
//!          +---+---+---+---+---+
//!   p -->  |   |   |   |   |   |  traction-free
//!   p -->  +---+---+---+---+---+  outer face r = b
//!   p -->  |   |   |   |   |   |
//!          +---+---+---+---+---+
//!        z = -H  u_z = 0 (bottom)
//!        r = a                  r = b
//!   nr x 2 Q8 elements (a CylinderMesher mesh mapped r -> a + r (b - a)),
//!   uniform or graded towards the inner face; consistent loads
//!   f_k = int N_k p 2 pi a dz on the inner face.
//! ```
//!
//! Parameters: a = 1 mm, b = 2 mm, H = 0.5 mm, p = 100 MPa, E = 20000 MPa, nu = 0.3.

mod common;

use common::linear::{LAME, lame_solve};

/// Observed order of convergence between two element sizes.
fn order(e0: f64, e1: f64, h0: f64, h1: f64) -> f64 {
    (e0 / e1).ln() / (h0 / h1).ln()
}

/// The solver shall converge to Lamé's displacement and stresses under uniform
/// refinement, at order >= 3 for nodal u_r and close to 2 (> 1.75, still
/// pre-asymptotic) for the largest Gauss-point stress error.
#[test]
fn lame_cylinder_converges_under_refinement() {
    let errors: Vec<_> = [8, 16, 32]
        .iter()
        .map(|&n| lame_solve(&LAME, n, 2, 1.0))
        .collect();
    for e in &errors {
        assert!((e.load_sum - 1.0).abs() < 1e-13, "{e:?}");
        assert!(e.u_z < 1e-12, "plane strain violated: {e:?}");
    }
    for w in errors.windows(2) {
        let pu = order(w[0].u_r, w[1].u_r, w[0].h_inner, w[1].h_inner);
        let ps = order(w[0].sigma, w[1].sigma, w[0].h_inner, w[1].h_inner);
        assert!(pu > 2.9, "u_r order {pu:.2}: {errors:?}");
        assert!(ps > 1.75, "stress order {ps:.2}: {errors:?}");
    }
}

/// The solver shall match Lamé's solution to 1e-4 (u_r) and 1e-2 p (stresses) on an
/// 8-element mesh graded towards the inner face.
#[test]
fn lame_cylinder_graded_mesh_matches_closed_form() {
    let e = lame_solve(&LAME, 8, 2, 1.3);
    assert!(e.u_r < 1e-4, "{e:?}");
    assert!(e.sigma < 1e-2, "{e:?}");
}

/// Prints the Lamé convergence table of docs/validation.md.
#[test]
#[ignore = "study: prints the Lamé table of docs/validation.md"]
fn refinement_lame_table() {
    println!(
        "| mesh (nr x nz) | grading | h at r = a (mm) | max nodal u_r error / u_r(a) | order | max Gauss-point stress error / p | order |"
    );
    println!("|---|---|---|---|---|---|---|");
    for q in [1.0_f64, 1.3] {
        let mut prev: Option<common::linear::LameErrors> = None;
        for n in [2, 4, 8, 16, 32] {
            let e = lame_solve(&LAME, n, 2, q.powf(8.0 / n as f64));
            let (ou, os) = prev.map_or((String::from("-"), String::from("-")), |p| {
                (
                    format!("{:.2}", order(p.u_r, e.u_r, p.h_inner, e.h_inner)),
                    format!("{:.2}", order(p.sigma, e.sigma, p.h_inner, e.h_inner)),
                )
            });
            println!(
                "| {n} x 2 | {:.4} | {:.4} | {:.2e} | {ou} | {:.2e} | {os} |",
                q.powf(8.0 / n as f64),
                e.h_inner,
                e.u_r,
                e.sigma
            );
            prev = Some(e);
        }
    }
}
