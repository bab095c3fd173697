//! Closed-form pre-fits of an indentation curve's loading and hold: the half-space
//! solutions of a rigid axisymmetric punch (Sneddon's cone, Hertz's sphere, the flat punch)
//! for an elastic solid, and Lee and Radok's viscoelastic form of them for the Maxwell law
//! at the finite element solver's backward-Euler time discretization (docs/analysis.md,
//! "Closed-form starts").
//!
//! A rigid punch whose elastic force is `F = E* k h^q` (`E* = E / (1 - nu^2)`; cone
//! `k = 2 tan(alpha) / pi`, `q = 2`; sphere `k = 4 sqrt(R) / 3`, `q = 3/2`; flat punch of
//! radius `a`: `k = 2 a`, `q = 1`) has, on a linear viscoelastic half-space while the contact
//! radius does not decrease, Lee and Radok's force `F(t) = k int Psi(t - s) d(h^q)(s)`, with
//! `Psi` the relaxation function of the plane-strain modulus. For the Maxwell law (viscous in
//! shear, `nu` fixed) `Psi(t) = E (A e^(-lambda t) + B e^(-mu t))` with, at `E = 1`,
//! `A = G`, `B = 9 K G / (3K + 4G)`, `G = 1/(2(1+nu))`, `K = 1/(3(1-2nu))`,
//! `lambda = 1/tau`, `mu = lambda 3K / (3K + 4G)`, `tau = eta (1 + nu) / E`
//! (`A + B = 1 / (1 - nu^2)`: the elastic limit). Backward Euler with `h^q` linear over each
//! step turns each exponential into `y_n = (y_(n-1) + A Delta(h^q)_n) / (1 + lambda dt_n)`,
//! so `F_n = E Phi_n(tau)`, `Phi` the unit-modulus force. The best `E` is linear in the data,
//! `E = <rho Phi, F> / <rho Phi, rho Phi>` (`rho` the finite element model's ratio to the
//! half-space solution, per sample, [`model_ratio`]; 1 when not known), and for Maxwell
//! `tau` is a one-dimensional search (a logarithmic grid refined by golden sections).
//!
//! Pure numerics: no file IO, no finite element run (the study layer runs the calibration).

use std::f64::consts::PI;

/// A rigid axisymmetric punch with a closed-form elastic force `F = E* k h^q`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Punch {
    /// A cone of half-angle `half_angle_deg` (degrees, from the axis); pyramids as their
    /// area-equivalent cone (Berkovich and Vickers 70.3 deg). Sneddon (1965).
    Cone {
        /// Half-angle (deg).
        half_angle_deg: f64,
    },
    /// A sphere (paraboloid) of radius `radius` (mm). Hertz (1882).
    Sphere {
        /// Radius (mm).
        radius: f64,
    },
    /// A flat cylindrical punch of radius `radius` (mm). Sneddon (1965).
    Flat {
        /// Radius (mm).
        radius: f64,
    },
}

impl Punch {
    /// The coefficient `k` and exponent `q` of `F = E* k h^q`.
    pub fn law(&self) -> (f64, f64) {
        match *self {
            Punch::Cone { half_angle_deg } => (2.0 * half_angle_deg.to_radians().tan() / PI, 2.0),
            Punch::Sphere { radius } => (4.0 * radius.sqrt() / 3.0, 1.5),
            Punch::Flat { radius } => (2.0 * radius, 1.0),
        }
    }

    /// The solution's name and reference, for messages and reports.
    pub fn solution(&self) -> &'static str {
        match self {
            Punch::Cone { .. } => "Sneddon's cone",
            Punch::Sphere { .. } => "Hertz's sphere",
            Punch::Flat { .. } => "the flat punch (Sneddon)",
        }
    }

    /// The elastic force (N) at depth `h` (mm) for `E` (MPa) and `nu`.
    pub fn elastic_force(&self, e: f64, nu: f64, h: f64) -> f64 {
        let (k, q) = self.law();
        e / (1.0 - nu * nu) * k * h.max(0.0).powf(q)
    }

    fn valid(&self) -> bool {
        match *self {
            Punch::Cone { half_angle_deg } => half_angle_deg > 0.0 && half_angle_deg < 90.0,
            Punch::Sphere { radius } | Punch::Flat { radius } => radius > 0.0 && radius.is_finite(),
        }
    }
}

/// Why a closed-form pre-fit gives no start.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ClosedFormError {
    /// Times, depths and forces of different lengths, or a non-finite sample.
    #[error("the curve's samples are not usable: {0}")]
    Samples(String),
    /// No loading: fewer than 4 samples up to the deepest one, or no positive depth.
    #[error("the curve has no loading to fit (fewer than 4 samples rising to a positive depth)")]
    NoLoading,
    /// Poisson's ratio or the punch outside its range.
    #[error("{0}")]
    Input(String),
    /// The loading has no hold at its deepest depth: the viscosity has no closed form.
    #[error(
        "the loading has no hold at its deepest depth (fewer than 3 samples): a relaxation \
         time, hence the viscosity, has no closed form from it"
    )]
    NoHold,
    /// The best relaxation time lies at an end of the search range: the data do not tell it.
    #[error(
        "the best relaxation time lies at the end of the range searched ({lo:.3e} to \
         {hi:.3e} s, 1e-4 to 1e4 times the loading and hold): the curve does not tell the \
         viscosity"
    )]
    NoRelaxation {
        /// Shortest time searched (s).
        lo: f64,
        /// Longest time searched (s).
        hi: f64,
    },
    /// The best modulus is not positive (forces of the wrong sign).
    #[error("the best modulus is not positive ({0:e} MPa): the forces do not rise with the depth")]
    NotPositive(f64),
}

/// The samples a pre-fit uses: time (s), depth (mm), force (N), from the first sample.
#[derive(Clone, Debug)]
pub struct Curve<'a> {
    /// Times (s).
    pub t: &'a [f64],
    /// Depths (mm).
    pub h: &'a [f64],
    /// Forces (N).
    pub f: &'a [f64],
}

impl Curve<'_> {
    fn check(&self) -> Result<(), ClosedFormError> {
        if self.t.len() != self.h.len() || self.f.len() != self.h.len() {
            return Err(ClosedFormError::Samples(format!(
                "{} times, {} depths and {} forces",
                self.t.len(),
                self.h.len(),
                self.f.len()
            )));
        }
        let bad = (0..self.h.len())
            .find(|&n| !(self.t[n].is_finite() && self.h[n].is_finite() && self.f[n].is_finite()));
        match bad {
            Some(n) => Err(ClosedFormError::Samples(format!(
                "sample {n} is not finite"
            ))),
            None => Ok(()),
        }
    }
}

/// A modulus fitted to an elastic closed form.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModulusFit {
    /// Young's modulus (MPa).
    pub e: f64,
    /// RMS of the residuals over the samples fitted, relative to the largest force.
    pub rms_rel: f64,
    /// Samples fitted.
    pub samples: usize,
}

/// A Maxwell law fitted to Lee and Radok's form.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MaxwellFit {
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

/// The first sample of `0..=end` at the deepest depth of `0..=end` (the loading's end).
pub fn loading_end(h: &[f64], end: usize) -> usize {
    let h_max = h[..=end].iter().copied().fold(f64::NEG_INFINITY, f64::max);
    (0..=end).find(|&n| h[n] >= h_max).unwrap_or(end)
}

/// Lee and Radok's force at unit `E` of the Maxwell law on samples `0..=end` of `(t, h)`
/// at the backward-Euler discretization, for `punch`, Poisson's ratio `nu` and relaxation
/// time `tau` (s); `tau = inf` is the elastic closed form `k h^q / (1 - nu^2)`.
pub fn unit_forces(t: &[f64], h: &[f64], end: usize, punch: Punch, nu: f64, tau: f64) -> Vec<f64> {
    let (k_tip, q) = punch.law();
    let g = 1.0 / (2.0 * (1.0 + nu));
    let k = 1.0 / (3.0 * (1.0 - 2.0 * nu));
    let a = g;
    let b = 9.0 * k * g / (3.0 * k + 4.0 * g);
    let lambda = 1.0 / tau;
    let mu = lambda * 3.0 * k / (3.0 * k + 4.0 * g);
    let x = |n: usize| h[n].max(0.0).powf(q);
    let mut out = Vec::with_capacity(end + 1);
    // the first sample as an instantaneous (elastic) step from zero
    let (mut ya, mut yb) = (a * x(0), b * x(0));
    out.push(k_tip * (ya + yb));
    for n in 1..=end {
        let dt = t[n] - t[n - 1];
        let dx = x(n) - x(n - 1);
        ya = (ya + a * dx) / (1.0 + lambda * dt);
        yb = (yb + b * dx) / (1.0 + mu * dt);
        out.push(k_tip * (ya + yb));
    }
    out
}

/// The best `E` of the unit forces `phi` times `rho` against `f` over `from..=end`, and the
/// residual sum of squares.
fn best_e(phi: &[f64], rho: &[f64], f: &[f64], from: usize, end: usize) -> (f64, f64) {
    let rp = |n: usize| rho.get(n).copied().unwrap_or(1.0) * phi[n];
    let (mut pf, mut pp) = (0.0, 0.0);
    for n in from..=end {
        pf += rp(n) * f[n];
        pp += rp(n) * rp(n);
    }
    if pp <= 0.0 {
        return (f64::NAN, f64::INFINITY);
    }
    let e = pf / pp;
    // the residuals summed directly (`|f|^2 - e <p, f>` cancels near the minimum)
    let sse = (from..=end).map(|n| (f[n] - e * rp(n)).powi(2)).sum();
    (e, sse)
}

/// The samples fitted: from the first at a third of the deepest depth (the finite element
/// model's node-quantized contact radius matters less there) to `last`; the loading's end
/// and the hold's end (`rising_end`).
fn fitted_range(
    curve: &Curve<'_>,
    nu: f64,
    punch: Punch,
) -> Result<(usize, usize, usize), ClosedFormError> {
    curve.check()?;
    if !(nu > -1.0 && nu < 0.5) {
        return Err(ClosedFormError::Input(format!(
            "Poisson's ratio {nu} is outside (-1, 0.5)"
        )));
    }
    if !punch.valid() {
        return Err(ClosedFormError::Input(format!(
            "the punch {punch:?} has no closed form (a half-angle in (0, 90) deg, a positive radius)"
        )));
    }
    if curve.h.is_empty() {
        return Err(ClosedFormError::NoLoading);
    }
    let end = rising_end(curve.h);
    let load = loading_end(curve.h, end);
    let h_max = curve.h[load];
    if load < 3 || !(h_max > 0.0) {
        return Err(ClosedFormError::NoLoading);
    }
    let from = (0..=load).find(|&n| curve.h[n] >= h_max / 3.0).unwrap_or(0);
    Ok((from, load, end))
}

fn rms_rel(sse: f64, f: &[f64], from: usize, end: usize) -> f64 {
    let f_max = f[from..=end]
        .iter()
        .copied()
        .fold(0.0, |a: f64, b| a.max(b.abs()));
    (sse / (end + 1 - from) as f64).sqrt() / f_max
}

/// Fits Young's modulus of an elastic solid to the loading of `curve` (up to its deepest
/// sample; samples from a third of that depth) with the closed form of `punch` and
/// Poisson's ratio `nu`, scaled per sample by the model ratio `rho` (empty: 1).
///
/// # Errors
/// Unusable samples, `nu` or punch out of range, no loading, a modulus that is not positive.
pub fn fit_modulus(
    curve: &Curve<'_>,
    rho: &[f64],
    punch: Punch,
    nu: f64,
) -> Result<ModulusFit, ClosedFormError> {
    let (from, load, _) = fitted_range(curve, nu, punch)?;
    let phi = unit_forces(curve.t, curve.h, load, punch, nu, f64::INFINITY);
    let (e, sse) = best_e(&phi, rho, curve.f, from, load);
    if !(e.is_finite() && e > 0.0) {
        return Err(ClosedFormError::NotPositive(e));
    }
    Ok(ModulusFit {
        e,
        rms_rel: rms_rel(sse, curve.f, from, load),
        samples: load + 1 - from,
    })
}

/// Fits `(E, eta)` of the Maxwell law to the loading and hold of `curve` with Lee and
/// Radok's form for `punch` at Poisson's ratio `nu`, scaled per sample by the model ratio
/// `rho` (empty: 1).
///
/// # Errors
/// As [`fit_modulus`]; no hold at the deepest depth ([`ClosedFormError::NoHold`]); the best
/// relaxation time at an end of the range searched, `1e-4` to `1e4` times the loading and
/// hold's duration ([`ClosedFormError::NoRelaxation`]).
pub fn fit_maxwell(
    curve: &Curve<'_>,
    rho: &[f64],
    punch: Punch,
    nu: f64,
) -> Result<MaxwellFit, ClosedFormError> {
    let (from, load, end) = fitted_range(curve, nu, punch)?;
    if end < load + 3 {
        return Err(ClosedFormError::NoHold);
    }
    let duration = curve.t[end] - curve.t[0];
    if !(duration > 0.0) {
        return Err(ClosedFormError::Samples(
            "the loading and hold take no time".into(),
        ));
    }
    let fit = |ln_tau: f64| {
        let phi = unit_forces(curve.t, curve.h, end, punch, nu, ln_tau.exp());
        best_e(&phi, rho, curve.f, from, end)
    };
    let sse = |x: f64| fit(x).1;
    let (lo, hi) = ((duration * 1e-4).ln(), (duration * 1e4).ln());
    let n_grid = 81;
    let grid: Vec<f64> = (0..n_grid)
        .map(|i| lo + (hi - lo) * i as f64 / (n_grid - 1) as f64)
        .collect();
    let costs: Vec<f64> = grid.iter().map(|&x| sse(x)).collect();
    let best = (0..n_grid)
        .min_by(|&i, &j| costs[i].total_cmp(&costs[j]))
        .unwrap_or(0);
    if best == 0 || best == n_grid - 1 {
        return Err(ClosedFormError::NoRelaxation {
            lo: lo.exp(),
            hi: hi.exp(),
        });
    }
    // golden sections on the bracket around the grid's best
    let g = crate::fit::golden_section(sse, grid[best - 1], grid[best + 1], 100, 1e-12);
    let ln_tau = 0.5 * (g.lo + g.hi);
    let tau = ln_tau.exp();
    let (e, s) = fit(ln_tau);
    if !(e.is_finite() && e > 0.0) {
        return Err(ClosedFormError::NotPositive(e));
    }
    Ok(MaxwellFit {
        e,
        eta: tau * e / (1.0 + nu),
        tau,
        rms_rel: rms_rel(s, curve.f, from, end),
        samples: end + 1 - from,
    })
}

/// The model ratio per sample: the finite element forces `fe` (at `E` = `e` and relaxation
/// time `tau`, `inf` for an elastic law) over the closed form's on the same samples (the
/// loading and hold; 1 where either is not positive, and after).
pub fn model_ratio(
    t: &[f64],
    h: &[f64],
    fe: &[f64],
    punch: Punch,
    nu: f64,
    e: f64,
    tau: f64,
) -> Vec<f64> {
    let end = rising_end(h).min(t.len().saturating_sub(1));
    let phi = if h.is_empty() {
        Vec::new()
    } else {
        unit_forces(t, h, end, punch, nu, tau)
    };
    (0..t.len())
        .map(|n| match (phi.get(n), fe.get(n)) {
            (Some(&p), Some(&f)) if p > 0.0 && f > 0.0 && e > 0.0 => f / (e * p),
            _ => 1.0,
        })
        .collect()
}
