//! A law outside the built-ins, checked as an author outside the workspace checks theirs:
//! the worked example of docs/adding-a-law.md (a Burgers solid), registered behind the
//! feature `example-law`, built through the registry by its configuration name and checked
//! with the public `indentify_laws::testing` (feature `testing`): every Jacobian block
//! against finite differences, and creep against its closed form.
//!
//! `cargo test -p indentify-laws --features testing,example-law --test example_law`

use indentify_laws::catalog;
use indentify_laws::registry::{self, SpecValue};
use indentify_laws::testing::{Point, Shear, check_material, shear_history};

const C: [(&str, f64); 5] = [
    ("E", 3000.0),
    ("nu", 0.35),
    ("eta", 5e4),
    ("Gk", 800.0),
    ("etak", 2000.0),
];

fn build() -> registry::Built {
    let fields: Vec<(String, SpecValue)> = C
        .iter()
        .map(|(n, v)| (n.to_string(), SpecValue::Number(*v)))
        .collect();
    registry::build("Burgers", &fields).unwrap()
}

/// The registered law is found by name, listed by the catalog with its parameters, and
/// every block of its material point matches finite differences.
#[test]
fn the_registered_example_passes_the_block_checks() {
    assert!(registry::VARIANTS.contains(&"Burgers"));
    let listed = catalog::catalog().unwrap();
    let b = listed
        .iter()
        .find(|l| l.entry.variant == "Burgers")
        .unwrap();
    let names: Vec<&str> = b.params().iter().map(|p| p.name).collect();
    assert_eq!(names, ["E", "nu", "eta", "Gk", "etak"]);
    let built = build();
    let c = built.params.clone();
    let m = built.material.as_ref();
    assert_eq!(m.n_internal(), 4);
    // deterministic points from small to large steps, with a prior stress and Kelvin strain
    for k in 0..12 {
        let x = k as f64;
        let mut y0 = [0.0; 8];
        y0[..4].copy_from_slice(&[3.0 * x.sin(), -2.0 + x.cos(), 1.5, 4.0 * (0.7 * x).sin()]);
        // a deviatoric Kelvin strain (Mandel rr, zz, tt, rz)
        let (a, b2) = (1e-4 * (1.0 + x), -2e-4 * x.cos());
        y0[4..].copy_from_slice(&[a, b2, -a - b2, 1e-4]);
        let deps = indentify_laws::Vec4([1e-3 * x.cos(), -4e-3, 2e-3 * (x - 5.0) / 5.0, 3e-3]);
        let pt = Point {
            c: &c,
            y0: &y0,
            deps,
            dt: 10f64.powf(-2.0 + 0.35 * x),
        };
        let r = check_material(m, &pt, 1e-6);
        assert!(r.is_ok(), "point {k}: {r:?}");
    }
}

/// Creep under a held shear stress follows the exact backward-Euler solution (Maxwell
/// part `s t / eta`, Kelvin part `s/(2 Gk) (1 - (etak/(etak + dt Gk))^n)`).
#[test]
fn the_registered_example_creeps_as_its_closed_form() {
    let built = build();
    let c = built.params.clone();
    let (s, t_end, n) = (10.0, 4.0, 40);
    let dt = t_end / n as f64;
    let mut steps = vec![(Shear::Stress(s), 0.0)];
    steps.extend(std::iter::repeat_n((Shear::Stress(s), dt), n));
    let last = shear_history(built.material.as_ref(), &c, &[0.0; 8], &steps)
        .unwrap()
        .pop()
        .unwrap();
    let g2 = c[0] / (1.0 + c[1]);
    let ek = s / (2.0 * c[3]) * (1.0 - (c[4] / (c[4] + dt * c[3])).powi(n as i32));
    let exact = s / g2 + s * t_end / c[2] + ek;
    assert!(
        (last.eps[3] - exact).abs() <= 1e-12 * exact,
        "{} vs {exact}",
        last.eps[3]
    );
}
