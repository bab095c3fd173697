//! Helpers shared by the end-to-end tests: running the binary, reading its outputs, and
//! checking that bad input is rejected with a message instead of a panic.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The repository's `examples/` directory.
pub fn examples() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples")
}

/// `examples/NAME` as a string argument.
pub fn example(name: &str) -> String {
    examples().join(name).display().to_string()
}

/// Runs `indentify ARGS`.
pub fn indentify<S: AsRef<std::ffi::OsStr>>(args: &[S]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_indentify"))
        .args(args)
        .output()
        .expect("the indentify binary runs")
}

/// Runs `indentify ARGS` in the working directory `dir`.
pub fn indentify_in<S: AsRef<std::ffi::OsStr>>(dir: &Path, args: &[S]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_indentify"))
        .current_dir(dir)
        .args(args)
        .output()
        .expect("the indentify binary runs")
}

/// Standard error as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Standard output as text.
pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// Zero exit status, or the standard error in the failure message.
pub fn assert_ok(o: &Output) {
    assert!(o.status.success(), "failed: {}", stderr(o));
}

/// Non-zero exit, every needle in standard error, no panic.
pub fn assert_rejected(o: &Output, needles: &[&str], case: &str) {
    let err = stderr(o);
    assert!(!o.status.success(), "{case}: accepted; stderr:\n{err}");
    assert!(!err.contains("panicked"), "{case}: panicked:\n{err}");
    assert!(err.contains("error: "), "{case}: {err}");
    for n in needles {
        assert!(err.contains(n), "{case}: `{n}` missing from:\n{err}");
    }
}

/// Rows `[t, h, F, a]` of a CSV curve, after checking its header.
pub fn parse_curve(text: &str) -> Vec<[f64; 4]> {
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("t,h,F,a"));
    lines
        .map(|l| {
            let v: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
            [v[0], v[1], v[2], v[3]]
        })
        .collect()
}

/// A coarse, short run for smoke tests: 6 x 6 mesh, 4 steps per segment.
pub const COARSE: [&str; 10] = [
    "--set",
    "specimen.nr=6",
    "--set",
    "specimen.nz=6",
    "--set",
    "history.segments.0.steps=4",
    "--set",
    "history.segments.1.steps=4",
    "--set",
    "history.segments.2.steps=4",
];

/// `args` followed by [`COARSE`].
pub fn coarse(args: &[&str]) -> Vec<String> {
    args.iter()
        .chain(COARSE.iter())
        .map(|s| s.to_string())
        .collect()
}

/// Parses standard output as one JSON object.
pub fn json(o: &Output) -> serde_json::Value {
    serde_json::from_str(&stdout(o)).unwrap_or_else(|e| panic!("not JSON ({e}):\n{}", stdout(o)))
}
