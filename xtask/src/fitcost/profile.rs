//! `cargo xtask fit-cost --batch --profile`: where one batch indent's time goes. For a few
//! indents of the synthetic Maxwell map (the first of each phase), on one thread, the
//! stages a batch indent runs (`study::batch::run` -> `study::identify::run`), timed one by
//! one: loading and resolving the configuration, setting up the problem (mesh, schedule,
//! record, solver pattern), one cold forward run at the start (the unit), the fit (the
//! optimizer to its last iterate, with its solve counts), the identifiability summary after
//! it, and then the whole pipeline again as the batch runs it, whose remainder after the
//! last iterate is the start curve solved again and the files written (`result.json`,
//! `history.csv`, `fit.csv`, `status.json`). The batch's own work around the indents
//! (manifest, `results.csv`, the maps) is timed on a folder whose indents are all done.

use std::path::Path;
use std::time::Instant;

use anyhow::Result;
use indentify_identify::{Evaluator, IterationRecord};
use indentify_study::ConfigSource;
use indentify_study::batch::{self, BatchOptions};
use indentify_study::identify::{self, IdentifyOptions, Observer, RunInfo};
use indentify_study::synthetic::MapFiles;
use serde_json::{Value, json};

/// Timestamps of a run's observer callbacks (seconds since `clock`).
struct Stamps {
    clock: Instant,
    started: f64,
    iterations: Vec<f64>,
}

impl Observer for Stamps {
    fn started(&mut self, _info: &RunInfo) {
        self.started = self.clock.elapsed().as_secs_f64();
    }
    fn iteration(&mut self, _r: &IterationRecord) {
        self.iterations.push(self.clock.elapsed().as_secs_f64());
    }
}

/// The options `study::batch` gives indent `id` of `map` (record `records/<id>.csv`,
/// report folder `out/indents/<id>`), with `start` as its start overrides.
pub fn indent_options(
    map: &MapFiles,
    id: &str,
    out: &Path,
    starts: &[(String, f64)],
) -> IdentifyOptions {
    let dir = map.manifest.parent().unwrap_or(Path::new("."));
    let mut o = IdentifyOptions::new(ConfigSource::Path(map.base.clone()));
    o.data = Some(dir.join("records").join(format!("{id}.csv")));
    o.out = Some(out.join("indents").join(id));
    o.force = true;
    o.refine = false;
    o.figures = false;
    o.jobs = Some(1);
    o.overrides.starts = starts.to_vec();
    o
}

/// One indent's stages on the current (one-thread) pool.
fn stages(map: &MapFiles, id: &str, out: &Path, starts: &[(String, f64)]) -> Result<Value> {
    let opts = indent_options(map, id, out, starts);
    let clock = Instant::now();
    let resolved = identify::resolve(&opts)?;
    let t_resolve = clock.elapsed().as_secs_f64();
    let clock = Instant::now();
    let s = identify::setup(resolved, &opts)?;
    let t_setup = clock.elapsed().as_secs_f64();
    let start: Vec<f64> = s
        .id_cfg
        .params
        .iter()
        .map(|p| p.value.unwrap_or(0.0))
        .collect();
    // the unit: one cold forward run at the start (a fresh evaluator: pattern and
    // factorization set up inside)
    let clock = Instant::now();
    Evaluator::new(&s.problem)?.cost(&start)?;
    let t_forward = clock.elapsed().as_secs_f64();
    let clock = Instant::now();
    let mut last = 0.0;
    let r = indentify_identify::identify(&s.problem, &s.id_cfg, &mut |_| {
        last = clock.elapsed().as_secs_f64();
    })?;
    let t_fit_all = clock.elapsed().as_secs_f64();
    // the whole pipeline as the batch runs it (files included)
    let mut st = Stamps {
        clock: Instant::now(),
        started: 0.0,
        iterations: Vec::new(),
    };
    identify::run(&opts, &mut st)?;
    let t_run = st.clock.elapsed().as_secs_f64();
    let last_run = st.iterations.last().copied().unwrap_or(st.started);
    let identifiability = t_fit_all - last;
    Ok(json!({
        "id": id,
        "resolve_s": t_resolve,
        "setup_s": t_setup,
        "forward_s": t_forward,
        "fit_s": last,
        "identifiability_s": identifiability,
        "run_s": t_run,
        "run_setup_s": st.started,
        "run_fit_s": last_run - st.started,
        // after the last iterate: the identifiability summary, the start curve solved
        // again, the files
        "run_tail_s": t_run - last_run,
        "run_tail_less_identifiability_s": t_run - last_run - identifiability,
        "iterations": r.iterations,
        "forward_solves": r.forward_solves,
        "sensitivity_solves": r.sensitivity_solves,
        "adjoint_solves": r.adjoint_solves,
        "rejected_trials": r.rejected_trials,
        "newton_iterations": r.newton_iterations,
        "factorizations": r.factorizations,
        "stop": r.stop_reason.to_string(),
    }))
}

/// The stages of the first indent of each phase of `map`, on one thread, from the base
/// start and (when given) from `starts` (per id: the start overrides of the after case);
/// and the batch's own work around the indents.
pub fn measure(
    map: &MapFiles,
    dir: &Path,
    starts: &dyn Fn(&str) -> Vec<(String, f64)>,
) -> Result<Value> {
    let out = dir.join("out-profile");
    let _ = std::fs::remove_dir_all(&out);
    let mut ids: Vec<&str> = Vec::new();
    for phase in ['A', 'B'] {
        if let Some((id, ..)) = map.indents.iter().find(|i| i.3 == phase) {
            ids.push(id);
        }
    }
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    let mut rows = Vec::new();
    for id in &ids {
        for (case, st) in [("base start", Vec::new()), ("manifest start", starts(id))] {
            if case == "manifest start" && st.is_empty() {
                continue;
            }
            let mut v = pool.install(|| stages(map, id, &out, &st))?;
            v["case"] = json!(case);
            rows.push(v);
        }
    }
    // the batch around its indents: every indent of a 1-row manifest already done
    let manifest = dir.join("manifest-profile.csv");
    let text = std::fs::read_to_string(&map.manifest)?;
    let keep: Vec<&str> = text
        .lines()
        .enumerate()
        .filter(|(k, l)| *k == 0 || ids.iter().any(|id| l.starts_with(&format!("{id},"))))
        .map(|(_, l)| l)
        .collect();
    std::fs::write(&manifest, keep.join("\n") + "\n")?;
    let bout = dir.join("out-profile-batch");
    let _ = std::fs::remove_dir_all(&bout);
    let mut o = BatchOptions::new(manifest, bout);
    o.config = Some(map.base.clone());
    o.jobs = 1;
    let clock = Instant::now();
    batch::run(&o, &())?;
    let first = clock.elapsed().as_secs_f64();
    let clock = Instant::now();
    batch::run(&o, &())?;
    let again = clock.elapsed().as_secs_f64();
    Ok(json!({
        "indents": rows,
        "batch_with_indents_s": first,
        "batch_all_done_s": again,
        "batch_indents": ids.len(),
    }))
}

/// The table of [`measure`]'s result: each stage in seconds and in forward runs.
pub fn table(m: &Value) -> String {
    let mut s = String::from(
        "| indent | start | resolve | set-up | forward (unit) | fit | identifiability | pipeline: set-up | fit | after the fit | iterations | forward solves | sensitivity solves | rejected | stop |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    let empty = Vec::new();
    for r in m["indents"].as_array().unwrap_or(&empty) {
        let f = |k: &str| r[k].as_f64().unwrap_or(f64::NAN);
        let u = f("forward_s");
        let cell = |k: &str| format!("{:.3} s ({:.2})", f(k), f(k) / u);
        s.push_str(&format!(
            "| {} | {} | {} | {} | {:.3} s | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            r["id"].as_str().unwrap_or(""),
            r["case"].as_str().unwrap_or(""),
            cell("resolve_s"),
            cell("setup_s"),
            u,
            cell("fit_s"),
            cell("identifiability_s"),
            cell("run_setup_s"),
            cell("run_fit_s"),
            cell("run_tail_s"),
            r["iterations"],
            r["forward_solves"],
            r["sensitivity_solves"],
            r["rejected_trials"],
            r["stop"].as_str().unwrap_or(""),
        ));
    }
    s.push_str(&format!(
        "(in brackets: forward runs; the batch around its {} indents: {:.3} s with them, {:.3} s \
         with all done: manifest, results.csv, maps)\n",
        m["batch_indents"],
        m["batch_with_indents_s"].as_f64().unwrap_or(f64::NAN),
        m["batch_all_done_s"].as_f64().unwrap_or(f64::NAN),
    ));
    s
}
