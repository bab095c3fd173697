//! Closed-form references of the viscous indentation tests: the relaxation function of
//! the indentation modulus of the Maxwell law (shear dashpot, elastic bulk), and the
//! hereditary integrals of Lee & Radok (cone, contact growing), Ting (cone, contact
//! shrinking) and the flat punch, evaluated either exactly in continuous time or at the
//! backward-Euler discretization of the solver.
//!
//! Derivations: docs/validation-viscous.md §1-§3. Nothing here comes from the code
//! under test: the module uses no crate of the workspace (the runners over the solver
//! live in the test files).

#![allow(dead_code)]

use std::f64::consts::PI;

/// Young's modulus of R1 (MPa), docs/theory.md §11.
pub const E: f64 = 20000.0;
/// Poisson's ratio of R1.
pub const NU: f64 = 0.3;
/// Viscosity of R1 (MPa s).
pub const ETA: f64 = 30000.0;
/// Cone half-angle of the reference problems (deg, from the axis).
pub const ALPHA_DEG: f64 = 68.0;
/// Maximum depth of the trapezoid (mm).
pub const H_MAX: f64 = 0.1;

/// Relative difference `x / reference - 1`.
pub fn rel(x: f64, reference: f64) -> f64 {
    x / reference - 1.0
}

/// Shear and bulk moduli `(G, K)` of `(E, nu)` (MPa).
pub fn shear_bulk(e: f64, nu: f64) -> (f64, f64) {
    (e / (2.0 * (1.0 + nu)), e / (3.0 * (1.0 - 2.0 * nu)))
}

/// Indentation (plane-strain) modulus `E* = E / (1 - nu^2) = 4 G (3K + G) / (3K + 4G)`.
pub fn e_star(e: f64, nu: f64) -> f64 {
    e / (1.0 - nu * nu)
}

/// A relaxation function written as a sum of exponentials,
/// `Psi(t) = sum_k A_k exp(-lambda_k t)` (MPa), with `(A_k, lambda_k)` in `terms`.
#[derive(Clone, Debug, PartialEq)]
pub struct Relaxation {
    /// `(A_k (MPa), lambda_k (1/s))`.
    pub terms: Vec<(f64, f64)>,
}

impl Relaxation {
    /// Relaxation function of the indentation modulus `E*` of the Maxwell law
    /// `deps = S dsigma + P sigma dt / eta` (shear viscous, bulk elastic):
    ///
    /// ```text
    ///   Psi(t) = G exp(-t / tau) + 9 K G / (3K + 4G) exp(-t / tau_2),
    ///   tau = eta / (2G),   tau_2 = tau (3K + 4G) / (3K)
    /// ```
    ///
    /// (Laplace domain: `G(s) = G s / (s + 1/tau)`, `K(s) = K`, then the partial
    /// fractions of `E*(s) / s`; docs/validation-viscous.md §1).
    pub fn maxwell_indentation(e: f64, nu: f64, eta: f64) -> Relaxation {
        let (g, k) = shear_bulk(e, nu);
        let lambda = 2.0 * g / eta;
        let mu = lambda * 3.0 * k / (3.0 * k + 4.0 * g);
        Relaxation {
            terms: vec![(g, lambda), (9.0 * k * g / (3.0 * k + 4.0 * g), mu)],
        }
    }

    /// `Psi(t)` (MPa).
    pub fn at(&self, t: f64) -> f64 {
        self.terms.iter().map(|&(a, l)| a * (-l * t).exp()).sum()
    }

    /// Laplace transform `sum_k A_k / (s + lambda_k)` (MPa s).
    pub fn laplace(&self, s: f64) -> f64 {
        self.terms.iter().map(|&(a, l)| a / (s + l)).sum()
    }

    /// Backward-Euler kernel: the value at `t[n]` of a unit increment of the driving
    /// strain made over step `j` (`1 <= j <= n`), `sum_k A_k prod_{m=j..n} 1/(1 + lambda_k
    /// dt_m)`. Each term `y' = -lambda y + A x'` stepped by backward Euler; for a constant
    /// step this is the exact discrete counterpart of `Psi(t_n - t_j)` (the rational
    /// substitution `s -> (1 - z^-1) / dt` commutes with the partial fractions).
    pub fn backward_euler(&self, t: &[f64], j: usize, n: usize) -> f64 {
        self.terms
            .iter()
            .map(|&(a, l)| {
                let mut w = a;
                for m in j..=n {
                    w /= 1.0 + l * (t[m] - t[m - 1]);
                }
                w
            })
            .sum()
    }
}

/// Laplace-domain indentation modulus of the Maxwell law,
/// `E*(s) = 4 G(s) (3K + G(s)) / (3K + 4 G(s))` with `G(s) = G s / (s + 2G/eta)`:
/// the independent form against which [`Relaxation::maxwell_indentation`] is checked
/// (`s Psi_bar(s) = E*(s)`).
pub fn maxwell_indentation_modulus_laplace(e: f64, nu: f64, eta: f64, s: f64) -> f64 {
    let (g, k) = shear_bulk(e, nu);
    let gs = g * s / (s + 2.0 * g / eta);
    4.0 * gs * (3.0 * k + gs) / (3.0 * k + 4.0 * gs)
}

/// How the hereditary integrals are evaluated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Time {
    /// Exactly, with the continuous kernel `Psi(t - tau)` and the piecewise-linear depth.
    Continuous,
    /// At the backward-Euler discretization of the schedule: the kernel is constant over
    /// each step, equal to [`Relaxation::backward_euler`].
    BackwardEuler,
}

/// Hereditary integrals `int K_n(tau) d(h^p)` over a piecewise-linear depth history
/// `h(t)` given at the times `t` (the schedule of the solver), evaluated at `t[n]`.
#[derive(Clone, Debug)]
pub struct Hereditary<'a> {
    /// Relaxation function.
    pub psi: &'a Relaxation,
    /// Schedule times (s), `t[0] = 0`.
    pub t: &'a [f64],
    /// Depths at those times (mm), `h[0] = 0`.
    pub h: &'a [f64],
    /// Continuous or backward Euler.
    pub time: Time,
}

/// `(int_lo^hi e^{-l (t - tau)} dtau, int_lo^hi (tau - lo) e^{-l (t - tau)} dtau)`,
/// written `e^{-l (t - hi)} (d phi1(l d), d^2 phi2(l d))` with `d = hi - lo`,
/// `phi1(x) = (1 - e^{-x}) / x`, `phi2(x) = (x - 1 + e^{-x}) / x^2`, both by their series
/// for small `x` (no cancellation, also in the elastic limit `l -> 0`).
fn exp_moments(l: f64, t: f64, lo: f64, hi: f64) -> (f64, f64) {
    let d = hi - lo;
    let x = l * d;
    let (phi1, phi2) = if x < 0.1 {
        // phi1 = sum (-x)^k / (k+1)!, phi2 = sum (-x)^k / (k+2)!
        let (mut p1, mut p2, mut term) = (0.0, 0.0, 1.0);
        for k in 0..12 {
            p1 += term / (k + 1) as f64;
            p2 += term / ((k + 1) * (k + 2)) as f64;
            term *= -x / (k + 1) as f64;
        }
        (p1, p2)
    } else {
        let em = (-x).exp_m1(); // e^{-x} - 1
        (-em / x, (x + em) / (x * x))
    };
    let eb = (-l * (t - hi)).exp();
    (eb * d * phi1, eb * d * d * phi2)
}

impl Hereditary<'_> {
    /// Depth at time `tau`, linear between schedule times.
    pub fn depth(&self, tau: f64) -> f64 {
        let j = self
            .t
            .partition_point(|&x| x < tau)
            .clamp(1, self.t.len() - 1);
        let f = (tau - self.t[j - 1]) / (self.t[j] - self.t[j - 1]);
        self.h[j - 1] + f * (self.h[j] - self.h[j - 1])
    }

    /// `int_a^b K_n(tau) d(h(tau)^p)/dtau dtau` for `p = 1` or `2`, `0 <= a <= b <= t[n]`,
    /// with `K_n(tau) = Psi(t_n - tau)` or its backward-Euler staircase.
    pub fn integral(&self, n: usize, a: f64, b: f64, p: i32) -> f64 {
        let mut sum = 0.0;
        for j in 1..=n {
            let (lo, hi) = (a.max(self.t[j - 1]), b.min(self.t[j]));
            if hi <= lo {
                continue;
            }
            let (h0, h1) = (self.depth(lo), self.depth(hi));
            sum += match self.time {
                Time::BackwardEuler => {
                    self.psi.backward_euler(self.t, j, n) * (h1.powi(p) - h0.powi(p))
                }
                Time::Continuous => {
                    let v = (self.h[j] - self.h[j - 1]) / (self.t[j] - self.t[j - 1]);
                    self.psi
                        .terms
                        .iter()
                        .map(|&(amp, l)| {
                            let (i0, i1) = exp_moments(l, self.t[n], lo, hi);
                            match p {
                                1 => amp * v * i0,
                                2 => 2.0 * amp * v * (h0 * i0 + v * i1),
                                _ => panic!("p = {p}: only h and h^2 are integrated"),
                            }
                        })
                        .sum::<f64>()
                }
            };
        }
        sum
    }

    /// Flat punch of radius `a` on the half-space, contact fixed:
    /// `F(t_n) = 2 a int_0^t_n K_n(tau) dh` (N).
    pub fn flat_force(&self, n: usize, a: f64) -> f64 {
        2.0 * a * self.integral(n, 0.0, self.t[n], 1)
    }

    /// Cone of half-angle `alpha_deg` on the half-space at `t[n]`: `(F (N), a (mm), t1
    /// (s))` by Lee & Radok while the contact radius grows or stays, by Ting once it
    /// shrinks; `F = 0, a = 0` after the loss of contact.
    ///
    /// The history must rise to its maximum at `t[l]` and not rise again after it
    /// (load, hold, unload). With `t1(t) <= t[l]` the time at which the contact radius was
    /// last what it is now, defined by Ting's edge condition
    /// `int_t1^t K(tau) dh = 0` (`t1 = t` while loading, `t1 = t[l]` while holding):
    ///
    /// ```text
    ///   F(t) = (2 tan(alpha) / pi) int_0^t1 K(tau) d(h^2),   a(t) = 2 h(t1) tan(alpha) / pi
    /// ```
    ///
    /// and no contact once `int_0^t K dh <= 0` (docs/validation-viscous.md §2).
    pub fn cone(&self, n: usize, alpha_deg: f64) -> (f64, f64, f64) {
        let tan = alpha_deg.to_radians().tan();
        let l =
            (0..self.h.len()).fold(0, |best, j| if self.h[j] > self.h[best] { j } else { best });
        assert!(
            self.h[..=l].windows(2).all(|w| w[1] >= w[0])
                && self.h[l..].windows(2).all(|w| w[1] <= w[0]),
            "the history must load, then hold or unload"
        );
        let t1 = if n <= l {
            self.t[n]
        } else if self.integral(n, self.t[l], self.t[n], 1) >= 0.0 {
            self.t[l]
        } else if self.integral(n, 0.0, self.t[n], 1) <= 0.0 {
            return (0.0, 0.0, 0.0);
        } else {
            // the edge integral decreases with t1 on the loading branch: bisection
            let (mut lo, mut hi) = (0.0, self.t[l]);
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if self.integral(n, mid, self.t[n], 1) > 0.0 {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            0.5 * (lo + hi)
        };
        let force = 2.0 * tan / PI * self.integral(n, 0.0, t1, 2);
        (force, 2.0 * self.depth(t1) * tan / PI, t1)
    }
}
