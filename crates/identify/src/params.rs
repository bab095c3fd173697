//! Free and fixed parameters, box bounds (the paper's closed convex set Q, §3) and the
//! scaling that maps each free parameter `c_k` to an optimizer variable `y_k` of order
//! one, so that `E ~ 1e5 MPa` and `m ~ 5` are treated alike.
//!
//! Scalings (per free parameter, bounds `[lo, hi]`, start `c0`):
//!
//! | [`Scaling`] | `y(c)` | `c(y)` | `dc/dy` |
//! |---|---|---|---|
//! | `Log` | `ln c` | `exp y` | `c` |
//! | `Bounds` | `(c - lo) / (hi - lo)` | `lo + y (hi - lo)` | `hi - lo` |
//! | `Linear` | `c / |c0|` | `|c0| y` | `|c0|` |
//!
//! An instrument parameter (`Cf`, `vd`, `h0`; [`crate::instrument`]) that starts at 0 and
//! is linearly scaled takes its nominal scale ([`Instrument::nominal_scale`]) for `|c0|`.
//!
//! The box maps to a box in `y`. The optimizer's point is projected onto it before use,
//! `c = c(P(y))`, so `J(c(P(y)))` is defined everywhere; its gradient is
//! `dc/dy * dJ/dc` inside the box (and on its faces) and 0 along a coordinate that lies
//! strictly outside (the composite is flat there).

use indentify_laws::Material;

use crate::IdentifyError;
use crate::instrument::Instrument;

/// How a free parameter is scaled for the optimizer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Scaling {
    /// `y = ln c` (relative changes alike; needs `c > 0`). The default for parameters whose
    /// admissible range is positive.
    #[default]
    Log,
    /// `y = (c - lo) / (hi - lo)`, the box becomes `[0, 1]` (needs finite bounds).
    Bounds,
    /// `y = c / |c0|` with `c0` the start (needs `c0 != 0`).
    Linear,
}

/// One law parameter as the user configures it: fixed at a value, or free with a start,
/// optional bounds (default: the law's admissible range) and a scaling.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamSpec {
    /// Parameter name as in the law's metadata (`E`, `nu`, `eta`, `K`, `m`, `sY`).
    pub name: String,
    /// `true` to identify it, `false` to hold it at `value`.
    pub free: bool,
    /// Start (free) or value (fixed).
    pub value: Option<f64>,
    /// Lower bound (free only); `None` = the law's admissible minimum.
    pub lower: Option<f64>,
    /// Upper bound (free only); `None` = the law's admissible maximum.
    pub upper: Option<f64>,
    /// Scaling (free only).
    pub scaling: Scaling,
}

impl ParamSpec {
    /// A free parameter starting at `start` within `[lower, upper]`, log-scaled.
    pub fn free(name: &str, start: f64, lower: f64, upper: f64) -> ParamSpec {
        ParamSpec {
            name: name.into(),
            free: true,
            value: Some(start),
            lower: Some(lower),
            upper: Some(upper),
            scaling: Scaling::Log,
        }
    }

    /// A parameter held at `value`.
    pub fn fixed(name: &str, value: f64) -> ParamSpec {
        ParamSpec {
            name: name.into(),
            free: false,
            value: Some(value),
            lower: None,
            upper: None,
            scaling: Scaling::Log,
        }
    }

    /// The same spec with another scaling.
    pub fn with_scaling(mut self, scaling: Scaling) -> ParamSpec {
        self.scaling = scaling;
        self
    }
}

/// One free parameter, resolved.
#[derive(Clone, Debug, PartialEq)]
pub struct FreeParam {
    /// Index in the law's parameter vector.
    pub index: usize,
    /// Name.
    pub name: &'static str,
    /// Unit.
    pub unit: &'static str,
    /// Start value.
    pub start: f64,
    /// Lower bound (physical).
    pub lower: f64,
    /// Upper bound (physical).
    pub upper: f64,
    /// Scaling.
    pub scaling: Scaling,
    /// `|start|` (the `Linear` scale).
    scale: f64,
}

impl FreeParam {
    /// `y(c)`.
    pub fn to_scaled(&self, c: f64) -> f64 {
        match self.scaling {
            Scaling::Log => c.ln(),
            Scaling::Bounds => (c - self.lower) / (self.upper - self.lower),
            Scaling::Linear => c / self.scale,
        }
    }

    /// `c(y)` (no projection); the start's own `y` maps back to the start exactly.
    pub fn to_physical(&self, y: f64) -> f64 {
        if y.to_bits() == self.to_scaled(self.start).to_bits() {
            return self.start;
        }
        match self.scaling {
            Scaling::Log => y.exp(),
            Scaling::Bounds => self.lower + y * (self.upper - self.lower),
            Scaling::Linear => y * self.scale,
        }
    }

    /// `dc/dy` at physical value `c`.
    pub fn dc_dy(&self, c: f64) -> f64 {
        match self.scaling {
            Scaling::Log => c,
            Scaling::Bounds => self.upper - self.lower,
            Scaling::Linear => self.scale,
        }
    }

    /// Scaled bounds `(y(lo), y(hi))` (infinite where the physical bound is, or `-inf` for
    /// a log-scaled zero bound).
    pub fn scaled_bounds(&self) -> (f64, f64) {
        let f = |c: f64| {
            if c.is_infinite() {
                c
            } else if self.scaling == Scaling::Log && c <= 0.0 {
                f64::NEG_INFINITY
            } else {
                self.to_scaled(c)
            }
        };
        (f(self.lower), f(self.upper))
    }
}

/// The resolved map between the law's full parameter vector `c` and the optimizer's
/// free scaled vector `y`.
#[derive(Clone, Debug, PartialEq)]
pub struct Parameterization {
    /// Law name.
    pub law: &'static str,
    /// Full parameter vector with the fixed values and the starts of the free ones.
    pub base: Vec<f64>,
    /// Free parameters, in the law's order.
    pub free: Vec<FreeParam>,
}

impl Parameterization {
    /// Resolves `specs` against `law`: every law parameter must be given exactly once.
    ///
    /// # Errors
    /// [`IdentifyError::UnknownParameter`], [`IdentifyError::DuplicateParameter`],
    /// [`IdentifyError::MissingParameter`], [`IdentifyError::FixedWithoutValue`],
    /// [`IdentifyError::StartMissing`], [`IdentifyError::BoundsExclude`],
    /// [`IdentifyError::StartOutsideBounds`], [`IdentifyError::InvalidSpec`] (a bound
    /// outside the law's admissible range, a log scaling with a negative bound, a bounds
    /// scaling without finite bounds, a fixed value that the law does not admit),
    /// [`IdentifyError::NothingFree`].
    pub fn new(law: &dyn Material, specs: &[ParamSpec]) -> Result<Parameterization, IdentifyError> {
        let infos = law.params();
        let names = || infos.iter().map(|i| i.name).collect::<Vec<_>>().join(", ");
        let mut given: Vec<Option<&ParamSpec>> = vec![None; infos.len()];
        for s in specs {
            let k = infos.iter().position(|i| i.name == s.name).ok_or_else(|| {
                IdentifyError::UnknownParameter {
                    law: law.name(),
                    name: s.name.clone(),
                    expected: names(),
                }
            })?;
            if given[k].is_some() {
                return Err(IdentifyError::DuplicateParameter {
                    name: s.name.clone(),
                });
            }
            given[k] = Some(s);
        }
        let mut base = vec![0.0; infos.len()];
        let mut free = Vec::new();
        for (k, info) in infos.iter().enumerate() {
            let s = given[k].ok_or(IdentifyError::MissingParameter {
                law: law.name(),
                name: info.name,
            })?;
            let invalid = |why: String| IdentifyError::InvalidSpec {
                name: s.name.clone(),
                why,
            };
            if !s.free {
                let v = s.value.ok_or_else(|| IdentifyError::FixedWithoutValue {
                    name: s.name.clone(),
                })?;
                if !info.admits(v) {
                    return Err(invalid(format!(
                        "fixed value {v} is outside the admissible range {}",
                        info.range_text()
                    )));
                }
                base[k] = v;
                continue;
            }
            let start = s.value.ok_or_else(|| IdentifyError::StartMissing {
                name: s.name.clone(),
            })?;
            let lower = s.lower.unwrap_or(info.min);
            let upper = s.upper.unwrap_or(info.max);
            if lower.is_nan() || upper.is_nan() || lower > upper {
                return Err(IdentifyError::BoundsExclude {
                    name: s.name.clone(),
                    lower,
                    upper,
                });
            }
            if lower < info.min || upper > info.max {
                return Err(invalid(format!(
                    "bounds [{lower}, {upper}] reach outside the admissible range {}",
                    info.range_text()
                )));
            }
            if !start.is_finite() || start < lower || start > upper {
                return Err(IdentifyError::StartOutsideBounds {
                    name: s.name.clone(),
                    value: start,
                    lower,
                    upper,
                });
            }
            match s.scaling {
                Scaling::Log if lower < 0.0 || start <= 0.0 => {
                    return Err(invalid(format!(
                        "log scaling needs positive values, but the box is [{lower}, {upper}] and the start {start}"
                    )));
                }
                Scaling::Bounds if !(lower.is_finite() && upper.is_finite() && upper > lower) => {
                    return Err(invalid(format!(
                        "bounds scaling needs finite bounds lower < upper, got [{lower}, {upper}]"
                    )));
                }
                Scaling::Linear
                    if start == 0.0 && Instrument::nominal_scale(info.name).is_none() =>
                {
                    return Err(invalid(
                        "linear scaling divides by the start, which is 0".into(),
                    ));
                }
                _ => {}
            }
            base[k] = start;
            free.push(FreeParam {
                index: k,
                name: info.name,
                unit: info.unit,
                start,
                lower,
                upper,
                scaling: s.scaling,
                scale: if start == 0.0 {
                    Instrument::nominal_scale(info.name).unwrap_or(0.0)
                } else {
                    start.abs()
                },
            });
        }
        if free.is_empty() {
            return Err(IdentifyError::NothingFree);
        }
        Ok(Parameterization {
            law: law.name(),
            base,
            free,
        })
    }

    /// Number of free parameters.
    pub fn n_free(&self) -> usize {
        self.free.len()
    }

    /// Names of the free parameters.
    pub fn free_names(&self) -> Vec<&'static str> {
        self.free.iter().map(|f| f.name).collect()
    }

    /// The free values of a full vector.
    pub fn free_values(&self, c: &[f64]) -> Vec<f64> {
        self.free.iter().map(|f| c[f.index]).collect()
    }

    /// Full vector with the free values replaced by `values` (free order).
    pub fn with_free_values(&self, values: &[f64]) -> Vec<f64> {
        let mut c = self.base.clone();
        for (f, &v) in self.free.iter().zip(values) {
            c[f.index] = v;
        }
        c
    }

    /// Scaled vector `y` of a full physical vector.
    pub fn to_scaled(&self, c: &[f64]) -> Vec<f64> {
        self.free.iter().map(|f| f.to_scaled(c[f.index])).collect()
    }

    /// Scaled box `(lower, upper)`.
    pub fn scaled_bounds(&self) -> (Vec<f64>, Vec<f64>) {
        self.free.iter().map(|f| f.scaled_bounds()).unzip()
    }

    /// Projection of `y` onto the scaled box.
    pub fn project(&self, y: &[f64]) -> Vec<f64> {
        self.free
            .iter()
            .zip(y)
            .map(|(f, &v)| {
                let (lo, hi) = f.scaled_bounds();
                v.clamp(lo, hi)
            })
            .collect()
    }

    /// Full physical vector `c(P(y))`; a coordinate on or beyond a face of the box maps to
    /// the physical bound exactly (a round trip through `exp`/`ln` would miss it by an ulp).
    pub fn to_physical(&self, y: &[f64]) -> Vec<f64> {
        let mut c = self.base.clone();
        for (f, &v) in self.free.iter().zip(y) {
            let (lo, hi) = f.scaled_bounds();
            c[f.index] = if v >= hi {
                f.upper
            } else if v <= lo {
                f.lower
            } else {
                f.to_physical(v).clamp(f.lower, f.upper)
            };
        }
        c
    }

    /// Gradient with respect to `y` of `J(c(P(y)))` from the full physical gradient
    /// `dJ/dc` at `c = c(P(y))`: `dc_k/dy_k dJ/dc_k`, and 0 for coordinates strictly
    /// outside the box.
    pub fn scaled_gradient(&self, y: &[f64], c: &[f64], dj_dc: &[f64]) -> Vec<f64> {
        self.free
            .iter()
            .zip(y)
            .map(|(f, &v)| {
                let (lo, hi) = f.scaled_bounds();
                if v < lo || v > hi {
                    0.0
                } else {
                    f.dc_dy(c[f.index]) * dj_dc[f.index]
                }
            })
            .collect()
    }

    /// Projected gradient in scaled coordinates at a point `y` inside the box: components
    /// that push out of the box through an active face are zeroed (the first-order
    /// optimality measure of a box-constrained problem).
    pub fn projected_gradient(&self, y: &[f64], g: &[f64]) -> Vec<f64> {
        self.free
            .iter()
            .zip(y.iter().zip(g))
            .map(|(f, (&v, &gk))| {
                let (lo, hi) = f.scaled_bounds();
                if (v <= lo && gk > 0.0) || (v >= hi && gk < 0.0) {
                    0.0
                } else {
                    gk
                }
            })
            .collect()
    }

    /// Checks that the free values of `c` lie in their bounds (for a resume point).
    ///
    /// # Errors
    /// [`IdentifyError::StartOutsideBounds`].
    pub fn check_inside(&self, c: &[f64]) -> Result<(), IdentifyError> {
        for f in &self.free {
            let v = c[f.index];
            if !v.is_finite() || v < f.lower || v > f.upper {
                return Err(IdentifyError::StartOutsideBounds {
                    name: f.name.into(),
                    value: v,
                    lower: f.lower,
                    upper: f.upper,
                });
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use indentify_laws::{LawMaterial, Maxwell, NortonHoff};

    fn maxwell_specs() -> Vec<ParamSpec> {
        vec![
            ParamSpec::free("E", 4000.0, 1000.0, 1e6),
            ParamSpec::fixed("nu", 0.3),
            ParamSpec::free("eta", 70000.0, 1000.0, 1e7),
        ]
    }

    #[test]
    fn scalings_round_trip_and_differentiate() {
        for scaling in [Scaling::Log, Scaling::Bounds, Scaling::Linear] {
            let specs: Vec<ParamSpec> = maxwell_specs()
                .into_iter()
                .map(|s| s.with_scaling(scaling))
                .collect();
            let p = Parameterization::new(&LawMaterial(&Maxwell), &specs).unwrap();
            let c = vec![20000.0, 0.3, 30000.0];
            let y = p.to_scaled(&c);
            let back = p.to_physical(&y);
            for k in [0, 2] {
                assert!((back[k] - c[k]).abs() <= 1e-12 * c[k], "{scaling:?}");
            }
            assert_eq!(back[1], 0.3);
            // dc/dy by central differences
            for (j, f) in p.free.iter().enumerate() {
                let h = 1e-6;
                let mut yp = y.clone();
                yp[j] += h;
                let mut ym = y.clone();
                ym[j] -= h;
                let fd = (p.to_physical(&yp)[f.index] - p.to_physical(&ym)[f.index]) / (2.0 * h);
                let an = f.dc_dy(c[f.index]);
                assert!((fd - an).abs() <= 1e-6 * an.abs(), "{scaling:?} {fd} {an}");
            }
        }
    }

    /// Log scaling shall put E ~ 1e5 and m ~ 5 on the same footing: a unit step in y is
    /// the same relative change for both.
    #[test]
    fn log_scaling_makes_relative_steps_alike() {
        let specs = vec![
            ParamSpec::free("E", 1e5, 1e3, 1e7),
            ParamSpec::fixed("nu", 0.3),
            ParamSpec::free("K", 1500.0, 1.0, 1e5),
            ParamSpec::free("m", 5.0, 1.1, 20.0),
            ParamSpec::free("sY", 500.0, 1.0, 5000.0),
        ];
        let p = Parameterization::new(&LawMaterial(&NortonHoff), &specs).unwrap();
        let y = p.to_scaled(&p.base);
        let y1: Vec<f64> = y.iter().map(|v| v + 0.1).collect();
        let c1 = p.to_physical(&y1);
        for f in &p.free {
            let ratio = c1[f.index] / p.base[f.index];
            assert!((ratio - 0.1f64.exp()).abs() < 1e-12, "{}", f.name);
        }
    }

    #[test]
    fn projection_clamps_to_the_box_and_zeroes_outside_gradients() {
        let p = Parameterization::new(&LawMaterial(&Maxwell), &maxwell_specs()).unwrap();
        let y = vec![(2e6f64).ln(), (5e4f64).ln()];
        let c = p.to_physical(&y);
        assert_eq!(c[0], 1e6);
        assert!((c[2] - 5e4).abs() < 1e-8);
        let g = p.scaled_gradient(&y, &c, &[1.0, 1.0, 1.0]);
        assert_eq!(g[0], 0.0);
        assert!((g[1] - c[2]).abs() < 1e-9);
    }

    #[test]
    fn bad_specs_are_rejected_with_clear_errors() {
        let mut s = maxwell_specs();
        s[0].value = Some(500.0);
        let e = Parameterization::new(&LawMaterial(&Maxwell), &s).unwrap_err();
        assert!(matches!(e, IdentifyError::StartOutsideBounds { .. }), "{e}");
        assert!(e.to_string().contains("outside its bounds"), "{e}");

        let mut s = maxwell_specs();
        s[0].lower = Some(5e6);
        let e = Parameterization::new(&LawMaterial(&Maxwell), &s).unwrap_err();
        assert!(matches!(e, IdentifyError::BoundsExclude { .. }), "{e}");
        assert!(e.to_string().contains("exclude each other"), "{e}");

        let mut s = maxwell_specs();
        s[1].value = None;
        let e = Parameterization::new(&LawMaterial(&Maxwell), &s).unwrap_err();
        assert!(matches!(e, IdentifyError::FixedWithoutValue { .. }), "{e}");
        assert_eq!(e.to_string(), "parameter `nu` is fixed but has no value");

        let mut s = maxwell_specs();
        s.pop();
        let e = Parameterization::new(&LawMaterial(&Maxwell), &s).unwrap_err();
        assert!(
            matches!(e, IdentifyError::MissingParameter { name: "eta", .. }),
            "{e}"
        );

        let mut s = maxwell_specs();
        s[2].name = "viscosity".into();
        let e = Parameterization::new(&LawMaterial(&Maxwell), &s).unwrap_err();
        assert!(e.to_string().contains("E, nu, eta"), "{e}");

        let s = vec![
            ParamSpec::fixed("E", 1.0),
            ParamSpec::fixed("nu", 0.3),
            ParamSpec::fixed("eta", 1.0),
        ];
        let e = Parameterization::new(&LawMaterial(&Maxwell), &s).unwrap_err();
        assert!(matches!(e, IdentifyError::NothingFree), "{e}");

        let mut s = maxwell_specs();
        s[0] = ParamSpec::free("E", 4000.0, 1000.0, f64::INFINITY).with_scaling(Scaling::Bounds);
        let e = Parameterization::new(&LawMaterial(&Maxwell), &s).unwrap_err();
        assert!(e.to_string().contains("finite bounds"), "{e}");
    }
}
