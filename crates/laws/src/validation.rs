//! Material-point validation of the laws with internal variables against closed forms
//! (docs/validation-laws.md): uniaxial tension, unloading and reversed compression of
//! `Plastic` for every hardening form, and the rate-independent limit of its Norton form.
//! (Prony's relaxation and creep are in `prony.rs`.)

use crate::hardening::{Hardening, Table};
use crate::material::Material;
use crate::plastic::{Plastic, Rate};
use crate::testing::{Shear, uniaxial_path};

const E: f64 = 7e4;
const NU: f64 = 0.3;
const SY: f64 = 300.0;

/// The hardening curves written out again, independently of `hardening.rs`.
fn flow_stress(form: &str, p: f64) -> f64 {
    match form {
        "Linear" => SY + 2000.0 * p,
        "Power" => SY * (1.0 + E * p / SY).powf(0.2),
        "Voce" => SY + 150.0 * (1.0 - (-40.0 * p).exp()),
        "Swift" => SY * (1.0 + p / 0.01).powf(0.25),
        "Table" => {
            let pts = [(0.0, 300.0), (0.004, 360.0), (0.02, 420.0), (0.1, 470.0)];
            let i = pts.iter().rposition(|q| q.0 <= p).unwrap().min(2);
            let (a, b) = (pts[i], pts[i + 1]);
            a.1 + (b.1 - a.1) * (p - a.0) / (b.0 - a.0)
        }
        _ => unreachable!(),
    }
}

fn law(form: &str, rate: Rate) -> (Plastic, Vec<f64>) {
    let (h, hp): (Hardening, Vec<f64>) = match form {
        "Linear" => (Hardening::Linear, vec![2000.0]),
        "Power" => (Hardening::Power, vec![0.2]),
        "Voce" => (Hardening::Voce, vec![150.0, 40.0]),
        "Swift" => (Hardening::Swift, vec![0.01, 0.25]),
        _ => (
            Hardening::Table(
                Table::new(&[(0.0, 300.0), (0.004, 360.0), (0.02, 420.0), (0.1, 470.0)]).unwrap(),
            ),
            vec![],
        ),
    };
    let mut c = vec![E, NU, SY];
    c.extend(hp);
    if rate == Rate::Norton {
        c.extend([1.0, 3.0]);
    }
    (Plastic::new(h, rate), c)
}

/// The root `p >= 0` of the increasing `f(p)`, by bisection (the reference's own solver).
fn bisect(f: impl Fn(f64) -> f64) -> f64 {
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if f(mid) > 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    0.5 * (lo + hi)
}

const FORMS: [&str; 5] = ["Linear", "Power", "Voce", "Swift", "Table"];

/// Uniaxial tension to 3 %, unloading, and compression to -3 %, rate-independent.
///
/// Reference: in uniaxial stress the plastic strain is `p` along the axis and `-p/2`
/// laterally. Loading: `eps = sigma_y(p)/E + p`, `sigma = sigma_y(p)`. Unloading from
/// `(eps_1, sigma_1 = sigma_y(p_1))` is elastic, `sigma = sigma_1 - E (eps_1 - eps)`,
/// until `sigma = -sigma_y(p_1)` (isotropic hardening); then, with `p` growing again,
/// `sigma = -sigma_y(p)` and `eps = -sigma_y(p)/E + 2 p_1 - p`. The radial return is exact
/// for this proportional path whatever the step, so the test demands agreement of
/// `sigma_zz` to 1e-9 of `sY` (and of the lateral strain and of `p`) at every step, for
/// 100 + 60 + 160 steps.
#[test]
fn uniaxial_tension_unloading_compression_follow_the_hardening_curve() {
    for form in FORMS {
        let (mat, c) = law(form, Rate::Independent);
        let (e1, e2) = (0.03, -0.03);
        let mut steps = vec![(Shear::Strain(e1 / 100.0), 1.0); 100];
        let sigma1 = flow_stress(form, bisect(|p| flow_stress(form, p) / E + p - e1));
        let unload = 2.0 * sigma1 / E * 0.9; // stays elastic
        steps.extend(vec![(Shear::Strain(-unload / 60.0), 1.0); 60]);
        let rest = e2 - (e1 - unload);
        steps.extend(vec![(Shear::Strain(rest / 160.0), 1.0); 160]);
        let path = uniaxial_path(&mat, &c, &[0.0; 5], &steps).unwrap();
        let p1 = bisect(|p| flow_stress(form, p) / E + p - e1);
        let mut worst = 0.0f64;
        for (i, pt) in path.iter().enumerate() {
            let eps = pt.eps[1];
            let (sigma, p) = if i < 100 && eps <= SY / E {
                (E * eps, 0.0)
            } else if i < 100 {
                let p = bisect(|p| flow_stress(form, p) / E + p - eps);
                (flow_stress(form, p), p)
            } else {
                let elastic = sigma1 - E * (e1 - eps);
                if elastic >= -flow_stress(form, p1) {
                    (elastic, p1)
                } else {
                    // eps = -sigma_y(p1 + q)/E + p1 - q, decreasing in q
                    let p = p1 + bisect(|q| -(-flow_stress(form, p1 + q) / E + p1 - q - eps));
                    (-flow_stress(form, p), p)
                }
            };
            let s = pt.sigma();
            let lateral = -NU * sigma / E - 0.5 * (if i < 100 { p } else { 2.0 * p1 - p });
            let err = ((s[1] - sigma).abs() / SY)
                .max(s[0].abs() / SY)
                .max((pt.y[4] - p).abs() / 1e-3)
                .max((pt.eps[0] - lateral).abs() / 1e-3);
            assert!(
                err <= 1e-9,
                "{form} step {i}: sigma {} vs {sigma}, p {} vs {p}, eps_rr {} vs {lateral}",
                s[1],
                pt.y[4],
                pt.eps[0]
            );
            worst = worst.max(err);
        }
        let last = path.last().unwrap();
        assert!(
            last.y[4] > 2.0 * p1 && last.sigma()[1] < -sigma1,
            "{form} reversed yielding"
        );
        eprintln!("{form}: sigma(3%) = {sigma1:.3} MPa, worst relative error {worst:e}");
    }
}

/// The rate-independent limit of the Norton form.
///
/// Reference: at a constant strain rate `r`, Norton's stress exceeds the rate-independent
/// flow stress by the overstress `K (dp/dt)^(1/m)`, with `dp/dt -> r` once plastic flow is
/// established, so `sigma_Norton - sigma_RI ~ K r^(1/m)` and tends to 0 as `K -> 0` or
/// `r -> 0`. More precisely, with `H'` the hardening slope, plastic flow takes the share
/// `dp/dt = r E / (E + H')` of the strain rate, and the overstress lowers `p` by
/// `(sigma_N - sigma_RI) / E`, which lowers `sigma_y` by `H'` times that: the difference
/// tends to `K r^(1/m) (E / (E + H'))^(1 + 1/m)`. Checked at 3 % strain (100 steps) for
/// every hardening form, `m = 3`, `K` from 10 to 0.01 MPa s^(1/3) and `r` from 1e-1 to
/// 1e-5 /s: the difference over `K r^(1/m)` equals that factor to 1e-3.
#[test]
fn norton_tends_to_the_rate_independent_curve() {
    for form in FORMS {
        let (ri, c_ri) = law(form, Rate::Independent);
        let (nt, mut c_nt) = law(form, Rate::Norton);
        let e1 = 0.03;
        let n = 100;
        let steps = vec![(Shear::Strain(e1 / n as f64), 1.0); n];
        let s_ri = uniaxial_path(&ri, &c_ri, &[0.0; 5], &steps)
            .unwrap()
            .last()
            .unwrap()
            .sigma()[1];
        let ki = c_nt.len() - 2;
        // the asymptote: (E / (E + H'))^(1 + 1/m) with H' the slope at p_RI(3 %)
        let p_ri = bisect(|p| flow_stress(form, p) / E + p - e1);
        let h = (flow_stress(form, p_ri + 1e-7) - flow_stress(form, p_ri - 1e-7)) / 2e-7;
        let expected = (E / (E + h)).powf(1.0 + 1.0 / 3.0);
        let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
        for k in [10.0, 1.0, 0.1, 0.01] {
            for r in [1e-1, 1e-3, 1e-5] {
                c_nt[ki] = k;
                let dt = e1 / n as f64 / r;
                let steps: Vec<(Shear, f64)> = steps.iter().map(|s| (s.0, dt)).collect();
                let s = uniaxial_path(&nt, &c_nt, &[0.0; 5], &steps)
                    .unwrap()
                    .last()
                    .unwrap()
                    .sigma()[1];
                let ratio = (s - s_ri) / (k * r.powf(1.0 / 3.0));
                (lo, hi) = (lo.min(ratio), hi.max(ratio));
                assert!(
                    (ratio - expected).abs() <= 1e-3,
                    "{form} K {k} r {r}: {s} vs {s_ri}, ratio {ratio} vs {expected}"
                );
            }
        }
        assert!(nt.check_params(&c_nt).is_ok());
        eprintln!(
            "{form}: sigma_RI(3%) = {s_ri:.3} MPa, (sigma_N - sigma_RI) / (K r^(1/m)) in [{lo:.4}, {hi:.4}]"
        );
    }
}
