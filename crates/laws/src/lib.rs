//! Constitutive laws of standard generalized materials for indentify: the [`Law`] trait,
//! Mandel-form tensors, and the laws themselves ([`Elastic`] so far).
//!
//! Units: MPa for stresses and moduli, s for times. This crate knows nothing of
//! elements, meshes or contact: it works at one material point.

pub mod elastic;
pub mod law;
pub mod mandel;

pub use elastic::Elastic;
pub use law::{Law, LocalFailure, LocalUpdate, ParamInfo};
pub use mandel::{Mat4, Vec4};

/// Errors of this crate: parameters outside their admissible range or unknown laws.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum LawError {
    /// A parameter value outside its admissible range.
    #[error("{law}: parameter `{name}` = {value} is outside its admissible range {range}")]
    Parameter {
        /// Law name.
        law: &'static str,
        /// Parameter name.
        name: &'static str,
        /// Offending value.
        value: f64,
        /// Admissible range in interval notation.
        range: String,
    },
    /// The parameter slice has the wrong length.
    #[error("{law}: expected {expected} parameters, got {got}")]
    ParameterCount {
        /// Law name.
        law: &'static str,
        /// Expected count.
        expected: usize,
        /// Given count.
        got: usize,
    },
    /// The cost is not differentiable at these parameters.
    #[error("{law}: not differentiable with respect to `{name}` at {value}: {why}")]
    NotDifferentiable {
        /// Law name.
        law: &'static str,
        /// Parameter name.
        name: &'static str,
        /// Its value.
        value: f64,
        /// Explanation.
        why: &'static str,
    },
}
