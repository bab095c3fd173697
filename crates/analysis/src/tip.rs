//! The indenter: its projected-area function `A(h_c)`, its elastic constants, the
//! geometric factor `epsilon` of the contact depth, and what a calibration adds (frame
//! compliance, an equivalent tip radius). Serialized as the tip file (`TIP.ron`).

use serde::{Deserialize, Serialize};

use crate::error::AnalysisError;

/// Young's modulus of diamond, MPa (1141 GPa; Oliver and Pharr 1992, ISO 14577-1).
pub const DIAMOND_MODULUS: f64 = 1_141_000.0;
/// Poisson's ratio of diamond (0.07; Oliver and Pharr 1992, ISO 14577-1).
pub const DIAMOND_POISSON: f64 = 0.07;
/// The area coefficient of an ideal Berkovich (and Vickers) pyramid, `A = 24.5 h_c^2`
/// (ISO 14577-1: 24.50 for the Berkovich face angle 65.27 deg).
pub const BERKOVICH_C0: f64 = 24.5;

/// Projected contact area `A(h_c)` as a function of the contact depth (h_c in mm, A in mm^2).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum AreaFunction {
    /// Ideal Berkovich (or Vickers) pyramid: `A = 24.5 h_c^2`.
    Berkovich,
    /// Cone of the given half-angle (degrees): `A = pi tan^2(theta) h_c^2`.
    Cone {
        /// Half-angle, degrees (0 < theta < 90).
        half_angle_deg: f64,
    },
    /// Sphere of radius R (mm): `A = pi (2 R h_c - h_c^2)` for `h_c <= R`.
    Sphere {
        /// Radius, mm.
        radius: f64,
    },
    /// Flat cylindrical punch of radius R (mm): `A = pi R^2` at any depth.
    Flat {
        /// Radius, mm.
        radius: f64,
    },
    /// The ISO 14577 polynomial `A = C0 h_c^2 + C1 h_c + C2 h_c^(1/2) + C3 h_c^(1/4) + ...`
    /// (h_c in mm, A in mm^2: C0 dimensionless, C1 in mm, C2 in mm^(3/2), ...).
    Iso {
        /// `C0, C1, C2, ...` in mm-based units.
        coefficients: Vec<f64>,
    },
}

impl AreaFunction {
    /// `A(h_c)`, mm^2 (NaN for a negative depth, or a sphere deeper than its radius).
    pub fn area(&self, hc: f64) -> f64 {
        if !(hc >= 0.0) {
            return f64::NAN;
        }
        match self {
            AreaFunction::Berkovich => BERKOVICH_C0 * hc * hc,
            AreaFunction::Cone { half_angle_deg } => {
                let t = half_angle_deg.to_radians().tan();
                std::f64::consts::PI * t * t * hc * hc
            }
            AreaFunction::Sphere { radius } => {
                if hc > *radius {
                    f64::NAN
                } else {
                    std::f64::consts::PI * (2.0 * radius * hc - hc * hc)
                }
            }
            AreaFunction::Flat { radius } => std::f64::consts::PI * radius * radius,
            AreaFunction::Iso { coefficients } => coefficients
                .iter()
                .enumerate()
                .map(|(k, c)| c * iso_power(hc, k))
                .sum(),
        }
    }

    /// The geometric `epsilon` of `h_c = h_max - epsilon F_max / S` for this shape
    /// (Oliver and Pharr 1992): 0.75 for the Berkovich pyramid and the calibrated polynomial
    /// (their empirical value) and for a sphere (paraboloid of revolution), `2 (pi - 2) / pi`
    /// = 0.7268 for a cone (Sneddon), 1 for a flat punch.
    pub fn epsilon(&self) -> f64 {
        match self {
            AreaFunction::Cone { .. } => 2.0 * (std::f64::consts::PI - 2.0) / std::f64::consts::PI,
            AreaFunction::Flat { .. } => 1.0,
            AreaFunction::Berkovich | AreaFunction::Sphere { .. } | AreaFunction::Iso { .. } => {
                0.75
            }
        }
    }

    /// In words, with units (nm for lengths).
    pub fn describe(&self) -> String {
        match self {
            AreaFunction::Berkovich => "ideal Berkovich, A = 24.5 hc^2".into(),
            AreaFunction::Cone { half_angle_deg } => {
                format!("cone of half-angle {half_angle_deg} deg, A = pi tan^2(theta) hc^2")
            }
            AreaFunction::Sphere { radius } => format!(
                "sphere of radius {} um, A = pi (2 R hc - hc^2)",
                radius * 1e3
            ),
            AreaFunction::Flat { radius } => {
                format!("flat punch of radius {} um, A = pi R^2", radius * 1e3)
            }
            AreaFunction::Iso { coefficients } => {
                let terms: Vec<String> = coefficients
                    .iter()
                    .enumerate()
                    .map(|(k, c)| {
                        // the coefficient in nm units: C_k [mm^(2 - p)] * 1e6^(2 - p) with p the power
                        let p = iso_exponent(k);
                        format!("{:.6e} hc^{}", c * 1e6f64.powf(2.0 - p), exponent_text(k))
                    })
                    .collect();
                format!(
                    "ISO polynomial, A [nm^2] = {} (hc in nm)",
                    terms.join(" + ")
                )
            }
        }
    }

    /// Checks the shape's parameters.
    ///
    /// # Errors
    /// [`AnalysisError::Option`] naming the parameter and its allowed range.
    pub fn validate(&self) -> Result<(), AnalysisError> {
        let bad = |field: &str, v: f64, expected: &str| {
            Err(AnalysisError::Option {
                field: field.to_owned(),
                value: v.to_string(),
                expected: expected.to_owned(),
            })
        };
        match self {
            AreaFunction::Berkovich => Ok(()),
            AreaFunction::Cone { half_angle_deg: a } => {
                if *a > 0.0 && *a < 90.0 {
                    Ok(())
                } else {
                    bad("tip.area.half_angle_deg", *a, "0 < angle < 90 degrees")
                }
            }
            AreaFunction::Sphere { radius: r } | AreaFunction::Flat { radius: r } => {
                if *r > 0.0 && r.is_finite() {
                    Ok(())
                } else {
                    bad("tip.area.radius", *r, "a finite radius > 0 (mm)")
                }
            }
            AreaFunction::Iso { coefficients } => {
                if coefficients.is_empty() {
                    return Err(AnalysisError::Option {
                        field: "tip.area.coefficients".into(),
                        value: "[]".into(),
                        expected: "at least C0".into(),
                    });
                }
                for (k, c) in coefficients.iter().enumerate() {
                    if !c.is_finite() {
                        return bad(
                            &format!("tip.area.coefficients[{k}]"),
                            *c,
                            "a finite number",
                        );
                    }
                }
                if !(coefficients[0] > 0.0) {
                    return bad("tip.area.coefficients[0]", coefficients[0], "C0 > 0");
                }
                Ok(())
            }
        }
    }
}

/// The exponent of the k-th ISO term: 2, 1, 1/2, 1/4, ...
pub fn iso_exponent(k: usize) -> f64 {
    2.0f64.powi(1 - k as i32)
}

fn iso_power(h: f64, k: usize) -> f64 {
    match k {
        0 => h * h,
        1 => h,
        2 => h.sqrt(),
        _ => h.powf(iso_exponent(k)),
    }
}

fn exponent_text(k: usize) -> String {
    match k {
        0 => "2".into(),
        1 => "1".into(),
        _ => format!("(1/{})", 1u64 << (k - 1)),
    }
}

/// An indenter, as given on the command line or read from a tip file (`TIP.ron`):
///
/// ```ron
/// (
///     name: "Berkovich calibrated on fused silica",
///     area: Iso(coefficients: [24.1, 1.2e-4, 3.0e-7]),  // mm-based units
///     modulus: 1141000.0,                                // MPa
///     poisson: 0.07,
///     frame_compliance: Some(4.1e-4),                     // mm/N
///     radius: Some(2.0e-4),                               // mm
/// )
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Tip {
    /// Name, for the report.
    #[serde(default)]
    pub name: String,
    /// The area function.
    pub area: AreaFunction,
    /// Young's modulus of the tip, MPa (diamond 1141000 by default).
    #[serde(default = "diamond_modulus")]
    pub modulus: f64,
    /// Poisson's ratio of the tip (diamond 0.07 by default).
    #[serde(default = "diamond_poisson")]
    pub poisson: f64,
    /// Frame (load-frame) compliance, mm/N, applied to the depth before the analysis
    /// (`h <- h - C F`); `None`: the file's own correction, or none.
    #[serde(default)]
    pub frame_compliance: Option<f64>,
    /// Equivalent tip radius, mm (a calibration's estimate; informative).
    #[serde(default)]
    pub radius: Option<f64>,
}

fn diamond_modulus() -> f64 {
    DIAMOND_MODULUS
}
fn diamond_poisson() -> f64 {
    DIAMOND_POISSON
}

impl Tip {
    /// A diamond tip of the given shape, no frame compliance.
    pub fn diamond(area: AreaFunction) -> Tip {
        Tip {
            name: area.describe(),
            area,
            modulus: DIAMOND_MODULUS,
            poisson: DIAMOND_POISSON,
            frame_compliance: None,
            radius: None,
        }
    }

    /// The ideal diamond Berkovich.
    pub fn berkovich() -> Tip {
        Tip::diamond(AreaFunction::Berkovich)
    }

    /// Checks the tip's values.
    ///
    /// # Errors
    /// [`AnalysisError::Option`] naming the field and its allowed range.
    pub fn validate(&self) -> Result<(), AnalysisError> {
        self.area.validate()?;
        if !(self.modulus > 0.0) || self.modulus.is_nan() {
            return Err(AnalysisError::Option {
                field: "tip.modulus".into(),
                value: self.modulus.to_string(),
                expected: "a modulus > 0 (MPa; infinite for a rigid tip)".into(),
            });
        }
        if !(self.poisson > -1.0 && self.poisson < 0.5) {
            return Err(AnalysisError::Option {
                field: "tip.poisson".into(),
                value: self.poisson.to_string(),
                expected: "-1 < nu < 0.5".into(),
            });
        }
        if let Some(c) = self.frame_compliance {
            if !(c >= 0.0 && c.is_finite()) {
                return Err(AnalysisError::Option {
                    field: "tip.frame_compliance".into(),
                    value: c.to_string(),
                    expected: "a finite compliance >= 0 (mm/N)".into(),
                });
            }
        }
        Ok(())
    }

    /// The tip's share `(1 - nu_i^2) / E_i` of `1 / E_r`, 1/MPa.
    pub fn compliance_share(&self) -> f64 {
        (1.0 - self.poisson * self.poisson) / self.modulus
    }
}
