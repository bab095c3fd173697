//! Constitutive laws of standard generalized materials for indentify: the [`Law`] trait,
//! Mandel-form tensors, and the laws themselves: [`Elastic`], [`Maxwell`] viscoelasticity
//! and [`NortonHoff`] elastoviscoplasticity, found by name with [`law_by_name`].
//!
//! Units: MPa for stresses and moduli, s for times. This crate knows nothing of
//! elements, meshes or contact: it works at one material point.

pub mod catalog;
pub mod elastic;
#[cfg(test)]
mod example_law;
#[cfg(any(test, feature = "example-law"))]
pub mod example_material;
pub mod hardening;
pub mod law;
pub mod logstrain;
pub mod mandel;
pub mod material;
pub mod maxwell;
pub mod norton_hoff;
pub mod plastic;
pub mod prony;
pub mod registry;
#[cfg(any(test, feature = "testing"))]
pub mod testing;
#[cfg(test)]
mod validation;

pub use elastic::Elastic;
pub use hardening::{Hardening, Table};
pub use law::{ElasticDomain, Law, LocalFailure, LocalUpdate, ParamInfo};
pub use logstrain::LogStrain;
pub use mandel::{Mat4, Vec4};
pub use material::{InternalInfo, LawMaterial, Material, MaterialUpdate, Regime, Step};
pub use maxwell::Maxwell;
pub use norton_hoff::NortonHoff;
pub use plastic::{Plastic, Rate};
pub use prony::Prony;
pub use registry::{Built, LawEntry, REGISTRY, SpecValue, VARIANTS};

/// Names accepted by [`law_by_name`], in the order of increasing complexity.
pub const LAW_NAMES: [&str; 3] = ["elastic", "maxwell", "norton-hoff"];

/// The law registered under `name` (one of [`LAW_NAMES`]), or `None`.
pub fn law_by_name(name: &str) -> Option<&'static dyn Law> {
    match name {
        "elastic" => Some(&Elastic),
        "maxwell" => Some(&Maxwell),
        "norton-hoff" => Some(&NortonHoff),
        _ => None,
    }
}

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
    /// A structural field of a law's specification (a hardening table, a list of Prony
    /// terms, a kind name) that is not allowed.
    #[error("{law}: `{field}`: {message}")]
    Spec {
        /// Law name.
        law: &'static str,
        /// The field, as written in configurations (`hardening.points[2]`, `terms`).
        field: String,
        /// What is wrong and the allowed range.
        message: String,
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_listed_name_resolves_to_a_law_of_that_name() {
        for name in LAW_NAMES {
            let law = law_by_name(name).expect(name);
            assert_eq!(law.name(), name);
        }
        assert!(law_by_name("hooke").is_none());
    }
}
