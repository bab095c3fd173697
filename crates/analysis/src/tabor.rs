//! The modulus from the unloading stiffness and the representative stress from the mean
//! contact pressure (Tabor's hardness), for a sphere or a cone of any angle: the start of
//! a law with a yield stress where Dao's functions ([`crate::dao`]) do not apply
//! (docs/analysis.md, "Closed-form starts for laws with a yield stress").
//!
//! From a curve's [`Features`] (`P_m`, `h_m`, `S`): the contact depth of Oliver and Pharr,
//! `h_c = h_m - epsilon P_m/S` (`epsilon` 0.75 for a sphere, 0.72 for a cone), the contact
//! radius of the tip's profile at `h_c` (`a = sqrt(2 R h_c - h_c^2)`, `a = h_c tan(alpha)`),
//! Sneddon's stiffness of an axisymmetric rigid punch `S = 2 E* a` for `E* = E/(1 - nu^2)`,
//! the mean pressure `p_m = P_max/(pi a^2)` at the loading's end (its largest force: a
//! hold that relaxes or creeps changes the force, not the contact radius, much) and Tabor's `p_m = 3 sigma_r` at the
//! representative plastic strain `0.2 a/R` (sphere) or `0.2 cot(alpha)` (cone). These are
//! fully plastic rules of thumb (Tabor, The Hardness of Metals, 1951): a start, which the
//! study layer corrects with one finite element run.
//!
//! Pure numerics: no file IO.

use std::f64::consts::PI;

use crate::closed_form::Punch;
use crate::dao::{DaoError, Features};

/// Tabor's constraint factor `p_m / sigma_r`.
pub const CONSTRAINT: f64 = 3.0;

/// What the stiffness and the mean pressure give.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hardness {
    /// `E* = S/(2 a)` (MPa).
    pub e_star: f64,
    /// Young's modulus (MPa) at the `nu` given.
    pub e: f64,
    /// Contact depth (mm).
    pub h_c: f64,
    /// Contact radius (mm).
    pub a: f64,
    /// Mean contact pressure (MPa).
    pub p_mean: f64,
    /// Representative stress `p_m / 3` (MPa).
    pub sigma_r: f64,
    /// Representative plastic strain.
    pub eps_r: f64,
}

/// `E`, the contact radius, the mean pressure and Tabor's representative stress and strain
/// of a sphere or cone indent with force `m.p_m` at depth `m.h_m` where it unloads with
/// slope `m.s`, and largest force `m.p_max` at the loading's end.
///
/// # Errors
/// [`DaoError::Input`]: a flat punch (no representative strain), a punch out of range,
/// `nu` outside (-1, 0.5), a slope or force that is not positive, a contact depth that is
/// not positive (`epsilon P_m/S >= h_m`).
pub fn stiffness_and_hardness(m: &Features, punch: Punch, nu: f64) -> Result<Hardness, DaoError> {
    if !(nu > -1.0 && nu < 0.5) {
        return Err(DaoError::Input(format!(
            "Poisson's ratio {nu} is outside (-1, 0.5)"
        )));
    }
    for (what, v) in [("S", m.s), ("P_m", m.p_m), ("h_m", m.h_m)] {
        if !(v.is_finite() && v > 0.0) {
            return Err(DaoError::Input(format!(
                "{what} = {v} must be finite and positive"
            )));
        }
    }
    let epsilon = match punch {
        Punch::Sphere { .. } => 0.75,
        Punch::Cone { .. } => 0.72,
        Punch::Flat { .. } => {
            return Err(DaoError::Input(
                "a flat punch has no representative strain (Tabor's hardness needs a sphere or a cone)"
                    .into(),
            ));
        }
    };
    let h_c = m.h_m - epsilon * m.p_m / m.s;
    if !(h_c > 0.0) {
        return Err(DaoError::Input(format!(
            "the contact depth h_c = h_m - {epsilon} P_m/S = {h_c:e} mm is not positive: the \
             unloading is too soft for its force"
        )));
    }
    let (a, eps_r) = match punch {
        Punch::Sphere { radius } if radius > 0.0 && radius.is_finite() => {
            let a = if h_c < radius {
                (2.0 * radius * h_c - h_c * h_c).sqrt()
            } else {
                radius
            };
            (a, 0.2 * a / radius)
        }
        Punch::Cone { half_angle_deg } if half_angle_deg > 0.0 && half_angle_deg < 90.0 => {
            let t = half_angle_deg.to_radians().tan();
            (h_c * t, 0.2 / t)
        }
        p => {
            return Err(DaoError::Input(format!(
                "the punch {p:?} is out of range (a half-angle in (0, 90) deg, a positive radius)"
            )));
        }
    };
    let e_star = m.s / (2.0 * a);
    let p_mean = m.p_max / (PI * a * a);
    Ok(Hardness {
        e_star,
        e: e_star * (1.0 - nu * nu),
        h_c,
        a,
        p_mean,
        sigma_r: p_mean / CONSTRAINT,
        eps_r,
    })
}
