//! Patch test of the axisymmetric Q8 element: linear displacement fields on distorted,
//! graded patches, straight on the `fe` crate (assembly, Dirichlet data, Cholesky).
//!
//! Reference: B. M. Irons & A. Razzaque (1972), the patch test; Zienkiewicz, Taylor & Zhu,
//! *The Finite Element Method: Its Basis and Fundamentals* (chapters on the patch test
//! and on axisymmetric analysis, hoop strain `eps_tt = u_r / r`).
//!
//! Goal: the element passes the patch test and its B operator, hoop row included,
//! reproduces every linear field exactly.
//!
//! - For `u_r = a r + b z + c0`, `u_z = c r + d z + e` the strains are
//!   `eps_rr = a`, `eps_zz = d`, `eps_tt = a + (b z + c0)/r`, `eps_rz = (b + c)/2`.
//!   Quadratic isoparametric elements interpolate these fields exactly even on curved,
//!   distorted elements, so the Gauss-point strains must match to round-off.
//! - Without body force only `u_r = a r`, `u_z = d z + e` are in equilibrium (constant
//!   stress with `sigma_rr = sigma_tt`): the other linear fields need the body force
//!   `f_r = (lambda + 2 mu)(b z + c0)/r^2`, `f_z = -(lambda b + mu (b + c))/r`
//!   (from `div sigma + f = 0` with the hoop terms).
//! - Constant-strain states with Dirichlet data on the whole boundary are reproduced to
//!   round-off: the 3x3 rule integrates `(r dN/dr + N) det J` and `r dN/dz det J`
//!   exactly on Q8. The other linear fields, loaded by their body force integrated with
//!   the same rule (`f_a = sum_g w_g N_a f`), are reproduced to round-off as well: at
//!   every Gauss point the `1/r` of `sigma_tt` in the hoop row cancels against the `1/r^2`
//!   of `f_r` (times the weight's r), so the weak-form integrands are polynomials again.
//!
//! ```text
//!            r0                          r0 + 1
//!   z = 0    o-o--o---o------o   u_r, u_z given on every boundary node
//!            | |  |   |      |   (Pattern::constrain + rhs correction);
//!            o-o~~o~~~o------o   on the axis patch (r0 = 0) u_r = 0 on the
//!            |  \  \   \      |   axis is eliminated instead (DofMap)
//!            o---o~~o~~~o----o
//!            |   |  |   |    |   ~ : interior edges curved by the moved
//!   z = -1   o---o--o---o----o       interior nodes (midsides included)
//!   4 x 3 Q8 graded 1.4 along r (fine at r0) and 1.25 along z (fine at the top);
//!   interior nodes moved by up to 0.035 mm (a quarter of the smallest element).
//!   Patches: axis patch r0 = 0 and annulus patch r0 = 1 mm.
//! ```
//!
//! Parameters: E = 20000 MPa, nu = 0.3; field coefficients of order 1e-3.

mod common;

use common::linear::{
    body_force_loads, boundary_nodes, gauss_strains, lame_parameters, map_nodes, solve_dirichlet,
};
use common::{E, NU};
use indentify_laws::elastic::isotropic_stiffness;
use indentify_mesh::{CylinderMesher, Mesh};

/// Coefficients of `u_r = a r + b z + c0`, `u_z = c r + d z + e`.
#[derive(Clone, Copy, Debug)]
struct Linear {
    a: f64,
    b: f64,
    c0: f64,
    c: f64,
    d: f64,
    e: f64,
}

impl Linear {
    fn u(&self, [r, z]: [f64; 2]) -> [f64; 2] {
        [
            self.a * r + self.b * z + self.c0,
            self.c * r + self.d * z + self.e,
        ]
    }

    /// Exact Mandel strain at (r, z).
    fn eps(&self, [r, z]: [f64; 2]) -> [f64; 4] {
        [
            self.a,
            self.d,
            self.a + (self.b * z + self.c0) / r,
            (self.b + self.c) / std::f64::consts::SQRT_2,
        ]
    }

    /// Body force `f = -div sigma` that equilibrates the field (N/mm^3).
    fn body_force(&self, [r, z]: [f64; 2]) -> [f64; 2] {
        let (lambda, mu) = lame_parameters(E, NU);
        [
            (lambda + 2.0 * mu) * (self.b * z + self.c0) / (r * r),
            -(lambda * self.b + mu * (self.b + self.c)) / r,
        ]
    }

    fn scale(&self) -> f64 {
        [self.a, self.b, self.c0, self.c, self.d, self.e]
            .iter()
            .fold(0.0_f64, |m, v| m.max(v.abs()))
    }
}

/// A deterministic value in [-1, 1] for node k and component j.
fn jitter(k: usize, j: usize) -> f64 {
    let x = ((k * 2 + j) as f64 * 12.9898 + 78.233).sin() * 43758.5453;
    2.0 * (x - x.floor()) - 1.0
}

/// The 4 x 3 graded patch of the header, on `[r0, r0 + 1] x [-1, 0]`, interior nodes
/// (corners and midsides) moved by up to `amplitude` (mm) both ways.
fn patch(r0: f64, nr: usize, nz: usize, amplitude: f64) -> Mesh {
    let base = CylinderMesher {
        radius: 1.0,
        height: 1.0,
        nr,
        nz,
        grading_r: 1.4,
        grading_z: 1.25,
    }
    .build()
    .expect("valid patch");
    let boundary = boundary_nodes(&base);
    map_nodes(&base, |k, [r, z]| {
        if boundary.binary_search(&k).is_ok() {
            [r0 + r, z]
        } else {
            [
                r0 + r + amplitude * jitter(k, 0),
                z + amplitude * jitter(k, 1),
            ]
        }
    })
}

fn axis_patch() -> Mesh {
    patch(0.0, 4, 3, 0.035)
}

fn annulus_patch() -> Mesh {
    patch(1.0, 4, 3, 0.035)
}

/// Solves with `field` prescribed on every boundary node (u_r on the axis eliminated as
/// zero, the rest through `Pattern::constrain`) and the loads `f_ext`; returns the
/// displacement and the largest nodal error relative to the field's largest coefficient
/// (the patch is 1 mm wide).
fn solve_with_boundary_data(mesh: &Mesh, field: &Linear, f_ext: &[f64]) -> (Vec<f64>, f64) {
    let axis: Vec<usize> = mesh
        .node_set("axis")
        .iter()
        .filter(|&&n| mesh.nodes[n][0] == 0.0)
        .map(|&n| 2 * n)
        .collect();
    let mut prescribed = Vec::new();
    for n in boundary_nodes(mesh) {
        let u = field.u(mesh.nodes[n]);
        if !axis.contains(&(2 * n)) {
            prescribed.push((2 * n, u[0]));
        }
        prescribed.push((2 * n + 1, u[1]));
    }
    let c = isotropic_stiffness(E, NU);
    let u = solve_dirichlet(mesh, &c, &axis, &prescribed, f_ext);
    let mut err: f64 = 0.0;
    for (k, x) in mesh.nodes.iter().enumerate() {
        let ue = field.u(*x);
        err = err
            .max((u[2 * k] - ue[0]).abs())
            .max((u[2 * k + 1] - ue[1]).abs());
    }
    (u, err / field.scale())
}

/// Largest Gauss-point strain error relative to the field's scale.
fn strain_error(mesh: &Mesh, u: &[f64], field: &Linear) -> f64 {
    let (eps, pos) = gauss_strains(mesh, u);
    eps.iter()
        .zip(pos)
        .map(|(e, x)| {
            let ex = field.eps(x);
            (0..4).fold(0.0_f64, |m, i| m.max((e[i] - ex[i]).abs()))
        })
        .fold(0.0, f64::max)
        / field.scale()
}

const EQUILIBRATED: [Linear; 3] = [
    Linear {
        a: 1e-3,
        b: 0.0,
        c0: 0.0,
        c: 0.0,
        d: 0.0,
        e: 0.0,
    },
    Linear {
        a: 0.0,
        b: 0.0,
        c0: 0.0,
        c: 0.0,
        d: -2e-3,
        e: 5e-4,
    },
    Linear {
        a: -7e-4,
        b: 0.0,
        c0: 0.0,
        c: 0.0,
        d: 1.3e-3,
        e: -2e-4,
    },
];

/// The solver shall reproduce the equilibrated constant-strain states `u_r = a r`,
/// `u_z = d z + e` at every interior node and Gauss point of a distorted patch to 1e-10.
#[test]
fn patch_test_constant_strain_states_are_reproduced_exactly() {
    for mesh in [axis_patch(), annulus_patch()] {
        let (worst, _) = mesh.jacobian_ratio_range();
        assert!(worst < 0.8, "the patch is not distorted: {worst}");
        for field in &EQUILIBRATED {
            let f = vec![0.0; 2 * mesh.nodes.len()];
            let (u, err_u) = solve_with_boundary_data(&mesh, field, &f);
            assert!(err_u < 1e-10, "{field:?}: nodal error {err_u:.2e}");
            let err_e = strain_error(&mesh, &u, field);
            assert!(err_e < 1e-10, "{field:?}: strain error {err_e:.2e}");
        }
    }
}

/// The solver shall represent every linear field exactly: its nodal interpolation gives
/// the exact strains, hoop strain `(a r + b z + c0)/r` included, at every Gauss point.
#[test]
fn linear_fields_are_interpolated_exactly_with_their_hoop_strain() {
    for (mesh, field) in [(annulus_patch(), GENERAL), (axis_patch(), GENERAL_ON_AXIS)] {
        let u: Vec<f64> = mesh.nodes.iter().flat_map(|x| field.u(*x)).collect();
        let err = strain_error(&mesh, &u, &field);
        assert!(err < 1e-12, "{field:?}: strain error {err:.2e}");
    }
}

/// The general linear field, and its restriction admissible on the axis (u_r = 0 there).
const GENERAL: Linear = Linear {
    a: 1e-3,
    b: -4e-4,
    c0: 3e-4,
    c: 6e-4,
    d: -2e-3,
    e: 5e-4,
};
const GENERAL_ON_AXIS: Linear = Linear {
    b: 0.0,
    c0: 0.0,
    ..GENERAL
};

/// Nodal and strain errors of `field` loaded by its consistent body force.
fn body_force_errors(mesh: &Mesh, field: &Linear) -> (f64, f64) {
    let f = body_force_loads(mesh, |r, z| field.body_force([r, z]));
    let (u, err_u) = solve_with_boundary_data(mesh, field, &f);
    (err_u, strain_error(mesh, &u, field))
}

/// The solver shall reproduce the non-equilibrated linear fields (`b z`, `c0`, `c r`)
/// exactly (1e-10) when loaded by their consistent body force, on distorted patches.
#[test]
fn linear_fields_with_their_body_force_are_reproduced_exactly() {
    for (mesh, field) in [(annulus_patch(), GENERAL), (axis_patch(), GENERAL_ON_AXIS)] {
        let (err_u, err_e) = body_force_errors(&mesh, &field);
        assert!(err_u < 1e-10, "{field:?}: nodal error {err_u:.2e}");
        assert!(err_e < 1e-10, "{field:?}: strain error {err_e:.2e}");
    }
}

/// Prints the patch errors for docs/validation.md (run by the refinement study).
#[test]
#[ignore = "study: prints the patch-test table of docs/validation.md"]
fn refinement_patch_table() {
    println!("| patch | field | max nodal error / scale | max Gauss-point strain error / scale |");
    println!("|---|---|---|---|");
    for (name, mesh) in [
        ("axis, distorted", axis_patch()),
        ("annulus, distorted", annulus_patch()),
    ] {
        for field in &EQUILIBRATED {
            let f = vec![0.0; 2 * mesh.nodes.len()];
            let (u, err_u) = solve_with_boundary_data(&mesh, field, &f);
            let err_e = strain_error(&mesh, &u, field);
            println!(
                "| {name} | a={:e}, d={:e}, e={:e} | {err_u:.1e} | {err_e:.1e} |",
                field.a, field.d, field.e
            );
        }
    }
    for (name, mesh, field) in [
        ("axis, distorted", axis_patch(), GENERAL_ON_AXIS),
        ("annulus, distorted", annulus_patch(), GENERAL),
    ] {
        let (err_u, err_e) = body_force_errors(&mesh, &field);
        println!(
            "| {name} | general linear + body force (b={:e}, c0={:e}, c={:e}) | {err_u:.1e} | {err_e:.1e} |",
            field.b, field.c0, field.c
        );
    }
}
