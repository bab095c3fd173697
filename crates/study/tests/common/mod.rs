//! Set-ups shared by the study crate's test targets: the repository's examples folder,
//! the built-in configuration with `--set` values, and its coarse variant (R1 on a 6 x 6
//! mesh, 4 steps per segment) that the pipeline tests fit quickly.

// Each test target uses a part of this module.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

use indentify_study::ConfigSource;
use indentify_study::identify::IdentifyOptions;

/// The repository's `examples` folder.
pub fn examples() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples")
}

/// `name` in the repository's `examples` folder.
pub fn example(name: &str) -> PathBuf {
    examples().join(name)
}

/// The built-in configuration (R1) on a 6 x 6 mesh with 4 steps per segment.
pub const COARSE: [&str; 5] = [
    "specimen.nr=6",
    "specimen.nz=6",
    "history.segments.0.steps=4",
    "history.segments.1.steps=4",
    "history.segments.2.steps=4",
];

/// The built-in configuration with the `--set` values `sets`.
pub fn default_with(sets: &[&str]) -> IdentifyOptions {
    let mut o = IdentifyOptions::new(ConfigSource::Default);
    o.sets = sets.iter().map(|s| s.to_string()).collect();
    o
}

/// The built-in configuration, [`COARSE`].
pub fn coarse() -> IdentifyOptions {
    default_with(&COARSE)
}

/// The example `name` with the `--set` values `sets`, its data with 2% noise (seed 1), no
/// refined check, no figures, one thread.
pub fn noisy_example(name: &str, sets: &[&str]) -> IdentifyOptions {
    let mut o = IdentifyOptions::new(ConfigSource::Path(example(name)));
    o.sets = sets.iter().map(|s| s.to_string()).collect();
    o.noise = Some((0.02, 1));
    o.refine = false;
    o.figures = false;
    o.jobs = Some(1);
    o
}
