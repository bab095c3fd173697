//! A closed-form pre-fit of a Maxwell cone indentation: Lee and Radok's solution (the
//! contact radius the elastic one while the depth does not decrease) at the solver's
//! backward-Euler discretization (docs/validation-viscous.md §2-3), fitted to a record's
//! loading and hold by a one-dimensional least squares, for the starts of the 100-indent
//! batch (`batch_start.rs`).
//!
//! For the Maxwell law (viscous in shear, `nu` fixed) the half-space relaxation function of
//! the indentation modulus is `Psi(t) = A e^(-lambda t) + B e^(-mu t)` with, at `E = 1`,
//! `A = G`, `B = 9 K G / (3K + 4G)`, `G = 1/(2(1+nu))`, `K = 1/(3(1-2nu))`,
//! `lambda = 1/tau`, `mu = lambda 3K / (3K + 4G)`, and `tau = eta / (2G E) = eta (1 + nu) / E`.
//! Lee and Radok's force for a cone of half-angle `alpha` is
//! `F(t) = (2 tan(alpha)/pi) int Psi(t - s) d(h^2)`; backward Euler with the depth linear
//! over each step turns each exponential into the recursion
//! `y_n = (y_(n-1) + A_k Delta(h^2)_n) / (1 + lambda_k dt_n)`, so that
//! `F_n = E Phi_n(tau)` with `Phi` the unit-modulus force. For each `tau` the best `E` is
//! linear, `E(tau) = <rho Phi, F> / <rho Phi, rho Phi>`; `tau` is found on a logarithmic
//! grid refined by golden sections. `rho_n` is the finite element model's own ratio to the
//! half-space solution at each sample (mesh, finite cylinder, node-quantized contact radius),
//! measured once per configuration by one forward run ([`calibrate`]): on the rising branch
//! the Maxwell run's active sets are the elastic run's, so this ratio barely depends on the
//! parameters (docs/validation-viscous.md §4-5).

/// The samples of a record a pre-fit uses: time (s), depth (mm), force (N).
#[derive(Clone, Debug)]
pub struct Curve<'a> {
    /// Times, from the first sample at `h = 0` (s).
    pub t: &'a [f64],
    /// Depths (mm).
    pub h: &'a [f64],
    /// Forces (N).
    pub f: &'a [f64],
}

/// The pre-fit's result.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Prefit {
    /// Young's modulus (MPa).
    pub e: f64,
    /// Viscosity (MPa s).
    pub eta: f64,
    /// Relaxation time `eta (1 + nu) / E` (s).
    pub tau: f64,
    /// RMS of the residuals over the samples fitted, relative to the largest force.
    pub rms_rel: f64,
    /// Samples fitted.
    pub samples: usize,
}

/// The last sample of the loading and hold: the depth has not decreased up to it.
pub fn rising_end(h: &[f64]) -> usize {
    let mut end = 0;
    for n in 1..h.len() {
        if h[n] < h[n - 1] {
            break;
        }
        end = n;
    }
    end
}

/// Lee and Radok's force at unit `E` on samples `0..=end` of `(t, h)` at the backward-Euler
/// discretization, for a cone of half-angle `half_angle_deg`, Poisson's ratio `nu` and
/// relaxation time `tau`; `tau = inf` is the elastic (Sneddon) cone.
pub fn unit_forces(
    t: &[f64],
    h: &[f64],
    end: usize,
    half_angle_deg: f64,
    nu: f64,
    tau: f64,
) -> Vec<f64> {
    let g = 1.0 / (2.0 * (1.0 + nu));
    let k = 1.0 / (3.0 * (1.0 - 2.0 * nu));
    let a = g;
    let b = 9.0 * k * g / (3.0 * k + 4.0 * g);
    let lambda = 1.0 / tau;
    let mu = lambda * 3.0 * k / (3.0 * k + 4.0 * g);
    let c = 2.0 * half_angle_deg.to_radians().tan() / std::f64::consts::PI;
    let mut out = Vec::with_capacity(end + 1);
    out.push(c * h[0] * h[0] * (a + b));
    // the first sample as an instantaneous (elastic) step from zero
    let (mut ya, mut yb) = (a * h[0] * h[0], b * h[0] * h[0]);
    for n in 1..=end {
        let dt = t[n] - t[n - 1];
        let dx = h[n] * h[n] - h[n - 1] * h[n - 1];
        ya = (ya + a * dx) / (1.0 + lambda * dt);
        yb = (yb + b * dx) / (1.0 + mu * dt);
        out.push(c * (ya + yb));
    }
    out
}

/// The best `E` at `tau` and the residual sum of squares, over the samples `from..=end`.
fn best_e(
    curve: &Curve<'_>,
    rho: &[f64],
    from: usize,
    end: usize,
    angle: f64,
    nu: f64,
    tau: f64,
) -> (f64, f64) {
    let phi = unit_forces(curve.t, curve.h, end, angle, nu, tau);
    let rp = |n: usize| rho.get(n).copied().unwrap_or(1.0) * phi[n];
    let (mut pf, mut pp) = (0.0, 0.0);
    for n in from..=end {
        pf += rp(n) * curve.f[n];
        pp += rp(n) * rp(n);
    }
    if pp <= 0.0 {
        return (f64::NAN, f64::INFINITY);
    }
    let e = pf / pp;
    // the residuals summed directly (`|f|^2 - e <p, f>` cancels near the minimum)
    let sse = (from..=end).map(|n| (curve.f[n] - e * rp(n)).powi(2)).sum();
    (e, sse)
}

/// Fits `(E, eta)` to the loading and hold of `curve` (samples with `h >= h_max / 3`: the
/// node-quantized contact radius matters less there), with the model ratio `rho` per
/// sample (empty: 1), a cone of half-angle `angle` degrees and Poisson's ratio `nu`.
/// `None` when the curve has no loading, or the best relaxation time lies at the end of
/// the search range (`1e-4` to `1e4` times the loading and hold's duration: the data do
/// not tell it).
pub fn prefit(curve: &Curve<'_>, rho: &[f64], angle: f64, nu: f64) -> Option<Prefit> {
    let end = rising_end(curve.h);
    let h_max = curve.h[..=end].iter().copied().fold(0.0, f64::max);
    if end < 3 || h_max <= 0.0 || curve.f.len() <= end || curve.t.len() <= end {
        return None;
    }
    let from = (0..=end).find(|&n| curve.h[n] >= h_max / 3.0)?;
    let duration = curve.t[end] - curve.t[0];
    if !(duration > 0.0) {
        return None;
    }
    let sse = |ln_tau: f64| best_e(curve, rho, from, end, angle, nu, ln_tau.exp()).1;
    let (lo, hi) = ((duration * 1e-4).ln(), (duration * 1e4).ln());
    let n_grid = 81;
    let grid: Vec<f64> = (0..n_grid)
        .map(|i| lo + (hi - lo) * i as f64 / (n_grid - 1) as f64)
        .collect();
    let costs: Vec<f64> = grid.iter().map(|&x| sse(x)).collect();
    let best = (0..n_grid).min_by(|&i, &j| costs[i].total_cmp(&costs[j]))?;
    if best == 0 || best == n_grid - 1 {
        return None;
    }
    // golden sections on the bracket around the grid's best
    let (mut a, mut b) = (grid[best - 1], grid[best + 1]);
    let r = (5f64.sqrt() - 1.0) / 2.0;
    let mut x1 = b - r * (b - a);
    let mut x2 = a + r * (b - a);
    let (mut f1, mut f2) = (sse(x1), sse(x2));
    for _ in 0..80 {
        if f1 <= f2 {
            b = x2;
            x2 = x1;
            f2 = f1;
            x1 = b - r * (b - a);
            f1 = sse(x1);
        } else {
            a = x1;
            x1 = x2;
            f1 = f2;
            x2 = a + r * (b - a);
            f2 = sse(x2);
        }
        if b - a < 1e-12 {
            break;
        }
    }
    let tau = (0.5 * (a + b)).exp();
    let (e, s) = best_e(curve, rho, from, end, angle, nu, tau);
    let f_max = curve.f[..=end].iter().copied().fold(0.0, f64::max);
    let samples = end + 1 - from;
    (e.is_finite() && e > 0.0).then(|| Prefit {
        e,
        eta: tau * e / (1.0 + nu),
        tau,
        rms_rel: (s / samples as f64).sqrt() / f_max,
        samples,
    })
}

/// The model ratio per sample: the finite element forces `fe` at `(e, eta)` over Lee and
/// Radok's on the same samples (loading and hold; 1 where either is zero and after).
pub fn calibrate(
    t: &[f64],
    h: &[f64],
    fe: &[f64],
    angle: f64,
    nu: f64,
    e: f64,
    eta: f64,
) -> Vec<f64> {
    let end = rising_end(h);
    let phi = unit_forces(t, h, end, angle, nu, eta * (1.0 + nu) / e);
    (0..t.len())
        .map(|n| match (phi.get(n), fe.get(n)) {
            (Some(&p), Some(&f)) if p > 0.0 && f > 0.0 => f / (e * p),
            _ => 1.0,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A ramp to `h_max` in `t_r` then a hold of `t_h`, `n` steps each.
    fn ramp_hold(h_max: f64, t_r: f64, t_h: f64, n: usize) -> (Vec<f64>, Vec<f64>) {
        let mut t = vec![0.0];
        let mut h = vec![0.0];
        for i in 1..=n {
            t.push(t_r * i as f64 / n as f64);
            h.push(h_max * i as f64 / n as f64);
        }
        for i in 1..=n {
            t.push(t_r + t_h * i as f64 / n as f64);
            h.push(h_max);
        }
        (t, h)
    }

    #[test]
    fn the_elastic_limit_is_sneddons_cone() {
        // F = 2 E* tan(alpha) h^2 / pi, E* = E / (1 - nu^2) (E = 1)
        let (t, h) = ramp_hold(0.1, 1.0, 1.0, 30);
        let f = unit_forces(&t, &h, t.len() - 1, 68.0, 0.3, f64::INFINITY);
        for (fi, hi) in f.iter().zip(&h) {
            let sneddon =
                2.0 / (1.0 - 0.09) * 68f64.to_radians().tan() * hi * hi / std::f64::consts::PI;
            assert!(
                (fi - sneddon).abs() <= 1e-14 * sneddon.max(1e-30),
                "{fi} {sneddon}"
            );
        }
    }

    #[test]
    fn the_ramp_converges_to_its_continuous_closed_form_at_first_order() {
        // docs/validation-viscous.md §3: F = (4 tan(alpha) v^2 / pi) sum_k A_k
        // (t/lambda_k - (1 - e^(-lambda_k t))/lambda_k^2) on h = v t
        let (nu, tau, v, t_end, angle) = (0.3f64, 0.7f64, 0.1f64, 1.0f64, 68.0f64);
        let (g, k) = (1.0 / (2.0 * (1.0 + nu)), 1.0 / (3.0 * (1.0 - 2.0 * nu)));
        let (a, b) = (g, 9.0 * k * g / (3.0 * k + 4.0 * g));
        let (l, m) = (1.0 / tau, 3.0 * k / (3.0 * k + 4.0 * g) / tau);
        let term = |amp: f64, rate: f64| {
            amp * (t_end / rate - (1.0 - (-rate * t_end).exp()) / rate / rate)
        };
        let exact = 4.0 * angle.to_radians().tan() * v * v / std::f64::consts::PI
            * (term(a, l) + term(b, m));
        let error = |n: usize| {
            let t: Vec<f64> = (0..=n).map(|i| t_end * i as f64 / n as f64).collect();
            let h: Vec<f64> = t.iter().map(|t| v * t).collect();
            let f = unit_forces(&t, &h, n, angle, nu, tau);
            (f[n] - exact).abs() / exact
        };
        let (e1, e2, e3) = (error(100), error(200), error(400));
        assert!(e3 < 5e-3, "{e1} {e2} {e3}");
        for r in [e1 / e2, e2 / e3] {
            assert!((r - 2.0).abs() < 0.05, "first order: {e1} {e2} {e3}");
        }
    }

    #[test]
    fn a_curve_of_its_own_model_is_fitted_exactly() {
        let (t, h) = ramp_hold(0.1, 1.0, 1.0, 30);
        for (e, eta) in [(20000.0, 30000.0), (60000.0, 8000.0), (35000.0, 15000.0)] {
            let nu = 0.3;
            let tau = eta * (1.0 + nu) / e;
            let f: Vec<f64> = unit_forces(&t, &h, t.len() - 1, 68.0, nu, tau)
                .iter()
                .map(|p| e * p)
                .collect();
            let p = prefit(
                &Curve {
                    t: &t,
                    h: &h,
                    f: &f,
                },
                &[],
                68.0,
                nu,
            )
            .expect("a pre-fit");
            assert!((p.e / e - 1.0).abs() < 1e-6, "{p:?}");
            assert!((p.eta / eta - 1.0).abs() < 1e-6, "{p:?}");
            // with a model ratio: the same data over rho are fitted with rho
            let rho: Vec<f64> = (0..t.len())
                .map(|n| 1.0 + 0.01 * (n as f64).sin())
                .collect();
            let fr: Vec<f64> = f.iter().zip(&rho).map(|(f, r)| f * r).collect();
            let q = prefit(
                &Curve {
                    t: &t,
                    h: &h,
                    f: &fr,
                },
                &rho,
                68.0,
                nu,
            )
            .expect("a pre-fit");
            assert!(
                (q.e / e - 1.0).abs() < 1e-6 && (q.eta / eta - 1.0).abs() < 1e-6,
                "{q:?}"
            );
        }
    }

    #[test]
    fn an_elastic_curve_has_no_relaxation_time() {
        let (t, h) = ramp_hold(0.1, 1.0, 1.0, 30);
        let f: Vec<f64> = unit_forces(&t, &h, t.len() - 1, 68.0, 0.3, f64::INFINITY)
            .iter()
            .map(|p| 2e4 * p)
            .collect();
        assert_eq!(
            prefit(
                &Curve {
                    t: &t,
                    h: &h,
                    f: &f
                },
                &[],
                68.0,
                0.3
            ),
            None
        );
    }
}
