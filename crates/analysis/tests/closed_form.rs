//! The closed-form pre-fits (`indentify_analysis::closed_form`) against their formulas:
//! Sneddon's cone `F = 2 E* tan(alpha) h^2 / pi`, Hertz's sphere `F = 4 E* sqrt(R) h^1.5 / 3`
//! and the flat punch `F = 2 E* a h` (`E* = E / (1 - nu^2)`) written out here; a curve of
//! each closed form gives its `E` back to 1e-6; Lee and Radok's discrete Maxwell force
//! converges at first order to the continuous closed form of a ramp, and a curve of its own
//! gives `(E, eta)` back to 1e-6; bad input is an error naming why, not a panic.

use indentify_analysis::closed_form::{
    ClosedFormError, Curve, Punch, fit_maxwell, fit_modulus, model_ratio, unit_forces,
};
use std::f64::consts::PI;

/// A ramp to `h_max` in `t_r` then a hold of `t_h`, `n` steps each (no hold for `t_h = 0`).
fn ramp_hold(h_max: f64, t_r: f64, t_h: f64, n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut t = vec![0.0];
    let mut h = vec![0.0];
    for i in 1..=n {
        t.push(t_r * i as f64 / n as f64);
        h.push(h_max * i as f64 / n as f64);
    }
    if t_h > 0.0 {
        for i in 1..=n {
            t.push(t_r + t_h * i as f64 / n as f64);
            h.push(h_max);
        }
    }
    (t, h)
}

/// A closed form `F(E, nu, h)` written out.
type Formula = Box<dyn Fn(f64, f64, f64) -> f64>;

fn punches() -> [(Punch, Formula); 3] {
    // the formulas written out, independently of `Punch::law`
    let alpha = 68f64.to_radians();
    [
        (
            Punch::Cone {
                half_angle_deg: 68.0,
            },
            Box::new(move |e, nu, h| 2.0 * e / (1.0 - nu * nu) * alpha.tan() * h * h / PI),
        ),
        (
            Punch::Sphere { radius: 0.5 },
            Box::new(|e, nu, h: f64| 4.0 / 3.0 * e / (1.0 - nu * nu) * 0.5f64.sqrt() * h.powf(1.5)),
        ),
        (
            Punch::Flat { radius: 0.2 },
            Box::new(|e, nu, h| 2.0 * e / (1.0 - nu * nu) * 0.2 * h),
        ),
    ]
}

#[test]
fn the_elastic_limit_is_each_punchs_closed_form() {
    let (t, h) = ramp_hold(0.05, 1.0, 1.0, 30);
    for (punch, formula) in punches() {
        for nu in [0.0, 0.3, 0.45] {
            let f = unit_forces(&t, &h, t.len() - 1, punch, nu, f64::INFINITY);
            for (fi, hi) in f.iter().zip(&h) {
                let exact = formula(1.0, nu, *hi);
                assert!(
                    (fi - exact).abs() <= 1e-13 * exact.max(1e-30),
                    "{punch:?} nu {nu}: {fi} against {exact}"
                );
                assert!(
                    (punch.elastic_force(1.0, nu, *hi) - exact).abs() <= 1e-13 * exact.max(1e-30)
                );
            }
        }
    }
}

#[test]
fn a_curve_of_each_elastic_closed_form_gives_its_modulus_back() {
    let (t, h) = ramp_hold(0.05, 1.0, 0.5, 40);
    for (punch, formula) in punches() {
        for e in [2e3, 7e4, 4.1e5] {
            let f: Vec<f64> = h.iter().map(|&h| formula(e, 0.3, h)).collect();
            let fit = fit_modulus(
                &Curve {
                    t: &t,
                    h: &h,
                    f: &f,
                },
                &[],
                punch,
                0.3,
            )
            .expect("a modulus");
            assert!(
                (fit.e / e - 1.0).abs() < 1e-6,
                "{punch:?}: {fit:?} against {e}"
            );
            assert!(fit.rms_rel < 1e-12, "{fit:?}");
            // the model ratio of the closed form itself is 1, and a curve scaled by a
            // known ratio is fitted with it
            let rho = model_ratio(&t, &h, &f, punch, 0.3, e, f64::INFINITY);
            assert!(rho.iter().all(|r| (r - 1.0).abs() < 1e-12), "{rho:?}");
            let rho: Vec<f64> = (0..t.len())
                .map(|n| 0.9 + 0.01 * (n as f64).cos())
                .collect();
            let fr: Vec<f64> = f.iter().zip(&rho).map(|(f, r)| f * r).collect();
            let fit = fit_modulus(
                &Curve {
                    t: &t,
                    h: &h,
                    f: &fr,
                },
                &rho,
                punch,
                0.3,
            )
            .expect("a modulus");
            assert!((fit.e / e - 1.0).abs() < 1e-6, "{punch:?}: {fit:?}");
        }
    }
}

#[test]
fn the_maxwell_ramp_converges_to_its_continuous_closed_form_at_first_order() {
    // h = v t on a cone: F = (2 tan(alpha) / pi) int Psi(t - s) 2 v^2 s ds
    // = (4 tan(alpha) v^2 / pi) sum_k A_k (t / l_k - (1 - e^(-l_k t)) / l_k^2)
    let (nu, tau, v, t_end, angle) = (0.3f64, 0.7f64, 0.1f64, 1.0f64, 68.0f64);
    let (g, k) = (1.0 / (2.0 * (1.0 + nu)), 1.0 / (3.0 * (1.0 - 2.0 * nu)));
    let (a, b) = (g, 9.0 * k * g / (3.0 * k + 4.0 * g));
    let (l, m) = (1.0 / tau, 3.0 * k / (3.0 * k + 4.0 * g) / tau);
    let term =
        |amp: f64, rate: f64| amp * (t_end / rate - (1.0 - (-rate * t_end).exp()) / rate / rate);
    let exact = 4.0 * angle.to_radians().tan() * v * v / PI * (term(a, l) + term(b, m));
    let error = |n: usize| {
        let t: Vec<f64> = (0..=n).map(|i| t_end * i as f64 / n as f64).collect();
        let h: Vec<f64> = t.iter().map(|t| v * t).collect();
        let f = unit_forces(
            &t,
            &h,
            n,
            Punch::Cone {
                half_angle_deg: angle,
            },
            nu,
            tau,
        );
        (f[n] - exact).abs() / exact
    };
    let (e1, e2, e3) = (error(100), error(200), error(400));
    assert!(e3 < 5e-3, "{e1} {e2} {e3}");
    for r in [e1 / e2, e2 / e3] {
        assert!((r - 2.0).abs() < 0.05, "first order: {e1} {e2} {e3}");
    }
}

#[test]
fn a_maxwell_curve_of_its_own_form_gives_e_and_eta_back() {
    let (t, h) = ramp_hold(0.1, 1.0, 1.0, 30);
    for (punch, _) in punches() {
        for (e, eta) in [(20000.0, 30000.0), (60000.0, 8000.0)] {
            let nu = 0.3;
            let tau = eta * (1.0 + nu) / e;
            let f: Vec<f64> = unit_forces(&t, &h, t.len() - 1, punch, nu, tau)
                .iter()
                .map(|p| e * p)
                .collect();
            let p = fit_maxwell(
                &Curve {
                    t: &t,
                    h: &h,
                    f: &f,
                },
                &[],
                punch,
                nu,
            )
            .expect("a pre-fit");
            assert!((p.e / e - 1.0).abs() < 1e-6, "{punch:?} {p:?}");
            assert!((p.eta / eta - 1.0).abs() < 1e-6, "{punch:?} {p:?}");
        }
    }
}

#[test]
fn bad_input_is_an_error_naming_why() {
    let cone = Punch::Cone {
        half_angle_deg: 68.0,
    };
    let (t, h) = ramp_hold(0.1, 1.0, 0.0, 30);
    let f: Vec<f64> = h.iter().map(|&h| cone.elastic_force(2e4, 0.3, h)).collect();
    let c = Curve {
        t: &t,
        h: &h,
        f: &f,
    };
    // no hold: the modulus has its closed form, the viscosity has none
    assert!(fit_modulus(&c, &[], cone, 0.3).is_ok());
    let e = fit_maxwell(&c, &[], cone, 0.3).unwrap_err();
    assert_eq!(e, ClosedFormError::NoHold);
    assert!(e.to_string().contains("no hold"), "{e}");
    // an elastic curve with a hold: no relaxation time in the range searched
    let (t, h) = ramp_hold(0.1, 1.0, 1.0, 30);
    let f: Vec<f64> = h.iter().map(|&h| cone.elastic_force(2e4, 0.3, h)).collect();
    let e = fit_maxwell(
        &Curve {
            t: &t,
            h: &h,
            f: &f,
        },
        &[],
        cone,
        0.3,
    )
    .unwrap_err();
    assert!(matches!(e, ClosedFormError::NoRelaxation { .. }), "{e}");
    assert!(e.to_string().contains("viscosity"), "{e}");
    // samples of different lengths, a NaN, no loading, nu and punches out of range
    let short = &f[..10];
    let e = fit_modulus(
        &Curve {
            t: &t,
            h: &h,
            f: short,
        },
        &[],
        cone,
        0.3,
    )
    .unwrap_err();
    assert!(e.to_string().contains("61 depths and 10 forces"), "{e}");
    let mut nan = f.clone();
    nan[5] = f64::NAN;
    let e = fit_modulus(
        &Curve {
            t: &t,
            h: &h,
            f: &nan,
        },
        &[],
        cone,
        0.3,
    )
    .unwrap_err();
    assert!(e.to_string().contains("sample 5"), "{e}");
    let flat = vec![0.0; t.len()];
    let e = fit_modulus(
        &Curve {
            t: &t,
            h: &flat,
            f: &f,
        },
        &[],
        cone,
        0.3,
    )
    .unwrap_err();
    assert_eq!(e, ClosedFormError::NoLoading);
    let empty: [f64; 0] = [];
    let e = fit_maxwell(
        &Curve {
            t: &empty,
            h: &empty,
            f: &empty,
        },
        &[],
        cone,
        0.3,
    )
    .unwrap_err();
    assert_eq!(e, ClosedFormError::NoLoading);
    let e = fit_modulus(
        &Curve {
            t: &t,
            h: &h,
            f: &f,
        },
        &[],
        cone,
        0.5,
    )
    .unwrap_err();
    assert!(e.to_string().contains("Poisson's ratio 0.5"), "{e}");
    let e = fit_modulus(
        &Curve {
            t: &t,
            h: &h,
            f: &f,
        },
        &[],
        Punch::Sphere { radius: -1.0 },
        0.3,
    )
    .unwrap_err();
    assert!(e.to_string().contains("positive radius"), "{e}");
    let neg: Vec<f64> = f.iter().map(|f| -f).collect();
    let e = fit_modulus(
        &Curve {
            t: &t,
            h: &h,
            f: &neg,
        },
        &[],
        cone,
        0.3,
    )
    .unwrap_err();
    assert!(matches!(e, ClosedFormError::NotPositive(_)), "{e}");
}
