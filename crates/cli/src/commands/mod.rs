//! The subcommands of `indentify`, one module each.

pub mod check;
pub mod init;
pub mod simulate;
