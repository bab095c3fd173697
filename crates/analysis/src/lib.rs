//! Oliver-Pharr (ISO 14577) analysis of instrumented-indentation records, and the
//! calibration of a tip and a load frame on a reference of known modulus.
//!
//! Pure numerics on [`indentify_records::Record`]s (no file IO; the study layer reads the
//! files, applies the zero point, drift and frame-compliance corrections of
//! `indentify_records::prep` and writes the outputs). The method, its defaults and their
//! sources are in `docs/analysis.md`.
//!
//! - [`analyze`]: every unloading of a record (multi-cycle tests included) found from the
//!   force, the power law `F = alpha (h - h_f)^m` fitted over a force range
//!   ([`FitRange`]: the vendor's default for the format), `S = dF/dh` at `h_max`,
//!   `h_c = h_max - epsilon F_max/S`, `A_p(h_c)` from the [`Tip`]'s [`AreaFunction`],
//!   `H_IT = F_max/A_p`, `E_r = sqrt(pi) S / (2 beta sqrt(A_p))`, `E*` and `E_IT` with the
//!   tip's `E_i`, `nu_i`; the hold before it (creep `C_IT`, creep rate, strain-rate
//!   sensitivity) and the work ratio `eta_IT`. One unloading's failure is reported and the
//!   others analysed.
//! - [`calibrate`]: the frame compliance from `1/S = C_f + k/sqrt(F_max)` and the ISO area
//!   function from the areas a reference's modulus implies.
//! - [`closed_form`]: the modulus from the loading's elastic closed form (Sneddon's cone,
//!   Hertz's sphere, the flat punch) and the Maxwell law's `(E, eta)` from Lee and Radok's
//!   form of the loading and hold, the starts of a finite element fit.
//! - [`dao`]: Dao et al.'s dimensionless functions of the 70.3-degree cone, what a curve
//!   gives them, and their reverse analysis (`E`, the representative stress, `n`, `sY`);
//!   [`tabor`]: `E` from the unloading stiffness and the representative stress from the
//!   mean pressure for a sphere or any cone: the starts of laws with a yield stress.
//!
//! ```
//! use indentify_analysis::{AreaFunction, Options, Tip, analyze};
//! use indentify_records::{Format, Record};
//!
//! // an elastic cone (half-angle 70.3 deg) loaded to 1 um and unloaded: Sneddon's
//! // F = (2/pi) E_r tan(theta) h^2, E_r = 100 GPa
//! let (er, tan) = (1e5, 70.3f64.to_radians().tan());
//! let mut r = Record { name: "cone".into(), t: vec![], h: vec![], f: vec![], segment: None, meta: Default::default() };
//! for i in 0..=200 {
//!     let h = 1e-3 * (1.0 - (i as f64 - 100.0).abs() / 100.0);
//!     r.t.push(i as f64);
//!     r.h.push(h);
//!     r.f.push(2.0 / std::f64::consts::PI * er * tan * h * h);
//! }
//! let mut tip = Tip::diamond(AreaFunction::Cone { half_angle_deg: 70.3 });
//! tip.modulus = f64::INFINITY; // rigid
//! let a = analyze(&r, &Options::new(tip, Format::Csv))?;
//! let (_, op) = a.values().unwrap();
//! assert!((op.er / er - 1.0).abs() < 1e-6);
//! # Ok::<(), indentify_analysis::AnalysisError>(())
//! ```

pub mod calibrate;
pub mod closed_form;
pub mod dao;
mod error;
mod fit;
mod op;
mod special;
pub mod tabor;
mod tip;

pub use error::AnalysisError;
pub use fit::{PowerLaw, fit_power_law};
pub use op::{
    Epsilon, FitRange, Hold, OliverPharr, Options, TestAnalysis, Unloading, Work, analyze,
    oliver_pharr,
};
pub use special::{epsilon_of_m, gamma, ln_gamma};
pub use tip::{AreaFunction, BERKOVICH_C0, DIAMOND_MODULUS, DIAMOND_POISSON, Tip, iso_exponent};
