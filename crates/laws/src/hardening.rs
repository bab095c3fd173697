//! Isotropic hardening curves `sigma_y(p)` of [`crate::Plastic`]: linear, power (Dao),
//! Voce, Swift and a fixed table, with their slopes and parameter derivatives.

use crate::LawError;
use crate::law::ParamInfo;

/// The hardening form of a J2 law: the flow stress `sigma_y(p)` as a function of the
/// equivalent plastic strain `p >= 0`, the initial yield stress `sY` and the form's own
/// parameters (which follow `[E, nu, sY]` in the parameter slice).
///
/// | form | `sigma_y(p)` | parameters |
/// |---|---|---|
/// | `Linear` | `sY + H p` | `H >= 0` (MPa) |
/// | `Power` | `sY (1 + E p / sY)^n` (Dao et al.'s form; slope `n E` at `p = 0`) | `n` in `[0, 1]` |
/// | `Voce` | `sY + Q (1 - exp(-b p))` | `Q >= 0` (MPa), `b >= 0` |
/// | `Swift` | `sY (1 + p / eps0)^n` | `eps0 > 0`, `n` in `[0, 1]` |
/// | `Table` | `sY + T(p) - T(0)`, `T` the piecewise-linear table (extended by its last slope) | none (fixed) |
///
/// A table's shape is fixed and `sY` shifts it, so the table is reproduced exactly when
/// `sY` equals its first stress; its kinks are points where the hardening slope jumps
/// (like the elastic/plastic switch, a parameter change that moves a converged `p`
/// across a kink changes the derivative of the cost discontinuously).
#[derive(Clone, Debug, PartialEq)]
pub enum Hardening {
    /// `sigma_y = sY + H p`.
    Linear,
    /// `sigma_y = sY (1 + E p / sY)^n`.
    Power,
    /// `sigma_y = sY + Q (1 - exp(-b p))`.
    Voce,
    /// `sigma_y = sY (1 + p / eps0)^n`.
    Swift,
    /// `sigma_y = sY + T(p) - T(0)`.
    Table(Table),
}

/// A tabulated flow curve `(eps_p, sigma)`: `eps_p` strictly increasing from 0, `sigma`
/// non-decreasing, every value finite.
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    eps: Vec<f64>,
    sigma: Vec<f64>,
}

impl Table {
    /// Validates and stores `points`.
    ///
    /// # Errors
    /// [`LawError::Spec`] naming the offending point (`hardening.points[i]`) and the rule
    /// it breaks: at least two points, the first at `eps_p = 0`, `eps_p` strictly
    /// increasing, `sigma` non-decreasing and non-negative, all finite.
    pub fn new(points: &[(f64, f64)]) -> Result<Table, LawError> {
        let err = |i: Option<usize>, message: String| LawError::Spec {
            law: "plastic",
            field: match i {
                Some(i) => format!("hardening.points[{i}]"),
                None => "hardening.points".into(),
            },
            message,
        };
        if points.len() < 2 {
            return Err(err(
                None,
                format!(
                    "a table needs at least 2 points (eps_p, sigma), got {}",
                    points.len()
                ),
            ));
        }
        for (i, &(e, s)) in points.iter().enumerate() {
            if !(e.is_finite() && s.is_finite()) {
                return Err(err(Some(i), format!("({e}, {s}) is not finite")));
            }
            if s < 0.0 {
                return Err(err(Some(i), format!("sigma = {s} MPa must be in [0, inf)")));
            }
            if i == 0 && e != 0.0 {
                return Err(err(
                    Some(0),
                    format!("the first point must have eps_p = 0, got {e}"),
                ));
            }
            if i > 0 {
                let (e0, s0) = points[i - 1];
                if e <= e0 {
                    return Err(err(
                        Some(i),
                        format!(
                            "eps_p = {e} must be greater than the previous {e0} (strictly increasing)"
                        ),
                    ));
                }
                if s < s0 {
                    return Err(err(
                        Some(i),
                        format!(
                            "sigma = {s} MPa must be at least the previous {s0} MPa (non-decreasing: softening is not allowed)"
                        ),
                    ));
                }
            }
        }
        Ok(Table {
            eps: points.iter().map(|p| p.0).collect(),
            sigma: points.iter().map(|p| p.1).collect(),
        })
    }

    /// `(T(p) - T(0), T'(p))`, the segment to the right of a knot at a knot.
    fn eval(&self, p: f64) -> (f64, f64) {
        let n = self.eps.len();
        let mut i = 0;
        while i + 2 < n && p >= self.eps[i + 1] {
            i += 1;
        }
        let slope = (self.sigma[i + 1] - self.sigma[i]) / (self.eps[i + 1] - self.eps[i]);
        (
            self.sigma[i] + slope * (p - self.eps[i]) - self.sigma[0],
            slope,
        )
    }
}

const H_INFO: ParamInfo = ParamInfo {
    name: "H",
    unit: "MPa",
    description: "linear hardening modulus (sigma_y = sY + H p)",
    min: 0.0,
    min_inclusive: true,
    max: f64::INFINITY,
    max_inclusive: false,
};
const N_INFO: ParamInfo = ParamInfo {
    name: "n",
    unit: "-",
    description: "hardening exponent",
    min: 0.0,
    min_inclusive: true,
    max: 1.0,
    max_inclusive: true,
};
const Q_INFO: ParamInfo = ParamInfo {
    name: "Q",
    unit: "MPa",
    description: "Voce saturation stress increment",
    min: 0.0,
    min_inclusive: true,
    max: f64::INFINITY,
    max_inclusive: false,
};
const B_INFO: ParamInfo = ParamInfo {
    name: "b",
    unit: "-",
    description: "Voce saturation rate",
    min: 0.0,
    min_inclusive: true,
    max: f64::INFINITY,
    max_inclusive: false,
};
const EPS0_INFO: ParamInfo = ParamInfo {
    name: "eps0",
    unit: "-",
    description: "Swift pre-strain",
    min: 0.0,
    min_inclusive: false,
    max: f64::INFINITY,
    max_inclusive: false,
};

/// Index of `sY` in a plastic law's parameter slice; the hardening's own follow it.
pub(crate) const SY: usize = 2;
const H0: usize = 3;

impl Hardening {
    /// The configuration name of the form (`Linear`, `Power`, `Voce`, `Swift`, `Table`).
    pub fn kind(&self) -> &'static str {
        match self {
            Hardening::Linear => "Linear",
            Hardening::Power => "Power",
            Hardening::Voce => "Voce",
            Hardening::Swift => "Swift",
            Hardening::Table(_) => "Table",
        }
    }

    /// The form's own parameters, in slice order after `sY`.
    pub fn params(&self) -> &'static [ParamInfo] {
        match self {
            Hardening::Linear => &[H_INFO],
            Hardening::Power => &[N_INFO],
            Hardening::Voce => &[Q_INFO, B_INFO],
            Hardening::Swift => &[EPS0_INFO, N_INFO],
            Hardening::Table(_) => &[],
        }
    }

    /// `H` when the form is `Linear` (its slope is then constant).
    pub(crate) fn linear_modulus(&self, c: &[f64]) -> Option<f64> {
        matches!(self, Hardening::Linear).then(|| c[H0])
    }

    /// `(sigma_y(p), d sigma_y / dp)` at parameters `c` (the law's whole slice).
    pub fn value(&self, c: &[f64], p: f64) -> (f64, f64) {
        let sy = c[SY];
        match self {
            Hardening::Linear => (sy + c[H0] * p, c[H0]),
            Hardening::Power => {
                let (e, n) = (c[0], c[H0]);
                let u = 1.0 + e * p / sy;
                let un1 = u.powf(n - 1.0);
                (sy * un1 * u, n * e * un1)
            }
            Hardening::Voce => {
                let (q, b) = (c[H0], c[H0 + 1]);
                let x = (-b * p).exp();
                (sy + q * (1.0 - x), q * b * x)
            }
            Hardening::Swift => {
                let (e0, n) = (c[H0], c[H0 + 1]);
                let u = 1.0 + p / e0;
                let un1 = u.powf(n - 1.0);
                (sy * un1 * u, sy * n * un1 / e0)
            }
            Hardening::Table(t) => {
                let (v, slope) = t.eval(p);
                (sy + v, slope)
            }
        }
    }

    /// `d sigma_y / d c_k` at fixed `p` for every `k < out.len()` (the law's whole slice:
    /// the power form also depends on `E`).
    pub fn param_derivatives(&self, c: &[f64], p: f64, out: &mut [f64]) {
        out.fill(0.0);
        let sy = c[SY];
        match self {
            Hardening::Linear => {
                out[SY] = 1.0;
                out[H0] = p;
            }
            Hardening::Power => {
                let (e, n) = (c[0], c[H0]);
                let u = 1.0 + e * p / sy;
                let un1 = u.powf(n - 1.0);
                let un = un1 * u;
                out[0] = n * un1 * p;
                out[SY] = un - n * un1 * e * p / sy;
                out[H0] = sy * un * u.ln();
            }
            Hardening::Voce => {
                let (q, b) = (c[H0], c[H0 + 1]);
                let x = (-b * p).exp();
                out[SY] = 1.0;
                out[H0] = 1.0 - x;
                out[H0 + 1] = q * p * x;
            }
            Hardening::Swift => {
                let (e0, n) = (c[H0], c[H0 + 1]);
                let u = 1.0 + p / e0;
                let un1 = u.powf(n - 1.0);
                out[SY] = un1 * u;
                out[H0] = -sy * n * un1 * p / (e0 * e0);
                out[H0 + 1] = sy * un1 * u * u.ln();
            }
            Hardening::Table(_) => out[SY] = 1.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn forms() -> Vec<(Hardening, Vec<f64>)> {
        let table = Table::new(&[(0.0, 300.0), (0.01, 400.0), (0.05, 450.0)]).unwrap();
        vec![
            (Hardening::Linear, vec![7e4, 0.3, 300.0, 2000.0]),
            (Hardening::Power, vec![7e4, 0.3, 300.0, 0.2]),
            (Hardening::Voce, vec![7e4, 0.3, 300.0, 150.0, 40.0]),
            (Hardening::Swift, vec![7e4, 0.3, 300.0, 0.01, 0.25]),
            (Hardening::Table(table), vec![7e4, 0.3, 300.0]),
        ]
    }

    /// The system shall give `sigma_y(0) = sY` for every form, and slopes and parameter
    /// derivatives equal to central finite differences (relative 1e-7).
    #[test]
    fn slopes_and_parameter_derivatives_match_finite_differences() {
        for (h, c) in forms() {
            assert_eq!(h.value(&c, 0.0).0, c[SY], "{}", h.kind());
            for p in [0.0, 0.003, 0.02, 0.3] {
                let (s, slope) = h.value(&c, p);
                assert!(s >= c[SY]);
                let dp = 1e-7;
                let lo = if p == 0.0 { p } else { p - dp };
                let fd = (h.value(&c, p + dp).0 - h.value(&c, lo).0) / (p + dp - lo);
                assert!(
                    (fd - slope).abs() <= 1e-5 * slope.abs().max(1.0),
                    "{} p {p}: {slope} vs {fd}",
                    h.kind()
                );
                let mut d = vec![0.0; c.len()];
                h.param_derivatives(&c, p, &mut d);
                for k in 0..c.len() {
                    let step = 1e-6 * c[k].abs().max(1e-3);
                    let (mut cp, mut cm) = (c.clone(), c.clone());
                    cp[k] += step;
                    cm[k] -= step;
                    let fd = (h.value(&cp, p).0 - h.value(&cm, p).0) / (2.0 * step);
                    assert!(
                        (fd - d[k]).abs() <= 1e-6 * (d[k].abs() + 1e-3 * s),
                        "{} p {p} k {k}: {} vs {fd}",
                        h.kind(),
                        d[k]
                    );
                }
            }
        }
    }

    /// The system shall refuse a table that is not increasing, naming the point and rule.
    #[test]
    fn bad_tables_are_refused_naming_the_point() {
        for (pts, field, what) in [
            (vec![(0.0, 300.0)], "hardening.points", "at least 2"),
            (vec![(0.01, 300.0), (0.02, 310.0)], "points[0]", "eps_p = 0"),
            (
                vec![(0.0, 300.0), (0.0, 310.0)],
                "points[1]",
                "strictly increasing",
            ),
            (
                vec![(0.0, 300.0), (0.01, 310.0), (0.005, 320.0)],
                "points[2]",
                "strictly increasing",
            ),
            (
                vec![(0.0, 300.0), (0.01, 290.0)],
                "points[1]",
                "non-decreasing",
            ),
            (
                vec![(0.0, 300.0), (f64::NAN, 290.0)],
                "points[1]",
                "not finite",
            ),
            (vec![(0.0, -3.0), (0.1, 290.0)], "points[0]", "[0, inf)"),
        ] {
            let text = Table::new(&pts).unwrap_err().to_string();
            assert!(text.contains(field) && text.contains(what), "{text}");
        }
    }
}
