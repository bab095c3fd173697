//! `cargo xtask fit-cost`: the cost of a whole identification in forward runs of the same
//! configuration, on one thread. For each case (R2 with Levenberg-Marquardt, the real
//! records ht-nh, anon-nh and the 4-test joint ht-nh, one indent of the synthetic R1
//! Maxwell map) it times forward runs at the start (a warm-up, then `rounds` runs at new
//! points, before and again after the fit: back to back), then the fit itself (the
//! optimizer and its final identifiability summary, as `indentify identify` runs it,
//! without the discretization check or the report), and prints the fit's wall time over
//! the median forward run (also in CPU time, `/proc/self/stat`, which the machine's load
//! moves less) with the iterations, the forward, adjoint and sensitivity solves,
//! the rejected Levenberg-Marquardt trials (forward solves spent without progress), the
//! forward runs' Newton iterations and factorizations, and the stop reason. The fit's
//! forward runs are warm started from the accepted point's trajectory
//! (`Problem::set_warm_start`); `--cold` starts every one cold, for before/after counts
//! (the timed forward runs are always cold). `--json FILE` keeps the numbers and the fitted parameters with
//! their standard deviations; `--compare FILE` adds, for each case of an earlier `--json`
//! (another version of the code), the ratio before and after and every parameter's shift
//! in standard deviations, `|after - before| / sigma`. `--batch` times the
//! 100-indent map through the batch path (`batch.rs`: throughput from the base start, from
//! each row's Oliver-Pharr first guess and from its closed-form start (`batch --start closed-form`), `--jobs N` threads,
//! 2 by default; `--profile`: one indent's stages timed, `profile.rs`).
//! `--no-chi2` turns the chi-square stop of fits with an undetermined parameter off
//! (`StopCriteria::chi2_stop`), for before/after counts; `--valley` turns the stop along an
//! undetermined valley on (`StopCriteria::valley_stop`, `--valley-steps N`,
//! `--valley-chi2 X` its settings); `--columns` times a sensitivity
//! pass of every parameter against one of the free ones (`columns.rs`). `--lm-radius R`,
//! `--line-model` and `--geodesic` set the Levenberg-Marquardt strategy of the fits
//! (`StopCriteria::lm`: the first damping from the Gauss-Newton step's length, rejected
//! trials shortened by the quadratic line model, geodesic acceleration), for before/after
//! counts; `--lm-radius 0` turns the first radius off where the configuration sets one.
//! `--lm-subspace` adds the steps in the determined subspace while a parameter is
//! undetermined (`LmStrategy::subspace`); `--compare` then also prints each parameter's
//! 2-sigma interval before and after and whether each end point lies inside the other's.
//! `--c2f N` runs each fit coarse to fine (`study::coarse_to_fine`: at most N iterations
//! on the 2x coarser model, then the full-fidelity fit from its optimum); the fit's time
//! then includes the coarse phase, and the coarse phase's iterations and solves are
//! printed beside the fine ones (`--c2f-tight`: the coarse phase without the statistical
//! stops, to its own gradient or relative-decrease stop; `--c2f-space F` the coarse mesh F x
//! coarser instead of 2x, 1 the fine mesh; `--c2f-keep-time` the fine time grid;
//! `--c2f-correct K` K output corrections after the coarse fit, each a fine forward run at
//! its end point and a coarse fit of the targets corrected by the discrepancy there).
//! `--proposed-step` fits each case with the stop on the
//! proposed step and, where it fired, without it, back to back, and prints every
//! parameter's shift in standard deviations and both outcomes (`propstep.rs`; without
//! `--only` the further Levenberg-Marquardt examples too; `--both` makes the run without
//! it also where it did not fire); `--no-proposed-step` turns it off for the other modes.
//! Each fit also prints the schedule steps its forward runs ran, the rejected trials'
//! runs stopped early (`LmStrategy::stop_rejected`, on in configurations) and the steps
//! they skipped; `--no-stop-rejected` runs every trial in full, for before/after counts.
//! `--lm-damping NAME` sets Levenberg-Marquardt's damping update on top of the
//! configuration's strategy (`classic`, `nielsen`, `marquardt-fletcher`, `gain-capped`,
//! `delayed`: `LmStrategy::damping`), for before/after counts and shifts.

mod batch;
mod columns;
mod profile;
mod propstep;

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use indentify_identify::{Evaluator, IdentifyResult, LmDamping, LmStrategy, ValleyStop};
use indentify_study::ConfigSource;
use indentify_study::identify::{self, IdentifyOptions};
use serde_json::{Value, json};

/// `--valley-steps N` or `--valley-chi2 X` (`a`) with its value: the valley stop's
/// settings (the stop turned on).
fn valley_option(valley: &mut Option<ValleyStop>, a: &str, v: &str) -> Result<()> {
    let rule = valley.get_or_insert_with(ValleyStop::default);
    if a == "--valley-steps" {
        rule.steps = v.parse().context("--valley-steps: a number >= 1")?;
    } else {
        rule.chi2 = v
            .parse()
            .context("--valley-chi2: a chi-square decrease > 0")?;
    }
    Ok(())
}

/// `--c2f-tight`: the coarse phase without the statistical stops (`step_sigma`,
/// `proposed_step`), to its own gradient or relative-decrease stop.
static C2F_TIGHT: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// `--lm-subspace`: Levenberg-Marquardt's steps in the determined subspace while a
/// parameter is undetermined (`LmStrategy::subspace`), on top of the configuration's or
/// the options' strategy.
static LM_SUBSPACE: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// `--c2f N` with `--c2f-space F`, `--c2f-keep-time` and `--c2f-correct K`: at most N
/// coarse iterations on the model F x coarser in space (and 2x in time unless kept), then
/// K output corrections (`coarse_to_fine::coarse_phase_corrected`).
#[derive(Clone, Copy, Debug)]
struct C2f {
    iterations: usize,
    how: indentify_study::coarse_to_fine::Coarsening,
    corrections: usize,
    /// `--c2f-fine-radius R`: the fine phase's `lm_radius` (0: off), else the
    /// configuration's.
    fine_radius: Option<f64>,
}

/// Sets the `--c2f*` option `a` (with its value `v` where it takes one).
fn c2f_option(c2f: &mut Option<C2f>, a: &str, v: &mut dyn FnMut() -> String) -> Result<()> {
    let c = c2f.get_or_insert(C2f {
        iterations: 20,
        how: Default::default(),
        corrections: 0,
        fine_radius: None,
    });
    match a {
        "--c2f" => c.iterations = v().parse().context("--c2f: coarse iterations, >= 1")?,
        "--c2f-space" => {
            c.how.space = v().parse().context("--c2f-space: a factor in [1, 4]")?;
        }
        "--c2f-keep-time" => c.how.time = false,
        "--c2f-fine-radius" => {
            let r: f64 = v().parse().context("--c2f-fine-radius: a length >= 0")?;
            c.fine_radius = Some(r);
        }
        _ => c.corrections = v().parse().context("--c2f-correct: corrections, >= 0")?,
    }
    Ok(())
}

/// The cases, in the order they run.
const CASES: [&str; 6] = [
    "r1-map",
    "r2",
    "r2-noisy",
    "ht-nh",
    "anon-nh",
    "ht-nh-joint",
];

/// The options of `cargo xtask fit-cost` (see [`run`]).
struct Opts {
    only: Option<Vec<String>>,
    quick: bool,
    rounds: usize,
    json_out: Option<PathBuf>,
    compare: Option<PathBuf>,
    cold: bool,
    chi2: bool,
    valley: Option<ValleyStop>,
    columns_mode: bool,
    batch_mode: bool,
    jobs: usize,
    map_n: usize,
    profile: bool,
    op: bool,
    lm: Option<LmStrategy>,
    stop_rejected: Option<bool>,
    damping: Option<LmDamping>,
    c2f: Option<C2f>,
    proposed: Option<bool>,
    pairs_mode: bool,
    both: bool,
}

impl Default for Opts {
    fn default() -> Opts {
        Opts {
            only: None,
            quick: false,
            rounds: 3,
            json_out: None,
            compare: None,
            cold: false,
            chi2: true,
            valley: None,
            columns_mode: false,
            batch_mode: false,
            jobs: 2,
            map_n: 10,
            profile: false,
            op: false,
            lm: None,
            stop_rejected: None,
            damping: None,
            c2f: None,
            proposed: None,
            pairs_mode: false,
            both: false,
        }
    }
}

/// Parses `cargo xtask fit-cost`'s options.
fn parse(args: &[String]) -> Result<Opts> {
    let mut o = Opts::default();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut val = || it.next().cloned().unwrap_or_default();
        match a.as_str() {
            "--only" => o.only = Some(val().split(',').map(str::to_string).collect()),
            "--quick" => o.quick = true,
            "--rounds" => o.rounds = val().parse().context("--rounds: a number >= 1")?,
            "--json" => o.json_out = Some(PathBuf::from(val())),
            "--compare" => o.compare = Some(PathBuf::from(val())),
            "--cold" => o.cold = true,
            "--no-chi2" => o.chi2 = false,
            "--valley" => o.valley = Some(ValleyStop::default()),
            "--valley-steps" | "--valley-chi2" => valley_option(&mut o.valley, a, &val())?,
            "--columns" => o.columns_mode = true,
            "--batch" => o.batch_mode = true,
            "--profile" => o.profile = true,
            "--op" => o.op = true,
            "--jobs" => o.jobs = val().parse().context("--jobs: a number >= 1")?,
            "--map-n" => o.map_n = val().parse().context("--map-n: a number >= 1")?,
            "--lm-radius" => {
                let r: f64 = val()
                    .parse()
                    .context("--lm-radius: a length > 0 in the scaled variables, 0 off")?;
                if !(r >= 0.0 && r.is_finite()) {
                    bail!("--lm-radius: a length > 0 in the scaled variables, 0 off (got {r})");
                }
                o.lm.get_or_insert_with(LmStrategy::default).first_radius = (r > 0.0).then_some(r);
            }
            "--line-model" => o.lm.get_or_insert_with(LmStrategy::default).line_model = true,
            "--geodesic" => o.lm.get_or_insert_with(LmStrategy::default).geodesic = true,
            "--no-stop-rejected" => o.stop_rejected = Some(false),
            "--lm-damping" => {
                let v = val();
                let names: Vec<&str> = LmDamping::ALL.iter().map(|d| d.name()).collect();
                o.damping = Some(LmDamping::parse(&v).with_context(|| {
                    format!("--lm-damping: one of {} (got `{v}`)", names.join(", "))
                })?);
            }
            "--proposed-step" => o.pairs_mode = true,
            "--both" => o.both = true,
            "--no-proposed-step" => o.proposed = Some(false),
            "--c2f" | "--c2f-space" | "--c2f-keep-time" | "--c2f-correct" | "--c2f-fine-radius" => {
                c2f_option(&mut o.c2f, a, &mut val)?;
            }
            "--c2f-tight" => C2F_TIGHT.store(true, std::sync::atomic::Ordering::Relaxed),
            "--lm-subspace" => LM_SUBSPACE.store(true, std::sync::atomic::Ordering::Relaxed),
            other => bail!("unknown option {other}"),
        }
    }
    Ok(o)
}

/// `cargo xtask fit-cost [--only r2,r1-map] [--quick] [--rounds N] [--json FILE]
/// [--compare FILE] [--cold] [--no-chi2] [--valley [--valley-steps N] [--valley-chi2 X]] [--lm-radius R] [--line-model] [--geodesic]
/// [--c2f N [--c2f-tight] [--c2f-space F] [--c2f-keep-time] [--c2f-correct K]]
/// [--columns] [--batch [--jobs N] [--map-n N] [--profile]] [--proposed-step [--both]]
/// [--no-proposed-step] [--no-stop-rejected] [--lm-damping NAME] [--lm-subspace]`.
pub fn run(args: &[String]) -> Result<()> {
    let Opts {
        only,
        quick,
        mut rounds,
        json_out,
        compare,
        cold,
        chi2,
        valley,
        columns_mode,
        batch_mode,
        jobs,
        map_n,
        profile,
        op,
        lm,
        stop_rejected,
        damping,
        c2f,
        proposed,
        pairs_mode,
        both,
    } = parse(args)?;
    if rounds == 0 {
        bail!("--rounds takes a number >= 1");
    }
    // a strategy given replaces the configuration's: its stop of rejected trials kept
    let lm = lm.map(|mut l| {
        l.stop_rejected = stop_rejected.unwrap_or(true);
        l
    });
    let lm_stop = stop_rejected;
    if let Some(o) = &only {
        let known = |c: &str| CASES.contains(&c) || propstep::EXTRA.iter().any(|e| e.0 == c);
        if let Some(bad) = o.iter().find(|c| !known(c)) {
            let extra: Vec<&str> = propstep::EXTRA.iter().map(|e| e.0).collect();
            bail!(
                "--only: unknown case `{bad}` (cases: {}, {})",
                CASES.join(", "),
                extra.join(", ")
            );
        }
    }
    // quick: the two cheap cases, one forward run on each side of the fit
    let cases: Vec<&str> = CASES
        .iter()
        .copied()
        .chain(propstep::EXTRA.iter().map(|e| e.0))
        .filter(|c| match &only {
            Some(o) => o.iter().any(|x| x == c),
            None if CASES.contains(c) => !quick || matches!(*c, "r1-map" | "r2"),
            None => pairs_mode && !quick,
        })
        .collect();
    if quick {
        rounds = 1;
    }
    let before: Option<Value> = match &compare {
        Some(p) => Some(serde_json::from_str(
            &std::fs::read_to_string(p).with_context(|| format!("reading {}", p.display()))?,
        )?),
        None => None,
    };
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_default();
    if batch_mode {
        if jobs == 0 || map_n == 0 {
            bail!("--jobs and --map-n take numbers >= 1");
        }
        if profile {
            let m = batch::profile(map_n)?;
            println!("{}", profile::table(&m));
            return write_json(json_out.as_deref(), &m);
        }
        let m = batch::measure(jobs, map_n, op)?;
        println!("{}", batch::table(&m));
        return write_json(json_out.as_deref(), &m);
    }
    if columns_mode {
        let results = columns::sweep(&root, &cases, rounds)?;
        return write_json(json_out.as_deref(), &Value::Array(results));
    }
    if pairs_mode {
        let run = |case: &str, on: bool| {
            measure(
                &root,
                case,
                rounds,
                cold,
                (chi2, valley, Some(on)),
                (lm, lm_stop, damping),
                c2f,
            )
        };
        return propstep::sweep(&cases, both, json_out.as_deref(), run);
    }
    let mut results = Vec::new();
    println!(
        "| case | forward (s) | fit (s) | fit / forward | CPU fit / forward | iterations | forward solves | rejected trials | adjoint | sensitivity | Newton iterations | factorizations | schedule steps run | runs stopped | steps skipped | stop |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for case in cases {
        let m = measure(
            &root,
            case,
            rounds,
            cold,
            (chi2, valley, proposed),
            (lm, lm_stop, damping),
            c2f,
        )?;
        println!(
            "| {case} | {:.3} | {:.2} | {:.1} | {:.1} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            m["forward_s"].as_f64().unwrap_or(f64::NAN),
            m["fit_s"].as_f64().unwrap_or(f64::NAN),
            m["ratio"].as_f64().unwrap_or(f64::NAN),
            m["cpu_ratio"].as_f64().unwrap_or(f64::NAN),
            m["iterations"],
            m["forward_solves"],
            m["rejected_trials"],
            m["adjoint_solves"],
            m["sensitivity_solves"],
            m["newton_iterations"],
            m["factorizations"],
            m["schedule_steps"],
            m["stopped_runs"],
            m["steps_skipped"],
            m["stop"].as_str().unwrap_or("")
        );
        if !m["coarse"].is_null() {
            println!("  coarse phase of {case}: {}", m["coarse"]);
        }
        results.push(m);
    }
    if let Some(b) = &before {
        println!("\n{}", compare_table(b, &results));
    }
    write_json(json_out.as_deref(), &Value::Array(results))
}

/// Writes `v` to `path`, if given.
pub(crate) fn write_json(path: Option<&Path>, v: &Value) -> Result<()> {
    if let Some(p) = path {
        std::fs::write(p, serde_json::to_string_pretty(v)?)
            .with_context(|| format!("writing {}", p.display()))?;
        eprintln!("wrote {}", p.display());
    }
    Ok(())
}

/// The options of a case.
fn options(root: &Path, case: &str) -> Result<IdentifyOptions> {
    let path = |p: &str| ConfigSource::Path(root.join(p));
    let mut o = match case {
        "r2" | "r2-noisy" => IdentifyOptions::new(path("examples/r2-norton-hoff.ron")),
        "ht-nh" => IdentifyOptions::new(path("examples/real/ht-nh.ron")),
        "anon-nh" => IdentifyOptions::new(path("examples/real/anon-nh.ron")),
        "ht-nh-joint" => IdentifyOptions::new(path("examples/real/ht-nh-joint.ron")),
        "r1-map" => {
            // one indent (phase A, 2% noise) of the synthetic map of `cargo xtask make-map`
            let dir = std::env::temp_dir().join("indentify-fit-cost-map");
            let map = indentify_study::synthetic::make_map(
                &dir,
                &indentify_study::synthetic::MapOptions {
                    n: 2,
                    ..Default::default()
                },
            )?;
            let mut o = IdentifyOptions::new(ConfigSource::Path(map.base.clone()));
            o.data = Some(dir.join("records").join("p00_00.csv"));
            o
        }
        other => match propstep::options(root, other) {
            Some(o) => o,
            None => bail!("unknown case {other}"),
        },
    };
    if case == "r2-noisy" {
        o.noise = Some((0.02, 1));
    }
    o.refine = false;
    o.figures = false;
    o.jobs = Some(1);
    Ok(o)
}

/// The process's CPU time (s, user + system, every thread), from `/proc/self/stat`
/// (clock ticks of 10 ms); `NaN` where it cannot be read.
fn cpu_seconds() -> f64 {
    let Ok(text) = std::fs::read_to_string("/proc/self/stat") else {
        return f64::NAN;
    };
    // the fields after the command name (which may hold spaces) in parentheses
    let Some(rest) = text.rsplit_once(')').map(|(_, r)| r) else {
        return f64::NAN;
    };
    let f: Vec<&str> = rest.split_whitespace().collect();
    // utime and stime are fields 14 and 15 of stat, 12 and 13 after the name
    match (
        f.get(11).and_then(|v| v.parse::<f64>().ok()),
        f.get(12).and_then(|v| v.parse::<f64>().ok()),
    ) {
        (Some(u), Some(k)) => (u + k) / 100.0,
        _ => f64::NAN,
    }
}

/// Times `rounds` forward runs at new points near `start` (after a warm-up) on `problem`'s
/// pool: wall and CPU seconds of each.
fn forward_times(
    problem: &indentify_identify::Problem,
    start: &[f64],
    rounds: usize,
    first: usize,
) -> Result<Vec<(f64, f64)>> {
    let point = |r: usize| -> Vec<f64> {
        start
            .iter()
            .map(|v| v * (1.0 + 1e-6 * (r as f64 + 1.0)))
            .collect()
    };
    problem.install(|| -> Result<Vec<(f64, f64)>> {
        let mut ev = Evaluator::new(problem)?;
        ev.cost(&point(first + rounds))?;
        let mut t = Vec::with_capacity(rounds);
        for r in 0..rounds {
            let (clock, cpu) = (Instant::now(), cpu_seconds());
            ev.cost(&point(first + r))?;
            t.push((clock.elapsed().as_secs_f64(), cpu_seconds() - cpu));
        }
        Ok(t)
    })
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// One case: forward runs, the fit, forward runs again.
fn measure(
    root: &Path,
    case: &str,
    rounds: usize,
    cold: bool,
    (chi2, valley, proposed): (bool, Option<ValleyStop>, Option<bool>),
    (lm, lm_stop, damping): (Option<LmStrategy>, Option<bool>, Option<LmDamping>),
    c2f: Option<C2f>,
) -> Result<Value> {
    let opts = options(root, case)?;
    let resolved = identify::resolve(&opts)?;
    let mut s = identify::setup(resolved, &opts)?;
    s.id_cfg.stop.chi2_stop = chi2;
    s.id_cfg.stop.valley_stop = valley;
    if let Some(on) = proposed {
        s.id_cfg.stop.proposed_step = on;
    }
    if let Some(lm) = lm {
        s.id_cfg.stop.lm = lm;
    }
    if let Some(on) = lm_stop {
        s.id_cfg.stop.lm.stop_rejected = on;
    }
    if let Some(d) = damping {
        s.id_cfg.stop.lm.damping = d;
    }
    if LM_SUBSPACE.load(std::sync::atomic::Ordering::Relaxed) {
        s.id_cfg.stop.lm.subspace = true;
    }
    s.problem.set_threads(1)?;
    // the forward runs are timed cold (their points are 1e-6 apart: warm, each would start
    // from the last one's solution)
    s.problem.set_warm_start(false);
    let start: Vec<f64> = s
        .id_cfg
        .params
        .iter()
        .map(|p| p.value.unwrap_or(0.0))
        .collect();
    let mut fwd = forward_times(&s.problem, &start, rounds, 0)?;
    s.problem.set_warm_start(!cold);
    let (clock, cpu) = (Instant::now(), cpu_seconds());
    let mut observer = |rec: &indentify_identify::IterationRecord| {
        let at: Vec<String> = rec.params.iter().map(|v| format!("{v:.5e}")).collect();
        eprintln!(
            "  {case}: iteration {} J = {:.6e} ({:.1} s) at {}",
            rec.iteration,
            rec.cost,
            rec.seconds,
            at.join(" ")
        );
    };
    let mut coarse = None;
    let r: IdentifyResult = match c2f {
        None => s
            .problem
            .install(|| indentify_identify::identify(&s.problem, &s.id_cfg, &mut observer))?,
        Some(c) => {
            let (r, phase) = s.problem.install(|| coarse_to_fine(&s, c, &mut observer))?;
            coarse = Some(coarse_json(&phase));
            r
        }
    };
    let (fit, fit_cpu) = (clock.elapsed().as_secs_f64(), cpu_seconds() - cpu);
    s.problem.set_warm_start(false);
    fwd.extend(forward_times(&s.problem, &start, rounds, rounds + 1)?);
    let forward = median(&mut fwd.iter().map(|t| t.0).collect::<Vec<f64>>());
    let forward_cpu = median(&mut fwd.iter().map(|t| t.1).collect::<Vec<f64>>());
    let params: Vec<Value> = r
        .params
        .iter()
        .filter(|p| p.free)
        .map(|p| {
            let sd = r.identifiability.as_ref().and_then(|id| {
                id.names
                    .iter()
                    .position(|n| *n == p.name)
                    .map(|k| id.std_dev[k])
            });
            // the summary's 2-sigma interval (the undetermined parameters accounted for)
            let interval = r.identifiability.as_ref().and_then(|id| {
                id.names
                    .iter()
                    .position(|n| *n == p.name)
                    .and_then(|k| id.intervals.get(k).copied())
            });
            json!({ "name": p.name, "value": p.value, "sd": sd, "interval": interval })
        })
        .collect();
    Ok(json!({
        "case": case,
        "forward_s": forward,
        "fit_s": fit,
        "ratio": fit / forward,
        "forward_cpu_s": forward_cpu,
        "fit_cpu_s": fit_cpu,
        "cpu_ratio": fit_cpu / forward_cpu,
        "iterations": r.iterations,
        "forward_solves": r.forward_solves,
        "adjoint_solves": r.adjoint_solves,
        "sensitivity_solves": r.sensitivity_solves,
        "rejected_trials": r.rejected_trials,
        "newton_iterations": r.newton_iterations,
        "factorizations": r.factorizations,
        "schedule_steps": r.schedule_steps,
        "stopped_runs": r.stopped_runs,
        "steps_skipped": r.steps_skipped,
        "stop": r.stop_reason.to_string(),
        "converged": r.stop_reason.is_converged(),
        "fired": propstep::fired(&r),
        "outcome": propstep::outcome(&s, &r),
        "cost": r.cost,
        "params": params,
        "coarse": coarse,
    }))
}

/// The fit of `s` coarse to fine as `c` asks (`--c2f-tight`: the coarse phase without the
/// statistical stops), on the current pool.
fn coarse_to_fine(
    s: &identify::Setup,
    c: C2f,
    observer: &mut dyn FnMut(&indentify_identify::IterationRecord),
) -> Result<(IdentifyResult, indentify_study::coarse_to_fine::CoarsePhase)> {
    use indentify_study::coarse_to_fine as c2f;
    let mut cc = s.id_cfg.clone();
    if C2F_TIGHT.load(std::sync::atomic::Ordering::Relaxed) {
        cc.stop.step_sigma = None;
        cc.stop.proposed_step = false;
    }
    let (mut fine, phase) = c2f::coarse_phase_corrected(
        s,
        c2f::coarse_problem_with(s, c.how),
        &cc,
        (c.iterations, c.corrections),
        observer,
    );
    fine.stop = s.id_cfg.stop;
    if let Some(r) = c.fine_radius {
        fine.stop.lm.first_radius = (r > 0.0).then_some(r);
    }
    let r = indentify_identify::identify(&s.problem, &fine, observer)?;
    Ok((r, phase))
}

/// What `--json` keeps of a coarse phase.
fn coarse_json(phase: &indentify_study::coarse_to_fine::CoarsePhase) -> Value {
    let first = phase.result.as_ref();
    let (it, fw, se, rej, fine) = phase.totals();
    json!({
        "model": phase.model,
        "fallback": phase.fallback,
        "seconds": phase.seconds,
        "iterations": first.map(|r| r.iterations),
        "forward_solves": first.map(|r| r.forward_solves),
        "sensitivity_solves": first.map(|r| r.sensitivity_solves),
        "rejected_trials": first.map(|r| r.rejected_trials),
        "stop": first.map(|r| r.stop_reason.to_string()),
        "c_first": first.map(|r| r.c.clone()),
        "c": phase.end().map(|r| r.c.clone()),
        "corrections": phase.corrections.iter().map(|c| json!({
            "discrepancy": c.discrepancy,
            "iterations": c.result.iterations,
            "forward_solves": c.result.forward_solves,
            "sensitivity_solves": c.result.sensitivity_solves,
            "stop": c.result.stop_reason.to_string(),
            "c": c.result.c,
        })).collect::<Vec<_>>(),
        "total": { "iterations": it, "forward_solves": fw, "sensitivity_solves": se,
                   "rejected_trials": rej, "fine_forward_runs": fine },
    })
}

/// Before (an earlier `--json`) against after: the ratios, then every parameter's shift
/// in the after run's standard deviations (the before one's when after has none).
fn compare_table(before: &Value, after: &[Value]) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "| case | fit / forward before | after | iterations before | after | forward solves before | after | rejected before | after | sensitivity before | after | Newton iterations before | after | factorizations before | after |"
    );
    let _ = writeln!(
        s,
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    );
    let find = |case: &str| -> Option<&Value> {
        before
            .as_array()
            .and_then(|a| a.iter().find(|b| b["case"] == case))
    };
    for a in after {
        let case = a["case"].as_str().unwrap_or("");
        if let Some(b) = find(case) {
            let _ = writeln!(
                s,
                "| {case} | {:.1} | {:.1} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
                b["ratio"].as_f64().unwrap_or(f64::NAN),
                a["ratio"].as_f64().unwrap_or(f64::NAN),
                b["iterations"],
                a["iterations"],
                b["forward_solves"],
                a["forward_solves"],
                b["rejected_trials"],
                a["rejected_trials"],
                b["sensitivity_solves"],
                a["sensitivity_solves"],
                b["newton_iterations"],
                a["newton_iterations"],
                b["factorizations"],
                a["factorizations"]
            );
        }
    }
    let _ = writeln!(
        s,
        "\n| case | parameter | before | after | sigma | abs(after - before) / sigma |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|");
    for a in after {
        let case = a["case"].as_str().unwrap_or("");
        let Some(b) = find(case) else { continue };
        let empty = Vec::new();
        let bp = b["params"].as_array().unwrap_or(&empty);
        for p in a["params"].as_array().unwrap_or(&empty) {
            let Some(q) = bp.iter().find(|q| q["name"] == p["name"]) else {
                continue;
            };
            let (va, vb) = (
                p["value"].as_f64().unwrap_or(f64::NAN),
                q["value"].as_f64().unwrap_or(f64::NAN),
            );
            // an undetermined parameter has no deviation (null in the JSON): said so, and
            // its shift is not measured in one
            let sd = p["sd"]
                .as_f64()
                .filter(|v| v.is_finite() && *v > 0.0)
                .or_else(|| q["sd"].as_f64().filter(|v| v.is_finite() && *v > 0.0));
            let _ = writeln!(
                s,
                "| {case} | {} | {} | {} | {} | {} |",
                p["name"].as_str().unwrap_or(""),
                sig(vb),
                sig(va),
                sd_cell(sd),
                shift_cell(sd.map(|sd| (va - vb).abs() / sd))
            );
        }
    }
    let _ = writeln!(
        s,
        "\n| case | parameter | before's 2-sigma interval | after's | after in before's | before in after's |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|");
    for a in after {
        let case = a["case"].as_str().unwrap_or("");
        let Some(b) = find(case) else { continue };
        let empty = Vec::new();
        let bp = b["params"].as_array().unwrap_or(&empty);
        for p in a["params"].as_array().unwrap_or(&empty) {
            let Some(q) = bp.iter().find(|q| q["name"] == p["name"]) else {
                continue;
            };
            let (va, vb) = (
                p["value"].as_f64().unwrap_or(f64::NAN),
                q["value"].as_f64().unwrap_or(f64::NAN),
            );
            let (ia, ib) = (interval_of(p), interval_of(q));
            let inside = |i: Option<(f64, f64)>, v: f64| {
                i.map_or(
                    "-",
                    |(lo, hi)| if lo <= v && v <= hi { "yes" } else { "NO" },
                )
            };
            let _ = writeln!(
                s,
                "| {case} | {} | {} | {} | {} | {} |",
                p["name"].as_str().unwrap_or(""),
                interval_cell(ib),
                interval_cell(ia),
                inside(ib, va),
                inside(ia, vb)
            );
        }
    }
    s
}

/// A parameter's `interval` in the JSON (`null` entries, infinite ends, are open).
fn interval_of(p: &Value) -> Option<(f64, f64)> {
    let i = p["interval"].as_array()?;
    let end = |v: &Value, inf: f64| v.as_f64().unwrap_or(inf);
    Some((
        end(i.first()?, f64::NEG_INFINITY),
        end(i.get(1)?, f64::INFINITY),
    ))
}

/// An interval's cell, six significant digits.
fn interval_cell(i: Option<(f64, f64)>) -> String {
    i.map_or_else(
        || "-".to_owned(),
        |(lo, hi)| format!("[{}, {}]", sig(lo), sig(hi)),
    )
}

/// A deviation's cell: six significant digits, or "undetermined" where the fit gave none.
fn sd_cell(sd: Option<f64>) -> String {
    sd.map_or_else(|| "undetermined".to_owned(), sig)
}

/// A shift's cell in deviations: three decimals, or "-" where there is no deviation.
fn shift_cell(z: Option<f64>) -> String {
    z.map_or_else(|| "-".to_owned(), |z| format!("{z:.3}"))
}

/// Six significant digits.
fn sig(v: f64) -> String {
    if v.is_finite() && v != 0.0 {
        let d = (5 - v.abs().log10().floor() as i32).max(0) as usize;
        format!("{v:.d$}")
    } else {
        format!("{v}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An undetermined parameter (no deviation, null in the JSON) prints as such, not NaN.
    #[test]
    fn an_undetermined_parameter_prints_no_deviation_and_no_shift() {
        let case = |k: f64, sd: Option<f64>| {
            json!({ "case": "ht-nh", "ratio": 1.0, "params": [
                { "name": "E", "value": 84627.4, "sd": 1483.0 },
                { "name": "K", "value": k, "sd": sd },
            ]})
        };
        let before = json!([case(220727.0, None)]);
        let table = compare_table(&before, &[case(219172.0, None)]);
        assert!(!table.contains("NaN"), "{table}");
        let k_row = table
            .lines()
            .find(|l| l.starts_with("| ht-nh | K |"))
            .unwrap();
        assert!(k_row.ends_with("| undetermined | - |"), "{k_row}");
        let e_row = table
            .lines()
            .find(|l| l.starts_with("| ht-nh | E |"))
            .unwrap();
        assert!(e_row.ends_with("| 1483.00 | 0.000 |"), "{e_row}");
        // the before run's deviation stands in where the after run has none
        let before = json!([case(220727.0, Some(1000.0))]);
        let table = compare_table(&before, &[case(219172.0, None)]);
        assert!(table.contains("| 1000.00 | 1.555 |"), "{table}");
    }
}
