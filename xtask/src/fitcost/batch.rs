//! `cargo xtask fit-cost --batch`: the 100 indents of the synthetic R1 Maxwell map of
//! `cargo xtask make-map` (10 x 10, 2% noise) identified through the study's batch path
//! (`indentify batch`: `study::batch::run`) on `--jobs` threads (2 by default), back to
//! back in one process: from the base configuration's start (the map's manifest); with
//! `--op`, from each row's Oliver-Pharr first guess where the analysis gives one (manifest
//! columns `identify.params.*.start` computed here once); from each row's closed-form start
//! with its own calibration run (what `indentify batch --start closed-form` runs); from
//! the closed-form starts seeded per configuration (`study::batch_seed`,
//! `BatchOptions::seeded`); each start with the stop on the proposed step off and on (a
//! manifest column `identify.stop.proposed_step`, false or true on every row), the run with
//! it on compared with the same start's run without it. Printed: the time (the starts' computation included),
//! throughput, iterations, convergence and every parameter's shift in standard deviations
//! against the base start. `--profile`: one indent of each phase stage by stage
//! (`profile.rs`).

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Result;
use indentify_study::batch::{self, BatchOptions};
use indentify_study::synthetic::{MapFiles, MapOptions, make_map};
use serde_json::{Value, json};
use xtask::batch_start::{closed_form_start, start_manifest};

/// One batch of `manifest` into a fresh `out` on `jobs` threads: its wall time and every
/// indent's status.
fn run_batch(
    map: &MapFiles,
    manifest: &Path,
    out: &Path,
    jobs: usize,
    closed_form: bool,
    seeded: bool,
) -> Result<(f64, Vec<batch::IndentStatus>)> {
    let _ = std::fs::remove_dir_all(out);
    let mut o = BatchOptions::new(manifest.to_path_buf(), out.to_path_buf());
    o.config = Some(map.base.clone());
    o.jobs = jobs;
    o.closed_form_start = closed_form;
    o.seeded = seeded;
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

/// Converged indents and LM iterations of a batch.
fn summary(st: &[batch::IndentStatus]) -> (usize, usize) {
    let conv = st
        .iter()
        .filter(|s| s.state == batch::State::Converged)
        .count();
    (conv, st.iter().map(|s| s.iterations).sum())
}

/// Every free parameter's shift `|after - before| / sigma` (after's sigma): the largest
/// and the mean.
fn shifts(before: &[batch::IndentStatus], after: &[batch::IndentStatus]) -> (f64, f64) {
    let mut worst: f64 = 0.0;
    let mut mean = 0.0;
    let mut count = 0usize;
    for (b, a) in before.iter().zip(after) {
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
    (
        worst,
        if count > 0 {
            mean / count as f64
        } else {
            f64::NAN
        },
    )
}

/// One case's row: its time (its starts' computation included), throughput, iterations
/// and shifts against `before`.
fn case_row(
    name: &str,
    seconds: f64,
    starts_s: f64,
    started: usize,
    st: &[batch::IndentStatus],
    before: &[batch::IndentStatus],
    before_s: f64,
) -> Value {
    let (conv, its) = summary(st);
    let (worst, mean) = shifts(before, st);
    let total = seconds + starts_s;
    json!({
        "case": name,
        "batch_s": seconds,
        "starts_s": starts_s,
        "started": started,
        "seconds": total,
        "per_s": st.len() as f64 / total,
        "throughput_ratio": before_s / total,
        "converged": conv,
        "iterations": its,
        "max_shift_sigma": worst,
        "mean_shift_sigma": mean,
    })
}

/// `map`'s manifest with the column `identify.stop.proposed_step` = `on` on every row
/// (`StopCriteria::proposed_step`), written to `out`.
fn proposed_step_manifest(map: &MapFiles, out: &Path, on: bool) -> Result<PathBuf> {
    let text = std::fs::read_to_string(&map.manifest)?;
    let mut s = String::new();
    for (k, line) in text.lines().enumerate() {
        s.push_str(line);
        s.push_str(if k == 0 {
            ",identify.stop.proposed_step\n"
        } else {
            if on { ",true\n" } else { ",false\n" }
        });
    }
    std::fs::write(out, s)?;
    Ok(out.to_path_buf())
}

/// `row` (a case with the stop on the proposed step) with its shifts against `off`, the
/// same start's batch without the rule, and the indents whose state differs.
fn against_off(mut row: Value, st: &[batch::IndentStatus], off: &[batch::IndentStatus]) -> Value {
    let (worst, mean) = shifts(off, st);
    row["max_shift_vs_off"] = json!(worst);
    row["mean_shift_vs_off"] = json!(mean);
    row["state_changes"] = json!(
        st.iter()
            .zip(off)
            .filter(|(a, b)| a.state != b.state)
            .count()
    );
    row
}

/// Rows whose status names a start containing `what`.
fn started(st: &[batch::IndentStatus], what: &str) -> usize {
    st.iter()
        .filter(|s| s.start.as_deref().is_some_and(|t| t.contains(what)))
        .count()
}

/// `--batch`: before and after on `jobs` threads, a map of `n x n` indents: every indent
/// from the base start (before); with `op`, from its Oliver-Pharr first guess where the
/// analysis gives one (run only if some row has one); from its closed-form start with its
/// own calibration run (`indentify batch --start closed-form`); seeded by its
/// configuration's first indent (`BatchOptions::seeded`). The base, closed-form and seeded
/// starts each without and with `identify.stop.proposed_step` (a manifest column), the
/// run with it compared with the one without it.
pub fn measure(jobs: usize, n: usize, op: bool) -> Result<Value> {
    let dir = std::env::temp_dir().join("indentify-fit-cost-batch");
    let _ = std::fs::remove_dir_all(&dir);
    let map = make_map(
        &dir,
        &MapOptions {
            n,
            ..Default::default()
        },
    )?;
    let off = proposed_step_manifest(&map, &dir.join("manifest-off.csv"), false)?;
    let on = proposed_step_manifest(&map, &dir.join("manifest-on.csv"), true)?;
    let (tb, before) = run_batch(&map, &off, &dir.join("out-before"), jobs, false, false)?;
    let mut cases = vec![case_row("base start", tb, 0.0, 0, &before, &before, tb)];
    let (t, st) = run_batch(&map, &on, &dir.join("out-base-on"), jobs, false, false)?;
    let row = case_row("base start + proposed_step", t, 0.0, 0, &st, &before, tb);
    cases.push(against_off(row, &st, &before));
    let (mut guessed, mut guess_s) = (0, 0.0);
    if op {
        let clock = Instant::now();
        let (op_manifest, g) = start_manifest(&map, &dir.join("manifest-op-start.csv"))?;
        guess_s = clock.elapsed().as_secs_f64();
        guessed = g;
        if guessed > 0 {
            let (ta, after) =
                run_batch(&map, &op_manifest, &dir.join("out-op"), jobs, false, false)?;
            cases.push(case_row(
                "O&P first guess",
                ta,
                guess_s,
                guessed,
                &after,
                &before,
                tb,
            ));
        } else {
            eprintln!("no row has an O&P first guess: that batch would repeat the base one");
        }
    }
    // each closed-form start without the rule, then with it
    for (name, seeded, what) in [
        (
            "closed-form start, own calibration (batch --start closed-form)",
            false,
            "closed form",
        ),
        (
            "closed-form start seeded per configuration (BatchOptions::seeded)",
            true,
            "seeded by",
        ),
    ] {
        let tag = if seeded { "seeded" } else { "closed-form" };
        let (t, st_off) = run_batch(
            &map,
            &off,
            &dir.join(format!("out-{tag}")),
            jobs,
            true,
            seeded,
        )?;
        let started_off = started(&st_off, what);
        cases.push(case_row(name, t, 0.0, started_off, &st_off, &before, tb));
        let (t, st) = run_batch(
            &map,
            &on,
            &dir.join(format!("out-{tag}-on")),
            jobs,
            true,
            seeded,
        )?;
        let row = case_row(
            &format!("{name} + proposed_step"),
            t,
            0.0,
            started(&st, what),
            &st,
            &before,
            tb,
        );
        cases.push(against_off(row, &st, &st_off));
    }
    Ok(json!({
        "indents": map.indents.len(),
        "jobs": jobs,
        "op_guessed": guessed,
        "op_guess_s": guess_s,
        "cases": cases,
    }))
}

/// `--batch --profile`: one indent of each phase of an `n x n` map, stage by stage, from
/// the base start and from its closed-form start (its calibration run timed apart).
pub fn profile(n: usize) -> Result<Value> {
    let dir = std::env::temp_dir().join("indentify-fit-cost-batch-profile");
    let _ = std::fs::remove_dir_all(&dir);
    let map = make_map(
        &dir,
        &MapOptions {
            n,
            ..Default::default()
        },
    )?;
    let seconds = std::cell::Cell::new(0.0);
    let starts = |id: &str| match closed_form_start(&map, id) {
        Ok(c) => {
            eprintln!("{id}: {} in {:.3} s", c.summary(), c.seconds);
            seconds.set(seconds.get() + c.seconds);
            c.values
        }
        Err(e) => {
            eprintln!("{id}: no closed-form start: {e:#}");
            Vec::new()
        }
    };
    let mut m = super::profile::measure(&map, &dir, &starts)?;
    m["closed_form_start_s"] = json!(seconds.get());
    Ok(m)
}

/// The table of [`measure`]'s result.
pub fn table(m: &Value) -> String {
    let mut s = format!(
        "{} indents on {} threads\n\n| start | seconds (starts included) | starts (s) | rows started | indents/s | throughput / base | converged | LM iterations | max abs(shift) / sigma | mean | against the same start without proposed_step: max | mean | states changed |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
        m["indents"], m["jobs"]
    );
    let empty = Vec::new();
    for c in m["cases"].as_array().unwrap_or(&empty) {
        let f = |k: &str| c[k].as_f64().unwrap_or(f64::NAN);
        s.push_str(&format!(
            "| {} | {:.1} | {:.2} | {} | {:.3} | {:.2} | {} | {} | {:.3} | {:.3} | {:.3} | {:.3} | {} |\n",
            c["case"].as_str().unwrap_or(""),
            f("seconds"),
            f("starts_s"),
            c["started"],
            f("per_s"),
            f("throughput_ratio"),
            c["converged"],
            c["iterations"],
            f("max_shift_sigma"),
            f("mean_shift_sigma"),
            f("max_shift_vs_off"),
            f("mean_shift_vs_off"),
            c["state_changes"].as_u64().map_or("-".into(), |v| v.to_string()),
        ));
    }
    s
}
