//! Automatic specimen: a cylinder sized and meshed from the punch and the maximum depth,
//! so that a 2 um indent and a 0.1 mm indent are resolved alike.
//!
//! # Rule
//!
//! With `a = Punch::contact_radius_bound(h_max)` (the geometric intersection radius times
//! the pile-up allowance 1.2):
//!
//! - radius = height = `size_factor * a` (k, default 48): the finite cylinder (clamped
//!   bottom, free outer face) is stiffer than the half space by `C / k`, measured
//!   C = 0.32 (elastic cone) and 0.37 (sphere): +0.67% and +0.78% at k = 48
//!   (`docs/validation.md`, "Instrument scale");
//! - a uniform core `0 <= r <= a`, `-a <= z <= 0` of `elements_in_contact` squares per
//!   side (default 12: element edges across the bounded contact radius on the surface;
//!   the elastic contact radius, 0.53 a for a cone, spans about 6 of them; the mesh study
//!   of `docs/discretization.md` puts the viscoplastic force of the real examples within
//!   1% of the converged one with 12, up to 1.5% off with 8);
//! - the far field grows geometrically from the core with ratio at most `grading`
//!   (default 1.5): 25 x 25 = 625 elements with the defaults.
//!
//! Every length of the mesh is `a` times a number that depends on the options only, so
//! the mesh, and the elastic force over `E h^2` of a cone, are the same at every scale.

use indentify_mesh::ZonedCylinderMesher;
use serde::{Deserialize, Serialize};

use super::Punch;
use crate::ContactError;

/// Options of the automatic specimen ([`auto_specimen`]). Every field has a default, so a
/// config may give none, some or all: `(elements_in_contact: 16)`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct AutoOptions {
    /// Element edges across the contact-radius bound on the top surface, in [2, 64]
    /// (default 12).
    pub elements_in_contact: usize,
    /// Radius and height of the cylinder in contact-radius bounds, k in [5, 10000]
    /// (default 48; the elastic force is about 0.35/k above the half space's).
    pub size_factor: f64,
    /// Largest size ratio of neighbouring elements outside the core, in [1.05, 3]
    /// (default 1.5).
    pub grading: f64,
}

impl Default for AutoOptions {
    fn default() -> AutoOptions {
        AutoOptions {
            elements_in_contact: 12,
            size_factor: 48.0,
            grading: 1.5,
        }
    }
}

impl AutoOptions {
    /// Checks the ranges.
    ///
    /// # Errors
    /// [`ContactError::Input`] naming the field (`specimen.<field>`), value and range.
    pub fn validate(&self) -> Result<(), ContactError> {
        if !(2..=64).contains(&self.elements_in_contact) {
            return Err(ContactError::Input {
                field: "specimen.elements_in_contact",
                value: self.elements_in_contact.to_string(),
                allowed: "an integer in [2, 64]".into(),
            });
        }
        if !(self.size_factor.is_finite() && (5.0..=1e4).contains(&self.size_factor)) {
            return Err(ContactError::Input {
                field: "specimen.size_factor",
                value: self.size_factor.to_string(),
                allowed: "a ratio of specimen size to contact radius in [5, 10000]".into(),
            });
        }
        if !(self.grading.is_finite() && (1.05..=3.0).contains(&self.grading)) {
            return Err(ContactError::Input {
                field: "specimen.grading",
                value: self.grading.to_string(),
                allowed: "a ratio of neighbouring element sizes in [1.05, 3]".into(),
            });
        }
        Ok(())
    }
}

/// The automatic specimen for `punch` pressed to the depth `h_max` (mm): a
/// [`ZonedCylinderMesher`] of radius = height = `size_factor * a`, a uniform core of side
/// `a` cut into `elements_in_contact` squares per side, graded beyond it, with
/// `a = punch.contact_radius_bound(h_max)` (see the module's rule).
///
/// # Errors
/// [`ContactError::Input`] for an invalid punch or options, `h_max` not finite and > 0
/// (field `specimen.h_max`), or a profile that never reaches `h_max` (a tabulated punch
/// ending flat below it).
pub fn auto_specimen(
    punch: &Punch,
    h_max: f64,
    options: &AutoOptions,
) -> Result<ZonedCylinderMesher, ContactError> {
    punch.validate()?;
    punch.require_profile()?;
    options.validate()?;
    if !(h_max.is_finite() && h_max > 0.0) {
        return Err(ContactError::Input {
            field: "specimen.h_max",
            value: h_max.to_string(),
            allowed: "a finite maximum depth > 0 (mm)".into(),
        });
    }
    let a = punch.contact_radius_bound(h_max);
    if !(a.is_finite() && a > 0.0) {
        return Err(ContactError::Input {
            field: "specimen.h_max",
            value: h_max.to_string(),
            allowed: format!(
                "a depth the punch profile reaches ({} has contact-radius bound {a} mm there)",
                punch.describe()
            ),
        });
    }
    let mesher = ZonedCylinderMesher {
        radius: options.size_factor * a,
        height: options.size_factor * a,
        core: a,
        core_elements: options.elements_in_contact,
        grading: options.grading,
    };
    mesher.validate().map_err(|e| ContactError::Input {
        field: "specimen",
        value: format!("auto (a = {a} mm)"),
        allowed: format!("a valid mesher: {e}"),
    })?;
    Ok(mesher)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_specimen_of_a_berkovich_indent() {
        let p = Punch::Berkovich { tip_radius: None };
        let m = auto_specimen(&p, 2e-3, &AutoOptions::default()).unwrap();
        let a = 1.2 * 2e-3 * 70.3_f64.to_radians().tan();
        assert!((m.core - a).abs() < 1e-15, "{m:?}");
        assert!((m.radius - 48.0 * a).abs() < 1e-15 && m.height == m.radius);
        let (nr, nz) = m.counts().unwrap();
        assert_eq!((nr, nz), (25, 25));
        let mesh = m.build().unwrap();
        mesh.check_quality().unwrap();
    }

    #[test]
    fn quality_holds_at_every_scale_and_for_every_punch() {
        let punches = [
            Punch::Berkovich { tip_radius: None },
            Punch::Vickers {
                tip_radius: Some(2e-4),
            },
            Punch::CubeCorner { tip_radius: None },
            Punch::Sphere { radius: 0.01 },
            Punch::Flat { radius: 0.05 },
            Punch::SpheroCone {
                radius: 1e-3,
                half_angle_deg: 60.0,
            },
        ];
        for p in &punches {
            for h in [1e-5, 1e-4, 2e-3, 0.1, 1.0] {
                let m = auto_specimen(p, h, &AutoOptions::default()).unwrap();
                let mesh = m.build().unwrap();
                mesh.check_quality().unwrap();
                assert!(mesh.elements.len() <= 625, "{p:?} {h}: {m:?}");
            }
        }
    }

    #[test]
    fn invalid_inputs_give_clear_errors() {
        let p = Punch::Berkovich { tip_radius: None };
        let err = |h: f64, o: AutoOptions| auto_specimen(&p, h, &o).unwrap_err().to_string();
        for h in [0.0, -1e-3, f64::NAN, f64::INFINITY] {
            let e = err(h, AutoOptions::default());
            assert!(e.contains("specimen.h_max"), "{e}");
        }
        let e = err(
            1e-3,
            AutoOptions {
                elements_in_contact: 1000,
                ..AutoOptions::default()
            },
        );
        assert!(
            e.contains("specimen.elements_in_contact") && e.contains("1000"),
            "{e}"
        );
        let e = err(
            1e-3,
            AutoOptions {
                size_factor: 1.0,
                ..AutoOptions::default()
            },
        );
        assert!(e.contains("specimen.size_factor"), "{e}");
        let e = err(
            1e-3,
            AutoOptions {
                grading: 1.0,
                ..AutoOptions::default()
            },
        );
        assert!(e.contains("specimen.grading"), "{e}");
        let flat_tail = Punch::Tabulated {
            r: vec![0.0, 1.0, 2.0],
            z: vec![0.0, 0.1, 0.1],
        };
        let e = auto_specimen(&flat_tail, 0.2, &AutoOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("specimen.h_max") && e.contains("reaches"), "{e}");
        let bad = Punch::CubeCorner {
            tip_radius: Some(-1.0),
        };
        let e = auto_specimen(&bad, 0.1, &AutoOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("punch.tip_radius"), "{e}");
    }
}
