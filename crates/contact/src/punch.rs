//! Rigid axisymmetric punch profiles `phi(r)`: the height of the punch surface above its
//! tip at radius r (mm). The gap at a surface node is `phi(r) - U - u_z`.

use serde::{Deserialize, Serialize};

use crate::ContactError;

/// A rigid, frictionless, axisymmetric punch. Angles are half-angles measured from the
/// axis (a Berkovich-equivalent cone is 70.3 deg); lengths in mm.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Punch {
    /// Cone of half-angle `half_angle_deg` from the axis: `phi = r / tan(alpha)`.
    Cone {
        /// Half-angle from the axis, in (0, 90) degrees.
        half_angle_deg: f64,
    },
    /// Sphere of radius `radius`, exact profile `R - sqrt(R^2 - r^2)` (not the paraboloid);
    /// beyond r = R the punch is a vertical wall (infinite `phi`).
    Sphere {
        /// Radius (mm), > 0.
        radius: f64,
    },
    /// Flat-ended cylinder of radius `radius`: `phi = 0` for `r <= R`, infinite beyond.
    Flat {
        /// Radius (mm), > 0.
        radius: f64,
    },
    /// Spherical tip of radius `radius` blended tangentially into a cone of half-angle
    /// `half_angle_deg` at `r_t = R cos(alpha)`.
    SpheroCone {
        /// Tip radius (mm), > 0.
        radius: f64,
        /// Cone half-angle from the axis, in (0, 90) degrees.
        half_angle_deg: f64,
    },
    /// Tabulated profile: heights `z` (mm, >= 0, from 0 at `r = 0`) at increasing radii `r`
    /// (mm, from 0), interpolated linearly and extrapolated with the last slope.
    Tabulated {
        /// Radii, strictly increasing, starting at 0.
        r: Vec<f64>,
        /// Heights above the tip, starting at 0, non-decreasing.
        z: Vec<f64>,
    },
}

fn check_angle(field: &'static str, a: f64) -> Result<(), ContactError> {
    if a.is_finite() && a > 0.0 && a < 90.0 {
        Ok(())
    } else {
        Err(ContactError::Input {
            field,
            value: a.to_string(),
            allowed: "an angle in (0, 90) degrees".into(),
        })
    }
}

fn check_positive(field: &'static str, v: f64) -> Result<(), ContactError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(ContactError::Input {
            field,
            value: v.to_string(),
            allowed: "a finite length > 0 (mm)".into(),
        })
    }
}

impl Punch {
    /// Checks the geometric inputs.
    ///
    /// # Errors
    /// [`ContactError::Input`] naming the field (`punch.<field>`), value and range.
    pub fn validate(&self) -> Result<(), ContactError> {
        match self {
            Punch::Cone { half_angle_deg } => check_angle("punch.half_angle_deg", *half_angle_deg),
            Punch::Sphere { radius } | Punch::Flat { radius } => {
                check_positive("punch.radius", *radius)
            }
            Punch::SpheroCone {
                radius,
                half_angle_deg,
            } => {
                check_positive("punch.radius", *radius)?;
                check_angle("punch.half_angle_deg", *half_angle_deg)
            }
            Punch::Tabulated { r, z } => {
                if r.len() != z.len() || r.len() < 2 {
                    return Err(ContactError::Input {
                        field: "punch.r",
                        value: format!("{} radii and {} heights", r.len(), z.len()),
                        allowed: "at least 2 points, as many radii as heights".into(),
                    });
                }
                if r[0] != 0.0 || z[0] != 0.0 {
                    return Err(ContactError::Input {
                        field: "punch.r",
                        value: format!("first point ({}, {})", r[0], z[0]),
                        allowed: "a first point at r = 0, z = 0 (the tip)".into(),
                    });
                }
                for i in 1..r.len() {
                    if !(r[i] > r[i - 1]) || !r[i].is_finite() {
                        return Err(ContactError::Input {
                            field: "punch.r",
                            value: format!("r[{i}] = {} after r[{}] = {}", r[i], i - 1, r[i - 1]),
                            allowed: "strictly increasing finite radii".into(),
                        });
                    }
                    if !(z[i] >= z[i - 1]) || !z[i].is_finite() {
                        return Err(ContactError::Input {
                            field: "punch.z",
                            value: format!("z[{i}] = {} after z[{}] = {}", z[i], i - 1, z[i - 1]),
                            allowed: "non-decreasing finite heights".into(),
                        });
                    }
                }
                Ok(())
            }
        }
    }

    /// Profile `phi(r)` (mm): height of the punch surface above the tip at radius `r >= 0`.
    /// Infinite where the punch has no surface (beyond a flat punch or a sphere).
    pub fn profile(&self, r: f64) -> f64 {
        match self {
            Punch::Cone { half_angle_deg } => r / half_angle_deg.to_radians().tan(),
            Punch::Sphere { radius } => {
                if r <= *radius {
                    radius - (radius * radius - r * r).sqrt()
                } else {
                    f64::INFINITY
                }
            }
            Punch::Flat { radius } => {
                if r <= *radius * (1.0 + 1e-12) {
                    0.0
                } else {
                    f64::INFINITY
                }
            }
            Punch::SpheroCone {
                radius,
                half_angle_deg,
            } => {
                let a = half_angle_deg.to_radians();
                let rt = radius * a.cos();
                if r <= rt {
                    radius - (radius * radius - r * r).sqrt()
                } else {
                    let zt = radius - (radius * radius - rt * rt).sqrt();
                    zt + (r - rt) / a.tan()
                }
            }
            Punch::Tabulated { r: rs, z } => {
                let n = rs.len();
                let i = match rs.partition_point(|&x| x <= r) {
                    0 => 0,
                    k if k >= n => n - 2,
                    k => k - 1,
                };
                z[i] + (z[i + 1] - z[i]) * (r - rs[i]) / (rs[i + 1] - rs[i])
            }
        }
    }

    /// Short description for reports, e.g. `cone (half-angle 68 deg)`.
    pub fn describe(&self) -> String {
        match self {
            Punch::Cone { half_angle_deg } => format!("cone (half-angle {half_angle_deg} deg)"),
            Punch::Sphere { radius } => format!("sphere (R = {radius} mm)"),
            Punch::Flat { radius } => format!("flat cylinder (R = {radius} mm)"),
            Punch::SpheroCone {
                radius,
                half_angle_deg,
            } => {
                format!("sphero-cone (tip R = {radius} mm, half-angle {half_angle_deg} deg)")
            }
            Punch::Tabulated { r, .. } => format!("tabulated ({} points)", r.len()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cone_profile_is_linear() {
        let p = Punch::Cone {
            half_angle_deg: 45.0,
        };
        assert!((p.profile(0.3) - 0.3).abs() < 1e-15);
    }

    #[test]
    fn sphere_profile_is_exact_not_parabolic() {
        let p = Punch::Sphere { radius: 1.0 };
        let r: f64 = 0.6;
        assert!((p.profile(r) - 0.2).abs() < 1e-15);
        assert!((p.profile(r) - r * r / 2.0).abs() > 0.01);
        assert!(p.profile(1.5).is_infinite());
    }

    #[test]
    fn sphero_cone_is_continuous_with_continuous_slope() {
        let (rad, alpha) = (0.5, 60.0_f64);
        let p = Punch::SpheroCone {
            radius: rad,
            half_angle_deg: alpha,
        };
        let rt = rad * alpha.to_radians().cos();
        let h = 1e-7;
        let (a, b) = (p.profile(rt - h), p.profile(rt + h));
        assert!((a - b).abs() < 1e-6);
        let slope_in = (p.profile(rt - h) - p.profile(rt - 2.0 * h)) / h;
        let slope_out = (p.profile(rt + 2.0 * h) - p.profile(rt + h)) / h;
        assert!(
            (slope_in - slope_out).abs() < 1e-4,
            "{slope_in} {slope_out}"
        );
        assert!((slope_out - 1.0 / alpha.to_radians().tan()).abs() < 1e-6);
    }

    #[test]
    fn tabulated_interpolates_and_extrapolates() {
        let p = Punch::Tabulated {
            r: vec![0.0, 1.0, 2.0],
            z: vec![0.0, 1.0, 3.0],
        };
        p.validate().unwrap();
        assert!((p.profile(0.5) - 0.5).abs() < 1e-15);
        assert!((p.profile(1.5) - 2.0).abs() < 1e-15);
        assert!((p.profile(3.0) - 5.0).abs() < 1e-15);
        let bad = Punch::Tabulated {
            r: vec![0.0, 1.0, 1.0],
            z: vec![0.0, 1.0, 3.0],
        };
        assert!(bad.validate().unwrap_err().to_string().contains("punch.r"));
    }

    #[test]
    fn invalid_angles_are_rejected() {
        let e = Punch::Cone {
            half_angle_deg: 95.0,
        }
        .validate()
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("punch.half_angle_deg") && e.contains("95"),
            "{e}"
        );
    }
}
