//! Numbers the documents quote in their prose from the tool's output are the tool's: each
//! entry of [`QUOTES`] names a document, a snippet of it as written (whitespace
//! collapsed), which number of the snippet is meant, the command that produces it ([`RUNS`])
//! and where the command prints it (a field of its result.json or the n-th number after a
//! text in its output). The number the tool prints today must equal the quoted one at the
//! quoted precision (`1875.4` stands for [1875.35, 1875.45], `25` for 25, `5%` for 4.5-5.5%).
//!
//! Whole outputs are pinned as samples by `doc_samples.rs` (`<!-- sample: NAME -->`); this
//! file checks the single numbers a sentence or a table repeats. Runs that take seconds
//! to a minute in a test build are checked by `cheap_quotes_match_the_tool`; the expensive
//! ones (the anon-nh fit, about 13 minutes in a release build) are `#[ignore]`d and run by
//! `cargo xtask doc-numbers` (a release build of this test, `--include-ignored`).
//!
//! When a quoted number changes on purpose: run the command of its entry, write the new
//! value into the document, and keep the snippet of its entry in step with the text.

mod common;

use std::path::{Path, PathBuf};

/// A command whose output the documents quote.
struct Run {
    name: &'static str,
    /// Arguments of `indentify`, run in a fresh folder that sees `examples/`; `OUT` is the
    /// report folder, whose result.json the JSON fields read.
    args: &'static [&'static str],
    /// Minutes in a release build: checked by the xtask only.
    expensive: bool,
}

/// Where a run prints a number.
enum Field {
    /// A path into result.json: `iterations`, `fit_quality.r2`, `parameters[name=E].value`,
    /// `identifiability.std_dev.E`.
    Json(&'static str),
    /// The `nth` number (from 0) after the first occurrence of `after` in the run's
    /// standard output and error.
    Output { after: &'static str, nth: usize },
}

/// A number a document quotes.
struct Quote {
    doc: &'static str,
    /// The snippet as written in the document (runs of whitespace count as one space).
    text: &'static str,
    /// Which number of the snippet (from 0).
    nth: usize,
    run: &'static str,
    field: Field,
    /// The quoted number is the tool's times this (100 for a percentage of a fraction).
    scale: f64,
}

const RUNS: &[Run] = &[
    Run {
        name: "anon-maxwell",
        args: &[
            "identify",
            "examples/real/anon-maxwell.ron",
            "--out",
            "OUT",
            "--no-refine",
            "-q",
        ],
        expensive: false,
    },
    Run {
        name: "check-ht-nh",
        args: &["check", "examples/real/ht-nh.ron"],
        expensive: false,
    },
    Run {
        name: "anon-nh",
        args: &[
            "identify",
            "examples/real/anon-nh.ron",
            "--out",
            "OUT",
            "--no-refine",
            "-q",
        ],
        expensive: true,
    },
];

const TUTORIAL: &str = "docs/tutorial-real-data.md";
const DISCRETIZATION: &str = "docs/discretization.md";

/// `Quote` with scale 1.
const fn q(
    doc: &'static str,
    text: &'static str,
    nth: usize,
    run: &'static str,
    field: Field,
) -> Quote {
    Quote {
        doc,
        text,
        nth,
        run,
        field,
        scale: 1.0,
    }
}

const QUOTES: &[Quote] = &[
    // the Maxwell fit of the Berkovich record (tutorial §4, its sample pinned whole)
    Quote {
        scale: 100.0,
        ..q(
            TUTORIAL,
            "RMS residual of about 5% of F_max",
            0,
            "anon-maxwell",
            Field::Json("fit_quality.rms_rel"),
        )
    },
    q(
        TUTORIAL,
        "(the Maxwell fit's 1543.3)",
        0,
        "anon-maxwell",
        Field::Json("parameters[name=E].value"),
    ),
    q(
        DISCRETIZATION,
        "(BFGS, 8 iterations either way)",
        0,
        "anon-maxwell",
        Field::Json("iterations"),
    ),
    q(
        DISCRETIZATION,
        "E 1548.5 -> 1543.3 MPa",
        1,
        "anon-maxwell",
        Field::Json("parameters[name=E].value"),
    ),
    q(
        DISCRETIZATION,
        "eta 103568 -> 103783 MPa s",
        1,
        "anon-maxwell",
        Field::Json("parameters[name=eta].value"),
    ),
    // the sphere record's resampling (tutorial §6)
    q(
        TUTORIAL,
        "60 points: 21 / 22 / 16 steps on load / hold / unload",
        1,
        "check-ht-nh",
        Field::Output {
            after: "between knots",
            nth: 2,
        },
    ),
    q(
        TUTORIAL,
        "60 points: 21 / 22 / 16 steps on load / hold / unload",
        2,
        "check-ht-nh",
        Field::Output {
            after: "between knots",
            nth: 3,
        },
    ),
    q(
        TUTORIAL,
        "60 points: 21 / 22 / 16 steps on load / hold / unload",
        3,
        "check-ht-nh",
        Field::Output {
            after: "between knots",
            nth: 4,
        },
    ),
    // the Norton-Hoff fit of the Berkovich record with today's defaults (tutorial §5,
    // docs/discretization.md)
    q(
        TUTORIAL,
        "25 iterations, E = 1875.4 MPa",
        0,
        "anon-nh",
        Field::Json("iterations"),
    ),
    q(
        TUTORIAL,
        "25 iterations, E = 1875.4 MPa",
        1,
        "anon-nh",
        Field::Json("parameters[name=E].value"),
    ),
    q(
        TUTORIAL,
        "K = 152.0, m = 7.36",
        0,
        "anon-nh",
        Field::Json("parameters[name=K].value"),
    ),
    q(
        TUTORIAL,
        "K = 152.0, m = 7.36",
        1,
        "anon-nh",
        Field::Json("parameters[name=m].value"),
    ),
    q(
        TUTORIAL,
        "sY = 8.78 MPa undetermined",
        0,
        "anon-nh",
        Field::Json("parameters[name=sY].value"),
    ),
    q(
        TUTORIAL,
        "sY = 8.78 MPa undetermined, R² = 0.99715",
        1,
        "anon-nh",
        Field::Json("fit_quality.r2"),
    ),
    q(
        DISCRETIZATION,
        "E 1878.9 -> 1875.4 MPa",
        1,
        "anon-nh",
        Field::Json("parameters[name=E].value"),
    ),
    q(
        DISCRETIZATION,
        "K 156.9 -> 152.0, m 6.65 -> 7.36",
        1,
        "anon-nh",
        Field::Json("parameters[name=K].value"),
    ),
    q(
        DISCRETIZATION,
        "K 156.9 -> 152.0, m 6.65 -> 7.36",
        3,
        "anon-nh",
        Field::Json("parameters[name=m].value"),
    ),
    q(
        DISCRETIZATION,
        "R² 0.99716 -> 0.99715",
        1,
        "anon-nh",
        Field::Json("fit_quality.r2"),
    ),
    q(
        DISCRETIZATION,
        "19 iterations and 34 forward solves in 267 s -> 25 and 45",
        3,
        "anon-nh",
        Field::Json("iterations"),
    ),
    q(
        DISCRETIZATION,
        "19 iterations and 34 forward solves in 267 s -> 25 and 45",
        4,
        "anon-nh",
        Field::Json("forward_solves"),
    ),
];

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Runs of whitespace as one space.
fn collapse(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// The numbers written in `s`, in order, as written (`1875.4`, `-0.995`, `1.8e-08`; a
/// `²` or a letter ends a number, a digit glued to a letter, as in `R2`, is no number).
fn numbers(s: &str) -> Vec<&str> {
    let b = s.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let starts =
            b[i].is_ascii_digit() || (b[i] == b'-' && i + 1 < b.len() && b[i + 1].is_ascii_digit());
        let glued = i > 0 && (b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'.');
        if !starts || glued {
            i += 1;
            continue;
        }
        let start = i;
        i += 1;
        while i < b.len() && b[i].is_ascii_digit() {
            i += 1;
        }
        if i + 1 < b.len() && b[i] == b'.' && b[i + 1].is_ascii_digit() {
            i += 1;
            while i < b.len() && b[i].is_ascii_digit() {
                i += 1;
            }
        }
        if i + 1 < b.len()
            && (b[i] == b'e' || b[i] == b'E')
            && (b[i + 1].is_ascii_digit() || (b[i + 1] == b'-' && i + 2 < b.len()))
        {
            let mut j = i + 1;
            if b[j] == b'-' {
                j += 1;
            }
            if j < b.len() && b[j].is_ascii_digit() {
                while j < b.len() && b[j].is_ascii_digit() {
                    j += 1;
                }
                i = j;
            }
        }
        out.push(&s[start..i]);
    }
    out
}

/// Half a unit of the last digit written: `1875.4` -> 0.05, `25` -> 0.5, `1.8e-08` -> 5e-10.
fn half_unit(written: &str) -> f64 {
    let (mantissa, exp) = match written.find(['e', 'E']) {
        Some(k) => (&written[..k], written[k + 1..].parse::<i32>().unwrap_or(0)),
        None => (written, 0),
    };
    let decimals = mantissa.find('.').map_or(0, |k| mantissa.len() - k - 1) as i32;
    0.5 * 10f64.powi(exp - decimals)
}

/// Whether `value` prints as `written` at `written`'s precision (with a relative margin
/// of 1e-9 for the binary representation of the ends).
fn agrees(value: f64, written: &str) -> bool {
    let Ok(q) = written.parse::<f64>() else {
        return false;
    };
    (value - q).abs() <= half_unit(written) * (1.0 + 1e-9) + 1e-12 * q.abs()
}

/// The value at `path` in `v` (see [`Field::Json`]).
fn json_at(v: &serde_json::Value, path: &str) -> Option<f64> {
    let mut cur = v;
    for seg in path.split('.') {
        let (key, select) = match seg.find('[') {
            Some(k) => (&seg[..k], Some(seg[k + 1..].trim_end_matches(']'))),
            None => (seg, None),
        };
        cur = cur.get(key)?;
        match select {
            None => {}
            Some(sel) => match sel.split_once('=') {
                Some((field, want)) => {
                    cur = cur
                        .as_array()?
                        .iter()
                        .find(|e| e.get(field).and_then(|x| x.as_str()) == Some(want))?;
                }
                None => cur = cur.get(sel.parse::<usize>().ok()?)?,
            },
        }
    }
    cur.as_f64()
}

/// The output of one run: its standard output and error, and its result.json if any.
struct Printed {
    text: String,
    json: Option<serde_json::Value>,
}

fn run(r: &Run) -> Printed {
    let dir = tempfile::tempdir().unwrap();
    std::os::unix::fs::symlink(root().join("examples"), dir.path().join("examples")).unwrap();
    let out = dir.path().join("out");
    let args: Vec<String> = r
        .args
        .iter()
        .map(|a| {
            if *a == "OUT" {
                out.display().to_string()
            } else {
                a.to_string()
            }
        })
        .collect();
    let o = common::indentify_in(dir.path(), &args);
    // an undetermined parameter ends with exit status 3: its numbers are still printed
    assert!(
        o.status.success() || o.status.code() == Some(3),
        "{}: indentify {} failed: {}",
        r.name,
        r.args.join(" "),
        common::stderr(&o)
    );
    let json = std::fs::read_to_string(out.join("result.json"))
        .ok()
        .map(|s| serde_json::from_str(&s).unwrap());
    Printed {
        text: format!("{}{}", common::stdout(&o), common::stderr(&o)),
        json,
    }
}

/// The tool's value of `field` in `p`.
fn value(p: &Printed, field: &Field) -> Option<f64> {
    match field {
        Field::Json(path) => json_at(p.json.as_ref()?, path),
        Field::Output { after, nth } => {
            let at = p.text.find(after)? + after.len();
            numbers(&p.text[at..]).get(*nth)?.parse().ok()
        }
    }
}

/// The quote's number as written, or why it cannot be found.
fn written(quote: &Quote) -> Result<String, String> {
    let doc = std::fs::read_to_string(root().join(quote.doc)).map_err(|e| e.to_string())?;
    let text = collapse(quote.text);
    if !collapse(&doc).contains(&text) {
        return Err(format!(
            "{}: the quoted text `{text}` is not in the document (edited? update the entry)",
            quote.doc
        ));
    }
    numbers(&text)
        .get(quote.nth)
        .map(|s| s.to_string())
        .ok_or_else(|| format!("{}: `{text}` has no number {}", quote.doc, quote.nth))
}

/// Runs the runs of the given cost and compares every quote of theirs.
fn check(expensive: bool) {
    let mut failures = Vec::new();
    let mut checked = 0;
    for r in RUNS.iter().filter(|r| r.expensive == expensive) {
        let printed = run(r);
        for quote in QUOTES.iter().filter(|q| q.run == r.name) {
            let shown = match written(quote) {
                Ok(s) => s,
                Err(e) => {
                    failures.push(e);
                    continue;
                }
            };
            let Some(v) = value(&printed, &quote.field) else {
                failures.push(format!(
                    "{}: `{}`: the run `{}` printed no such field",
                    quote.doc, quote.text, r.name
                ));
                continue;
            };
            let v = v * quote.scale;
            checked += 1;
            println!(
                "{}: `{}` quotes {shown}, the tool prints {v}",
                quote.doc, quote.text
            );
            if !agrees(v, &shown) {
                failures.push(format!(
                    "{}: `{}` quotes {shown}; `indentify {}` prints {v} today",
                    quote.doc,
                    quote.text,
                    r.args.join(" ")
                ));
            }
        }
    }
    assert!(checked > 0 || !failures.is_empty(), "no quote checked");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn quoted_numbers_are_parsed_and_compared_at_their_printed_precision() {
    assert_eq!(
        numbers("25 iterations, E = 1875.4 MPa, R² = 0.99715, R2 x, 1.8e-08 and -0.995"),
        ["25", "1875.4", "0.99715", "1.8e-08", "-0.995"]
    );
    assert_eq!(numbers("21 / 22 / 16 steps"), ["21", "22", "16"]);
    assert_eq!(numbers("[27, 10, 22] steps"), ["27", "10", "22"]);
    assert!(agrees(1875.43, "1875.4") && agrees(1875.449, "1875.4"));
    assert!(!agrees(1875.46, "1875.4") && !agrees(1901.4, "1875.4"));
    assert!(agrees(25.0, "25") && !agrees(22.0, "25"));
    assert!(agrees(1.83e-8, "1.8e-08") && !agrees(3.1e-3, "1.8e-08"));
    assert!(agrees(4.873, "5") && !agrees(5.6, "5"));
    let v: serde_json::Value = serde_json::json!({
        "iterations": 8,
        "parameters": [{"name": "E", "value": 1543.3488}, {"name": "eta", "value": 103783.2}],
        "identifiability": {"std_dev": {"E": 23.9}},
        "tests": [{"n": 60}],
    });
    assert_eq!(json_at(&v, "iterations"), Some(8.0));
    assert_eq!(json_at(&v, "parameters[name=eta].value"), Some(103783.2));
    assert_eq!(json_at(&v, "identifiability.std_dev.E"), Some(23.9));
    assert_eq!(json_at(&v, "tests[0].n"), Some(60.0));
    assert_eq!(json_at(&v, "parameters[name=K].value"), None);
}

/// Every entry names a run and finds its snippet and number in its document (no run).
#[test]
fn every_quote_is_in_its_document() {
    for quote in QUOTES {
        assert!(
            RUNS.iter().any(|r| r.name == quote.run),
            "{}: no run `{}`",
            quote.text,
            quote.run
        );
        if let Err(e) = written(quote) {
            panic!("{e}");
        }
    }
}

/// The quotes of runs that take at most a minute in a test build.
#[test]
fn cheap_quotes_match_the_tool() {
    check(false);
}

/// The quotes of the long runs (the anon-nh fit): `cargo xtask doc-numbers`.
#[test]
#[ignore]
fn expensive_quotes_match_the_tool() {
    check(true);
}
