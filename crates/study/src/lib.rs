//! The application layer of indentify, shared by every front end (the `indentify` CLI,
//! the Python package, the batch runner, `cargo xtask`): the configuration schema (RON,
//! `--set` overrides, validation with field paths), the set-up of an experiment from a
//! configuration (mesh, model, schedule, measured record), the pipelines (simulate,
//! gradient, gradient check, identify, batch) with an [`identify::Observer`] for
//! progress, serializable results, and report directories written atomically.
//!
//! It knows nothing of terminals or argument parsers: front ends map their arguments onto
//! the option types here ([`identify::IdentifyOptions`], [`batch::BatchOptions`], ...)
//! and print the outcomes their own way. It may do file IO; the numerical crates below it
//! do none.
//!
//! ```no_run
//! use indentify_study::{ConfigSource, identify::{self, IdentifyOptions}};
//!
//! let outcome = identify::run(&IdentifyOptions::new(ConfigSource::Default), &mut ())?;
//! println!("E = {:?} MPa, converged: {}", outcome.value("E"), outcome.converged());
//! # Ok::<(), indentify_study::Error>(())
//! ```

pub mod adequacy;
pub mod analysis_figures;
pub mod analyze;
pub mod atomic;
pub mod batch;
pub mod batch_analysis;
mod batch_seed;
pub mod check;
pub mod closed_form_start;
mod closed_form_yield;
pub mod coarse_to_fine;
pub mod config;
pub mod costmap;
pub mod data;
pub mod design;
pub mod discretization;
pub mod error;
pub mod explore;
pub mod figures;
pub mod first_guess;
pub mod first_guess_laws;
pub mod format;
pub mod fuzzing;
pub mod gradient;
mod gradient_load;
pub mod history;
pub mod identify;
mod identify_load;
mod instrument;
pub mod laws_list;
pub mod op_beside;
pub mod output;
pub mod run_folder;
pub mod simulate;
pub mod solve;
pub mod source;
pub mod start_from_analysis;
pub mod stoppable;
pub mod synthetic;
pub mod templates;

pub use error::{Classify, Error, ErrorKind, Result};
// what the front ends (cli, python, xtask) need of the crates below, so that they depend on
// `study` alone for it
pub use indentify_analysis::{AreaFunction, Epsilon, FitRange, Tip};
pub use indentify_contact::Punch;
pub use indentify_contact::punch::Rim;
pub use indentify_identify::profile::ProfileSettings;
pub use indentify_identify::{
    Cancel, Identifiability, IterationRecord, NoiseModel, StopReason, multiplicative_noise,
};
pub use indentify_laws::law_by_name;
pub use indentify_records as records;
pub use indentify_report::{FitQuality, Observable};
pub use source::{ConfigSource, DEFAULT_CONFIG, DEFAULT_NAME};
