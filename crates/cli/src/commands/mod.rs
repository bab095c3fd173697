//! The subcommands of `indentify`, one module each.

pub mod analyze;
pub mod batch;
pub mod check;
pub mod design;
pub mod gradient;
pub mod gradient_check;
pub mod identify;
pub mod init;
pub mod map;
pub mod serve;
pub mod simulate;
