//! The analysis against closed forms: Sneddon's elastic cone and Hertz's sphere give back
//! their exact stiffness and modulus; a power-law unloading of known `alpha, m, h_f` its
//! exact `S`, `h_c`, `H`, `E`; multi-cycle tests every cycle; bad tests a message naming
//! the test and the reason while the other unloadings are analysed.

use indentify_analysis::{AreaFunction, Epsilon, Options, Tip, analyze};
use indentify_records::{Format, Record};
use std::f64::consts::PI;

fn record(name: &str, pts: &[(f64, f64, f64)]) -> Record {
    Record {
        name: name.into(),
        t: pts.iter().map(|p| p.0).collect(),
        h: pts.iter().map(|p| p.1).collect(),
        f: pts.iter().map(|p| p.2).collect(),
        segment: None,
        meta: Default::default(),
    }
}

/// Load along `f(h)` to `h_max` then unload along it, `n` samples each way, 1 s apart.
fn elastic(f: impl Fn(f64) -> f64, h_max: f64, n: usize) -> Vec<(f64, f64, f64)> {
    (0..=2 * n)
        .map(|i| {
            let h = h_max * (1.0 - (i as f64 - n as f64).abs() / n as f64);
            (i as f64, h, f(h))
        })
        .collect()
}

#[test]
fn sneddon_cone_gives_the_exact_modulus() {
    // E = 70 GPa, nu = 0.2 under a diamond cone of 70.3 deg (Berkovich-equivalent)
    let (e, nu) = (70_000.0, 0.2);
    let tip = Tip::diamond(AreaFunction::Cone {
        half_angle_deg: 70.3,
    });
    let er = 1.0 / ((1.0 - nu * nu) / e + tip.compliance_share());
    let tan = 70.3f64.to_radians().tan();
    let h_max = 1e-3;
    let r = record(
        "cone",
        &elastic(|h| 2.0 / PI * er * tan * h * h, h_max, 400),
    );
    for eps in [Epsilon::Tip, Epsilon::FromM] {
        let mut o = Options::new(tip.clone(), Format::Csv);
        o.nu = nu;
        o.epsilon = eps;
        let a = analyze(&r, &o).unwrap();
        assert_eq!(a.unloadings.len(), 1, "{a:?}");
        let (u, op) = a.values().unwrap();
        let fit = u.fit.as_ref().unwrap();
        assert!((fit.m - 2.0).abs() < 1e-6, "{fit:?}");
        let s_exact = 4.0 / PI * er * tan * h_max;
        assert!((op.s / s_exact - 1.0).abs() < 1e-6, "{} {}", op.s, s_exact);
        assert!((op.hc / (2.0 / PI * h_max) - 1.0).abs() < 1e-6, "{}", op.hc);
        assert!((op.er / er - 1.0).abs() < 1e-6, "{} {er}", op.er);
        assert!((op.e.unwrap() / e - 1.0).abs() < 1e-5, "{:?}", op.e);
        // an elastic cycle: no work dissipated
        assert!((u.work.eta - 100.0).abs() < 0.1, "{:?}", u.work);
    }
}

#[test]
fn hertz_sphere_gives_the_modulus() {
    // R = 10 um, 20 nm deep (h/R = 0.002): the sphere's area pi (2 R h_c - h_c^2) differs
    // from Hertz's paraboloid 2 pi R h_c by h_c/(2R) = 5e-4 relative, E_r by half that
    let (er, radius, h_max) = (100_000.0, 1e-2, 2e-5);
    let mut tip = Tip::diamond(AreaFunction::Sphere { radius });
    tip.modulus = f64::INFINITY;
    let r = record(
        "sphere",
        &elastic(|h| 4.0 / 3.0 * er * radius.sqrt() * h.powf(1.5), h_max, 300),
    );
    let mut o = Options::new(tip, Format::Csv);
    o.epsilon = Epsilon::FromM;
    let a = analyze(&r, &o).unwrap();
    let (u, op) = a.values().unwrap();
    assert!((u.fit.as_ref().unwrap().m - 1.5).abs() < 1e-6);
    let s_exact = 2.0 * er * (radius * h_max).sqrt();
    assert!((op.s / s_exact - 1.0).abs() < 1e-6);
    assert!((op.hc / (0.5 * h_max) - 1.0).abs() < 1e-6, "{}", op.hc);
    assert!((op.er / er - 1.0).abs() < 3e-4, "{} {er}", op.er);
    assert!((op.er / er - 1.0).abs() > 1e-5); // the stated area-function difference is seen
}

/// An elastic-plastic test: loading `F = k h^2` to `f_max`, a hold with logarithmic creep,
/// a power-law unloading of known `alpha, m, h_f`, to zero.
fn elastic_plastic(f_max: f64, m: f64, hold: f64, t0: f64) -> (Vec<(f64, f64, f64)>, f64, f64) {
    let h_load = 1e-3 * (f_max / 10e-3).sqrt();
    let k = f_max / (h_load * h_load);
    let mut pts = Vec::new();
    let n = 200;
    for i in 0..=n {
        let h = h_load * i as f64 / n as f64;
        pts.push((t0 + i as f64 * 0.1, h, k * h * h));
    }
    let mut t = t0 + n as f64 * 0.1;
    let mut h_max = h_load;
    let nh = (hold * 10.0) as usize;
    for i in 1..=nh {
        t += 0.1;
        h_max = h_load * (1.0 + 0.01 * (1.0 + i as f64).ln());
        pts.push((t, h_max, f_max));
    }
    let h_f = 0.7 * h_max;
    let alpha = f_max / (h_max - h_f).powf(m);
    for i in 1..=n {
        t += 0.1;
        let h = h_max - (h_max - h_f) * i as f64 / n as f64;
        pts.push((t, h, alpha * (h - h_f).powf(m)));
    }
    (pts, h_max, alpha * m * (h_max - h_f).powf(m - 1.0))
}

#[test]
fn a_power_law_unloading_gives_the_exact_values() {
    let (pts, h_max, s_exact) = elastic_plastic(10e-3, 1.35, 10.0, 0.0);
    let r = record("ep", &pts);
    let o = Options::new(Tip::berkovich(), Format::AntonPaar);
    let a = analyze(&r, &o).unwrap();
    let (u, op) = a.values().unwrap();
    assert_eq!(u.h_max, h_max);
    assert!((op.s / s_exact - 1.0).abs() < 1e-7, "{} {s_exact}", op.s);
    // the Oliver-Pharr chain by hand
    let hc = h_max - 0.75 * 10e-3 / s_exact;
    let area = 24.5 * hc * hc;
    let er = PI.sqrt() * s_exact / (2.0 * area.sqrt());
    let e = (1.0 - 0.09) / (1.0 / er - (1.0 - 0.07 * 0.07) / 1_141_000.0);
    assert!((op.hc / hc - 1.0).abs() < 1e-7);
    assert!((op.hardness / (10e-3 / area) - 1.0).abs() < 1e-6);
    assert!((op.er / er - 1.0).abs() < 1e-6);
    assert!((op.e.unwrap() / e - 1.0).abs() < 1e-6);
    // the hold: 10 s of creep h_load (1 + 0.01 ln(1 + i)), i = 1..100, from the first
    // sample within 0.2 % of F_max (the loading's last sample, at h_load: the one before
    // it is 1 % below F_max)
    let hold = u.hold.as_ref().unwrap();
    let h_load = 1e-3;
    let h0 = h_load;
    assert!((hold.h.0 / h0 - 1.0).abs() < 1e-12, "{hold:?}");
    let creep = h_max - h0;
    assert!((hold.creep / creep - 1.0).abs() < 1e-9, "{hold:?}");
    assert!((hold.c_it - 100.0 * creep / h0).abs() < 1e-9);
    // creep rate at the end: d/dt h_load 0.01 ln(1 + 10 t') = h_load 0.01 * 10/(1 + 10 t') at t' ~ 8.75 s
    assert!(hold.rate > 0.0 && hold.rate < 2e-6, "{}", hold.rate);
}

#[test]
fn every_cycle_of_a_multi_cycle_test_is_analysed() {
    // three cycles to 2.5, 5, 10 mN, each unloading to 10 % (the next reloads from there)
    let mut pts = Vec::new();
    let mut t = 0.0;
    let mut exact = Vec::new();
    for (c, f_max) in [2.5e-3, 5e-3, 10e-3].into_iter().enumerate() {
        let (p, h_max, s) = elastic_plastic(f_max, 1.5, 2.0, t);
        let start = if c == 0 { 0 } else { 1 };
        // keep the unloading only down to 10 % of F_max
        let keep: Vec<_> = p
            .into_iter()
            .skip(start)
            .enumerate()
            .filter(|(i, q)| *i <= 200 || q.2 >= 0.1 * f_max)
            .map(|x| x.1)
            .collect();
        // the loading of cycles 2 and 3 starts where the last unloading ended: drop the
        // part of their loading below that force
        let floor = pts.last().map_or(0.0, |q: &(f64, f64, f64)| q.2);
        pts.extend(
            keep.into_iter()
                .filter(|q| c == 0 || q.2 > floor * 1.01 || q.0 > t + 20.0),
        );
        t = pts.last().unwrap().0 + 0.1;
        exact.push((f_max, h_max, s));
    }
    let r = record("cycles", &pts);
    let a = analyze(&r, &Options::new(Tip::berkovich(), Format::Csv)).unwrap();
    assert_eq!(a.unloadings.len(), 3, "{:#?}", a.unloadings);
    for (u, (f_max, h_max, s)) in a.unloadings.iter().zip(exact) {
        let op = u.op.as_ref().unwrap();
        assert_eq!(u.f_max, f_max);
        assert_eq!(u.h_max, h_max);
        assert!((op.s / s - 1.0).abs() < 1e-6, "{} {s}", op.s);
    }
    assert_eq!(a.main, Some(2));
}

#[test]
fn bad_tests_are_named_and_the_rest_analysed() {
    // no unloading at all
    let load: Vec<_> = (0..100)
        .map(|i| (i as f64, 1e-5 * i as f64, 1e-4 * i as f64))
        .collect();
    let a = analyze(
        &record("loading only", &load),
        &Options::new(Tip::berkovich(), Format::Csv),
    )
    .unwrap();
    let e = a.error.unwrap();
    assert!(e.contains("no unloading"), "{e}");
    assert!(a.unloadings.is_empty());
    // two cycles: the first unloads as a power law, the second drops in a step (the depth
    // does not move while the force falls): a power law cannot fit it
    let (mut pts, _, _) = elastic_plastic(5e-3, 1.4, 1.0, 0.0);
    let t_end = pts.last().unwrap().0;
    let h_end = pts.last().unwrap().1;
    for i in 1..=100 {
        pts.push((
            t_end + i as f64 * 0.1,
            h_end + 1e-5 * i as f64,
            1e-4 * i as f64,
        ));
    }
    let (t1, h1) = (pts.last().unwrap().0, pts.last().unwrap().1);
    for i in 1..=50 {
        pts.push((
            t1 + i as f64 * 0.1,
            h1 + 1e-9 * (i % 2) as f64,
            1e-2 * (1.0 - i as f64 / 50.0),
        ));
    }
    let a = analyze(
        &record("step", &pts),
        &Options::new(Tip::berkovich(), Format::Csv),
    )
    .unwrap();
    assert_eq!(a.unloadings.len(), 2, "{:#?}", a.unloadings);
    assert!(a.unloadings[0].op.is_some());
    let e = a.unloadings[1].error.as_ref().unwrap();
    assert!(!e.is_empty());
    assert_eq!(a.main, Some(0));
    assert!(a.error.is_none());
    // options out of range
    let mut o = Options::new(Tip::berkovich(), Format::Csv);
    o.fit_range.lower = 0.99;
    let e = analyze(&record("x", &pts), &o).unwrap_err().to_string();
    assert!(e.contains("fit_range"), "{e}");
}

/// A depth-controlled hold: the force relaxes by 40% at the held depth (more than the
/// unloading criterion's 10% drop) before a power-law unloading of known `alpha, m, h_f`;
/// the unloading is the one where the depth recedes, its stiffness the exact
/// `m alpha (h_max - h_f)^(m - 1)` from the relaxed force.
#[test]
fn a_relaxation_at_held_depth_is_not_the_unloading() {
    let (h_max, h_f, m) = (1e-3, 0.6e-3, 1.5);
    let f_peak = 0.02;
    let mut pts: Vec<(f64, f64, f64)> = (0..=200)
        .map(|i| {
            let x = i as f64 / 200.0;
            (i as f64 * 0.05, h_max * x, f_peak * x * x)
        })
        .collect();
    let t0 = pts.last().unwrap().0;
    // relaxation at h_max: F = f_peak (0.6 + 0.4 e^(-t/2)), 200 samples over 20 s
    for i in 1..=200 {
        let t = i as f64 * 0.1;
        pts.push((t0 + t, h_max, f_peak * (0.6 + 0.4 * (-t / 2.0).exp())));
    }
    let (t1, f_end) = (pts.last().unwrap().0, pts.last().unwrap().2);
    let alpha = f_end / (h_max - h_f).powf(m);
    for i in 1..=200 {
        let h = h_max - (h_max - h_f) * i as f64 / 200.0;
        pts.push((t1 + i as f64 * 0.05, h, alpha * (h - h_f).powf(m)));
    }
    let a = analyze(
        &record("depth hold", &pts),
        &Options::new(Tip::berkovich(), Format::Csv),
    )
    .unwrap();
    assert_eq!(a.unloadings.len(), 1, "{:#?}", a.unloadings);
    let (u, op) = a.values().unwrap();
    let fit = u.fit.as_ref().unwrap();
    assert!((fit.m - m).abs() < 1e-3, "{fit:?}");
    let s_exact = m * alpha * (h_max - h_f).powf(m - 1.0);
    assert!((op.s / s_exact - 1.0).abs() < 1e-3, "{} {s_exact}", op.s);
}
