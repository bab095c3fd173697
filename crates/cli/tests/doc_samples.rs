//! The sample outputs shown in README.md, docs/cli.md and docs/tutorial-real-data.md are the
//! tool's own: each block marked `<!-- sample: NAME -->` is compared with what the command
//! of NAME prints today, so the documentation cannot drift from the code.
//!
//! Wall times (a number followed by ` s` after `, `, `; `, `time `, `forward ` or
//! `sweep `: see [`VOLATILE`]) differ from run to run and machine to machine; they are masked
//! on both sides before the comparison. Every other character must match.
//!
//! To regenerate the blocks after an intended change of the output:
//! `INDENTIFY_BLESS=1 cargo test -p indentify-cli --test doc_samples` (or
//! `cargo xtask doc-samples`), then review the diff of the documents.

mod common;

use std::path::{Path, PathBuf};

/// A documented sample: its name in the marker, the document it lives in, the commands run
/// before it (their output is not shown), and the command whose standard output it is.
struct Sample {
    name: &'static str,
    doc: &'static str,
    setup: &'static [&'static [&'static str]],
    command: &'static [&'static str],
    /// Whether the sample is the command's standard error (its log) rather than its output.
    stderr: bool,
}

const SAMPLES: &[Sample] = &[
    Sample {
        name: "identify-default",
        doc: "README.md",
        setup: &[],
        command: &["identify", "--out", "out/default", "--force"],
        stderr: false,
    },
    Sample {
        name: "gradient-r1",
        doc: "docs/cli.md",
        setup: &[&["simulate", "examples/r1-maxwell.ron", "--out", "curve.csv"]],
        command: &[
            "gradient",
            "examples/r1-maxwell.ron",
            "--data",
            "curve.csv",
            "--set",
            "law.eta=25000",
        ],
        stderr: false,
    },
    Sample {
        name: "check-anon-maxwell",
        doc: "docs/tutorial-real-data.md",
        setup: &[],
        command: &["check", "examples/real/anon-maxwell.ron"],
        stderr: true,
    },
    Sample {
        name: "identify-anon-maxwell",
        doc: "docs/tutorial-real-data.md",
        setup: &[],
        command: &[
            "identify",
            "examples/real/anon-maxwell.ron",
            "--out",
            "out/tutorial-maxwell",
        ],
        stderr: false,
    },
];

/// Text right before a wall time: the number after it, up to ` s`, is masked.
const VOLATILE: &[&str] = &[
    ", ",
    "; ",
    "total wall time ",
    "forward ",
    "adjoint sweep ",
    "adjoint / forward = ",
];

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Whether `s` is a decimal number with a fraction (`2.4`, `0.135`).
fn is_time(s: &str) -> bool {
    s.contains('.') && !s.is_empty() && s.chars().all(|c| c.is_ascii_digit() || c == '.')
}

/// Masks wall times: a number with a fraction after a [`VOLATILE`] prefix, followed by
/// ` s` (or, for the adjoint / forward ratio, by anything).
fn mask(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    'scan: while !rest.is_empty() {
        for p in VOLATILE {
            if let Some(after) = rest.strip_prefix(p) {
                let end = after
                    .find(|c: char| !(c.is_ascii_digit() || c == '.'))
                    .unwrap_or(after.len());
                let (num, tail) = after.split_at(end);
                let ratio = p.starts_with("adjoint / forward");
                if is_time(num) && (ratio || tail.starts_with(" s")) {
                    out.push_str(p);
                    out.push('#');
                    rest = tail;
                    continue 'scan;
                }
            }
        }
        let c = rest.chars().next().expect("non-empty");
        out.push(c);
        rest = &rest[c.len_utf8()..];
    }
    out
}

/// The block after `<!-- sample: NAME -->`: (byte range of its content, the content).
fn block(doc: &str, name: &str) -> Option<(std::ops::Range<usize>, String)> {
    let marker = format!("<!-- sample: {name} -->");
    let at = doc.find(&marker)? + marker.len();
    let open = at + doc[at..].find("```")?;
    let start = open + doc[open..].find('\n')? + 1;
    let end = start + doc[start..].find("```")?;
    Some((start..end, doc[start..end].to_string()))
}

/// Runs a sample's commands in a fresh folder that sees the repository's `examples/`, and
/// returns the last command's standard output (or error, for a log sample).
fn run(sample: &Sample) -> String {
    let dir = tempfile::tempdir().unwrap();
    std::os::unix::fs::symlink(root().join("examples"), dir.path().join("examples")).unwrap();
    for args in sample.setup {
        common::assert_ok(&common::indentify_in(dir.path(), args));
    }
    let o = common::indentify_in(dir.path(), sample.command);
    common::assert_ok(&o);
    if sample.stderr {
        common::stderr(&o)
    } else {
        common::stdout(&o)
    }
}

#[test]
fn documented_samples_are_the_tools_output() {
    let bless = std::env::var_os("INDENTIFY_BLESS").is_some();
    let mut failures = Vec::new();
    for s in SAMPLES {
        let path = root().join(s.doc);
        let doc = std::fs::read_to_string(&path).unwrap();
        let Some((range, shown)) = block(&doc, s.name) else {
            failures.push(format!(
                "{}: no block marked `<!-- sample: {} -->`",
                s.doc, s.name
            ));
            continue;
        };
        let actual = run(s);
        if mask(&shown) == mask(&actual) {
            continue;
        }
        if bless {
            let mut new = doc.clone();
            new.replace_range(range, &actual);
            std::fs::write(&path, new).unwrap();
            eprintln!("{}: `{}` rewritten", s.doc, s.name);
        } else {
            failures.push(format!(
                "{}: the sample `{}` (indentify {}) differs from the tool's output\n--- shown\n{}--- printed\n{}",
                s.doc,
                s.name,
                s.command.join(" "),
                mask(&shown),
                mask(&actual)
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "{}\n\nIf the change is intended: INDENTIFY_BLESS=1 cargo test -p indentify-cli --test doc_samples",
        failures.join("\n\n")
    );
}

#[test]
fn wall_times_are_masked_and_nothing_else() {
    let line =
        "  J = 1.5e-15 N^2 (start 7.4e5), 15 iterations, 21 forward and 16 adjoint solves, 2.4 s";
    assert!(
        mask(line).ends_with("adjoint solves, # s"),
        "{}",
        mask(line)
    );
    assert_eq!(
        mask(
            "forward 0.135 s (23 factorizations), adjoint sweep 0.073 s (20 factorizations): adjoint / forward = 0.54"
        ),
        "forward # s (23 factorizations), adjoint sweep # s (20 factorizations): adjoint / forward = #"
    );
    // A duration that is part of the set-up is not masked, nor a count.
    assert_eq!(mask("59 steps over 96.426 s"), "59 steps over 96.426 s");
    assert_eq!(mask("a, 15 s"), "a, 15 s");
    assert_ne!(mask("total wall time 4.6 s"), mask("total wall time 4.6 N"));
    assert_eq!(
        mask("shift E -6.01e-3; 1.9 s (--no-refine skips it)"),
        "shift E -6.01e-3; # s (--no-refine skips it)"
    );
}
