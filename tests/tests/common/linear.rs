//! Linear elastostatics straight on the `fe` crate (no contact, no time): assembly with
//! one uniform tangent, Dirichlet data by elimination (`DofMap`) or by
//! [`Pattern::constrain`] with the matching right-hand-side correction, and the sparse
//! Cholesky solve. Shared by the patch test, Lamé's cylinder and the refinement study.

use std::collections::BTreeMap;

use indentify_fe::{Discretization, DofMap, Pattern, QP_PER_ELEMENT, SparseCholesky};
use indentify_laws::Mat4;
use indentify_laws::elastic::isotropic_stiffness;
use indentify_mesh::{CylinderMesher, Mesh, q8};

/// Lamé's first parameter and the shear modulus `(lambda, mu)` of `(E, nu)`.
pub fn lame_parameters(e: f64, nu: f64) -> (f64, f64) {
    (
        e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)),
        e / (2.0 * (1.0 + nu)),
    )
}

/// Solves `K u = f` for the mesh with tangent `c` at every Gauss point.
///
/// - `eliminated`: global dofs fixed to zero and removed from the system (`DofMap`);
/// - `prescribed`: `(dof, value)` pairs kept in the system as equations `K_kk u_k = K_kk
///   ubar_k` by [`Pattern::constrain`], their coupling moved to the right-hand side
///   (`f_free - K_free,c ubar_c`);
/// - `f_ext`: external nodal forces over all dofs (N, full circle).
///
/// Returns the displacement over all dofs (eliminated ones are 0).
pub fn solve_dirichlet(
    mesh: &Mesh,
    c: &Mat4,
    eliminated: &[usize],
    prescribed: &[(usize, f64)],
    f_ext: &[f64],
) -> Vec<f64> {
    let disc = Discretization::new(mesh);
    let dofs = DofMap::new(disc.n_dofs(), eliminated);
    let pattern = Pattern::new(&disc, &dofs);
    let mut k = vec![0.0; pattern.nnz()];
    pattern.assemble_b_c_b_uniform(&disc, c, &mut k);
    let n = dofs.n_eq;
    let mut constrained = vec![false; n];
    let mut ubar = vec![0.0; n];
    for &(d, v) in prescribed {
        let e = dofs
            .equation(d)
            .expect("a prescribed dof is not eliminated");
        constrained[e] = true;
        ubar[e] = v;
    }
    let mut kc = vec![0.0; pattern.nnz()];
    pattern.constrain(&k, &constrained, &mut kc);
    let mut k_ubar = vec![0.0; n];
    pattern.sym_mul_add(&k, &ubar, &mut k_ubar);
    let mut f = vec![0.0; n];
    dofs.restrict(f_ext, &mut f);
    let mut rhs: Vec<f64> = (0..n)
        .map(|e| {
            if constrained[e] {
                kc[pattern.diag[e]] * ubar[e]
            } else {
                f[e] - k_ubar[e]
            }
        })
        .collect();
    let mut chol = SparseCholesky::analyse(&pattern).expect("symbolic analysis");
    chol.factorize(&kc).expect("SPD stiffness");
    chol.solve_in_place(&mut rhs);
    let mut u = vec![0.0; disc.n_dofs()];
    for (d, ud) in u.iter_mut().enumerate() {
        if let Some(e) = dofs.equation(d) {
            *ud = rhs[e];
        }
    }
    u
}

/// Strain `B u` at every Gauss point (Mandel `[rr, zz, tt, sqrt2 rz]`) and the points'
/// `(r, z)`.
pub fn gauss_strains(mesh: &Mesh, u: &[f64]) -> (Vec<[f64; 4]>, Vec<[f64; 2]>) {
    let disc = Discretization::new(mesh);
    let mut eps = vec![[0.0; 4]; disc.n_qp()];
    disc.strains(u, &mut eps);
    let pos = disc.qp.iter().map(|q| [q.r, q.z]).collect();
    (eps, pos)
}

/// Consistent nodal forces `f_a = sum_g w_g N_a(x_g) b(x_g)` of a body force `b(r, z)`
/// (N/mm^3, full circle), with the 3x3 rule of the stiffness.
pub fn body_force_loads(mesh: &Mesh, b: impl Fn(f64, f64) -> [f64; 2]) -> Vec<f64> {
    let disc = Discretization::new(mesh);
    let rule = q8::gauss3x3();
    let mut f = vec![0.0; disc.n_dofs()];
    for e in 0..mesh.elements.len() {
        for (g, ([xi, eta], _)) in rule.iter().enumerate() {
            let qp = &disc.qp[QP_PER_ELEMENT * e + g];
            let n = q8::shape(*xi, *eta);
            let bf = b(qp.r, qp.z);
            for (a, &node) in mesh.elements[e].iter().enumerate() {
                f[2 * node] += qp.w * n[a] * bf[0];
                f[2 * node + 1] += qp.w * n[a] * bf[1];
            }
        }
    }
    f
}

/// Nodes on the boundary of a structured mesh built by [`CylinderMesher`] (union of its
/// four node sets), sorted.
pub fn boundary_nodes(mesh: &Mesh) -> Vec<usize> {
    let mut b: Vec<usize> = ["axis", "outer", "top", "bottom"]
        .iter()
        .flat_map(|s| mesh.node_set(s).iter().copied())
        .collect();
    b.sort_unstable();
    b.dedup();
    b
}

/// Rebuilds `mesh` with node `k` moved to `map(k, [r, z])` (same connectivity and sets).
pub fn map_nodes(mesh: &Mesh, map: impl Fn(usize, [f64; 2]) -> [f64; 2]) -> Mesh {
    let nodes = mesh
        .nodes
        .iter()
        .enumerate()
        .map(|(k, &x)| map(k, x))
        .collect();
    let sets: BTreeMap<String, Vec<usize>> = mesh.node_sets.clone();
    Mesh::new(nodes, mesh.elements.clone(), sets).expect("mapped mesh has positive Jacobians")
}

// ---------------------------------------------------------------------------------------
// Lamé's thick-walled cylinder under internal pressure, plane strain (u_z = 0).
// Timoshenko & Goodier, Theory of Elasticity, 3rd ed. (1970), ch. 4 (thick-walled
// cylinder); Barber, Elasticity (thick cylinder under pressure):
//   sigma_rr = p a^2/(b^2-a^2) (1 - b^2/r^2),  sigma_tt = p a^2/(b^2-a^2) (1 + b^2/r^2),
//   sigma_zz = 2 nu p a^2/(b^2-a^2),
//   u_r = (1+nu) p a^2 / (E (b^2-a^2)) ((1-2nu) r + b^2/r).
// ---------------------------------------------------------------------------------------

/// The closed form: `(u_r, sigma_rr, sigma_tt, sigma_zz)` at radius r.
pub fn lame_exact(r: f64, a: f64, b: f64, p: f64, e: f64, nu: f64) -> (f64, f64, f64, f64) {
    let k = p * a * a / (b * b - a * a);
    let u = (1.0 + nu) * k / e * ((1.0 - 2.0 * nu) * r + b * b / r);
    (
        u,
        k * (1.0 - b * b / (r * r)),
        k * (1.0 + b * b / (r * r)),
        2.0 * nu * k,
    )
}

/// Geometry and load of the Lamé case.
#[derive(Clone, Copy, Debug)]
pub struct LameCase {
    /// Inner radius (mm).
    pub a: f64,
    /// Outer radius (mm).
    pub b: f64,
    /// Height of the slice (mm).
    pub height: f64,
    /// Internal pressure (MPa).
    pub p: f64,
    /// Young's modulus (MPa).
    pub e: f64,
    /// Poisson's ratio.
    pub nu: f64,
}

/// The reference Lamé case of the suite: a = 1, b = 2 mm, slice 0.5 mm, p = 100 MPa.
pub const LAME: LameCase = LameCase {
    a: 1.0,
    b: 2.0,
    height: 0.5,
    p: 100.0,
    e: 20000.0,
    nu: 0.3,
};

/// Errors of one Lamé solve.
#[derive(Clone, Copy, Debug)]
pub struct LameErrors {
    /// Radial element size at the inner face (mm).
    pub h_inner: f64,
    /// `max_nodes |u_r - u_r,exact| / u_r,exact(a)`.
    pub u_r: f64,
    /// `max_nodes |u_z| / u_r,exact(a)` (0 in the exact solution).
    pub u_z: f64,
    /// `max_qp |sigma_h - sigma_exact|` over rr, zz, tt, rz, divided by p.
    pub sigma: f64,
    /// Sum of the consistent pressure loads divided by `2 pi a H p`.
    pub load_sum: f64,
}

/// Annulus `a <= r <= b`, `-H <= z <= 0`, with `nr x nz` elements graded by `q` towards
/// the inner face: a [`CylinderMesher`] mesh mapped by `r -> a + r (b - a) / R`. Its
/// `axis` set becomes the inner face.
pub fn annulus(case: &LameCase, nr: usize, nz: usize, q: f64) -> Mesh {
    let base = CylinderMesher {
        radius: 1.0,
        height: case.height,
        nr,
        nz,
        grading_r: q,
        grading_z: 1.0,
    }
    .build()
    .expect("valid mesh");
    map_nodes(&base, |_, [r, z]| [case.a + r * (case.b - case.a), z])
}

/// Consistent nodal forces of a pressure `p` on the inner face `r = a` (set `axis` of the
/// mapped mesh, sorted by z, quadratic edges): `f_k = int N_k p 2 pi a dz` along +r,
/// by 3-point Gauss on each edge.
pub fn inner_pressure_loads(mesh: &Mesh, a: f64, p: f64) -> Vec<f64> {
    let face = mesh.node_set("axis");
    let mut f = vec![0.0; 2 * mesh.nodes.len()];
    let g = (0.6f64).sqrt();
    for e in (0..face.len() - 1).step_by(2) {
        let (z0, z1) = (mesh.nodes[face[e]][1], mesh.nodes[face[e + 2]][1]);
        for (xi, w) in [(-g, 5.0 / 9.0), (0.0, 8.0 / 9.0), (g, 5.0 / 9.0)] {
            let n = [0.5 * xi * (xi - 1.0), 1.0 - xi * xi, 0.5 * xi * (xi + 1.0)];
            for k in 0..3 {
                f[2 * face[e + k]] +=
                    w * n[k] * p * 2.0 * std::f64::consts::PI * a * 0.5 * (z1 - z0);
            }
        }
    }
    f
}

/// Solves the Lamé case on `annulus(case, nr, nz, q)` and measures the errors.
pub fn lame_solve(case: &LameCase, nr: usize, nz: usize, q: f64) -> LameErrors {
    let mesh = annulus(case, nr, nz, q);
    let mut fixed: Vec<usize> = mesh.node_set("top").iter().map(|n| 2 * n + 1).collect();
    fixed.extend(mesh.node_set("bottom").iter().map(|n| 2 * n + 1));
    let f = inner_pressure_loads(&mesh, case.a, case.p);
    let c = isotropic_stiffness(case.e, case.nu);
    let u = solve_dirichlet(&mesh, &c, &fixed, &[], &f);
    let (u_a, ..) = lame_exact(case.a, case.a, case.b, case.p, case.e, case.nu);
    let mut err = LameErrors {
        h_inner: 0.0,
        u_r: 0.0,
        u_z: 0.0,
        sigma: 0.0,
        load_sum: f.iter().sum::<f64>()
            / (2.0 * std::f64::consts::PI * case.a * case.height * case.p),
    };
    for (k, x) in mesh.nodes.iter().enumerate() {
        let (ue, ..) = lame_exact(x[0], case.a, case.b, case.p, case.e, case.nu);
        err.u_r = err.u_r.max((u[2 * k] - ue).abs() / u_a);
        err.u_z = err.u_z.max(u[2 * k + 1].abs() / u_a);
    }
    let face = mesh.node_set("axis");
    let next = mesh.node_set("bottom")[2];
    err.h_inner = mesh.nodes[next][0] - mesh.nodes[face[0]][0];
    let (eps, pos) = gauss_strains(&mesh, &u);
    for (e, [r, _]) in eps.iter().zip(pos) {
        let s = c.mul_vec(&indentify_laws::Vec4(*e));
        let (_, srr, stt, szz) = lame_exact(r, case.a, case.b, case.p, case.e, case.nu);
        let d = [s[0] - srr, s[1] - szz, s[2] - stt, s[3]];
        err.sigma = err
            .sigma
            .max(d.iter().fold(0.0_f64, |m, v| m.max(v.abs())) / case.p);
    }
    err
}
