//! `punch: Calibrated(file: "TIP.ron")`: reads the tip file of `indentify calibrate` (the
//! analysis crate's [`Tip`]) and gives the contact crate the area function as an
//! [`AreaProfile`], the axisymmetric profile with that projected area at every depth, and
//! the tip's frame compliance, which the record's preprocessing then applies.

use std::path::{Path, PathBuf};

use anyhow::{Result, anyhow};
use indentify_analysis::{AreaFunction, BERKOVICH_C0, Tip, iso_exponent};
use indentify_contact::Punch;
use indentify_contact::punch::AreaProfile;

/// A punch ready for a model: a calibrated tip with its profile read, and its file's frame
/// compliance (mm/N).
pub struct ResolvedPunch {
    /// The punch (unchanged unless calibrated).
    pub punch: Punch,
    /// The calibrated tip's frame compliance, if its file gives one.
    pub frame_compliance: Option<f64>,
    /// The tip file read.
    pub file: Option<PathBuf>,
}

/// The tip file's path: absolute, or relative to `base` (the configuration's folder).
pub fn tip_path(file: &str, base: Option<&Path>) -> PathBuf {
    let p = PathBuf::from(file);
    match base {
        Some(b) if p.is_relative() => b.join(p),
        _ => p,
    }
}

/// Reads the tip file of a [`Punch::Calibrated`] (other punches are returned as they are).
///
/// # Errors
/// An unreadable tip file, RON that is not a tip (file and line), a value out of range
/// (file and field, e.g. `tip.area.coefficients[0]`), or an area function that is not a
/// punch (a flat punch's constant area, an area that does not grow with the depth).
pub fn resolve(punch: &Punch, base: Option<&Path>) -> Result<ResolvedPunch> {
    let Punch::Calibrated { file, .. } = punch else {
        return Ok(ResolvedPunch {
            punch: punch.clone(),
            frame_compliance: None,
            file: None,
        });
    };
    let path = tip_path(file, base);
    let tip: Tip = crate::analyze::read_tip(&path)
        .map_err(|e| anyhow!("punch.file: {e} (the tip file of `punch: Calibrated(file: ...)`, relative to the configuration's folder)"))?;
    let profile =
        area_profile(&tip.area).map_err(|e| anyhow!("{}: tip.area: {e:#}", path.display()))?;
    Ok(ResolvedPunch {
        punch: Punch::calibrated(file.clone(), profile),
        frame_compliance: tip.frame_compliance,
        file: Some(path),
    })
}

/// The contact crate's area function of a tip's `A(h_c)` (h in mm, A in mm^2).
///
/// # Errors
/// A flat punch (its area does not grow: use `punch: Flat(radius: R)`), or an area the
/// contact crate refuses.
pub fn area_profile(area: &AreaFunction) -> Result<AreaProfile> {
    use std::f64::consts::PI;
    let (terms, limit) = match area {
        AreaFunction::Berkovich => (vec![(BERKOVICH_C0, 2.0)], f64::INFINITY),
        AreaFunction::Cone { half_angle_deg } => {
            let t = half_angle_deg.to_radians().tan();
            (vec![(PI * t * t, 2.0)], f64::INFINITY)
        }
        AreaFunction::Sphere { radius } => (vec![(2.0 * PI * radius, 1.0), (-PI, 2.0)], *radius),
        AreaFunction::Flat { radius } => {
            return Err(anyhow!(
                "a flat punch's area (Flat(radius: {radius})) does not grow with the depth: \
                 it is no profile; use `punch: Flat(radius: {radius})`"
            ));
        }
        AreaFunction::Iso { coefficients } => (
            coefficients
                .iter()
                .enumerate()
                .map(|(k, &c)| (c, iso_exponent(k)))
                .collect(),
            f64::INFINITY,
        ),
    };
    Ok(AreaProfile::new(terms, limit)?)
}
