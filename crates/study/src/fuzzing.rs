//! Configuration fuzzing, shared by `cargo xtask fuzz-configs` and a fast test: RON texts
//! mutated (spans deleted, lines repeated, numbers replaced by extreme or malformed values,
//! bytes inserted, text cut short) and random `--set` overrides, each run through loading,
//! validation, set-up and, when small enough, a simulation. Any outcome is fine but a panic
//! or a non-finite force.

use std::panic::{AssertUnwindSafe, catch_unwind};

use indentify_identify::SplitMix64;

use crate::config::Reference;
use crate::simulate::{self, SimulateOptions};
use crate::source::ConfigSource;

/// Values that break numbers and fields.
const NASTY: [&str; 22] = [
    "0",
    "-1",
    "1e308",
    "-1e308",
    "NaN",
    "inf",
    "-inf",
    "1e-320",
    "18446744073709551616",
    "-0",
    "1e999",
    "abc",
    "\"\"",
    "()",
    "[]",
    "0.5",
    "2000",
    "1",
    "3",
    "0.49999",
    "1e-9",
    "true",
];

/// How the cases ended.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FuzzCounts {
    /// Cases run.
    pub cases: usize,
    /// Refused with a configuration error (syntax, field, range, set-up).
    pub config_errors: usize,
    /// Refused with a data error.
    pub data_errors: usize,
    /// Set up, simulation failed with a clear error (a step failing after cuts is an `Ok`
    /// outcome with its failure stated, counted in `simulated`).
    pub solver_errors: usize,
    /// Simulated (possibly stopping early with its failure stated).
    pub simulated: usize,
    /// Valid, but too large to simulate within the per-case budget.
    pub too_large: usize,
    /// Panics: must be 0.
    pub panics: usize,
    /// Simulations that returned a non-finite force: must be 0.
    pub non_finite: usize,
}

/// A mutated configuration and its overrides.
#[derive(Clone, Debug)]
pub struct Case {
    /// RON text.
    pub text: String,
    /// `--set` overrides.
    pub sets: Vec<String>,
}

fn pick<'a, T>(rng: &mut SplitMix64, v: &'a [T]) -> &'a T {
    &v[(rng.next_u64() % v.len() as u64) as usize]
}

/// Dotted paths of every scalar of a JSON value (`law.Maxwell.E`, `history.segments.0.steps`).
fn scalar_paths(v: &serde_json::Value, prefix: &str, out: &mut Vec<String>) {
    let join = |k: &str| {
        if prefix.is_empty() {
            k.to_string()
        } else {
            format!("{prefix}.{k}")
        }
    };
    match v {
        serde_json::Value::Object(m) => {
            for (k, x) in m {
                scalar_paths(x, &join(k), out);
            }
        }
        serde_json::Value::Array(a) => {
            for (k, x) in a.iter().enumerate() {
                scalar_paths(x, &join(&k.to_string()), out);
            }
        }
        _ => out.push(prefix.to_string()),
    }
}

/// The `seed`-th case: a reference template, mutated.
pub fn case(seed: u64) -> Case {
    let mut rng = SplitMix64::new(seed);
    let reference = *pick(&mut rng, &Reference::ALL);
    let mut text = crate::templates::template(reference);
    // keep cases small: a coarse mesh and few steps, unless a mutation undoes it
    let mut sets = vec![
        "specimen.nr=4".to_string(),
        "specimen.nz=4".to_string(),
        "history.segments.0.steps=3".to_string(),
        "history.segments.1.steps=3".to_string(),
        "history.segments.2.steps=3".to_string(),
    ];
    let mutations = 1 + rng.next_u64() % 3;
    for _ in 0..mutations {
        if text.is_empty() {
            break;
        }
        match rng.next_u64() % 8 {
            0 => {
                // delete a span
                let n = text.len();
                let a = (rng.next_u64() as usize) % n;
                let b = (a + 1 + (rng.next_u64() as usize) % 40).min(n);
                let (a, b) = (floor_char(&text, a), floor_char(&text, b));
                text.replace_range(a..b, "");
            }
            1 => {
                // repeat a line
                let lines: Vec<&str> = text.lines().collect();
                let k = (rng.next_u64() as usize) % lines.len();
                let mut v: Vec<String> = lines.iter().map(|s| s.to_string()).collect();
                v.insert(k, lines[k].to_string());
                text = v.join("\n");
            }
            2 | 3 => {
                // replace a number
                let starts: Vec<usize> = text
                    .char_indices()
                    .filter(|(i, c)| {
                        c.is_ascii_digit()
                            && (*i == 0 || !text.as_bytes()[i - 1].is_ascii_alphanumeric())
                    })
                    .map(|(i, _)| i)
                    .collect();
                if let Some(&a) = starts.get((rng.next_u64() as usize) % starts.len().max(1)) {
                    let b = a + text[a..]
                        .find(|c: char| !(c.is_ascii_alphanumeric() || c == '.' || c == '-'))
                        .unwrap_or(text.len() - a);
                    let v: &&str = pick(&mut rng, &NASTY);
                    text.replace_range(a..b, v);
                }
            }
            4 => {
                // insert a byte: a control character, a quote, a bracket, a non-ASCII letter
                let k = floor_char(&text, (rng.next_u64() as usize) % text.len());
                let c = *pick(
                    &mut rng,
                    &['\u{1}', '\u{7f}', '"', '(', ')', ',', ':', 'é', '\t'],
                );
                text.insert(k, c);
            }
            5 => {
                // cut short
                let k = floor_char(&text, (rng.next_u64() as usize) % text.len());
                text.truncate(k);
            }
            _ => {
                // a random --set
                let value = crate::config::parse(&text, "fuzz")
                    .ok()
                    .and_then(|c| serde_json::to_value(&c).ok());
                if let Some(v) = value {
                    let mut paths = Vec::new();
                    scalar_paths(&v, "", &mut paths);
                    paths.push("no.such.path".into());
                    let p = pick(&mut rng, &paths).clone();
                    sets.push(format!("{p}={}", pick(&mut rng, &NASTY)));
                }
            }
        }
    }
    Case { text, sets }
}

fn floor_char(s: &str, mut i: usize) -> usize {
    i = i.min(s.len());
    while !s.is_char_boundary(i) {
        i -= 1;
    }
    i
}

/// Runs one case: load, set up, and simulate when the model is small (at most `max_nodes`
/// nodes and `max_steps` steps).
pub fn run_case(c: &Case, max_nodes: usize, max_steps: usize, counts: &mut FuzzCounts) {
    counts.cases += 1;
    let outcome = catch_unwind(AssertUnwindSafe(|| {
        let source = ConfigSource::Text {
            text: c.text.clone(),
            name: "fuzz.ron".into(),
        };
        let cfg = match source.load(&c.sets) {
            Ok(cfg) => cfg,
            Err(e) => return Err(e.kind()),
        };
        let prepared = crate::identify::prepare(&cfg, "fuzz").map_err(|e| e.kind())?;
        if prepared.model.mesh.nodes.len() > max_nodes || prepared.schedule.n_steps() > max_steps {
            return Ok(None);
        }
        let mut opts = SimulateOptions::new(source);
        opts.sets = c.sets.clone();
        let o = simulate::run(&opts).map_err(|e| e.kind())?;
        Ok(Some(
            o.rows.iter().all(|r| r.f.is_finite() && r.a.is_finite()),
        ))
    }));
    match outcome {
        Err(_) => counts.panics += 1,
        Ok(Err(crate::ErrorKind::Config)) => counts.config_errors += 1,
        Ok(Err(crate::ErrorKind::Data)) => counts.data_errors += 1,
        Ok(Err(_)) => counts.solver_errors += 1,
        Ok(Ok(None)) => counts.too_large += 1,
        Ok(Ok(Some(finite))) => {
            counts.simulated += 1;
            if !finite {
                counts.non_finite += 1;
            }
        }
    }
}

/// Runs cases `first .. first + n`.
pub fn run(first: u64, n: usize) -> FuzzCounts {
    let mut counts = FuzzCounts::default();
    for k in 0..n as u64 {
        run_case(&case(first + k), 2000, 200, &mut counts);
    }
    counts
}
