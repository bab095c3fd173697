//! Checking tools for law authors: finite-difference checks of every block of a
//! [`crate::Material`] and material-point drivers (uniaxial stress, simple shear), public
//! behind the `testing` feature; and, for this crate's own tests, the proptest harness
//! every stress-only [`crate::Law`] gets (`law_harness`).

#[cfg(test)]
mod law_harness;
#[cfg(test)]
pub(crate) use law_harness::*;

mod drivers;
mod fd;

pub use drivers::{Shear, UniaxialPoint, shear_history, uniaxial_path};
pub use fd::{BlockCheck, FdReport, Point, check_material};
