//! J2 plasticity with isotropic hardening: `Plastic(E, nu, sY, hardening, rate)`,
//! rate-independent (radial return, consistent tangent, held elastic/plastic partition)
//! or with Norton overstress, as a [`Material`] with the equivalent plastic strain `p` as
//! its internal variable.

use crate::LawError;
use crate::elastic::{E_INFO, NU_INFO, isotropic_compliance, isotropic_operator};
use crate::hardening::{Hardening, SY, Table};
use crate::law::{LocalFailure, ParamInfo};
use crate::mandel::{Mat4, Vec4};
use crate::material::{InternalInfo, Material, MaterialUpdate, Regime, Step, stress_of};
use crate::norton_hoff::{K_INFO, M_INFO, solve_overstress};
use crate::registry::{
    Built, FieldKind, FieldSchema, Fields, LawEntry, SpecValue, VariantSchema, number,
    ordered_params,
};

/// The rate form of a [`Plastic`] law.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rate {
    /// Rate-independent: `s_eq <= sigma_y(p)`, radial return.
    Independent,
    /// Norton overstress: `dp/dt = <(s_eq - sigma_y(p)) / K>_+^m`.
    Norton,
}

/// J2 (von Mises) plasticity, associative, isotropic hardening, small strain in Mandel
/// components (finite strain uses it in Hencky space like every law).
///
/// Parameters `c = [E, nu, sY, <hardening's>, (K, m if Norton)]` (MPa, -, MPa, ...,
/// MPa s^(1/m), -); state `y = [sigma, p]`, `p` the equivalent plastic strain. With
/// `s_eq = sqrt(3/2 s:s)`, `n = 3 s / (2 s_eq)`, `Delta p = p_1 - p_0`, the local residual
/// (strain units in the stress rows) is
///
/// - stress rows, all branches but the rate-independent elastic one:
///   `r_sigma = S (sigma_1 - sigma_0) + Delta p n(sigma_1) - deps`
///   (the plastic strain increment is `Delta p n`; the elastic branch drops the term);
/// - `p` row: rate-independent plastic `r_p = s_eq(sigma_1) - sigma_y(p_1)` (MPa),
///   rate-independent elastic `r_p = Delta p`, Norton
///   `r_p = Delta p - dt <(s_eq(sigma_1) - sigma_y(p_1)) / K>_+^m`.
///
/// The update is the radial return: with the trial deviator `s_tr = s_0 + 2G dev deps`
/// and `q_tr = s_eq(s_tr)`, `s_1 = s_tr q / q_tr` where `q + 3G Delta p = q_tr` and
/// `q = sigma_y(p_0 + Delta p)` (rate-independent) or
/// `q = sigma_y(p_0 + Delta p) + K x`, `Delta p = dt x^m` (Norton). The consistent
/// tangent is `C = 3 kappa J + 2G (q/q_tr) (P - N N) + 2G q' N N` with
/// `N = s_tr / |s_tr|` and `q' = dq/dq_tr`: `H'/(H' + 3G)` rate-independent,
/// `(1 + dt phi' H') / (1 + dt phi' H' + 3G dt phi')` with `phi' = (m/K) x^(m-1)` for
/// Norton (`H' = d sigma_y/dp` at `p_1`).
///
/// With `Linear` and `H = 0`, Norton is [`crate::NortonHoff`] (same scalar equation, same
/// solver). The rate-independent law has two residual branches; the converged branch
/// ([`Regime`]) is held by the adjoint, and where a parameter change moves a point's trial
/// stress across `sigma_y(p_0)` the cost's derivative jumps (docs/theory.md §12).
#[derive(Clone, Debug)]
pub struct Plastic {
    hardening: Hardening,
    rate: Rate,
    params: Vec<ParamInfo>,
}

/// `sY` of a plastic law: positive (the power and Swift forms divide by it).
const SY_INFO: ParamInfo = ParamInfo {
    name: "sY",
    unit: "MPa",
    description: "initial yield stress",
    min: 0.0,
    min_inclusive: false,
    max: f64::INFINITY,
    max_inclusive: false,
};

const INTERNAL: [InternalInfo; 1] = [InternalInfo {
    name: "p",
    unit: "-",
    description: "equivalent plastic strain",
}];

/// von Mises stress and normal `n = 3 s / (2 s_eq)` (zero at zero deviator).
struct J2 {
    q: f64,
    n: Vec4,
}

fn j2(sigma: &Vec4) -> J2 {
    let s = sigma.deviator();
    let q = (1.5 * s.dot(&s)).sqrt();
    let n = if q > 0.0 { s * (1.5 / q) } else { Vec4::ZERO };
    J2 { q, n }
}

/// `dn/dsigma = (3/(2 s_eq)) (P - (2/3) n (x) n)` (zero at zero deviator).
fn normal_derivative(j: &J2) -> Mat4 {
    if j.q > 0.0 {
        (Mat4::deviatoric_projector() - j.n.outer(&j.n) * (2.0 / 3.0)) * (1.5 / j.q)
    } else {
        Mat4::ZERO
    }
}

/// What every block of a step shares at one Gauss point: the compliance, the end
/// stress's `s_eq` and normal, the hardening `(sigma_y, H')` at `p_1`, the overstress
/// `v = s_eq - sigma_y` and (Norton) the rate `phi(v)` and its slope (zero for the
/// rate-independent law).
struct PointEval {
    compliance: Mat4,
    j: J2,
    h: f64,
    v: f64,
    phi: f64,
    dphi: f64,
}

fn failure(reason: String) -> LocalFailure {
    LocalFailure {
        reason,
        suggested_dt_factor: 0.25,
    }
}

impl Plastic {
    /// The law with this hardening form and rate.
    pub fn new(hardening: Hardening, rate: Rate) -> Plastic {
        let mut params = vec![E_INFO, NU_INFO, SY_INFO];
        params.extend_from_slice(hardening.params());
        if rate == Rate::Norton {
            params.extend_from_slice(&[K_INFO, M_INFO]);
        }
        Plastic {
            hardening,
            rate,
            params,
        }
    }
    /// The hardening form.
    pub fn hardening(&self) -> &Hardening {
        &self.hardening
    }
    /// The rate form.
    pub fn rate(&self) -> Rate {
        self.rate
    }
    /// Index of `K` (Norton only; `m` follows).
    fn k_index(&self) -> usize {
        SY + 1 + self.hardening.params().len()
    }
    /// `(phi, phi')` of the Norton rate at the overstress `v` (zero below yield).
    fn norton(&self, c: &[f64], v: f64) -> (f64, f64) {
        let (k, m) = (c[self.k_index()], c[self.k_index() + 1]);
        if v > 0.0 {
            let x = v / k;
            let xm1 = x.powf(m - 1.0);
            (xm1 * x, m / k * xm1)
        } else {
            (0.0, 0.0)
        }
    }
    fn flowing(&self, regime: Regime) -> bool {
        !(self.rate == Rate::Independent && regime == Regime::Elastic)
    }

    /// What every block of a step shares at one point ([`PointEval`]).
    fn point(&self, c: &[f64], step: &Step<'_>) -> PointEval {
        let j = j2(&stress_of(step.y1));
        let (sy, h) = self.hardening.value(c, step.y1[4]);
        let v = j.q - sy;
        let (phi, dphi) = match self.rate {
            Rate::Norton => self.norton(c, v),
            Rate::Independent => (0.0, 0.0),
        };
        PointEval {
            compliance: isotropic_compliance(c[0], c[1]),
            j,
            h,
            v,
            phi,
            dphi,
        }
    }

    /// `A = dR/dy_1` (5 x 5) from the point's shared quantities.
    fn state_block(&self, _c: &[f64], step: &Step<'_>, pt: &PointEval, out: &mut [f64]) {
        let dp = step.y1[4] - step.y0[4];
        let j = &pt.j;
        let flowing = self.flowing(step.regime);
        let mut a = pt.compliance;
        if flowing {
            a += normal_derivative(j) * dp;
        }
        out.fill(0.0);
        for i in 0..4 {
            out[i * 5..i * 5 + 4].copy_from_slice(&a.0[i]);
            if flowing {
                out[i * 5 + 4] = j.n[i];
            }
        }
        let (row, diag) = match (self.rate, step.regime) {
            (Rate::Independent, Regime::Elastic) => (Vec4::ZERO, 1.0),
            (Rate::Independent, _) => (j.n, -pt.h),
            (Rate::Norton, _) => (j.n * (-step.dt * pt.dphi), 1.0 + step.dt * pt.dphi * pt.h),
        };
        out[20..24].copy_from_slice(&row.0);
        out[24] = diag;
    }

    /// `D = dR/dy_0` (5 x 5).
    fn previous_block(&self, step: &Step<'_>, pt: &PointEval, out: &mut [f64]) {
        let d = pt.compliance * -1.0;
        out.fill(0.0);
        let flowing = self.flowing(step.regime);
        for i in 0..4 {
            out[i * 5..i * 5 + 4].copy_from_slice(&d.0[i]);
            if flowing {
                out[i * 5 + 4] = -pt.j.n[i];
            }
        }
        out[24] = match (self.rate, step.regime) {
            (Rate::Independent, Regime::Elastic) | (Rate::Norton, _) => -1.0,
            (Rate::Independent, _) => 0.0,
        };
    }

    /// `P = dR/dc` (5 x n_c): the compliance's derivatives applied to `ds = s1 - s0` in
    /// closed form (`S v = ((1 + nu) v - nu tr(v) 1) / E`, so `dS/dE v = -S v / E` and
    /// `dS/dnu v = (v - tr(v) 1) / E`; no 4 x 4 matrix per point), and the `p` row.
    fn params_block(&self, c: &[f64], step: &Step<'_>, pt: &PointEval, out: &mut [f64]) {
        let nc = c.len();
        let (e, nu) = (c[0], c[1]);
        let ds = stress_of(step.y1) - stress_of(step.y0);
        let tr = ds.trace();
        let col_e = (ds * (1.0 + nu) - Vec4::ONE * (nu * tr)) * (-1.0 / (e * e));
        let col_nu = (ds - Vec4::ONE * tr) * (1.0 / e);
        out.fill(0.0);
        for i in 0..4 {
            out[i * nc] = col_e[i];
            out[i * nc + 1] = col_nu[i];
        }
        let p1 = step.y1[4];
        let row = &mut out[4 * nc..5 * nc];
        match (self.rate, step.regime) {
            (Rate::Independent, Regime::Elastic) => {}
            (Rate::Independent, _) => {
                self.hardening.param_derivatives(c, p1, row);
                for v in row.iter_mut() {
                    *v = -*v;
                }
            }
            (Rate::Norton, _) => {
                self.hardening.param_derivatives(c, p1, row);
                for d in row.iter_mut() {
                    *d *= step.dt * pt.dphi;
                }
                let ki = self.k_index();
                if pt.phi > 0.0 {
                    let (k, m) = (c[ki], c[ki + 1]);
                    row[ki] = step.dt * m * pt.phi / k;
                    row[ki + 1] = -step.dt * pt.phi * (pt.v / k).ln();
                }
            }
        }
    }

    /// Rate-independent return: `Delta p` with `q_tr - 3G Delta p = sigma_y(p0 + Delta p)`,
    /// in closed form for `Linear`, else Newton from `Delta p = 0` kept inside the
    /// bracket `[0, (q_tr - sigma_y(p0)) / 3G]` (widened by 1e-12 for the saturated
    /// curve, whose root is that end; bisection when a step leaves it; the
    /// function is decreasing since `sigma_y` never softens). Returns `Delta p`, the
    /// iterations and `(sigma_y, H')` at `p0 + Delta p` (evaluated once, not again by the
    /// caller).
    fn return_independent(
        &self,
        c: &[f64],
        g3: f64,
        p0: f64,
        q_tr: f64,
        d: f64,
    ) -> Result<(f64, u32, (f64, f64)), LocalFailure> {
        if let Some(h) = self.hardening.linear_modulus(c) {
            let dp = d / (g3 + h);
            return Ok((dp, 0, self.hardening.value(c, p0 + dp)));
        }
        // (the bracket widened by 1e-12: where the curve has saturated, `H' ~ 0`, the root
        // is `d / 3G` itself, and a Newton step landing on the bracket's end by rounding
        // would be refused and bisection take ~50 halvings to get there)
        let (mut lo, mut hi) = (0.0, d / g3 * (1.0 + 1e-12));
        let mut dp = 0.0;
        for it in 1..=200u32 {
            let (sy, h) = self.hardening.value(c, p0 + dp);
            let f = q_tr - g3 * dp - sy;
            if f.abs() <= 1e-14 * q_tr || hi - lo <= 1e-16 * hi {
                // (the curve at the accepted point: the caller's tangent needs it)
                return Ok((dp, it, (sy, h)));
            }
            if f > 0.0 {
                lo = dp;
            } else {
                hi = dp;
            }
            let next = dp + f / (g3 + h);
            dp = if next > lo && next < hi {
                next
            } else {
                0.5 * (lo + hi)
            };
        }
        Err(failure(format!(
            "plastic: return map did not converge (q_tr = {q_tr} MPa, p0 = {p0}, hardening {})",
            self.hardening.kind()
        )))
    }

    /// Norton return: the overstress `x = (q - sigma_y(p1))/K` with
    /// `q_tr - sigma_y(p0 + dt x^m) - K x - 3G dt x^m = 0`. For `Linear` this is
    /// Norton-Hoff's scalar equation with `3G dt` replaced by `(3G + H) dt` (its solver);
    /// otherwise Newton from that solution at the slope `H'(p0)`, kept inside
    /// `[0, min(d/K, (d/(3G dt))^(1/m))]` (hardening only lowers the root).
    fn return_norton(
        &self,
        c: &[f64],
        g3: f64,
        p0: f64,
        q_tr: f64,
        d: f64,
        dt: f64,
    ) -> Result<(f64, u32), LocalFailure> {
        let (k, m) = (c[self.k_index()], c[self.k_index() + 1]);
        let wrap = |f: LocalFailure| failure(format!("plastic (Norton): {}", f.reason));
        if let Some(h) = self.hardening.linear_modulus(c) {
            return solve_overstress(k, (g3 + h) * dt, m, d).map_err(wrap);
        }
        // without hardening either term alone reaching `d` bounds the root
        let hi0 = (d / k).min((d / (g3 * dt)).powf(1.0 / m));
        let h0 = self.hardening.value(c, p0).1;
        let (mut x, it0) = solve_overstress(k, (g3 + h0) * dt, m, d).map_err(wrap)?;
        let sy0 = q_tr - d;
        let (mut lo, mut hi) = (0.0, hi0 * (1.0 + 1e-12));
        for it in 1..=200u32 {
            let xm1 = x.powf(m - 1.0);
            let (sy, h) = self.hardening.value(c, p0 + dt * xm1 * x);
            let f = d - (sy - sy0) - k * x - g3 * dt * xm1 * x;
            if f.abs() <= 1e-14 * q_tr || hi - lo <= 1e-16 * hi {
                return Ok((x, it0 + it));
            }
            if f > 0.0 {
                lo = x;
            } else {
                hi = x;
            }
            let slope = k + (h + g3) * dt * m * xm1;
            let next = x + f / slope;
            x = if next > lo && next < hi {
                next
            } else {
                0.5 * (lo + hi)
            };
        }
        Err(failure(format!(
            "plastic (Norton): return map did not converge (q_tr = {q_tr} MPa, p0 = {p0}, dt = {dt} s)"
        )))
    }
}

impl Material for Plastic {
    fn name(&self) -> &'static str {
        "plastic"
    }
    fn params(&self) -> &[ParamInfo] {
        &self.params
    }
    fn internal(&self) -> &[InternalInfo] {
        &INTERNAL
    }
    /// Norton needs `m > 1` (as Norton-Hoff); the rate-independent law is differentiable
    /// with its elastic/plastic partition held.
    ///
    /// # Errors
    /// [`LawError::NotDifferentiable`] naming `m` when `m <= 1`.
    fn check_differentiable(&self, c: &[f64]) -> Result<(), LawError> {
        if self.rate == Rate::Norton && c[self.k_index() + 1] <= 1.0 {
            return Err(LawError::NotDifferentiable {
                law: "plastic",
                name: "m",
                value: c[self.k_index() + 1],
                why: "the adjoint needs m > 1: the Norton rate <(s_eq - sigma_y)/K>_+^m must be \
                      differentiable across the yield surface",
            });
        }
        Ok(())
    }
    fn residual(&self, c: &[f64], step: &Step<'_>, r: &mut [f64]) {
        let (s0, s1) = (stress_of(step.y0), stress_of(step.y1));
        let (p0, p1) = (step.y0[4], step.y1[4]);
        let dp = p1 - p0;
        let j = j2(&s1);
        let mut rs = isotropic_compliance(c[0], c[1]).mul_vec(&(s1 - s0)) - *step.deps;
        if self.flowing(step.regime) {
            rs += j.n * dp;
        }
        r[..4].copy_from_slice(&rs.0);
        let sy = self.hardening.value(c, p1).0;
        r[4] = match (self.rate, step.regime) {
            (Rate::Independent, Regime::Elastic) => dp,
            (Rate::Independent, _) => j.q - sy,
            (Rate::Norton, _) => dp - step.dt * self.norton(c, j.q - sy).0,
        };
    }
    fn jac_state(&self, c: &[f64], step: &Step<'_>, out: &mut [f64]) {
        self.state_block(c, step, &self.point(c, step), out);
    }
    fn jac_previous(&self, c: &[f64], step: &Step<'_>, out: &mut [f64]) {
        self.previous_block(step, &self.point(c, step), out);
    }
    fn jac_params(&self, c: &[f64], step: &Step<'_>, out: &mut [f64]) {
        self.params_block(c, step, &self.point(c, step), out);
    }
    /// `A^T X = B` in closed form. With `S = P/(2G) + J/(3 kappa)` and
    /// `dn/dsigma = (3/(2 s_eq)) (P - (2/3) n (x) n)`, the stress block of `A` is
    /// `A_ss = alpha P + beta J - gamma n (x) n` (`alpha = 1/(2G) + 1.5 Delta p / s_eq`,
    /// `beta = 1/(3 kappa)`, `gamma = Delta p / s_eq` where the branch flows, else
    /// `gamma = 0`), its `p` column `c_n n` (`c_n` 1 where the branch flows, else 0), its
    /// `p` row `rho n` and corner `d` (`A`'s own entries). `n` is deviatoric, so
    /// `A_ss^-1 = P/alpha + J/beta + gamma/(alpha (alpha - gamma |n|^2)) n (x) n` and
    /// `A_ss^-1 n = n / (alpha - gamma |n|^2)`, and the bordered system
    /// `A_ss x_s + rho n x_p = b_s`, `c_n n.x_s + d x_p = b_p` has
    /// `x_p = (b_p - c_n n.A_ss^-1 b_s) / (d - c_n rho |n|^2 / (alpha - gamma |n|^2))`,
    /// `x_s = A_ss^-1 b_s - rho x_p n / (alpha - gamma |n|^2)` (the Schur complement is
    /// `-(H' + 3G)` rate-independent, the radial return's own). About 40 flops per
    /// right-hand side instead of an elimination.
    fn solve_state_transpose(
        &self,
        c: &[f64],
        step: &Step<'_>,
        a: &[f64],
        b: &mut [f64],
        nrhs: usize,
        _work: &mut [f64],
    ) -> bool {
        let (e, nu) = (c[0], c[1]);
        let alpha0 = (1.0 + nu) / e;
        let beta = (1.0 - 2.0 * nu) / e;
        let flowing = self.flowing(step.regime);
        let j = j2(&stress_of(step.y1));
        let dp = step.y1[4] - step.y0[4];
        let (alpha, gamma) = if flowing && j.q > 0.0 {
            (alpha0 + 1.5 * dp / j.q, dp / j.q)
        } else {
            (alpha0, 0.0)
        };
        let n = if flowing { j.n } else { Vec4::ZERO };
        let nn = n.dot(&n);
        // A's p row is rho n (zero, n or -dt phi' n): rho read at n's largest entry
        let big = (0..4).fold(0, |b, i| if n[i].abs() > n[b].abs() { i } else { b });
        let rho = match (self.rate, step.regime) {
            (Rate::Independent, Regime::Elastic) => 0.0,
            (Rate::Independent, _) => 1.0,
            (Rate::Norton, _) if n[big] != 0.0 => a[20 + big] / n[big],
            (Rate::Norton, _) => 0.0,
        };
        let d = a[24];
        let inv_schur_n = 1.0 / (alpha - gamma * nn);
        let kappa_n = gamma * inv_schur_n / alpha;
        let schur = d - rho * nn * inv_schur_n;
        if !(schur.is_finite() && schur != 0.0 && alpha > 0.0 && beta > 0.0) {
            return false;
        }
        for k in 0..nrhs {
            let bs = Vec4([b[k], b[nrhs + k], b[2 * nrhs + k], b[3 * nrhs + k]]);
            let bp = b[4 * nrhs + k];
            let tr = bs.trace() / 3.0;
            // A_ss^-1 b_s
            let mb = (bs - Vec4::ONE * tr) * (1.0 / alpha)
                + Vec4::ONE * (tr / beta)
                + n * (kappa_n * n.dot(&bs));
            let xp = (bp - n.dot(&mb)) / schur;
            let xs = mb - n * (rho * xp * inv_schur_n);
            for i in 0..4 {
                b[i * nrhs + k] = xs[i];
            }
            b[4 * nrhs + k] = xp;
        }
        true
    }
    /// The four blocks from one evaluation of `s_eq`, the normal, the hardening curve
    /// and the Norton rate at the point (`Plastic::point`): the same numbers as the
    /// four methods, without repeating that work per block.
    fn jac_blocks(
        &self,
        c: &[f64],
        step: &Step<'_>,
        a: &mut [f64],
        d: &mut [f64],
        e: &mut [f64],
        p: &mut [f64],
    ) {
        let pt = self.point(c, step);
        self.state_block(c, step, &pt, a);
        self.previous_block(step, &pt, d);
        self.jac_strain(c, step, e);
        self.params_block(c, step, &pt, p);
    }
    /// Radial return (see [`Plastic`]).
    ///
    /// # Errors
    /// [`LocalFailure`] (suggested factor 0.25) on non-finite input, a negative `dt` or
    /// `p0`, or a return map that does not converge.
    fn update(
        &self,
        c: &[f64],
        y0: &[f64],
        deps: &Vec4,
        dt: f64,
        y1: &mut [f64],
    ) -> Result<MaterialUpdate, LocalFailure> {
        let s0 = stress_of(y0);
        let p0 = y0[4];
        if !(dt.is_finite()
            && dt >= 0.0
            && s0.is_finite()
            && deps.is_finite()
            && p0 >= 0.0
            && p0.is_finite())
        {
            return Err(failure(format!(
                "plastic: invalid input dt = {dt}, s0 = {s0:?}, p0 = {p0}, deps = {deps:?}"
            )));
        }
        let (e, nu) = (c[0], c[1]);
        let g2 = e / (1.0 + nu);
        let g3 = 1.5 * g2;
        let kappa3 = e / (1.0 - 2.0 * nu);
        let s_tr = s0.deviator() + deps.deviator() * g2;
        let spherical = Vec4::ONE * ((s0.trace() + kappa3 * deps.trace()) / 3.0);
        let q_tr = (1.5 * s_tr.dot(&s_tr)).sqrt();
        let d = q_tr - self.hardening.value(c, p0).0;
        let elastic_regime = match self.rate {
            Rate::Independent => Regime::Elastic,
            Rate::Norton => Regime::Smooth,
        };
        if !(d > 0.0 && q_tr > 0.0) || (self.rate == Rate::Norton && dt == 0.0) {
            let sigma = s_tr + spherical;
            y1[..4].copy_from_slice(&sigma.0);
            y1[4] = p0;
            return Ok(MaterialUpdate {
                tangent: isotropic_operator(g2, kappa3),
                iterations: 0,
                regime: elastic_regime,
            });
        }
        let (dp, q, qprime, iterations, regime) = match self.rate {
            Rate::Independent => {
                let (dp, it, (sy, h)) = self.return_independent(c, g3, p0, q_tr, d)?;
                (dp, sy, h / (h + g3), it, Regime::Plastic)
            }
            Rate::Norton => {
                let (x, it) = self.return_norton(c, g3, p0, q_tr, d, dt)?;
                let (k, m) = (c[self.k_index()], c[self.k_index() + 1]);
                let xm1 = x.powf(m - 1.0);
                let dp = dt * xm1 * x;
                let (sy, h) = self.hardening.value(c, p0 + dp);
                let dphi = m / k * xm1;
                let num = 1.0 + dt * dphi * h;
                (
                    dp,
                    sy + k * x,
                    num / (num + g3 * dt * dphi),
                    it,
                    Regime::Smooth,
                )
            }
        };
        let sigma = s_tr * (q / q_tr) + spherical;
        if !sigma.is_finite() || !dp.is_finite() {
            return Err(failure(format!(
                "plastic: non-finite state from s0 = {s0:?}, p0 = {p0}, deps = {deps:?}, dt = {dt}"
            )));
        }
        let unit = s_tr * (1.5 / q_tr) * (2.0f64 / 3.0).sqrt();
        let ratio = q / q_tr;
        let tangent =
            isotropic_operator(g2 * ratio, kappa3) + unit.outer(&unit) * (g2 * qprime - g2 * ratio);
        y1[..4].copy_from_slice(&sigma.0);
        y1[4] = p0 + dp;
        Ok(MaterialUpdate {
            tangent,
            iterations,
            regime,
        })
    }
}

/// The registry entry: `Plastic(E, nu, sY, hardening: H, rate: R)` with `H` one of
/// `Linear(H: ..)`, `Power(n: ..)`, `Voce(Q: .., b: ..)`, `Swift(eps0: .., n: ..)`,
/// `Table(points: [(eps_p, sigma), ...])` and `R` omitted (rate-independent) or
/// `Norton(K: .., m: ..)`.
pub const ENTRY: LawEntry = LawEntry {
    name: "plastic",
    variant: "Plastic",
    summary: "J2 plasticity with isotropic hardening (Linear, Power, Voce, Swift, Table), \
              rate-independent or with Norton overstress",
    example: "Plastic(E: 70000.0, nu: 0.3, sY: 300.0, hardening: Power(n: 0.2), \
              rate: Norton(K: 200.0, m: 3.0))",
    fields: &[
        number("E"),
        number("nu"),
        number("sY"),
        FieldSchema {
            name: "hardening",
            kind: FieldKind::OneOf(&[
                VariantSchema {
                    name: "Linear",
                    fields: &[number("H")],
                },
                VariantSchema {
                    name: "Power",
                    fields: &[number("n")],
                },
                VariantSchema {
                    name: "Voce",
                    fields: &[number("Q"), number("b")],
                },
                VariantSchema {
                    name: "Swift",
                    fields: &[number("eps0"), number("n")],
                },
                VariantSchema {
                    name: "Table",
                    fields: &[FieldSchema {
                        name: "points",
                        kind: FieldKind::Pairs,
                        optional: false,
                    }],
                },
            ]),
            optional: false,
        },
        FieldSchema {
            name: "rate",
            kind: FieldKind::OneOf(&[VariantSchema {
                name: "Norton",
                fields: &[number("K"), number("m")],
            }]),
            optional: true,
        },
    ],
    build: build_spec,
};

const HARDENING_KINDS: &str = "Linear(H: ..), Power(n: ..), Voce(Q: .., b: ..), Swift(eps0: .., n: ..), \
                               Table(points: [(eps_p, sigma), ...])";

fn table_points(h: &mut Fields<'_>) -> Result<Vec<(f64, f64)>, LawError> {
    let Some(SpecValue::List(items)) = h.get("points") else {
        return Err(h.error(
            "points",
            "missing or not a list of (eps_p, sigma) pairs".into(),
        ));
    };
    items
        .iter()
        .enumerate()
        .map(|(i, v)| match v {
            SpecValue::Tuple(p) | SpecValue::List(p) => match p.as_slice() {
                [SpecValue::Number(e), SpecValue::Number(s)] => Ok((*e, *s)),
                _ => Err(h.error(
                    &format!("points[{i}]"),
                    "expected a pair (eps_p, sigma)".into(),
                )),
            },
            _ => Err(h.error(
                &format!("points[{i}]"),
                "expected a pair (eps_p, sigma)".into(),
            )),
        })
        .collect()
}

fn build_hardening(
    f: &mut Fields<'_>,
    values: &mut Vec<(&'static str, f64)>,
) -> Result<Hardening, LawError> {
    let (name, fields) = match f.get("hardening") {
        Some(SpecValue::Variant { name, fields }) => (name.as_str(), fields),
        Some(other) => {
            return Err(f.error(
                "hardening",
                format!("expected one of {HARDENING_KINDS}, got {other:?}"),
            ));
        }
        None => return Err(f.error("hardening", format!("missing (one of {HARDENING_KINDS})"))),
    };
    let mut h = Fields::new("plastic", "hardening.", fields);
    let (form, accepted): (Hardening, &[&str]) = match name {
        "Linear" => {
            values.push(("H", h.number("H")?));
            (Hardening::Linear, &["H"])
        }
        "Power" => {
            values.push(("n", h.number("n")?));
            (Hardening::Power, &["n"])
        }
        "Voce" => {
            values.push(("Q", h.number("Q")?));
            values.push(("b", h.number("b")?));
            (Hardening::Voce, &["Q", "b"])
        }
        "Swift" => {
            values.push(("eps0", h.number("eps0")?));
            values.push(("n", h.number("n")?));
            (Hardening::Swift, &["eps0", "n"])
        }
        "Table" => (
            Hardening::Table(Table::new(&table_points(&mut h)?)?),
            &["points"],
        ),
        other => {
            return Err(f.error(
                "hardening",
                format!("unknown hardening kind `{other}`; one of Linear, Power, Voce, Swift, Table ({HARDENING_KINDS})"),
            ));
        }
    };
    h.finish(accepted)?;
    Ok(form)
}

fn build_spec(fields: &[(String, SpecValue)]) -> Result<Built, LawError> {
    let mut f = Fields::new("plastic", "", fields);
    let mut values = vec![
        ("E", f.number("E")?),
        ("nu", f.number("nu")?),
        ("sY", f.number("sY")?),
    ];
    let hardening = build_hardening(&mut f, &mut values)?;
    let rate = match f.get("rate") {
        None => Rate::Independent,
        Some(SpecValue::Variant { name, fields }) if name == "None" && fields.is_empty() => {
            Rate::Independent
        }
        Some(SpecValue::Variant { name, fields }) if name == "Norton" => {
            let mut r = Fields::new("plastic", "rate.", fields);
            values.push(("K", r.number("K")?));
            values.push(("m", r.number("m")?));
            r.finish(&["K", "m"])?;
            Rate::Norton
        }
        Some(other) => {
            let what = match other {
                SpecValue::Variant { name, .. } => format!("unknown rate kind `{name}`"),
                v => format!("expected a rate kind, got {v:?}"),
            };
            return Err(f.error(
                "rate",
                format!("{what}; one of Norton(K: .., m: ..), or omit it for rate-independent plasticity"),
            ));
        }
    };
    f.finish(&["E", "nu", "sY", "hardening", "rate"])?;
    let material = Plastic::new(hardening, rate);
    let params = ordered_params(&material, &values)?;
    Ok(Built {
        material: Box::new(material),
        params,
    })
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::testing::{Point, check_material};
    use crate::{Law, NortonHoff};

    /// Every hardening form with parameters of a hardening metal (E = 70 GPa, sY = 300
    /// MPa), and the rate forms.
    pub(crate) fn laws() -> Vec<(Plastic, Vec<f64>)> {
        let table =
            Table::new(&[(0.0, 300.0), (0.004, 360.0), (0.02, 420.0), (0.1, 470.0)]).unwrap();
        let forms = [
            (Hardening::Linear, vec![2000.0]),
            (Hardening::Power, vec![0.2]),
            (Hardening::Voce, vec![150.0, 40.0]),
            (Hardening::Swift, vec![0.01, 0.25]),
            (Hardening::Table(table), vec![]),
        ];
        let mut out = Vec::new();
        for (h, hp) in forms {
            for rate in [Rate::Independent, Rate::Norton] {
                let mut c = vec![7e4, 0.3, 300.0];
                c.extend(&hp);
                if rate == Rate::Norton {
                    c.extend([200.0, 3.0]);
                }
                out.push((Plastic::new(h.clone(), rate), c));
            }
        }
        out
    }

    /// A deterministic stream of numbers in [-1, 1) (xorshift).
    pub(crate) struct Rng(pub u64);
    impl Rng {
        pub(crate) fn next(&mut self) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 11) as f64 / (1u64 << 52) as f64 - 1.0
        }
        pub(crate) fn vec4(&mut self) -> Vec4 {
            Vec4([self.next(), self.next(), self.next(), self.next()])
        }
    }

    /// The system shall give every block of `Plastic` (each hardening form, rate-
    /// independent and Norton) equal to central finite differences to 1e-6, and a
    /// residual below 1e-10 of its terms at the update, over 40 random points per law
    /// from elastic steps to steps of 50 times the yield strain, with hardened
    /// previous states.
    #[test]
    fn every_block_matches_finite_differences() {
        let mut rng = Rng(0x9e3779b97f4a7c15);
        for (law, c) in laws() {
            let (mut plastic, mut elastic, mut worst) = (0, 0, 0.0f64);
            let mut worst_solve = 0.0f64;
            for _ in 0..40 {
                let s0 = rng.vec4() * 250.0;
                let p0 = 0.05 * (rng.next() + 1.0);
                let y0 = [s0[0], s0[1], s0[2], s0[3], p0];
                let mag = 10f64.powf(-4.5 + 2.5 * (rng.next() + 1.0) / 2.0 * 1.4);
                let deps = rng.vec4() * mag;
                let dt = 10f64.powf(-2.0 + 2.0 * rng.next());
                let pt = Point {
                    c: &c,
                    y0: &y0,
                    deps,
                    dt,
                };
                let rep = check_material(&law, &pt, 1e-6)
                    .unwrap_or_else(|e| panic!("{:?}: {e}", law.hardening().kind()));
                assert!(rep.checks[0].error.unwrap() < 1e-10, "{rep:?}");
                // one call for every block: the same numbers as the four methods
                let joint = rep
                    .checks
                    .iter()
                    .find(|c| c.block.starts_with("jac_blocks"));
                assert_eq!(joint.and_then(|c| c.error), Some(0.0), "{rep:?}");
                // the closed-form solve with A^T: a backward error of round-off size
                let solve = rep.checks.iter().find(|c| c.block.starts_with("A^T solve"));
                let solve = solve.and_then(|c| c.error).expect("checked");
                assert!(solve < 1e-13, "{solve:e} {rep:?}");
                worst_solve = worst_solve.max(solve);
                worst = worst.max(rep.worst());
                if rep.regime == Regime::Elastic {
                    elastic += 1;
                } else {
                    plastic += 1;
                }
            }
            eprintln!(
                "{} {:?}: {plastic} flowing, {elastic} elastic, worst {worst:e}, A^T solve \
                 backward error {worst_solve:e}",
                law.hardening().kind(),
                law.rate()
            );
            if law.rate() == Rate::Independent {
                assert!(
                    plastic >= 10 && elastic >= 5,
                    "{plastic} plastic, {elastic} elastic"
                );
            }
        }
    }

    /// Voce's consistent tangent near and at saturation: at previous plastic strains from
    /// 0 to 50 / b (R2's bench parameters, `Q = 300 MPa, b = 20`, and the validation's
    /// `Q = 150, b = 40`), for plastic steps of 0.3 to 30 times the yield strain, the
    /// update's tangent equals finite differences of the update and `-A^-1 E` to 1e-6
    /// (the checks of `check_material`), and the return map converges in a handful of
    /// iterations.
    #[test]
    fn voce_tangent_is_consistent_near_saturation() {
        let law = Plastic::new(Hardening::Voce, Rate::Independent);
        let mut rng = Rng(31);
        let (mut worst, mut most) = (0.0f64, 0u32);
        for (e, sy, q, b) in [(1e5, 500.0, 300.0, 20.0), (7e4, 300.0, 150.0, 40.0)] {
            let c = [e, 0.3, sy, q, b];
            for p0 in [0.0, 0.1, 0.5, 1.0, 2.0, 5.0, 50.0].map(|x: f64| x / b) {
                // a previous state on the current yield surface, uniaxial-like
                let sig = sy + q * (1.0 - (-b * p0).exp());
                let s0 = Vec4([-sig / 3.0, 2.0 * sig / 3.0, -sig / 3.0, 0.0]);
                let y0 = [s0[0], s0[1], s0[2], s0[3], p0];
                for scale in [0.3, 3.0, 30.0] {
                    let deps = (Vec4([-0.5, 1.0, -0.5, 0.0]) + rng.vec4() * 0.2) * (scale * sy / e);
                    let pt = Point {
                        c: &c,
                        y0: &y0,
                        deps,
                        dt: 0.01,
                    };
                    let rep = check_material(&law, &pt, 1e-6)
                        .unwrap_or_else(|m| panic!("p0 {p0}, scale {scale}: {m}"));
                    assert_eq!(rep.regime, Regime::Plastic, "p0 {p0}, scale {scale}");
                    for c in rep.checks.iter().filter(|c| c.block.starts_with("tangent")) {
                        worst = worst.max(c.error.unwrap_or(0.0));
                    }
                    let mut y1 = [0.0; 5];
                    let up = law.update(&c, &y0, &deps, 0.01, &mut y1).unwrap();
                    if up.iterations > 8 {
                        eprintln!(
                            "slow: b {b}, p0 {p0}, scale {scale}: {} iterations",
                            up.iterations
                        );
                    }
                    most = most.max(up.iterations);
                }
            }
        }
        assert!(most <= 8, "{most} return-map iterations");
        eprintln!(
            "voce tangent against finite differences: worst {worst:e}, at most {most} iterations"
        );
    }

    /// The system shall reproduce Norton-Hoff with `Plastic(Linear(H: 0), Norton)` at the
    /// material point to 1e-8 relative (stress and tangent) along a path through
    /// yielding, creep and unloading (measured: the same bits).
    #[test]
    fn norton_with_no_hardening_is_norton_hoff() {
        let law = Plastic::new(Hardening::Linear, Rate::Norton);
        let (e, nu, sy, k, m) = (1e5, 0.3, 500.0, 1500.0, 5.0);
        let c = [e, nu, sy, 0.0, k, m];
        let nh = [e, nu, k, m, sy];
        let mut rng = Rng(7);
        let mut y = [0.0; 5];
        let mut s = Vec4::ZERO;
        let mut worst = 0.0f64;
        let mut identical = true;
        for i in 0..200 {
            let dir = if i < 120 { 1.0 } else { -0.7 };
            let deps = (Vec4([-0.4, 1.0, -0.4, 0.3]) * 2e-3 + rng.vec4() * 3e-4) * dir;
            let dt = 0.05 * (1.0 + rng.next());
            let up = NortonHoff.update(&nh, &s, &deps, dt).unwrap();
            let mut y1 = [0.0; 5];
            let mu = law.update(&c, &y, &deps, dt, &mut y1).unwrap();
            let s1 = stress_of(&y1);
            worst = worst
                .max((s1 - up.sigma).max_abs() / up.sigma.max_abs())
                .max((mu.tangent - up.tangent).max_abs() / up.tangent.max_abs());
            identical &= s1 == up.sigma;
            s = up.sigma;
            y = y1;
        }
        assert!(worst <= 1e-8, "{worst:e}");
        assert!(y[4] > 0.01, "the path flows: p = {}", y[4]);
        eprintln!(
            "norton vs norton-hoff: worst relative difference {worst:e}, identical bits: {identical}"
        );
    }

    /// The elastic/plastic switch (docs/theory.md §12): where the trial stress sits on the
    /// yield surface, the update is continuous in `sY` but its derivative jumps; each
    /// side's derivative is the one the blocks of its own regime give (`-A^-1 P`, regime
    /// held). Uniaxial trial stress `q_tr = 400 MPa`, `Linear(H: 2000)`: below
    /// `sY = 400` the step is plastic and `d sigma_zz / d sY = 3G/(3G + H)`-weighted, above
    /// it elastic and 0.
    #[test]
    fn the_switch_is_continuous_with_a_jump_in_the_derivative() {
        let law = Plastic::new(Hardening::Linear, Rate::Independent);
        let (e, nu, h) = (7e4, 0.3, 2000.0);
        // a deviatoric strain increment whose trial von Mises stress is 400 MPa
        let g2 = e / (1.0 + nu);
        let dir = Vec4([-0.5, 1.0, -0.5, 0.0]);
        let deps = dir * (400.0 / (1.5 * g2));
        let sigma = |sy: f64| {
            let mut y1 = [0.0; 5];
            let up = law
                .update(&[e, nu, sy, h], &[0.0; 5], &deps, 1.0, &mut y1)
                .unwrap();
            (y1, up.regime)
        };
        let (below, rb) = sigma(400.0 - 1e-9);
        let (above, ra) = sigma(400.0 + 1e-9);
        assert_eq!((rb, ra), (Regime::Plastic, Regime::Elastic));
        assert!(
            (below[1] - above[1]).abs() < 1e-6,
            "continuous: {} vs {}",
            below[1],
            above[1]
        );
        // one-sided derivatives from the blocks of each regime
        let slope = |sy: f64| {
            let c = [e, nu, sy, h];
            let (y1, regime) = sigma(sy);
            let step = Step {
                y0: &[0.0; 5],
                y1: &y1,
                deps: &deps,
                dt: 1.0,
                regime,
            };
            let (mut a, mut p) = (vec![0.0; 25], vec![0.0; 20]);
            law.jac_state(&c, &step, &mut a);
            law.jac_params(&c, &step, &mut p);
            let mut col: Vec<f64> = (0..5).map(|i| -p[i * 4 + 2]).collect();
            assert!(crate::material::dense_solve(&mut a, 5, &mut col));
            col[1]
        };
        let (d_below, d_above) = (slope(399.0), slope(401.0));
        assert_eq!(d_above, 0.0);
        // deviatoric zz part of the unit uniaxial-like direction: s_zz = (2/3) q, and
        // q = sY + H dp with dp = (q_tr - sY)/(3G + H): dq/dsY = 3G/(3G + H)
        let expected = 2.0 / 3.0 * (1.5 * g2) / (1.5 * g2 + h);
        assert!((d_below - expected).abs() < 1e-9, "{d_below} vs {expected}");
        // and finite differences on each side agree with them
        let fd = |sy: f64| (sigma(sy + 1e-3).0[1] - sigma(sy - 1e-3).0[1]) / 2e-3;
        assert!((fd(399.0) - d_below).abs() < 1e-6 && fd(401.0).abs() < 1e-12);
    }

    /// The system shall refuse negative or non-finite hardening and rate parameters,
    /// naming the parameter and its range.
    #[test]
    fn bad_parameters_name_the_field_and_range() {
        let cases: Vec<(Plastic, Vec<f64>, &str, &str)> = vec![
            (
                Plastic::new(Hardening::Linear, Rate::Independent),
                vec![7e4, 0.3, 300.0, -1.0],
                "`H`",
                "[0, inf)",
            ),
            (
                Plastic::new(Hardening::Power, Rate::Independent),
                vec![7e4, 0.3, 300.0, f64::NAN],
                "`n`",
                "[0, 1]",
            ),
            (
                Plastic::new(Hardening::Power, Rate::Independent),
                vec![7e4, 0.3, 300.0, 1.5],
                "`n`",
                "[0, 1]",
            ),
            (
                Plastic::new(Hardening::Voce, Rate::Independent),
                vec![7e4, 0.3, 300.0, -5.0, 3.0],
                "`Q`",
                "[0, inf)",
            ),
            (
                Plastic::new(Hardening::Voce, Rate::Independent),
                vec![7e4, 0.3, 300.0, 5.0, f64::INFINITY],
                "`b`",
                "[0, inf)",
            ),
            (
                Plastic::new(Hardening::Swift, Rate::Independent),
                vec![7e4, 0.3, 300.0, 0.0, 0.2],
                "`eps0`",
                "(0, inf)",
            ),
            (
                Plastic::new(Hardening::Linear, Rate::Norton),
                vec![7e4, 0.3, 300.0, 10.0, -2.0, 3.0],
                "`K`",
                "(0, inf)",
            ),
            (
                Plastic::new(Hardening::Linear, Rate::Norton),
                vec![7e4, 0.3, 300.0, 10.0, 2.0, 0.5],
                "`m`",
                "[1, inf)",
            ),
            (
                Plastic::new(Hardening::Linear, Rate::Independent),
                vec![7e4, 0.3, 0.0, 10.0],
                "`sY`",
                "(0, inf)",
            ),
        ];
        for (law, c, name, range) in cases {
            let text = law.check_params(&c).unwrap_err().to_string();
            assert!(
                text.contains(name) && text.contains(range) && text.contains("plastic"),
                "{text}"
            );
        }
        let law = Plastic::new(Hardening::Linear, Rate::Norton);
        assert!(
            law.check_differentiable(&[7e4, 0.3, 300.0, 10.0, 2.0, 1.0])
                .is_err()
        );
        assert!(
            law.check_differentiable(&[7e4, 0.3, 300.0, 10.0, 2.0, 1.5])
                .is_ok()
        );
        assert_eq!(law.params().len(), 6);
        assert_eq!(law.internal()[0].name, "p");
    }

    /// The system shall return a `LocalFailure` with a step factor below 1, never a NaN or
    /// a panic, on non-finite input, a negative step or plastic strain, and survive huge
    /// steps (1e4 times the yield strain, every form) with a finite state that zeroes
    /// the residual.
    #[test]
    fn bad_input_is_a_local_failure_and_huge_steps_converge() {
        for (law, c) in laws() {
            let mut y1 = [0.0; 5];
            let nan = Vec4([f64::NAN, 0.0, 0.0, 0.0]);
            let ok = Vec4([0.0, 1e-2, 0.0, 0.0]);
            for (y0, deps, dt) in [
                ([0.0; 5], nan, 0.1),
                ([0.0; 5], ok, -1.0),
                ([0.0; 5], ok, f64::INFINITY),
                ([0.0, 0.0, 0.0, 0.0, -1.0], ok, 0.1),
                ([f64::NAN, 0.0, 0.0, 0.0, 0.0], ok, 0.1),
            ] {
                let f = law.update(&c, &y0, &deps, dt, &mut y1).unwrap_err();
                assert!(
                    f.suggested_dt_factor < 1.0 && f.reason.contains("plastic"),
                    "{f}"
                );
            }
            for scale in [1e-1, 1.0, 30.0] {
                let deps = Vec4([-0.5, 1.0, -0.5, 0.2]) * scale;
                let y0 = [0.0; 5];
                let up = law.update(&c, &y0, &deps, 1e-3, &mut y1).unwrap();
                assert!(y1.iter().all(|v| v.is_finite()), "{y1:?}");
                let mut r = [0.0; 5];
                law.residual(
                    &c,
                    &Step {
                        y0: &y0,
                        y1: &y1,
                        deps: &deps,
                        dt: 1e-3,
                        regime: up.regime,
                    },
                    &mut r,
                );
                let stress_scale = stress_of(&y1).max_abs() / c[0] + deps.max_abs();
                assert!(
                    r[..4].iter().all(|v| v.abs() <= 1e-12 * stress_scale),
                    "{:?} {r:?}",
                    law.hardening().kind()
                );
            }
        }
    }
}
