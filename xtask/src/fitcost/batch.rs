//! `cargo xtask fit-cost --batch`: the 100 indents of the synthetic R1 Maxwell map of
//! `cargo xtask make-map` (10 x 10, 2% noise) identified through the study's batch path
//! (`indentify batch`: `study::batch::run`) on `--jobs` threads (2 by default), before
//! (the map's manifest: every indent from the base configuration's start) and after (a
//! manifest whose rows start from their own record's Oliver-Pharr first guess, the
//! `identify.params.*.start` columns computed here once, so an indent's start is fixed by
//! the manifest whatever the thread count), back to back: throughput, iterations,
//! convergence and each parameter's shift in standard deviations.

use std::path::Path;
use std::time::Instant;

use anyhow::Result;
use indentify_study::batch::{self, BatchOptions};
use indentify_study::synthetic::{MapFiles, MapOptions, make_map};
use serde_json::{Value, json};
use xtask::batch_start::start_manifest;

/// One batch of `manifest` into a fresh `out` on `jobs` threads: its wall time and every
/// indent's status.
fn run_batch(
    map: &MapFiles,
    manifest: &Path,
    out: &Path,
    jobs: usize,
) -> Result<(f64, Vec<batch::IndentStatus>)> {
    let _ = std::fs::remove_dir_all(out);
    let mut o = BatchOptions::new(manifest.to_path_buf(), out.to_path_buf());
    o.config = Some(map.base.clone());
    o.jobs = jobs;
    let clock = Instant::now();
    batch::run(&o, &())?;
    let seconds = clock.elapsed().as_secs_f64();
    let statuses = map
        .indents
        .iter()
        .filter_map(|(id, ..)| batch::read_status(out, id))
        .collect();
    Ok((seconds, statuses))
}

/// `--batch`: before and after on `jobs` threads, a map of `n x n` indents.
pub fn measure(jobs: usize, n: usize) -> Result<Value> {
    let dir = std::env::temp_dir().join("indentify-fit-cost-batch");
    let _ = std::fs::remove_dir_all(&dir);
    let map = make_map(
        &dir,
        &MapOptions {
            n,
            ..Default::default()
        },
    )?;
    let clock = Instant::now();
    let (op_manifest, guessed) = start_manifest(&map, &dir.join("manifest-op-start.csv"))?;
    let guess_s = clock.elapsed().as_secs_f64();
    let (tb, before) = run_batch(&map, &map.manifest, &dir.join("out-before"), jobs)?;
    // without a single guess the after manifest is the before one: not run again
    let (ta, after) = if guessed > 0 {
        run_batch(&map, &op_manifest, &dir.join("out-after"), jobs)?
    } else {
        eprintln!("no row has an O&P first guess: the after batch would repeat the before one");
        (tb, before.clone())
    };
    let summary = |st: &[batch::IndentStatus]| {
        let conv = st
            .iter()
            .filter(|s| s.state == batch::State::Converged)
            .count();
        let its: usize = st.iter().map(|s| s.iterations).sum();
        (conv, its)
    };
    let (cb, ib) = summary(&before);
    let (ca, ia) = summary(&after);
    // every free parameter's shift, |after - before| / sigma (after's sigma)
    let mut worst: f64 = 0.0;
    let mut mean = 0.0;
    let mut count = 0usize;
    for (b, a) in before.iter().zip(&after) {
        for k in 0..a.values.len() {
            if !a.free.get(k).copied().unwrap_or(false) {
                continue;
            }
            let sd = a.std_dev.get(k).copied().flatten().unwrap_or(f64::NAN);
            let (va, vb) = (a.values[k], b.values.get(k).copied().unwrap_or(f64::NAN));
            let z = (va - vb).abs() / sd;
            if z.is_finite() {
                worst = worst.max(z);
                mean += z;
                count += 1;
            }
        }
    }
    let indents = map.indents.len();
    Ok(json!({
        "indents": indents,
        "jobs": jobs,
        "guessed": guessed,
        "guess_s": guess_s,
        "before_s": tb,
        "after_s": ta + guess_s,
        "before_per_s": indents as f64 / tb,
        "after_per_s": indents as f64 / (ta + guess_s),
        "throughput_ratio": tb / (ta + guess_s),
        "converged_before": cb,
        "converged_after": ca,
        "iterations_before": ib,
        "iterations_after": ia,
        "max_shift_sigma": worst,
        "mean_shift_sigma": if count > 0 { mean / count as f64 } else { f64::NAN },
    }))
}

/// The table of [`measure`]'s result.
pub fn table(m: &Value) -> String {
    let f = |k: &str| m[k].as_f64().unwrap_or(f64::NAN);
    format!(
        "| indents | jobs | before (s) | after (s, guesses included) | indents/s before | after | throughput after / before | converged before | after | LM iterations before | after | max abs(shift) / sigma | mean |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|---|\n\
         | {} | {} | {:.1} | {:.1} | {:.2} | {:.2} | {:.2} | {} | {} | {} | {} | {:.3} | {:.3} |\n\
         ({} of the rows start from their O&P guess, computed in {:.2} s)\n",
        m["indents"],
        m["jobs"],
        f("before_s"),
        f("after_s"),
        f("before_per_s"),
        f("after_per_s"),
        f("throughput_ratio"),
        m["converged_before"],
        m["converged_after"],
        m["iterations_before"],
        m["iterations_after"],
        f("max_shift_sigma"),
        f("mean_shift_sigma"),
        m["guessed"],
        f("guess_s"),
    )
}
