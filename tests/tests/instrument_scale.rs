//! Instrument-scale indentation on the automatic specimen (`auto_specimen`): a Berkovich
//! tip (its area-equivalent cone, 70.3 deg) at 2 um and at 0.1 mm and a 10 um sphere at
//! 0.5 um against Sneddon's half-space solutions, the exact scale invariance of the elastic
//! cone, the element budget and the finite-size effect of the automatic cylinder.
//!
//! References: I. N. Sneddon, Int. J. Engng Sci. 3 (1965) 47-57 (cone and exact sphere,
//! closed forms in `common`); with `E* = E / (1 - nu^2)`:
//!
//! ```text
//!   cone (half-angle alpha):  F = 2 E tan(alpha) h^2 / (pi (1 - nu^2))   (exactly ~ h^2)
//!   sphere (radius R):        h = (a/2) ln((R+a)/(R-a)),
//!                             F = (E*/2) [(a^2+R^2) ln((R+a)/(R-a)) - 2 a R]
//! ```
//!
//! The elastic cone problem has no length scale: with a mesh proportional to h (the
//! automatic specimen is `a_max` times numbers that depend on the options only), the
//! discrete force over `E h^2` is the same at every depth, to round-off.
//!
//! Goal: forces within 2% of Sneddon at both scales (equal errors, to 1e-9), at most 625
//! elements, and a finite-size effect below 1% (doubling the cylinder changes F by < 1%).
//!
//! ```text
//!            punch (rigid, frictionless), one step to h
//!                \    /
//!   z = 0  o-o-o-o\oo/o-o-o--o---o-----o---------o   top: contact candidates
//!          |  core a x a: 8 x 8 squares |         |  a = 1.2 x intersection radius at h
//!          |----------+   graded <= 1.5 outwards  |  outer face r = k a: free
//!   axis   |          |                           |  k = 48 (default)
//!   z=-k a +--------------------------------------+
//!          bottom: u_z = 0               E = 20000 MPa, nu = 0.3 (R0's law)
//! ```
//!
//! The ignored `refinement_instrument_scale` prints the tables of `docs/validation.md`,
//! "Instrument scale".

mod common;

use common::*;
use indentify_contact::Punch;
use indentify_contact::punch::{AutoOptions, BERKOVICH_HALF_ANGLE_DEG, auto_specimen};

/// Relative tolerance of the force checks (as the Sneddon tests).
const TOL: f64 = 0.02;
/// Sphere radius (mm): a 10 um spherical tip.
const SPHERE_R: f64 = 0.01;
/// Sphere depth (mm): 0.5 um.
const SPHERE_H: f64 = 5e-4;

fn berkovich() -> Punch {
    Punch::Berkovich { tip_radius: None }
}

fn sphere() -> Punch {
    Punch::Sphere { radius: SPHERE_R }
}

/// Force at depth `h` on the automatic specimen of `options`, and its element count.
fn auto_force(punch: &Punch, h: f64, options: &AutoOptions) -> (f64, usize) {
    let mesh = auto_specimen(punch, h, options)
        .expect("valid automatic specimen")
        .build()
        .expect("valid mesh");
    let n = mesh.elements.len();
    (force_at_depth(mesh, punch.clone(), h), n)
}

/// Sneddon's force of the cone (Berkovich-equivalent) at depth h.
fn cone_reference(h: f64) -> f64 {
    sneddon_cone_force(h, BERKOVICH_HALF_ANGLE_DEG, e_star(E, NU))
}

/// The automatic specimen shall resolve a 2 um and a 0.1 mm Berkovich indent alike: both
/// forces within 2% of Sneddon's cone, with the same relative error to round-off (F ~ h^2
/// exactly), on at most 625 elements (the default 25 x 25).
#[test]
fn berkovich_at_2um_and_0p1mm_match_sneddon_equally() {
    let o = AutoOptions::default();
    let mut errors = Vec::new();
    for h in [2e-3, 0.1] {
        let (f, n) = auto_force(&berkovich(), h, &o);
        let err = rel(f, cone_reference(h));
        println!(
            "Berkovich h = {h} mm: F = {f:.6e} N, Sneddon {:.6e} N, {:+.4}%, {n} elements",
            cone_reference(h),
            100.0 * err
        );
        assert!(err.abs() < TOL, "h = {h}: {err}");
        assert!(n <= 625, "{n} elements");
        errors.push((f / (h * h), err));
    }
    let scale = rel(errors[0].0, errors[1].0);
    println!("F/h^2 at 2 um vs 0.1 mm: {scale:+.2e}");
    assert!(scale.abs() < 1e-9, "{errors:?}");
}

/// The elastic cone's force shall scale as h^2 exactly over five decades of depth on the
/// automatic specimen (0.1 um to 10 mm), to 1e-9.
#[test]
fn cone_force_scales_as_depth_squared() {
    let o = AutoOptions::default();
    let (f0, _) = auto_force(&berkovich(), 1e-3, &o);
    for h in [1e-4, 3e-2, 10.0] {
        let (f, _) = auto_force(&berkovich(), h, &o);
        let d = rel(f / (h * h), f0 / 1e-6);
        assert!(d.abs() < 1e-9, "h = {h}: {d:e}");
    }
}

/// A 10 um sphere at 0.5 um on the automatic specimen shall give Sneddon's exact-sphere
/// force within 2% on at most 625 elements (the default 25 x 25).
#[test]
fn sphere_10um_at_0p5um_matches_sneddon() {
    let (f, n) = auto_force(&sphere(), SPHERE_H, &AutoOptions::default());
    let (a, f_sn) = sneddon_sphere_at_depth(SPHERE_H, SPHERE_R, e_star(E, NU));
    let err = rel(f, f_sn);
    println!(
        "sphere R = 10 um, h = 0.5 um: F = {f:.6e} N, Sneddon {f_sn:.6e} N (a = {a:.4e} mm), {:+.4}%, {n} elements",
        100.0 * err
    );
    assert!(err.abs() < TOL, "{f} vs {f_sn}");
    assert!(n <= 625, "{n} elements");
}

/// Doubling the automatic cylinder (radius and height) shall change the force by less
/// than 1% (cone and sphere), and make it smaller (the clamped bottom stiffens).
#[test]
fn doubling_the_auto_cylinder_changes_the_force_by_less_than_one_percent() {
    let o = AutoOptions::default();
    let big = AutoOptions {
        size_factor: 2.0 * o.size_factor,
        ..o
    };
    for (p, h) in [(berkovich(), 2e-3), (sphere(), SPHERE_H)] {
        let (f, _) = auto_force(&p, h, &o);
        let (f2, _) = auto_force(&p, h, &big);
        let d = rel(f, f2);
        println!("{}: F(k) / F(2k) - 1 = {:+.4}%", p.describe(), 100.0 * d);
        assert!(d > 0.0 && d < 0.01, "{f} vs {f2}");
    }
}

/// Worn Berkovich and cube-corner tips shall run on their automatic specimens at 1 um
/// (sphero-cone profiles), within the element budget, the worn tip softer than the sharp
/// cone only by a little (R = 0.2 um << contact radius).
#[test]
fn rounded_tips_run_on_the_auto_specimen() {
    let o = AutoOptions::default();
    let h = 1e-3;
    let (sharp, _) = auto_force(&berkovich(), h, &o);
    let (worn, n) = auto_force(
        &Punch::Berkovich {
            tip_radius: Some(2e-4),
        },
        h,
        &o,
    );
    assert!(n <= 625);
    assert!(
        worn > 0.9 * sharp && worn < 1.2 * sharp,
        "{worn} vs {sharp}"
    );
    let (cc, _) = auto_force(&Punch::CubeCorner { tip_radius: None }, h, &o);
    let f_cc = sneddon_cone_force(h, 42.28, e_star(E, NU));
    assert!(rel(cc, f_cc).abs() < TOL, "cube corner {cc} vs {f_cc}");
}

// ---------------------------------------------------------------------------------------
// Studies (ignored): the tables of docs/validation.md, "Instrument scale".
// ---------------------------------------------------------------------------------------

fn cases() -> [(Punch, f64, f64, &'static str); 2] {
    let (_, f_sphere) = sneddon_sphere_at_depth(SPHERE_H, SPHERE_R, e_star(E, NU));
    [
        (
            berkovich(),
            2e-3,
            cone_reference(2e-3),
            "Berkovich, h = 2 um",
        ),
        (sphere(), SPHERE_H, f_sphere, "sphere R = 10 um, h = 0.5 um"),
    ]
}

/// Half-space force from the 1/k law through the two largest sizes `k` and `2k`.
fn extrapolated(f_k: f64, f_2k: f64) -> f64 {
    2.0 * f_2k - f_k
}

/// Prints the size, resolution, grading and scale tables of docs/validation.md.
#[test]
#[ignore]
fn refinement_instrument_scale() {
    let d = AutoOptions::default();
    println!("### Finite-size effect (8 elements in contact, grading 1.5)\n");
    let ks = [10.0, 20.0, 32.0, 48.0, 64.0, 96.0, 160.0, 320.0, 640.0];
    println!("| k | elements | cone F (N) | cone effect | sphere F (N) | sphere effect |");
    println!("|---|---|---|---|---|---|");
    let runs: Vec<Vec<(f64, usize)>> = cases()
        .iter()
        .map(|(p, h, _, _)| {
            ks.iter()
                .map(|&k| {
                    auto_force(
                        p,
                        *h,
                        &AutoOptions {
                            size_factor: k,
                            ..d
                        },
                    )
                })
                .collect()
        })
        .collect();
    let m = ks.len();
    let inf: Vec<f64> = runs
        .iter()
        .map(|r| extrapolated(r[m - 2].0, r[m - 1].0))
        .collect();
    for (i, k) in ks.iter().enumerate() {
        println!(
            "| {k} | {} | {:.6e} | {:+.3}% | {:.6e} | {:+.3}% |",
            runs[0][i].1,
            runs[0][i].0,
            100.0 * rel(runs[0][i].0, inf[0]),
            runs[1][i].0,
            100.0 * rel(runs[1][i].0, inf[1]),
        );
    }
    for (c, f) in cases().iter().zip(&inf) {
        println!(
            "\n{}: half space (1/k from k = 320, 640) {f:.6e} N, Sneddon {:.6e} N, {:+.3}%; C = effect x k at k = 48: {:.3}",
            c.3,
            c.2,
            100.0 * rel(*f, c.2),
            48.0 * rel(runs[if c.0 == berkovich() { 0 } else { 1 }][3].0, *f),
        );
    }

    println!("\n### Elements across the contact-radius bound (k = 48, grading 1.5)\n");
    println!(
        "| elements in contact | elements | cone error (k = 48) | cone error, half space | sphere error (k = 48) | sphere error, half space |"
    );
    println!("|---|---|---|---|---|---|");
    for n in [4, 6, 8, 10, 12, 16] {
        let mut row = Vec::new();
        let mut count = 0;
        for (p, h, f_ref, _) in cases() {
            let at = |k: f64| {
                auto_force(
                    &p,
                    h,
                    &AutoOptions {
                        elements_in_contact: n,
                        size_factor: k,
                        ..d
                    },
                )
            };
            let (f48, c) = at(48.0);
            let f_inf = extrapolated(at(320.0).0, at(640.0).0);
            count = c;
            row.push(format!(
                "{:+.3}% | {:+.3}%",
                100.0 * rel(f48, f_ref),
                100.0 * rel(f_inf, f_ref)
            ));
        }
        println!("| {n} | {count} | {} | {} |", row[0], row[1]);
    }

    println!("\n### Grading of the far field (8 elements in contact, k = 48)\n");
    println!("| grading | elements | cone error | sphere error |");
    println!("|---|---|---|---|");
    for q in [1.2, 1.3, 1.5, 2.0, 2.5] {
        let o = AutoOptions { grading: q, ..d };
        let r: Vec<(f64, usize)> = cases()
            .iter()
            .map(|(p, h, f_ref, _)| {
                let (f, n) = auto_force(p, *h, &o);
                (rel(f, *f_ref), n)
            })
            .collect();
        println!(
            "| {q} | {} | {:+.3}% | {:+.3}% |",
            r[0].1,
            100.0 * r[0].0,
            100.0 * r[1].0
        );
    }

    println!("\n### Scale invariance (Berkovich, defaults)\n");
    println!(
        "| h (mm) | a bound (mm) | F (N) | F / h^2 (N/mm^2) | vs h = 0.1 mm | error vs Sneddon |"
    );
    println!("|---|---|---|---|---|---|");
    let (f_ref, _) = auto_force(&berkovich(), 0.1, &d);
    for h in [1e-4, 2e-3, 5e-3, 0.1, 1.0] {
        let (f, _) = auto_force(&berkovich(), h, &d);
        println!(
            "| {h} | {:.4e} | {f:.6e} | {:.9e} | {:+.1e} | {:+.4}% |",
            berkovich().contact_radius_bound(h),
            f / (h * h),
            rel(f / (h * h), f_ref / 0.01),
            100.0 * rel(f, cone_reference(h))
        );
    }
}
