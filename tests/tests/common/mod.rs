//! Shared helpers of the validation tests: closed-form references (Sneddon's punches,
//! Lamé's cylinder), the meshes of the studies, and thin runners over the direct solver.
//!
//! Every reference here is a closed form or a quadrature of one, never a number the code
//! under test produced. Each test crate uses part of this module only, hence the
//! `dead_code` allowance below.

#![allow(dead_code)]

pub mod linear;

use std::f64::consts::PI;

use indentify_contact::{DirectSolver, Model, Punch, Schedule, Segment, SolverOptions, Trajectory};
use indentify_laws::Elastic;
use indentify_mesh::{CylinderMesher, Mesh};

/// Young's modulus of R0 (MPa), docs/theory.md §11.
pub const E: f64 = 20000.0;
/// Poisson's ratio of R0.
pub const NU: f64 = 0.3;
/// Cone half-angle of the reference problems (deg, from the axis).
pub const ALPHA_DEG: f64 = 68.0;
/// Maximum depth of the trapezoid (mm).
pub const H_MAX: f64 = 0.1;

/// Plane-strain (indentation) modulus `E* = E / (1 - nu^2)` (MPa).
pub fn e_star(e: f64, nu: f64) -> f64 {
    e / (1.0 - nu * nu)
}

// ---------------------------------------------------------------------------------------
// Sneddon (1965), "The relation between load and penetration in the axisymmetric
// Boussinesq problem for a punch of arbitrary profile", Int. J. Engng Sci. 3, 47-57: for a
// smooth profile f(r) (f(0) = 0, f' = df/dr) and contact radius a,
//   depth  h = a   int_0^a f'(r) / sqrt(a^2 - r^2) dr
//   load   F = 2 E* int_0^a r^2 f'(r) / sqrt(a^2 - r^2) dr
// and the worked cases flat-ended cylinder, cone and sphere. (Johnson, Contact Mechanics,
// 1985, ch. 3 and 5, for the same results and Hertz's limit.)
// ---------------------------------------------------------------------------------------

/// Sneddon's cone: `F = (2/pi) tan(alpha) E* h^2` (N), alpha the half-angle from the axis.
pub fn sneddon_cone_force(h: f64, alpha_deg: f64, e_star: f64) -> f64 {
    2.0 / PI * alpha_deg.to_radians().tan() * e_star * h * h
}

/// Sneddon's cone contact radius `a = 2 h tan(alpha) / pi` (mm).
pub fn sneddon_cone_radius(h: f64, alpha_deg: f64) -> f64 {
    2.0 * h * alpha_deg.to_radians().tan() / PI
}

/// Sneddon's exact sphere (not Hertz's paraboloid), radius `big_r`, contact radius `a`:
/// `h = (a/2) ln((R+a)/(R-a))`, `F = (E*/2) [(a^2+R^2) ln((R+a)/(R-a)) - 2 a R]`.
/// Returns `(h, F)`.
pub fn sneddon_sphere(a: f64, big_r: f64, e_star: f64) -> (f64, f64) {
    let l = ((big_r + a) / (big_r - a)).ln();
    let h = 0.5 * a * l;
    let f = 0.5 * e_star * ((a * a + big_r * big_r) * l - 2.0 * a * big_r);
    (h, f)
}

/// Contact radius and force of Sneddon's sphere at depth `h`: `h(a)` is increasing on
/// `(0, R)`, so `a` is found by bisection to round-off. Returns `(a, F)`.
pub fn sneddon_sphere_at_depth(h: f64, big_r: f64, e_star: f64) -> (f64, f64) {
    let (mut lo, mut hi) = (0.0, big_r * (1.0 - 1e-15));
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if sneddon_sphere(mid, big_r, e_star).0 < h {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let a = 0.5 * (lo + hi);
    (a, sneddon_sphere(a, big_r, e_star).1)
}

/// Hertz's paraboloid at depth h: `F = (4/3) E* sqrt(R) h^(3/2)` (N), for contrast only.
pub fn hertz_force(h: f64, big_r: f64, e_star: f64) -> f64 {
    4.0 / 3.0 * e_star * big_r.sqrt() * h.powf(1.5)
}

/// Flat cylindrical punch of radius a (Boussinesq): `F = 2 E* a h` (N).
pub fn flat_force(h: f64, a: f64, e_star: f64) -> f64 {
    2.0 * e_star * a * h
}

/// Sneddon's general integrals for a profile slope `df(r)` and contact radius `a`,
/// evaluated by composite Simpson quadrature after `r = a sin(theta)` removes the
/// inverse-square-root singularity. Returns `(h, F)`. Used to check the closed forms.
pub fn sneddon_integrals(df: impl Fn(f64) -> f64, a: f64, e_star: f64) -> (f64, f64) {
    let n = 4000; // even
    let dth = 0.5 * PI / n as f64;
    let (mut ih, mut ifo) = (0.0, 0.0);
    for k in 0..=n {
        let th = k as f64 * dth;
        let w = if k == 0 || k == n {
            1.0
        } else if k % 2 == 1 {
            4.0
        } else {
            2.0
        };
        let s = th.sin();
        let d = df(a * s);
        ih += w * d;
        ifo += w * s * s * d;
    }
    let (ih, ifo) = (ih * dth / 3.0, ifo * dth / 3.0);
    (a * ih, 2.0 * e_star * a * a * ifo)
}

// ---------------------------------------------------------------------------------------
// Meshes
// ---------------------------------------------------------------------------------------

/// The cylinder family of docs/theory.md §11: side `size` (mm) both ways, `n x n` elements,
/// grading `q` towards the axis and the top.
pub fn cylinder(size: f64, n: usize, q: f64) -> Mesh {
    CylinderMesher {
        radius: size,
        height: size,
        nr: n,
        nz: n,
        grading_r: q,
        grading_z: q,
    }
    .build()
    .expect("valid cylinder")
}

/// Side of the cylinder that prolongs the graded grid of `(side0, n0, q)` by `extra`
/// elements both ways with the same ratio: the first `n0` element rows and columns are
/// those of the `side0` cylinder (same near field), only the far field grows.
pub fn extended_side(side0: f64, n0: usize, q: f64, extra: usize) -> f64 {
    let h0 = side0 * (q - 1.0) / (q.powi(n0 as i32) - 1.0);
    h0 * (q.powi((n0 + extra) as i32) - 1.0) / (q - 1.0)
}

/// The extended cylinder of [`extended_side`].
pub fn extended_cylinder(side0: f64, n0: usize, q: f64, extra: usize) -> Mesh {
    cylinder(extended_side(side0, n0, q, extra), n0 + extra, q)
}

/// Radii of the `top` nodes (sorted).
pub fn top_radii(mesh: &Mesh) -> Vec<f64> {
    mesh.node_set("top")
        .iter()
        .map(|&n| mesh.nodes[n][0])
        .collect()
}

// ---------------------------------------------------------------------------------------
// Runners
// ---------------------------------------------------------------------------------------

/// Options without field recording (the validation only reads forces and active sets).
pub fn options() -> SolverOptions {
    SolverOptions {
        record_fields: false,
        ..SolverOptions::default()
    }
}

/// Runs `schedule` for the elastic law `[E, NU]` on a fresh model.
pub fn run_elastic(mesh: Mesh, punch: Punch, schedule: &Schedule) -> Trajectory {
    let model = Model::new(mesh, punch).expect("valid model");
    let mut solver = DirectSolver::new(&model).expect("symbolic analysis");
    solver
        .run(
            &indentify_laws::LawMaterial(&Elastic),
            &[E, NU],
            schedule,
            &options(),
        )
        .expect("elastic run converges")
}

/// One-step schedule from the undeformed state straight to depth `h` (valid for the
/// elastic law, whose contact solution does not depend on the path).
pub fn one_step(h: f64) -> Schedule {
    Schedule::from_segments(&[Segment {
        duration: 1.0,
        depth: h,
        steps: 1,
    }])
    .expect("valid schedule")
}

/// Force (N) at depth `h`, reached in one step.
pub fn force_at_depth(mesh: Mesh, punch: Punch, h: f64) -> f64 {
    run_elastic(mesh, punch, &one_step(h))
        .steps
        .last()
        .expect("one step")
        .force
}

/// Relative difference `x / reference - 1`.
pub fn rel(x: f64, reference: f64) -> f64 {
    x / reference - 1.0
}
