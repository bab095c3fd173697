//! Dao et al.'s reverse algorithm (`indentify_analysis::dao::reverse`) against their
//! forward one: every material of a grid over Dao's range comes back to round-off; what
//! `measure` reads off a closed-form curve with a hold; the inverses of `Pi4` and `Pi5`;
//! the reverse analysis of our own finite element curves of known truth (the numbers of
//! `cargo xtask dao`, docs/validation-laws.md §9) within the accuracy stated in
//! docs/analysis.md; bad input named. And `tabor::stiffness_and_hardness` against its
//! formulas written out.

use indentify_analysis::closed_form::Punch;
use indentify_analysis::dao::{
    self, DaoError, Features, ReverseInput, dao_forward, e_star, pi4, pi4_inverse, pi5,
    pi5_inverse, reverse, sigma_r, sy_of_sigma_r,
};
use indentify_analysis::tabor::stiffness_and_hardness;

/// The features Dao's forward algorithm predicts for `(E, nu, sY, n)` at depth `h_m`.
fn forward_input(e: f64, nu: f64, sy: f64, n: f64, h_m: f64) -> ReverseInput {
    let p = dao_forward(e, nu, sy, n);
    let c = p.c;
    ReverseInput {
        c,
        s: p.s_norm * e_star(e, nu) * h_m,
        h_m,
        p_m: c * h_m * h_m,
        hr_hm: p.hr_hm,
    }
}

#[test]
fn reverse_inverts_the_forward_algorithm_to_round_off() {
    let mut worst = [0.0f64; 4];
    let mut cases = 0;
    let mut ambiguous = 0;
    for e in [10_000.0, 70_000.0, 200_000.0] {
        for ratio in [30.0, 100.0, 300.0, 1000.0] {
            for n in [0.0, 0.1, 0.2, 0.3, 0.4, 0.5] {
                let sy = e / ratio;
                let es_sr = e_star(e, 0.3) / sigma_r(e, sy, n);
                // Dao's range of E*/sigma_r and Pi4's (h_r/h_m below 0.9952495)
                if !(10.0..=1000.0).contains(&es_sr) {
                    continue;
                }
                let input = forward_input(e, 0.3, sy, n, 2e-3);
                let r = reverse(&input, 0.3, None).expect("reverse");
                assert!(!r.n_clamped, "E {e}, sY {sy}, n {n}: {r:?}");
                // Pi2 may have two roots in n (small E*/sigma_r, large n): the truth is one
                if r.n_roots > 1 {
                    let roots =
                        dao::pi2_roots(r.e_star / r.sigma_r, input.s / (r.e_star * input.h_m));
                    assert!(
                        roots.iter().any(|x| (x - n).abs() < 1e-9),
                        "{roots:?} vs {n}"
                    );
                    let r2 = reverse(&input, 0.3, Some(n)).expect("reverse");
                    assert!(
                        (r2.n - n).abs() < 1e-9 && (r2.sy / sy - 1.0).abs() < 1e-7,
                        "{r2:?}"
                    );
                    ambiguous += 1;
                    continue;
                }
                let rel = |a: f64, b: f64| (a / b - 1.0).abs();
                let errs = [
                    rel(r.e, e),
                    rel(r.sigma_r, sigma_r(e, sy, n)),
                    (r.n - n).abs(),
                    rel(r.sy, sy),
                ];
                for (w, x) in worst.iter_mut().zip(errs) {
                    *w = w.max(x);
                }
                assert!(
                    errs[0] < 1e-9 && errs[1] < 1e-9 && errs[2] < 1e-9 && errs[3] < 1e-7,
                    "E {e}, sY {sy}, n {n}: {r:?}, errors {errs:?}"
                );
                cases += 1;
            }
        }
    }
    eprintln!(
        "{cases} materials with one root of Pi2 in n, {ambiguous} with two; worst E, sigma_r, n, sY errors {worst:?}"
    );
    assert!(cases > 30);
}

#[test]
fn the_work_ratio_gives_the_same_reverse_as_the_residual_depth() {
    let (e, sy, n) = (200_000.0, 1000.0, 0.2);
    let input = forward_input(e, 0.3, sy, n, 0.01);
    let wp_wt = pi5(input.hr_hm);
    let hr = pi5_inverse(wp_wt).unwrap();
    assert!((hr - input.hr_hm).abs() < 1e-12, "{hr} vs {}", input.hr_hm);
    let p = pi4(0.7);
    assert!((pi4_inverse(p) - 0.7).abs() < 1e-12);
    // through Features, as the study layer calls it
    let m = Features {
        h_m: input.h_m,
        p_m: input.p_m,
        p_max: input.p_m,
        c: input.c,
        s: input.s,
        h_r: Some(input.hr_hm * input.h_m),
        wp_wt: Some(wp_wt),
        loading_end: 10,
        unloading_start: 10,
    };
    let a = reverse(&ReverseInput::of(&m, true).unwrap(), 0.3, None).unwrap();
    let b = reverse(&ReverseInput::of(&m, false).unwrap(), 0.3, None).unwrap();
    assert!((a.e / e - 1.0).abs() < 1e-9 && (b.e / e - 1.0).abs() < 1e-9);
    assert!((a.sy / sy - 1.0).abs() < 1e-7 && (b.sy / sy - 1.0).abs() < 1e-7);
}

#[test]
fn sy_of_sigma_r_inverts_the_power_form() {
    for (e, sy, n) in [
        (200_000.0, 400.0, 0.2),
        (70_000.0, 50.0, 0.45),
        (1e4, 300.0, 0.01),
    ] {
        let got = sy_of_sigma_r(e, sigma_r(e, sy, n), n);
        assert!((got / sy - 1.0).abs() < 1e-10, "{got} vs {sy}");
    }
    assert_eq!(sy_of_sigma_r(200_000.0, 500.0, 0.0), 500.0);
}

/// Our finite element curves of known truth: `C/sigma_r`, `S/(E* h_m)` and `W_p/W_t` of
/// `cargo xtask dao` on the fine mesh (`k = 24`, docs/validation-laws.md §9; E = 200000,
/// nu = 0.3, friction 0.15, finite strain), reversed. Their deviation from Dao's functions
/// (C 0.96-1.04 of `Pi1` in 8 of 9, S 0.92-1.08 of `Pi2`) carries into the reverse: the
/// accuracy stated in docs/analysis.md is what this prints.
#[test]
fn reverse_of_our_finite_element_curves_recovers_the_truth_within_dao_s_accuracy() {
    let e = 200_000.0;
    // (E/sY, n, C/sigma_r, S/(E* h_m), W_p/W_t)
    let rows = [
        (50.0, 0.0, 51.564, 5.3299, 0.711),
        (50.0, 0.2, 48.699, 5.1429, 0.644),
        (50.0, 0.4, 45.296, 4.8637, 0.566),
        (200.0, 0.0, 83.484, 6.3144, 0.901),
        (200.0, 0.2, 74.831, 5.7549, 0.852),
        (200.0, 0.4, 67.625, 5.1765, 0.778),
        (1000.0, 0.0, 105.456, 7.7858, 0.977),
        (1000.0, 0.2, 93.720, 6.1925, 0.954),
        (1000.0, 0.4, 83.512, 5.4246, 0.906),
    ];
    let (mut worst_e, mut worst_sr) = (0.0f64, 0.0f64);
    for (ratio, n, c_sr, s_norm, wp_wt) in rows {
        let sy = e / ratio;
        let sr = sigma_r(e, sy, n);
        let es = e_star(e, 0.3);
        let h_m = 0.01;
        let m = Features {
            h_m,
            p_m: c_sr * sr * h_m * h_m,
            p_max: c_sr * sr * h_m * h_m,
            c: c_sr * sr,
            s: s_norm * es * h_m,
            h_r: None,
            wp_wt: Some(wp_wt),
            loading_end: 30,
            unloading_start: 30,
        };
        let r = match ReverseInput::of(&m, true).and_then(|i| reverse(&i, 0.3, Some(0.2))) {
            Ok(r) => r,
            Err(err) => {
                eprintln!("E/sY {ratio}, n {n}: {err}");
                continue;
            }
        };
        let (de, dsr) = (r.e / e - 1.0, r.sigma_r / sr - 1.0);
        eprintln!(
            "E/sY {ratio}, n {n}: E {:+.1}%, sigma_r {:+.1}%, n {:.3} (truth {n}), sY {:.0} (truth {sy:.0}){}",
            100.0 * de,
            100.0 * dsr,
            r.n,
            r.sy,
            if r.n_clamped { ", n clamped" } else { "" }
        );
        if ratio < 1000.0 {
            worst_e = worst_e.max(de.abs());
            worst_sr = worst_sr.max(dsr.abs());
        }
    }
    eprintln!("E/sY 50-200: worst E {worst_e:.3}, sigma_r {worst_sr:.3}");
    assert!(worst_e < 0.35 && worst_sr < 0.35, "{worst_e} {worst_sr}");
}

/// A loading `P = C h^2`, a hold at the deepest depth whose force relaxes by 10%, and an
/// unloading `P = P_m ((h - h_r)/(h_m - h_r))^2`: the loading ends at the force's maximum,
/// the unloading starts at the hold's end.
#[test]
fn measure_skips_a_hold_and_reads_a_closed_form_curve() {
    let (c, h_m, h_r) = (80_000.0, 0.01, 0.0085);
    let n = 1000;
    let mut h: Vec<f64> = (0..=n).map(|i| h_m * i as f64 / n as f64).collect();
    let mut f: Vec<f64> = h.iter().map(|x| c * x * x).collect();
    let p0 = c * h_m * h_m;
    for i in 1..=10 {
        h.push(h_m);
        f.push(p0 * (1.0 - 0.01 * i as f64));
    }
    let p_m = *f.last().unwrap();
    for i in 1..=n {
        let x = h_m * (1.0 - i as f64 / n as f64);
        let y = ((x - h_r) / (h_m - h_r)).max(0.0);
        h.push(x);
        f.push(p_m * y * y);
    }
    let m = dao::measure(&h, &f).unwrap();
    assert_eq!((m.loading_end, m.unloading_start), (n, n + 10));
    assert!((m.c / c - 1.0).abs() < 1e-12, "C {}", m.c);
    assert!(
        (m.s / (2.0 * p_m / (h_m - h_r)) - 1.0).abs() < 1e-9,
        "S {}",
        m.s
    );
    assert!((m.h_r.unwrap() / h_r - 1.0).abs() < 1e-6);
    assert_eq!((m.p_m, m.p_max), (p_m, p0));
    // the works: loading c h_m^3/3 (the hold at constant depth does none), unloading
    // p_m (h_m - h_r)/3
    let w = 1.0 - (p_m * (h_m - h_r) / 3.0) / (c * h_m.powi(3) / 3.0);
    assert!((m.wp_wt.unwrap() - w).abs() < 1e-5, "{:?} vs {w}", m.wp_wt);
    // an unloading that stops before zero force: no h_r, no work ratio, still S
    let cut = n + 10 + n / 10;
    let m2 = dao::measure(&h[..cut], &f[..cut]).unwrap();
    assert_eq!((m2.h_r, m2.wp_wt), (None, None));
    assert_eq!(m2.s, m.s);
    assert!(matches!(
        ReverseInput::of(&m2, true),
        Err(DaoError::Curve(s)) if s.contains("zero force")
    ));
    // no unloading, NaN, lengths
    assert!(dao::measure(&h[..=n], &f[..=n]).is_err());
    let mut g = f.clone();
    g[5] = f64::NAN;
    assert!(matches!(dao::measure(&h, &g), Err(DaoError::Curve(s)) if s.contains("sample 5")));
    assert!(dao::measure(&h, &f[1..]).is_err());
}

#[test]
fn bad_input_is_named() {
    let good = forward_input(200_000.0, 0.3, 1000.0, 0.2, 0.01);
    let e = reverse(&ReverseInput { s: -1.0, ..good }, 0.3, None).unwrap_err();
    assert!(e.to_string().contains("S = -1"), "{e}");
    let e = reverse(&good, 0.5, None).unwrap_err();
    assert!(e.to_string().contains("Poisson"), "{e}");
    let e = reverse(&ReverseInput { hr_hm: 1.0, ..good }, 0.3, None).unwrap_err();
    assert!(e.to_string().contains("h_r/h_m"), "{e}");
    // a loading far too stiff for its unloading: C/E* beyond Pi1's range
    let e = reverse(
        &ReverseInput {
            c: good.c * 1e4,
            p_m: good.p_m * 1e4,
            ..good
        },
        0.3,
        None,
    )
    .unwrap_err();
    assert!(
        matches!(e, DaoError::Range { .. } | DaoError::Input(_)),
        "{e}"
    );
    let e = pi5_inverse(0.1).unwrap_err();
    assert!(e.to_string().contains("W_p/W_t"), "{e}");
}

#[test]
fn tabor_follows_its_formulas() {
    let (e, nu, sr) = (100_000.0, 0.3, 400.0);
    let es = e / (1.0 - nu * nu);
    // a sphere R = 0.5 mm with contact radius 0.05 mm
    let (radius, a) = (0.5f64, 0.05f64);
    let h_c = radius - (radius * radius - a * a).sqrt();
    let p_m = 3.0 * sr * std::f64::consts::PI * a * a;
    let s = 2.0 * es * a;
    let m = Features {
        h_m: h_c + 0.75 * p_m / s,
        p_m,
        p_max: p_m,
        c: 1.0,
        s,
        h_r: None,
        wp_wt: None,
        loading_end: 5,
        unloading_start: 5,
    };
    let t = stiffness_and_hardness(&m, Punch::Sphere { radius }, nu).unwrap();
    assert!(
        (t.a / a - 1.0).abs() < 1e-9 && (t.e / e - 1.0).abs() < 1e-9,
        "{t:?}"
    );
    assert!((t.sigma_r / sr - 1.0).abs() < 1e-9 && (t.eps_r - 0.2 * a / radius).abs() < 1e-12);
    // a cone of 68 deg
    let tan = 68f64.to_radians().tan();
    let h_c = a / tan;
    let m = Features {
        h_m: h_c + 0.72 * p_m / s,
        ..m
    };
    let t = stiffness_and_hardness(
        &m,
        Punch::Cone {
            half_angle_deg: 68.0,
        },
        nu,
    )
    .unwrap();
    assert!(
        (t.a / a - 1.0).abs() < 1e-9 && (t.e / e - 1.0).abs() < 1e-9,
        "{t:?}"
    );
    assert!((t.eps_r - 0.2 / tan).abs() < 1e-12);
    // a flat punch, a contact depth below zero
    assert!(stiffness_and_hardness(&m, Punch::Flat { radius: 0.1 }, nu).is_err());
    let soft = Features {
        s: p_m / m.h_m * 0.5,
        ..m
    };
    let err = stiffness_and_hardness(
        &soft,
        Punch::Cone {
            half_angle_deg: 68.0,
        },
        nu,
    )
    .unwrap_err();
    assert!(err.to_string().contains("contact depth"), "{err}");
}
