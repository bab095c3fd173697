//! Rigid axisymmetric punch profiles `phi(r)`: the height of the punch surface above its
//! tip at radius r (mm). The gap at a surface node is `phi(r) - U - u_z` with vertical
//! contact ([`crate::ContactKind::Vertical`]); normal contact measures the displaced
//! node's distance along the surface normal ([`crate::normal::Surface`]). Instrument tips
//! (Berkovich, Vickers, cube corner) are their area-equivalent cones; [`specimen`] sizes
//! and meshes the specimen from the punch and the maximum depth.
//!
//! # Area-equivalent cones
//!
//! A pyramid is replaced by the cone with the same projected contact area at every depth
//! h (the same area function `A(h)`, hence the same hardness and, to first order, the same
//! load-depth curve). A cone of half-angle theta has `A = pi tan^2(theta) h^2`:
//!
//! - Berkovich (three faces at 65.27 deg from the axis): `A = 3 sqrt(3) tan^2(65.27 deg) h^2
//!   = 24.5 h^2`; Vickers (four faces at 68 deg): `A = 4 tan^2(68 deg) h^2 = 24.5 h^2`;
//!   `pi tan^2(theta) = 24.5` gives `theta = atan(sqrt(24.5 / pi)) = 70.30 deg`
//!   ([`BERKOVICH_HALF_ANGLE_DEG`], [`VICKERS_HALF_ANGLE_DEG`]).
//! - Cube corner (three faces at 35.26 deg): `A = 2.598 h^2`, `theta = 42.28 deg`
//!   ([`CUBE_CORNER_HALF_ANGLE_DEG`]).
//!
//! A worn tip is a sphere of radius `tip_radius` blended tangentially into that cone
//! (a [`Punch::SpheroCone`]).
//!
//! A flat punch's rim is a singular point of the solution: [`rim::treat_rim`] puts
//! quarter-point elements around it.
//!
//! A calibrated tip ([`Punch::Calibrated`]) is the axisymmetric profile with the projected
//! area of a calibrated area function at every depth ([`calibrated`]).

pub mod calibrated;
pub mod rim;
pub mod specimen;

use serde::{Deserialize, Serialize};

use crate::ContactError;

pub use calibrated::AreaProfile;
pub use rim::{Rim, treat_rim};
pub use specimen::{AutoOptions, auto_specimen};

/// Half-angle (deg, from the axis) of the cone area-equivalent to a Berkovich pyramid:
/// `pi tan^2(theta) = 24.5`.
pub const BERKOVICH_HALF_ANGLE_DEG: f64 = 70.3;
/// Half-angle (deg) of the cone area-equivalent to a Vickers pyramid (`A = 24.5 h^2`,
/// as Berkovich).
pub const VICKERS_HALF_ANGLE_DEG: f64 = 70.3;
/// Half-angle (deg) of the cone area-equivalent to a cube-corner pyramid (`A = 2.598 h^2`).
pub const CUBE_CORNER_HALF_ANGLE_DEG: f64 = 42.28;
/// Pile-up allowance of [`Punch::contact_radius_bound`]: the contact radius is bounded by
/// this factor times the radius where the undeformed profile meets the depth h. Elastic
/// sink-in gives a factor 2/pi = 0.64 (cone) or 1/sqrt(2) = 0.71 (sphere, small depth);
/// piling-up elastoplastic solids (low hardening, large E/sY) reach a contact depth
/// `h_c` of about 1.2 h (Bolshakov & Pharr, J. Mater. Res. 13, 1998), hence 1.2 on the
/// radius of a cone.
pub const PILE_UP_ALLOWANCE: f64 = 1.2;

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
    /// Flat-ended cylinder of radius `radius`: `phi = 0` for `r <= R` (to a relative 1e-9),
    /// infinite beyond.
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
    /// Berkovich pyramid as its area-equivalent cone of half-angle
    /// [`BERKOVICH_HALF_ANGLE_DEG`] (70.3 deg), sharp or with a rounded tip. Config:
    /// `Berkovich()` or `Berkovich(tip_radius: 2e-4)`.
    Berkovich {
        /// Tip radius (mm), >= 0 (absent or 0 = sharp): a sphere blended tangentially into
        /// the cone, as [`Punch::SpheroCone`].
        #[serde(default, skip_serializing_if = "Option::is_none")]
        tip_radius: Option<f64>,
    },
    /// Vickers pyramid as its area-equivalent cone of half-angle [`VICKERS_HALF_ANGLE_DEG`]
    /// (70.3 deg), sharp or with a rounded tip. Config: `Vickers()`,
    /// `Vickers(tip_radius: 5e-4)`.
    Vickers {
        /// Tip radius (mm), >= 0 (absent or 0 = sharp).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        tip_radius: Option<f64>,
    },
    /// Cube-corner pyramid as its area-equivalent cone of half-angle
    /// [`CUBE_CORNER_HALF_ANGLE_DEG`] (42.28 deg), sharp or with a rounded tip. Config:
    /// `CubeCorner()`, `CubeCorner(tip_radius: 5e-5)`.
    CubeCorner {
        /// Tip radius (mm), >= 0 (absent or 0 = sharp).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        tip_radius: Option<f64>,
    },
    /// Tabulated profile: heights `z` (mm, >= 0, from 0 at `r = 0`) at increasing radii `r`
    /// (mm, from 0), interpolated linearly and extrapolated with the last slope.
    Tabulated {
        /// Radii, strictly increasing, starting at 0.
        r: Vec<f64>,
        /// Heights above the tip, starting at 0, non-decreasing.
        z: Vec<f64>,
    },
    /// A calibrated tip: the axisymmetric profile with the projected area of the tip
    /// file's area function at every depth ([`calibrated`]). Config:
    /// `Calibrated(file: "TIP.ron")`, the tip file of `indentify calibrate`, relative to the
    /// configuration's folder. The application reads the file into `area` before a model
    /// is built ([`Punch::calibrated`]); until then the punch has no profile.
    Calibrated {
        /// The tip file, as the configuration names it.
        file: String,
        /// Its area function (not part of the configuration).
        #[serde(skip)]
        area: Option<AreaProfile>,
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
    /// The calibrated tip of `file` with the area function `area` (read from that file).
    pub fn calibrated(file: impl Into<String>, area: AreaProfile) -> Punch {
        Punch::Calibrated {
            file: file.into(),
            area: Some(area),
        }
    }

    /// The area function of a calibrated tip whose file has been read.
    ///
    /// # Errors
    /// [`ContactError::Input`] naming `punch.file` for a calibrated tip whose file has not
    /// been read (a model needs its profile).
    pub fn require_profile(&self) -> Result<(), ContactError> {
        match self {
            Punch::Calibrated { file, area: None } => Err(ContactError::Input {
                field: "punch.file",
                value: format!("`{file}` (not read)"),
                allowed: "a calibrated tip whose tip file the application has read \
                          (Punch::calibrated)"
                    .into(),
            }),
            _ => Ok(()),
        }
    }

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
            Punch::Berkovich { tip_radius }
            | Punch::Vickers { tip_radius }
            | Punch::CubeCorner { tip_radius } => match tip_radius {
                Some(t) if !(t.is_finite() && *t >= 0.0) => Err(ContactError::Input {
                    field: "punch.tip_radius",
                    value: t.to_string(),
                    allowed: "a finite tip radius >= 0 (mm; 0 or absent = sharp)".into(),
                }),
                _ => Ok(()),
            },
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
            Punch::Calibrated { file, .. } => {
                if file.trim().is_empty() {
                    Err(ContactError::Input {
                        field: "punch.file",
                        value: "\"\"".into(),
                        allowed: "the path of a tip file (indentify calibrate --out TIP.ron)"
                            .into(),
                    })
                } else {
                    Ok(())
                }
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
                // a node at the radius to a relative 1e-9 is on the face (and is the rim
                // node of `rim::treat_rim`)
                if r <= *radius * (1.0 + rim::RIM_TOLERANCE) {
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
            Punch::Berkovich { .. } | Punch::Vickers { .. } | Punch::CubeCorner { .. } => {
                self.equivalent().profile(r)
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
            Punch::Calibrated { area, .. } => area.as_ref().map_or(f64::NAN, |a| a.height(r)),
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
            Punch::Berkovich { tip_radius }
            | Punch::Vickers { tip_radius }
            | Punch::CubeCorner { tip_radius } => {
                let name = match self {
                    Punch::Berkovich { .. } => "Berkovich",
                    Punch::Vickers { .. } => "Vickers",
                    _ => "cube corner",
                };
                let alpha = self.half_angle_deg().unwrap_or(f64::NAN);
                match tip_radius {
                    Some(t) if *t > 0.0 => format!(
                        "{name} (area-equivalent cone, half-angle {alpha} deg, tip R = {t} mm)"
                    ),
                    _ => format!("{name} (area-equivalent cone, half-angle {alpha} deg)"),
                }
            }
            Punch::Tabulated { r, .. } => format!("tabulated ({} points)", r.len()),
            Punch::Calibrated { file, area } => match area {
                Some(a) => format!("calibrated tip `{file}` ({})", a.describe()),
                None => format!("calibrated tip `{file}`"),
            },
        }
    }

    /// The profile a preset stands for: its area-equivalent [`Punch::Cone`], or a
    /// [`Punch::SpheroCone`] with a tip radius > 0. Other punches are returned unchanged.
    pub fn equivalent(&self) -> Punch {
        let (half_angle_deg, tip_radius) = match self {
            Punch::Berkovich { tip_radius } => (BERKOVICH_HALF_ANGLE_DEG, tip_radius),
            Punch::Vickers { tip_radius } => (VICKERS_HALF_ANGLE_DEG, tip_radius),
            Punch::CubeCorner { tip_radius } => (CUBE_CORNER_HALF_ANGLE_DEG, tip_radius),
            other => return other.clone(),
        };
        match tip_radius {
            Some(radius) if *radius > 0.0 => Punch::SpheroCone {
                radius: *radius,
                half_angle_deg,
            },
            _ => Punch::Cone { half_angle_deg },
        }
    }

    /// Cone half-angle (deg, from the axis) of a conical punch: cones, sphero-cones and
    /// the presets (their area-equivalent cone); `None` for the others.
    pub fn half_angle_deg(&self) -> Option<f64> {
        match self {
            Punch::Cone { half_angle_deg } | Punch::SpheroCone { half_angle_deg, .. } => {
                Some(*half_angle_deg)
            }
            Punch::Berkovich { .. } => Some(BERKOVICH_HALF_ANGLE_DEG),
            Punch::Vickers { .. } => Some(VICKERS_HALF_ANGLE_DEG),
            Punch::CubeCorner { .. } => Some(CUBE_CORNER_HALF_ANGLE_DEG),
            Punch::Sphere { .. }
            | Punch::Flat { .. }
            | Punch::Tabulated { .. }
            | Punch::Calibrated { .. } => None,
        }
    }

    /// Geometric intersection radius (mm): where the undeformed profile reaches the depth
    /// `h`, the smallest r with `phi(r) >= h`; 0 for `h <= 0`.
    ///
    /// Cone `h tan(alpha)`; sphere `sqrt(h (2R - h))`, R from h = R on (the wall); flat
    /// punch R; sphero-cone the sphere up to the blend height `R (1 - sin(alpha))`, the
    /// cone beyond; tabulated: linear inversion, infinite if the last segment is flat and
    /// below h; calibrated: `sqrt(A(h) / pi)` (NaN before its file is read). Call on a
    /// validated punch.
    pub fn intersection_radius(&self, h: f64) -> f64 {
        if !(h > 0.0) {
            return 0.0;
        }
        let sphere = |radius: f64| {
            if h >= radius {
                radius
            } else {
                (h * (2.0 * radius - h)).sqrt()
            }
        };
        match self {
            Punch::Cone { half_angle_deg } => h * half_angle_deg.to_radians().tan(),
            Punch::Sphere { radius } => sphere(*radius),
            Punch::Flat { radius } => *radius,
            Punch::SpheroCone {
                radius,
                half_angle_deg,
            } => {
                let a = half_angle_deg.to_radians();
                let zt = radius * (1.0 - a.sin());
                if h <= zt {
                    sphere(*radius)
                } else {
                    radius * a.cos() + (h - zt) * a.tan()
                }
            }
            Punch::Berkovich { .. } | Punch::Vickers { .. } | Punch::CubeCorner { .. } => {
                self.equivalent().intersection_radius(h)
            }
            Punch::Tabulated { r, z } => {
                let n = r.len();
                // first segment whose upper end reaches h, else the last (extrapolated)
                let i = z[1..].iter().position(|&zi| zi >= h).unwrap_or(n - 2);
                let dz = z[i + 1] - z[i];
                if dz > 0.0 {
                    r[i] + (h - z[i]) * (r[i + 1] - r[i]) / dz
                } else {
                    f64::INFINITY
                }
            }
            Punch::Calibrated { area, .. } => area.as_ref().map_or(f64::NAN, |a| a.radius(h)),
        }
    }

    /// Upper estimate of the contact radius at depth `h` (mm), for sizing meshes:
    /// [`PILE_UP_ALLOWANCE`] (1.2) times the [`intersection_radius`](Self::intersection_radius),
    /// but never beyond the punch's own radius for a sphere (whose profile ends at R) and
    /// exactly R for a flat punch (its contact radius at any depth).
    ///
    /// The elastic contact radius is 0.53 of this bound for a cone (Sneddon:
    /// `a = 2 h tan(alpha) / pi`) and 0.59 for a sphere at small depth (`a = sqrt(R h)`).
    /// Infinite for a tabulated profile that never reaches h.
    pub fn contact_radius_bound(&self, h: f64) -> f64 {
        let a = self.intersection_radius(h);
        match self {
            Punch::Flat { radius } => *radius,
            Punch::Sphere { radius } => (PILE_UP_ALLOWANCE * a).min(*radius),
            // a tip that ends (a sphere-like area) is bounded by its last radius
            Punch::Calibrated { area: Some(p), .. } if p.depth_limit().is_finite() => {
                (PILE_UP_ALLOWANCE * a).min(p.radius(p.depth_limit()))
            }
            _ => PILE_UP_ALLOWANCE * a,
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

    #[test]
    fn presets_are_their_area_equivalent_cones() {
        use std::f64::consts::PI;
        // pi tan^2(theta) = A / h^2 of the pyramid
        let area = |deg: f64| PI * deg.to_radians().tan().powi(2);
        let berkovich = 3.0 * 3.0_f64.sqrt() * 65.27_f64.to_radians().tan().powi(2);
        let vickers = 4.0 * 68.0_f64.to_radians().tan().powi(2);
        assert!((area(BERKOVICH_HALF_ANGLE_DEG) / berkovich - 1.0).abs() < 1e-3);
        assert!((area(VICKERS_HALF_ANGLE_DEG) / vickers - 1.0).abs() < 1e-3);
        assert!((area(BERKOVICH_HALF_ANGLE_DEG) / 24.5 - 1.0).abs() < 1e-3);
        assert!((area(CUBE_CORNER_HALF_ANGLE_DEG) / 2.598 - 1.0).abs() < 1e-3);
        let b = Punch::Berkovich { tip_radius: None };
        b.validate().unwrap();
        assert_eq!(
            b.equivalent(),
            Punch::Cone {
                half_angle_deg: 70.3
            }
        );
        assert_eq!(b.profile(0.3), b.equivalent().profile(0.3));
        let v = Punch::Vickers {
            tip_radius: Some(1e-3),
        };
        assert_eq!(
            v.equivalent(),
            Punch::SpheroCone {
                radius: 1e-3,
                half_angle_deg: 70.3
            }
        );
        assert_eq!(
            Punch::CubeCorner {
                tip_radius: Some(0.0)
            }
            .equivalent(),
            Punch::Cone {
                half_angle_deg: 42.28
            }
        );
        assert!(b.describe().contains("Berkovich") && b.describe().contains("70.3"));
        assert!(
            v.describe().contains("tip R = 0.001 mm"),
            "{}",
            v.describe()
        );
        let e = Punch::Vickers {
            tip_radius: Some(f64::NAN),
        }
        .validate()
        .unwrap_err()
        .to_string();
        assert!(e.contains("punch.tip_radius"), "{e}");
    }

    #[test]
    fn intersection_radius_inverts_the_profile() {
        let punches = [
            Punch::Cone {
                half_angle_deg: 68.0,
            },
            Punch::Sphere { radius: 0.5 },
            Punch::SpheroCone {
                radius: 0.5,
                half_angle_deg: 60.0,
            },
            Punch::Berkovich { tip_radius: None },
            Punch::Vickers {
                tip_radius: Some(0.2),
            },
            Punch::CubeCorner { tip_radius: None },
            Punch::Tabulated {
                r: vec![0.0, 1.0, 2.0],
                z: vec![0.0, 1.0, 3.0],
            },
        ];
        for p in &punches {
            for h in [1e-6, 0.01, 0.05, 0.1, 0.3, 0.49, 2.0, 7.0] {
                let a = p.intersection_radius(h);
                if matches!(p, Punch::Sphere { .. }) && h >= 0.5 {
                    assert_eq!(a, 0.5);
                    continue;
                }
                assert!(
                    (p.profile(a) - h).abs() < 1e-12 * (1.0 + h),
                    "{p:?} {h} {a}"
                );
                let bound = p.contact_radius_bound(h);
                assert!(
                    (bound - 1.2 * a).abs() < 1e-15 * bound || bound == 0.5,
                    "{p:?}"
                );
            }
            assert_eq!(p.intersection_radius(0.0), 0.0);
        }
        let f = Punch::Flat { radius: 0.2 };
        assert_eq!(f.contact_radius_bound(0.1), 0.2);
        assert_eq!(
            Punch::Sphere { radius: 0.5 }.contact_radius_bound(0.45),
            0.5
        );
    }
}
