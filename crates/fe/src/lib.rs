//! Axisymmetric finite-element machinery for indentify: Gauss-point geometry and the B
//! operator ([`Discretization`]), dof numbering with Dirichlet elimination ([`DofMap`]),
//! assembly into a pattern built once ([`Pattern`]), and the sparse Cholesky solver with
//! a reused symbolic factorization ([`SparseCholesky`]).
//!
//! Conventions: dofs `2n` (u_r) and `2n+1` (u_z) of node n; Mandel strain/stress
//! `[rr, zz, tt, sqrt2*rz]`; weights integrate over the full circle, so forces are
//! full-circle newtons (N) with lengths in mm and stresses in MPa. This crate knows
//! nothing of contact or time histories.

pub mod assembly;
pub mod dofs;
pub mod finite;
pub mod geometry;
pub mod solver;

pub use assembly::{ElementCache, Pattern};
pub use dofs::DofMap;
pub use finite::Deformation;
pub use geometry::{Discretization, QP_PER_ELEMENT, QuadPoint};
pub use solver::{SolveScratch, SparseCholesky};

/// Errors of assembly and linear solves.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum FeError {
    /// The symbolic analysis failed.
    #[error("sparse factorization: {0}")]
    Factorization(String),
    /// The matrix is not numerically positive definite.
    #[error(
        "the stiffness matrix is not positive definite ({0}): a degenerate mesh (elements of vanishing size or extreme aspect ratio: check specimen sizes and gradings), a material tangent that is not positive definite, or a rigid-body mode left unconstrained"
    )]
    NotPositiveDefinite(String),
}
