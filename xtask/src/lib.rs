//! Library side of `cargo xtask`: the paper-table runs and renderers ([`paper`]), the
//! document writer ([`doc`]) and a small SVG plotter ([`svg`]), shared by the binary and
//! the snapshot test.

pub mod batch_start;
pub mod calculix;
pub mod dao;
pub mod doc;
pub mod mesh_study;
pub mod paper;
pub mod svg;
pub mod tidy;
