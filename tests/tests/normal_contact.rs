//! Normal contact (`ContactKind::Normal`: the gap of a displaced node along the punch
//! surface's normal, the reaction along that normal) against half-space references, and
//! its force change from the paper's vertical contact on the reference problems.
//!
//! References: I. N. Sneddon, Int. J. Engng Sci. 3 (1965) 47-57 (cone, sphere, flat
//! punch, as in `sneddon.rs`); J. C. Hay, A. Bolshakov & G. M. Pharr, "A critical
//! examination of the fundamental relations used in the analysis of nanoindentation
//! data", J. Mater. Res. 14 (1999) 2296-2305: Sneddon's solution imposes the vertical
//! displacement only, and the inward radial displacement of the surface under a cone
//! makes a body that keeps contact with the flank stiffer by the factor
//!
//! ```text
//!   gamma = pi (pi/4 + 0.1548 cot(alpha) (1 - 2 nu) / (4 (1 - nu)))
//!              / (pi/2 - 0.8312 cot(alpha) (1 - 2 nu) / (4 (1 - nu)))^2
//!         = 1.0761 for alpha = 68 deg, nu = 0.3
//! ```
//!
//! compared here, as the issue asks, with the force over Sneddon's. Hertz's sphere is
//! the small-depth limit where vertical and normal contact meet (the radial effect grows
//! with a/R).
//!
//! Mesh: R0's (docs/theory.md §11: 10 mm cylinder, 20 x 20 Q8 graded 1.3), the finite-cylinder
//! effect removed by prolonging the graded grid to sides 48.5 and 234 mm and
//! extrapolating linearly in 1/L (as `sneddon.rs`).
//!
//! ```text
//!            \   cone 68 deg /     rigid, frictionless; normal contact: the node x = X + u
//!   z = 0  o--o-o\oo-o-oo-o/-o--o   is kept on the flank along its normal n
//!          |ooooooooooo  graded 1.3   (axis node: u_r = 0, vertical by symmetry)
//!   axis   |o o o  o   o     o   |
//!   z = -10+---------------------+  bottom u_z = 0;  E = 20000 MPa, nu = 0.3, h = 0.1 mm
//! ```

mod common;

use common::*;
use indentify_contact::punch::treat_rim;
use indentify_contact::{
    ContactKind, DirectSolver, Model, Punch, Schedule, SolverOptions, Trajectory, trapezoid,
};
use indentify_laws::{Elastic, Law, Maxwell, NortonHoff};
use indentify_mesh::Mesh;
use indentify_mesh::cylinder::graded_positions;

const N0: usize = 20;
const Q0: f64 = 1.3;
const SIDE0: f64 = 10.0;

fn cone() -> Punch {
    Punch::Cone {
        half_angle_deg: ALPHA_DEG,
    }
}

/// Hay, Bolshakov & Pharr's (1999) radial-displacement factor of a cone.
fn hay_gamma(alpha_deg: f64, nu: f64) -> f64 {
    let cot = 1.0 / alpha_deg.to_radians().tan();
    let k = (1.0 - 2.0 * nu) / (4.0 * (1.0 - nu));
    let pi = std::f64::consts::PI;
    pi * (pi / 4.0 + 0.1548 * cot * k) / (pi / 2.0 - 0.8312 * cot * k).powi(2)
}

/// Elastic force at depth `h` reached in one step.
fn force(mesh: Mesh, punch: &Punch, kind: ContactKind, h: f64) -> f64 {
    let model = Model::with_contact(mesh, punch.clone(), kind).expect("model");
    let mut solver = DirectSolver::new(&model).expect("analysis");
    solver
        .run(
            &indentify_laws::LawMaterial(&Elastic),
            &[E, NU],
            &one_step(h),
            &options(),
        )
        .expect("elastic run")
        .steps[0]
        .force
}

/// Forces on the near field `(n, q)` prolonged to three sides and the half-space force
/// (linear in 1/L through the two largest), flat punches with their rim treated.
fn half_space_force(n: usize, q: f64, punch: &Punch, kind: ContactKind, h: f64) -> (f64, f64) {
    half_space_force_on(SIDE0, n, q, punch, kind, h)
}

/// [`half_space_force`] with the near field of side `side0` (mm).
fn half_space_force_on(
    side0: f64,
    n: usize,
    q: f64,
    punch: &Punch,
    kind: ContactKind,
    h: f64,
) -> (f64, f64) {
    let extras = [0, 6 * n / 20, 12 * n / 20];
    let side = extras.map(|x| extended_side(side0, n, q, x));
    let f = extras.map(|x| {
        let mut mesh = extended_cylinder(side0, n, q, x);
        if let Punch::Flat { .. } = punch {
            mesh = treat_rim(mesh, punch).expect("rim").0;
        }
        force(mesh, punch, kind, h)
    });
    let (l1, l2) = (1.0 / side[1], 1.0 / side[2]);
    (f[0], f[2] - (f[1] - f[2]) * l2 / (l1 - l2))
}

/// The reference shall be right: gamma = 1.076 for the 68 deg cone at nu = 0.3 (the
/// value Hay, Bolshakov & Pharr tabulate), 1 for an incompressible solid.
#[test]
fn hay_gamma_is_the_published_value() {
    let g = hay_gamma(68.0, 0.3);
    assert!((g - 1.0761).abs() < 5e-5, "{g}");
    assert!((hay_gamma(68.0, 0.5) - 1.0).abs() < 1e-12);
}

/// The solver with normal contact shall give the elastic cone's half-space force at
/// least 2% above Sneddon's and below gamma x Sneddon (Hay, Bolshakov & Pharr's estimate,
/// an upper bound here: within 5% of it), and 3% to 4.5% above vertical contact, on R0's
/// mesh.
#[test]
fn cone_matches_sneddon_with_the_radial_correction() {
    let es = e_star(E, NU);
    let f_sn = sneddon_cone_force(H_MAX, ALPHA_DEG, es);
    let gamma = hay_gamma(ALPHA_DEG, NU);
    let (f10_n, f_n) = half_space_force(N0, Q0, &cone(), ContactKind::Normal, H_MAX);
    let (f10_v, f_v) = half_space_force(N0, Q0, &cone(), ContactKind::Vertical, H_MAX);
    println!(
        "cone: Sneddon {f_sn:.3} N, gamma {gamma:.4}; normal F(10 mm) {f10_n:.3}, half space {f_n:.3} N = {:.4} x Sneddon ({:+.2}% vs gamma x Sneddon); vertical F(10 mm) {f10_v:.3}, half space {f_v:.3} N = {:.4} x Sneddon; normal/vertical {:+.2}%",
        f_n / f_sn,
        100.0 * rel(f_n, gamma * f_sn),
        f_v / f_sn,
        100.0 * rel(f_n, f_v)
    );
    assert!(f_n > 1.02 * f_sn && f_n < gamma * f_sn, "{f_n} vs {f_sn}");
    assert!(
        rel(f_n, gamma * f_sn).abs() < 0.05,
        "{f_n} vs {}",
        gamma * f_sn
    );
    assert!((0.03..0.045).contains(&rel(f_n, f_v)), "{f_n} vs {f_v}");
}

/// The sphere (R = 0.5 mm) with normal and vertical contact shall both tend to Hertz's
/// (and Sneddon's exact sphere) force as the depth decreases: their difference shrinks
/// like a/R at small a/R (halving a/R from 0.056 to 0.028 divides it by 1.6 to 2.5), to
/// less than 0.15 times its value at a/R = 0.43, and both are within 0.5% of Hertz at
/// a/R = 0.028. The mesh is R0's scaled
/// with the contact radius, so that every depth has the same elements under contact
/// (elasticity has no length scale but R: only a/R changes).
#[test]
fn sphere_tends_to_hertz_at_small_depth() {
    let es = e_star(E, NU);
    let big_r = 0.5;
    let punch = Punch::Sphere { radius: big_r };
    let a0 = sneddon_sphere_at_depth(H_MAX, big_r, es).0;
    let mut diffs = Vec::new();
    let mut last = (0.0, 0.0);
    for h in [0.1, 0.025, 0.00625, 0.0015625, 0.000390625] {
        let (a, f_sn) = sneddon_sphere_at_depth(h, big_r, es);
        let f_hz = hertz_force(h, big_r, es);
        let side = SIDE0 * a / a0;
        let (_, f_n) = half_space_force_on(side, N0, Q0, &punch, ContactKind::Normal, h);
        let (_, f_v) = half_space_force_on(side, N0, Q0, &punch, ContactKind::Vertical, h);
        last = (rel(f_n, f_hz), rel(f_v, f_hz));
        println!(
            "sphere h = {h}: a/R = {:.3}; Hertz {f_hz:.4} N, Sneddon {f_sn:.4} N; normal {f_n:.4} ({:+.2}% vs Sneddon, {:+.2}% vs Hertz), vertical {f_v:.4} ({:+.2}%, {:+.2}%); normal/vertical {:+.2}%",
            a / big_r,
            100.0 * rel(f_n, f_sn),
            100.0 * rel(f_n, f_hz),
            100.0 * rel(f_v, f_sn),
            100.0 * rel(f_v, f_hz),
            100.0 * rel(f_n, f_v)
        );
        diffs.push(rel(f_n, f_v));
    }
    assert!(diffs[4] > 0.0 && diffs[4] < 0.15 * diffs[0], "{diffs:?}");
    assert!((1.6..2.5).contains(&(diffs[3] / diffs[4])), "{diffs:?}");
    assert!(last.0.abs() < 0.005 && last.1.abs() < 0.005, "{last:?}");
}

/// The flat punch with normal contact shall give Boussinesq's `2 E* a h` within 2% in
/// the half space (quarter-point rim), the same force as vertical contact: on the face
/// the normal is vertical and the rim node moves inward.
#[test]
fn flat_punch_matches_boussinesq() {
    let es = e_star(E, NU);
    let a = graded_positions(SIDE0, N0, Q0)[6];
    let punch = Punch::Flat { radius: a };
    let f_ref = flat_force(H_MAX, a, es);
    let (_, f_n) = half_space_force(N0, Q0, &punch, ContactKind::Normal, H_MAX);
    let (_, f_v) = half_space_force(N0, Q0, &punch, ContactKind::Vertical, H_MAX);
    println!(
        "flat a = {a:.4}: Boussinesq {f_ref:.3} N; normal {f_n:.3} N ({:+.2}%), vertical {f_v:.3} N",
        100.0 * rel(f_n, f_ref)
    );
    assert!(rel(f_n, f_ref).abs() < 0.02);
    assert!(rel(f_n, f_v).abs() < 1e-9);
}

/// The R0/R1/R2 run of docs/theory.md §11 with contact `kind`.
fn reference_run(law: &dyn Law, c: &[f64], kind: ContactKind) -> Trajectory {
    let model = Model::with_contact(cylinder(SIDE0, N0, Q0), cone(), kind).unwrap();
    let mut solver = DirectSolver::new(&model).unwrap();
    let sched = Schedule::from_segments(&trapezoid(H_MAX, 1.0, 1.0, 1.0, 30)).unwrap();
    let opts = SolverOptions {
        record_fields: false,
        ..SolverOptions::default()
    };
    solver
        .run(&indentify_laws::LawMaterial(law), c, &sched, &opts)
        .unwrap()
}

/// Turning the gap direction from vertical to normal shall change R0's force by +3% to
/// +4.5% at every time with contact, R1's by less than +5% in magnitude, and R2's by -19%
/// to -35% (the ranges of the issue), at t = 0.5, 1, 1.5 and 2 s.
#[test]
fn normal_versus_vertical_on_the_reference_problems() {
    // name, law, parameters, admissible range of F_normal / F_vertical - 1
    type Case<'a> = (&'a str, &'a dyn Law, Vec<f64>, (f64, f64));
    let cases: [Case; 3] = [
        ("R0 elastic", &Elastic, vec![E, NU], (0.03, 0.045)),
        ("R1 Maxwell", &Maxwell, vec![E, NU, 30000.0], (-0.05, 0.05)),
        (
            "R2 Norton-Hoff",
            &NortonHoff,
            vec![1e5, 0.3, 1500.0, 5.0, 500.0],
            (-0.35, -0.19),
        ),
    ];
    for (name, law, c, (lo, hi)) in cases {
        let v = reference_run(law, &c, ContactKind::Vertical).forces();
        let n = reference_run(law, &c, ContactKind::Normal).forces();
        let mut line = format!("{name}:");
        for j in [15, 30, 45, 60] {
            let d = rel(n[j], v[j]);
            line += &format!(
                " t = {} s: {:.2} -> {:.2} N ({:+.1}%);",
                j as f64 / 30.0,
                v[j],
                n[j],
                100.0 * d
            );
            assert!((lo..hi).contains(&d), "{name} at step {j}: {d}");
        }
        println!("{line}");
    }
}

/// Prints the refinement table of docs/validation-contact.md (release profile:
/// `cargo test -p indentify-tests --release --test normal_contact -- --ignored --nocapture`).
#[test]
#[ignore = "study: prints the refinement table of docs/validation-contact.md (release, ~1 min)"]
fn refinement_table() {
    let es = e_star(E, NU);
    let f_sn = sneddon_cone_force(H_MAX, ALPHA_DEG, es);
    let gamma = hay_gamma(ALPHA_DEG, NU);
    println!(
        "| mesh | smallest element (mm) | normal: F half space / Sneddon | vs gamma x Sneddon | vertical: F / Sneddon | normal / vertical |"
    );
    println!("|---|---|---|---|---|---|");
    for n in [10, 20, 28, 40, 56, 80] {
        let q = Q0.powf(N0 as f64 / n as f64);
        let h0 = graded_positions(SIDE0, n, q)[1];
        let (_, f_n) = half_space_force(n, q, &cone(), ContactKind::Normal, H_MAX);
        let (_, f_v) = half_space_force(n, q, &cone(), ContactKind::Vertical, H_MAX);
        println!(
            "| {n} x {n}, q = {q:.4} | {h0:.4} | {:.4} | {:+.2}% | {:.4} | {:+.2}% |",
            f_n / f_sn,
            100.0 * rel(f_n, gamma * f_sn),
            f_v / f_sn,
            100.0 * rel(f_n, f_v)
        );
    }
}
