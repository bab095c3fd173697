//! The paper's Tables I-III (Constantinescu & Tardieu 2001) regenerated with indentify:
//! the reference problems R1 / R2 of docs/theory.md §11, synthetic data, the paper's starting
//! points, the identification runs (in parallel threads), the cost valley of Table III's
//! runs that stay off, and the markdown / SVG rendering.
//!
//! The same code serves `cargo xtask paper-tables` (reference set-up, every run) and the
//! snapshot test `xtask/tests/paper_tables.rs` (a coarse set-up and a documented subset).

use std::fmt::Write;
use std::sync::Mutex;
use std::time::Instant;

use anyhow::{Context, Result};
use indentify_contact::{DirectSolver, Model, Punch, Schedule, SolverOptions, trapezoid};
use indentify_identify::{
    Evaluator, ForceRecord, IdentifyConfig, IdentifyResult, Method, ParamSpec, Problem,
    multiplicative_noise,
};
use indentify_laws::{Law, Maxwell, NortonHoff};
use indentify_mesh::CylinderMesher;

use crate::svg::{Plot, Series, Style};

/// Mesh and history of a set-up: a `radius x height` cylinder, `n x n` Q8 graded by
/// `grading` towards the axis and the top, cone 68 deg, trapezoid 0.1 mm / 1 s ramp /
/// 1 s hold / 1 s unload with `steps` steps per segment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Setup {
    /// Cylinder radius (mm).
    pub radius: f64,
    /// Cylinder height (mm).
    pub height: f64,
    /// Elements along r and z.
    pub n: usize,
    /// Geometric grading ratio.
    pub grading: f64,
    /// Time steps per segment.
    pub steps: usize,
}

impl Setup {
    /// docs/theory.md §11: 10 x 10 mm, 20 x 20 Q8 graded 1.3, 30 steps per segment.
    pub const REFERENCE: Setup = Setup {
        radius: 10.0,
        height: 10.0,
        n: 20,
        grading: 1.3,
        steps: 30,
    };

    /// The snapshot test's coarse set-up: 4 x 4 mm, 8 x 8 Q8 graded 1.45, 8 steps per
    /// segment (about 50x cheaper than the reference).
    pub const COARSE: Setup = Setup {
        radius: 4.0,
        height: 4.0,
        n: 8,
        grading: 1.45,
        steps: 8,
    };

    /// The model (mesh + cone).
    pub fn model(&self) -> Result<Model> {
        let mesh = CylinderMesher {
            radius: self.radius,
            height: self.height,
            nr: self.n,
            nz: self.n,
            grading_r: self.grading,
            grading_z: self.grading,
        }
        .build()?;
        Ok(Model::new(
            mesh,
            Punch::Cone {
                half_angle_deg: 68.0,
            },
        )?)
    }

    /// The depth schedule.
    pub fn schedule(&self) -> Result<Schedule> {
        Ok(Schedule::from_segments(&trapezoid(
            0.1, 1.0, 1.0, 1.0, self.steps,
        ))?)
    }

    /// One-line description for the documents.
    pub fn describe(&self) -> String {
        format!(
            "{} x {} mm cylinder, {} x {} Q8 graded {} towards axis and top, cone 68 deg, trapezoid 0.1 mm (1 s ramp, 1 s hold, 1 s unload), {} steps per segment",
            self.radius, self.height, self.n, self.n, self.grading, self.steps
        )
    }
}

/// Which table a run belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Table {
    /// R1 (Maxwell), exact data.
    I,
    /// R1 with 10% multiplicative noise.
    II,
    /// R2 (Norton-Hoff), exact data.
    III,
}

/// R1's truth `[E, nu, eta]`.
pub const R1_TRUTH: [f64; 3] = [20000.0, 0.3, 30000.0];
/// R2's truth `[E, nu, K, m, sY]`.
pub const R2_TRUTH: [f64; 5] = [1e5, 0.3, 1500.0, 5.0, 500.0];

/// Table I of the paper: start and final (E, eta).
pub const PAPER_I: [([f64; 2], [f64; 2]); 4] = [
    ([4000.0, 70000.0], [20002.0, 30004.0]),
    ([60000.0, 10000.0], [20002.0, 30009.0]),
    ([10000.0, 5000.0], [20002.0, 30006.0]),
    ([60000.0, 90000.0], [19999.0, 29999.0]),
];

/// Table II of the paper: noise realization (1 or 2), start and final (E, eta).
pub const PAPER_II: [(u64, [f64; 2], [f64; 2]); 4] = [
    (1, [4000.0, 70000.0], [20580.0, 30490.0]),
    (1, [10000.0, 5000.0], [20611.0, 30457.0]),
    (2, [60000.0, 10000.0], [19509.0, 29130.0]),
    (2, [60000.0, 90000.0], [19509.0, 29136.0]),
];

/// Table III of the paper: start and final (E, K, m, sY).
pub const PAPER_III: [([f64; 4], [f64; 4]); 8] = [
    (
        [130000.0, 800.0, 2.0, 1000.0],
        [99664.3, 1533.36, 5.38417, 446.414],
    ),
    (
        [150000.0, 1000.0, 3.0, 1000.0],
        [100228.0, 1524.64, 5.00296, 491.795],
    ),
    (
        [150000.0, 2000.0, 3.0, 200.0],
        [99429.3, 1598.24, 6.18529, 343.533],
    ),
    (
        [150000.0, 2000.0, 8.0, 1000.0],
        [99288.9, 1657.20, 6.98908, 246.959],
    ),
    (
        [70000.0, 2000.0, 8.0, 200.0],
        [99126.5, 1682.47, 6.94556, 238.366],
    ),
    (
        [70000.0, 3000.0, 8.0, 250.0],
        [100598.0, 1451.36, 4.24316, 602.651],
    ),
    (
        [70000.0, 1000.0, 3.0, 250.0],
        [99630.1, 1521.18, 4.94161, 497.229],
    ),
    (
        [150000.0, 1000.0, 3.0, 250.0],
        [99778.0, 1516.32, 5.28676, 464.255],
    ),
];

/// Seeds of the two noise realizations of Table II (SplitMix64, amplitude 0.1).
pub const NOISE_SEEDS: [u64; 2] = [1, 2];

/// One identification to run.
#[derive(Clone, Debug, PartialEq)]
pub struct Job {
    /// Table.
    pub table: Table,
    /// Row number in the paper's table (1-based).
    pub row: usize,
    /// Start: values of the free parameters.
    pub start: Vec<f64>,
    /// Noise realization (1 or 2) for Table II.
    pub realization: Option<usize>,
    /// The paper's final values.
    pub paper: Vec<f64>,
    /// Method override (otherwise BFGS for Tables I-II and `Options::method_r2` for III).
    pub method: Option<Method>,
}

/// Every job of the three tables, in the paper's order.
pub fn all_jobs() -> Vec<Job> {
    let mut jobs = Vec::new();
    for (k, (s, f)) in PAPER_I.iter().enumerate() {
        jobs.push(Job {
            table: Table::I,
            row: k + 1,
            start: s.to_vec(),
            realization: None,
            paper: f.to_vec(),
            method: None,
        });
    }
    for (k, (r, s, f)) in PAPER_II.iter().enumerate() {
        jobs.push(Job {
            table: Table::II,
            row: k + 1,
            start: s.to_vec(),
            realization: Some(*r as usize),
            paper: f.to_vec(),
            method: None,
        });
    }
    for (k, (s, f)) in PAPER_III.iter().enumerate() {
        jobs.push(Job {
            table: Table::III,
            row: k + 1,
            start: s.to_vec(),
            realization: None,
            paper: f.to_vec(),
            method: None,
        });
    }
    jobs
}

/// The paper's algorithm (BFGS-Armijo) on Table III's test 5, the case of the paper's
/// Fig. 9 and its valley: shown beside the LM table.
pub fn bfgs_reference_job() -> Job {
    let (s, f) = PAPER_III[4];
    Job {
        table: Table::III,
        row: 5,
        start: s.to_vec(),
        realization: None,
        paper: f.to_vec(),
        method: Some(Method::Bfgs),
    }
}

/// Options of a table run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    /// Mesh and history.
    pub setup: Setup,
    /// Worker threads.
    pub threads: usize,
    /// BFGS iteration limit for Tables I and II.
    pub max_iterations_r1: usize,
    /// BFGS iteration limit for Table III.
    pub max_iterations_r2: usize,
    /// Compute the valley of Table III runs whose m or sY end more than 5% off.
    pub valleys: bool,
    /// Method for Table III.
    pub method_r2: Method,
    /// Iteration limit of the BFGS reference run of Table III's test 5.
    pub max_iterations_bfgs_r2: usize,
}

/// The outcome of one job.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// The job.
    pub job: Job,
    /// The identification (or its error as text).
    pub result: std::result::Result<IdentifyResult, String>,
    /// Valley: `(s, J / J_ref)` along `c(s) = truth + s (end - truth)`.
    pub valley: Vec<(f64, f64)>,
    /// Which end point the valley goes to.
    pub valley_of: ValleyEnd,
}

/// The end point of a valley line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ValleyEnd {
    /// No valley computed.
    None,
    /// Our identified point (m or sY more than 5% off).
    Ours,
    /// The paper's final point (ours converged; the paper's stayed off).
    Paper,
}

/// The data sets: depth history, exact R1 and R2 forces, noisy R1 forces.
pub struct Data {
    /// The schedule (times, depths).
    pub schedule: Schedule,
    /// R1 exact forces at the schedule times.
    pub r1: Vec<f64>,
    /// R1 forces with the two noise realizations.
    pub r1_noisy: [Vec<f64>; 2],
    /// R2 exact forces.
    pub r2: Vec<f64>,
}

fn simulate(model: &Model, law: &dyn Law, c: &[f64], schedule: &Schedule) -> Result<Vec<f64>> {
    let mut s = DirectSolver::new(model)?;
    Ok(s.run(
        &indentify_laws::LawMaterial(law),
        c,
        schedule,
        &SolverOptions::default(),
    )?
    .forces())
}

impl Data {
    /// Synthesizes the data of `setup` (the "experimental" curves of the paper are
    /// computed with the same discretization as the identification).
    pub fn new(setup: &Setup, need_r2: bool) -> Result<Data> {
        let schedule = setup.schedule()?;
        let model = setup.model()?;
        let r1 = simulate(&model, &Maxwell, &R1_TRUTH, &schedule)?;
        let r1_noisy = [
            multiplicative_noise(&r1, 0.1, NOISE_SEEDS[0]),
            multiplicative_noise(&r1, 0.1, NOISE_SEEDS[1]),
        ];
        let r2 = if need_r2 {
            simulate(&model, &NortonHoff, &R2_TRUTH, &schedule)?
        } else {
            vec![]
        };
        Ok(Data {
            schedule,
            r1,
            r1_noisy,
            r2,
        })
    }

    fn problem(&self, setup: &Setup, law: &'static dyn Law, forces: &[f64]) -> Result<Problem> {
        let record = ForceRecord::new(self.schedule.t.clone(), forces.to_vec())?;
        Ok(Problem::new(
            setup.model()?,
            law,
            self.schedule.clone(),
            &record,
            None,
            SolverOptions::default(),
        )?)
    }
}

/// The identification set-up of a table: free parameters, bounds (log scaling), nu fixed.
pub fn config(table: Table, start: &[f64], max_iterations: usize) -> IdentifyConfig {
    let params = match table {
        Table::I | Table::II => vec![
            ParamSpec::free("E", start[0], 1e3, 1e6),
            ParamSpec::fixed("nu", 0.3),
            ParamSpec::free("eta", start[1], 1e3, 1e7),
        ],
        Table::III => vec![
            ParamSpec::free("E", start[0], 1e4, 1e6),
            ParamSpec::fixed("nu", 0.3),
            ParamSpec::free("K", start[1], 10.0, 1e5),
            ParamSpec::free("m", start[2], 1.1, 30.0),
            ParamSpec::free("sY", start[3], 1.0, 5000.0),
        ],
    };
    let mut cfg = IdentifyConfig::new(params);
    cfg.stop.max_iterations = max_iterations;
    cfg
}

/// Relative errors of the free values against the truth.
pub fn rel_errors(table: Table, free: &[f64]) -> Vec<f64> {
    let truth: Vec<f64> = match table {
        Table::I | Table::II => vec![R1_TRUTH[0], R1_TRUTH[2]],
        Table::III => vec![R2_TRUTH[0], R2_TRUTH[2], R2_TRUTH[3], R2_TRUTH[4]],
    };
    free.iter().zip(&truth).map(|(v, t)| (v - t) / t).collect()
}

/// Runs `jobs` on `opts.threads` threads (longest first) and returns the outcomes in the
/// jobs' order.
///
/// # Errors
/// When a data set or a problem cannot be built.
pub fn run_jobs(opts: &Options, data: &Data, jobs: &[Job]) -> Result<Vec<Outcome>> {
    let setup = &opts.setup;
    let p1 = data.problem(setup, &Maxwell, &data.r1)?;
    let pn = [
        data.problem(setup, &Maxwell, &data.r1_noisy[0])?,
        data.problem(setup, &Maxwell, &data.r1_noisy[1])?,
    ];
    let p2 = if jobs.iter().any(|j| j.table == Table::III) {
        Some(data.problem(setup, &NortonHoff, &data.r2)?)
    } else {
        None
    };
    // Table III first: the long runs start early and the short ones fill the gaps
    let mut order: Vec<usize> = (0..jobs.len()).collect();
    order.sort_by_key(|&i| match (jobs[i].table, jobs[i].method) {
        (Table::III, Some(_)) => 0,
        (Table::III, None) => 1,
        _ => 2,
    });
    let queue = Mutex::new(order);
    let results: Mutex<Vec<Option<Outcome>>> = Mutex::new(vec![None; jobs.len()]);
    std::thread::scope(|scope| {
        for _ in 0..opts.threads.max(1) {
            scope.spawn(|| {
                loop {
                    let next = queue.lock().map(|mut q| {
                        if q.is_empty() {
                            None
                        } else {
                            Some(q.remove(0))
                        }
                    });
                    let Ok(Some(i)) = next else { break };
                    let job = &jobs[i];
                    let problem = match (job.table, job.realization) {
                        (Table::I, _) => &p1,
                        (Table::II, r) => &pn[r.unwrap_or(1).clamp(1, 2) - 1],
                        (Table::III, _) => match &p2 {
                            Some(p) => p,
                            None => break,
                        },
                    };
                    let out = run_one(opts, problem, job);
                    if let Ok(mut r) = results.lock() {
                        r[i] = Some(out);
                    }
                }
            });
        }
    });
    let results = results
        .into_inner()
        .map_err(|_| anyhow::anyhow!("a worker panicked"))?;
    results
        .into_iter()
        .map(|o| o.context("a job was not run"))
        .collect()
}

fn run_one(opts: &Options, problem: &Problem, job: &Job) -> Outcome {
    let max_it = match job.table {
        Table::III => opts.max_iterations_r2,
        _ => opts.max_iterations_r1,
    };
    let mut cfg = config(job.table, &job.start, max_it);
    if job.table == Table::III {
        cfg.method = opts.method_r2;
    }
    if let Some(m) = job.method {
        cfg.method = m;
        if m == Method::Bfgs {
            cfg.stop.max_iterations = opts.max_iterations_bfgs_r2;
        }
    }
    let trace = std::env::var_os("XTASK_TRACE").is_some();
    let result = indentify_identify::identify(problem, &cfg, &mut |h| {
        if trace {
            eprintln!(
                "{:?} {} it {:3} J {:.4e} |g| {:.3e} c {:?} fwd {} adj {} t {:.1}",
                job.table,
                job.row,
                h.iteration,
                h.cost,
                h.grad_norm,
                h.params,
                h.forward_solves,
                h.adjoint_solves,
                h.seconds
            );
        }
    })
    .map_err(|e| e.to_string());
    let mut valley = Vec::new();
    let mut valley_of = ValleyEnd::None;
    if let (Table::III, Ok(r), true, None) = (job.table, &result, opts.valleys, job.method) {
        let off = |v: &[f64]| {
            let e = rel_errors(Table::III, v);
            e[2].abs() > 0.05 || e[3].abs() > 0.05
        };
        if off(&r.free_values()) {
            valley = compute_valley(problem, &R2_TRUTH, &r.c, Some(r.cost)).unwrap_or_default();
            valley_of = ValleyEnd::Ours;
        } else if (3..=6).contains(&job.row) {
            // the paper's tests whose m and sY stayed off (its §5.3)
            let c = [job.paper[0], 0.3, job.paper[1], job.paper[2], job.paper[3]];
            valley = compute_valley(problem, &R2_TRUTH, &c, None).unwrap_or_default();
            valley_of = ValleyEnd::Paper;
        }
    }
    Outcome {
        job: job.clone(),
        result,
        valley,
        valley_of,
    }
}

/// `J / J_ref` along `c(s) = truth + s (end - truth)` for s = 0, 0.25, 0.5, 0.75, 1, 1.5
/// (J(truth) = 0 with exact data; J(end) is known).
fn compute_valley(
    problem: &Problem,
    truth: &[f64],
    end: &[f64],
    j_end: Option<f64>,
) -> Result<Vec<(f64, f64)>> {
    let mut ev = Evaluator::new(problem)?;
    let jr = problem.reference_cost();
    let mut out = vec![(0.0, 0.0)];
    for s in [0.25, 0.5, 0.75, 1.0, 1.5] {
        if let (1.0, Some(j)) = (s, j_end) {
            out.push((s, j / jr));
            continue;
        }
        let c: Vec<f64> = truth
            .iter()
            .zip(end)
            .map(|(t, e)| t + s * (e - t))
            .collect();
        let j = ev.cost(&c)?;
        out.push((s, j / jr));
    }
    Ok(out)
}

/// `v` with `digits` significant digits, plain notation between 1e-3 and 1e7.
pub fn sig(v: f64, digits: usize) -> String {
    if !v.is_finite() {
        return format!("{v}");
    }
    if v == 0.0 {
        return "0".into();
    }
    let e = v.abs().log10().floor() as i32;
    if !(-3..7).contains(&e) {
        return format!("{:.*e}", digits.saturating_sub(1), v);
    }
    let decimals = (digits as i32 - 1 - e).max(0) as usize;
    format!("{:.*}", decimals, v)
}

/// Relative error in percent: 4 decimals (`+0.0123%`); in the document (`exact`) an error
/// below 5e-7 is shown in scientific notation (`+3.1e-8%`), in the snapshot as `0.0000%`
/// (those digits are round-off and vary with the machine).
fn pct_in(e: f64, exact: bool) -> String {
    if exact && e != 0.0 && (100.0 * e).abs() < 5e-5 {
        return format!("{:+.1e}%", 100.0 * e);
    }
    pct(e)
}

/// Relative error in percent with 4 decimals (`+0.0123%`).
fn pct(e: f64) -> String {
    let s = format!("{:+.4}%", 100.0 * e);
    if s == "-0.0000%" || s == "+0.0000%" {
        "0.0000%".into()
    } else {
        s
    }
}

/// A start as typed: 5 significant digits, trailing zeros dropped (`(4000, 2)`).
fn start_tuple(v: &[f64]) -> String {
    format!(
        "({})",
        v.iter()
            .map(|x| {
                let t = sig(*x, 5);
                if t.contains('.') && !t.contains('e') {
                    t.trim_end_matches('0').trim_end_matches('.').to_string()
                } else {
                    t
                }
            })
            .collect::<Vec<_>>()
            .join(", ")
    )
}

fn tuple(v: &[f64], digits: usize) -> String {
    format!(
        "({})",
        v.iter()
            .map(|x| sig(*x, digits))
            .collect::<Vec<_>>()
            .join(", ")
    )
}

/// `J` for a table: with `timing` (the document) the value; without (the snapshot) a
/// value at round-off (`J / J_ref < 1e-12`) is shown as `round-off`, being machine noise.
fn cost_text(j: f64, j_ref: f64, timing: bool) -> String {
    if !timing && j / j_ref < 1e-12 {
        "round-off".into()
    } else {
        sig(j, 4)
    }
}

/// Renders the tables of `outcomes` (markdown). `timing` adds the wall-time column and the
/// round-off costs (the document); the snapshot renders without them.
pub fn render_tables(outcomes: &[Outcome], timing: bool) -> String {
    let mut s = String::new();
    for table in [Table::I, Table::II, Table::III] {
        let rows: Vec<&Outcome> = outcomes
            .iter()
            .filter(|o| o.job.table == table && o.job.method.is_none())
            .collect();
        if rows.is_empty() {
            continue;
        }
        let t = if timing { " time (s) |" } else { "" };
        let tl = if timing { "---|" } else { "" };
        match table {
            Table::I => {
                let _ = writeln!(s, "#### Table I — R1 (Maxwell), exact data\n");
                let _ = writeln!(
                    s,
                    "| # | start (E, eta) | paper final | ours final | err E | err eta | iter | fwd | adj | J start | J final | stop |{t}"
                );
                let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|---|---|{tl}");
            }
            Table::II => {
                let _ = writeln!(
                    s,
                    "#### Table II — R1 (Maxwell), 10% multiplicative noise\n"
                );
                let _ = writeln!(
                    s,
                    "| # | noise | start (E, eta) | paper final | paper err (E, eta) | ours final | err E | err eta | iter | fwd | adj | J final | stop |{t}"
                );
                let _ = writeln!(
                    s,
                    "|---|---|---|---|---|---|---|---|---|---|---|---|---|{tl}"
                );
            }
            Table::III => {
                let m = rows
                    .iter()
                    .find_map(|o| o.result.as_ref().ok().map(|r| r.method.name()))
                    .unwrap_or("-");
                let _ = writeln!(
                    s,
                    "#### Table III — R2 (Norton-Hoff), exact data, nu = 0.3 fixed, method `{m}`\n"
                );
                let _ = writeln!(
                    s,
                    "| test | start (E, K, m, sY) | paper final | ours final | err E | err K | err m | err sY | iter | fwd | adj | J final | stop |{t}"
                );
                let _ = writeln!(
                    s,
                    "|---|---|---|---|---|---|---|---|---|---|---|---|---|{tl}"
                );
            }
        }
        for o in rows {
            let j = &o.job;
            let r = match &o.result {
                Ok(r) => r,
                Err(e) => {
                    let _ = writeln!(
                        s,
                        "| {} | {} | {} | failed: {e} |",
                        j.row,
                        start_tuple(&j.start),
                        tuple(&j.paper, 6)
                    );
                    continue;
                }
            };
            let fin = r.free_values();
            let err = rel_errors(j.table, &fin);
            let errs: Vec<String> = err.iter().map(|e| pct_in(*e, timing)).collect();
            let time = if timing {
                format!(" {:.1} |", r.seconds)
            } else {
                String::new()
            };
            let stop = short_stop(r);
            match j.table {
                Table::I => {
                    let _ = writeln!(
                        s,
                        "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {stop} |{time}",
                        j.row,
                        start_tuple(&j.start),
                        tuple(&j.paper, 5),
                        tuple(&fin, 5),
                        errs[0],
                        errs[1],
                        r.iterations,
                        r.forward_solves,
                        r.adjoint_solves,
                        sig(r.initial_cost, 4),
                        cost_text(r.cost, r.reference_cost, timing),
                    );
                }
                Table::II => {
                    let perr: Vec<String> = rel_errors(j.table, &j.paper)
                        .iter()
                        .map(|e| pct(*e))
                        .collect();
                    let _ = writeln!(
                        s,
                        "| {} | {} | {} | {} | ({}, {}) | {} | {} | {} | {} | {} | {} | {} | {stop} |{time}",
                        j.row,
                        j.realization.unwrap_or(0),
                        start_tuple(&j.start),
                        tuple(&j.paper, 5),
                        perr[0],
                        perr[1],
                        tuple(&fin, 5),
                        errs[0],
                        errs[1],
                        r.iterations,
                        r.forward_solves,
                        r.adjoint_solves,
                        cost_text(r.cost, r.reference_cost, timing),
                    );
                }
                Table::III => {
                    let _ = writeln!(
                        s,
                        "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {stop} |{time}",
                        j.row,
                        start_tuple(&j.start),
                        tuple(&j.paper, 6),
                        tuple(&fin, 5),
                        errs[0],
                        errs[1],
                        errs[2],
                        errs[3],
                        r.iterations,
                        r.forward_solves,
                        r.adjoint_solves,
                        cost_text(r.cost, r.reference_cost, timing),
                    );
                }
            }
        }
        s.push('\n');
    }
    s
}

fn short_stop(r: &IdentifyResult) -> &'static str {
    use indentify_identify::StopReason::*;
    match r.stop_reason {
        GradientNorm => "grad",
        RelativeDecrease => "decrease",
        TargetCost => "target",
        RoundOff => "round-off",
        StepBelowSigma { .. } => "step < sigma",
        Chi2BelowSigma { .. } => "chi2 < sigma^2",
        ProposedBelowSigma { .. } => "next step < sigma",
        ValleyBelowSigma { .. } => "valley",
        SubspaceBelowSigma { .. } => "subspace",
        MaxIterations => "max-iter",
        Interrupted => "interrupted",
        Stalled(_) => "stalled",
        Undetermined { .. } => "undetermined",
    }
}

/// The valley table (Table III runs with m or sY more than 5% off).
pub fn render_valleys(outcomes: &[Outcome]) -> String {
    let rows: Vec<&Outcome> = outcomes.iter().filter(|o| !o.valley.is_empty()).collect();
    if rows.is_empty() {
        return "No Table III run ended with m or sY more than 5% off: no valley to show.\n".into();
    }
    let mut s = String::new();
    let head: Vec<String> = rows[0]
        .valley
        .iter()
        .map(|(x, _)| format!("s = {x}"))
        .collect();
    let _ = writeln!(s, "| test | end point c(1) | {} |", head.join(" | "));
    let _ = writeln!(s, "|---|---|{}", "---|".repeat(head.len()));
    for o in rows {
        let v: Vec<String> = o.valley.iter().map(|(_, j)| sig(*j, 3)).collect();
        let end = match o.valley_of {
            ValleyEnd::Paper => format!("paper's final {}", tuple(&o.job.paper, 4)),
            _ => match &o.result {
                Ok(r) => format!("our final {}", tuple(&r.free_values(), 4)),
                Err(_) => "-".into(),
            },
        };
        let _ = writeln!(s, "| {} | {end} | {} |", o.job.row, v.join(" | "));
    }
    s
}

/// SVG of the indentation curves (F against depth) of one outcome: data, start, final.
pub fn curve_figure(title: &str, data: &Data, o: &Outcome) -> Option<String> {
    let r = o.result.as_ref().ok()?;
    let (forces_data, name) = match (o.job.table, o.job.realization) {
        (Table::I, _) => (&data.r1, "experimental (exact)"),
        (Table::II, Some(k)) => (&data.r1_noisy[k - 1], "experimental (10% noise)"),
        (Table::II, None) => (&data.r1_noisy[0], "experimental (10% noise)"),
        (Table::III, _) => (&data.r2, "experimental (exact)"),
    };
    let pts = |f: &[f64]| -> Vec<(f64, f64)> {
        data.schedule
            .depth
            .iter()
            .zip(f)
            .map(|(&h, &v)| (h, v))
            .collect()
    };
    let plot = Plot {
        title: title.into(),
        x_label: "punch depth U (mm)".into(),
        y_label: "force F (N)".into(),
        series: vec![
            Series {
                name: name.into(),
                points: pts(forces_data),
                style: Style::Markers,
                color: "black",
            },
            Series {
                name: format!("initial {}", start_tuple(&o.job.start)),
                points: pts(&r.initial_forces),
                style: Style::Dashed,
                color: "#c0392b",
            },
            Series {
                name: format!("converged {}", tuple(&r.free_values(), 4)),
                points: pts(&r.forces),
                style: Style::Solid,
                color: "#2166ac",
            },
        ],
        log_y: false,
    };
    Some(plot.render())
}

/// SVG of the valleys (J / J_ref against s, log scale).
pub fn valley_figure(outcomes: &[Outcome]) -> Option<String> {
    let colors = [
        "#2166ac", "#c0392b", "#1a9850", "#762a83", "#e08214", "#555555",
    ];
    let series: Vec<Series> = outcomes
        .iter()
        .filter(|o| !o.valley.is_empty())
        .enumerate()
        .map(|(k, o)| Series {
            name: format!(
                "test {} ({})",
                o.job.row,
                if o.valley_of == ValleyEnd::Paper {
                    "to the paper's end"
                } else {
                    "to our end"
                }
            ),
            points: o.valley.iter().filter(|(s, _)| *s > 0.0).cloned().collect(),
            style: Style::Solid,
            color: colors[k % colors.len()],
        })
        .collect();
    if series.is_empty() {
        return None;
    }
    Some(
        Plot {
            title: "Table III: J / J_ref along c = truth + s (end - truth)".into(),
            x_label: "s (0 = truth, 1 = end point)".into(),
            y_label: "J / J_ref".into(),
            series,
            log_y: true,
        }
        .render(),
    )
}

/// Wall-clock helper.
pub struct Stopwatch(Instant);

impl Stopwatch {
    /// Starts now.
    pub fn start() -> Stopwatch {
        Stopwatch(Instant::now())
    }
    /// Seconds since the start.
    pub fn seconds(&self) -> f64 {
        self.0.elapsed().as_secs_f64()
    }
}

/// The BFGS-Armijo run of Table III's test 5 (the paper's algorithm): a summary and its
/// path every 5 iterations, with the iterate nearest to the paper's end point marked.
pub fn render_bfgs_reference(outcomes: &[Outcome], timing: bool) -> String {
    let Some(o) = outcomes
        .iter()
        .find(|o| o.job.table == Table::III && o.job.method == Some(Method::Bfgs))
    else {
        return String::new();
    };
    let Ok(r) = &o.result else {
        return format!("BFGS run failed: {:?}\n", o.result.as_ref().err());
    };
    let mut s = String::new();
    let free = |c: &[f64]| vec![c[0], c[2], c[3], c[4]];
    let dist = |c: &[f64]| -> f64 {
        free(c)
            .iter()
            .zip(&o.job.paper)
            .map(|(a, b)| (a / b).ln().powi(2))
            .sum()
    };
    let nearest = r
        .history
        .iter()
        .min_by(|a, b| dist(&a.params).total_cmp(&dist(&b.params)))
        .map_or(0, |h| h.iteration);
    let _ = writeln!(
        s,
        "| iter | (E, K, m, sY) | err E | err K | err m | err sY | J | fwd | adj |{}",
        if timing { " time (s) |" } else { "" }
    );
    let _ = writeln!(
        s,
        "|---|---|---|---|---|---|---|---|---|{}",
        if timing { "---|" } else { "" }
    );
    for h in &r.history {
        let last = h.iteration == r.iterations;
        if h.iteration % 5 != 0 && h.iteration != nearest && !last {
            continue;
        }
        let f = free(&h.params);
        let e: Vec<String> = rel_errors(Table::III, &f).iter().map(|x| pct(*x)).collect();
        let mark = if h.iteration == nearest {
            " (nearest to the paper's end point)"
        } else {
            ""
        };
        let _ = writeln!(
            s,
            "| {}{mark} | {} | {} | {} | {} | {} | {} | {} | {} |{}",
            h.iteration,
            tuple(&f, 5),
            e[0],
            e[1],
            e[2],
            e[3],
            cost_text(h.cost, r.reference_cost, timing),
            h.forward_solves,
            h.adjoint_solves,
            if timing {
                format!(" {:.1} |", h.seconds)
            } else {
                String::new()
            }
        );
    }
    let _ = writeln!(s, "\nStop: {}.", r.stop_reason);
    s
}
