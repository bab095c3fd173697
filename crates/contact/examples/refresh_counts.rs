//! The inexact Newton solves' counts and times for every law on R2's mesh and history
//! (docs/theory.md §11: 20 x 20 Q8, cone 68 deg, vertical contact), under depth control
//! (the trapezoid, 30 steps per segment) and load control (the depth-controlled load and
//! hold's force history, one load segment per step, against the same depth-controlled
//! load and hold), with each refresh rule (docs/performance.md, "The preconditioner
//! refresh policy"):
//! `cargo run --release -p indentify-contact --example refresh_counts -- [REPEAT] [FILTER]`
//! prints, per law, control and rule, Newton iterations (of the converged steps), cut
//! steps (sub-steps a failed step was cut into), PCG solves, CG iterations, fallbacks and
//! factorizations, then the fastest and median of REPEAT runs (alternated:
//! every law and rule in turn, REPEAT rounds) and the ratios to Norton-Hoff's forward and
//! to the depth-controlled run. `REFRESH_LOG=1` prints the CG iterations of every PCG
//! solve of the first round (`N:i` converged in `i` at the step's `N`-th Newton solve,
//! `N:i!` fell back), `REFRESH_RULES=legacy,adaptive` chooses the rules compared,
//! `REFRESH_CONTROLS=trapezoid,depth,load` the runs. Times are the process's CPU time
//! (the sum of its threads' run time from `/proc/self/task/*/schedstat`, Linux), which a
//! loaded machine disturbs far less than the wall clock; the wall clock where it is not
//! available.
use std::time::Instant;

use indentify_contact::{
    DirectSolver, LoadHistory, Model, Punch, RefreshRule, Schedule, Segment, SolverOptions,
    Trajectory, trapezoid,
};
use indentify_laws::{Hardening, LawMaterial, Material, NortonHoff, Plastic, Prony, Rate};
use indentify_mesh::CylinderMesher;

/// A law of the table: name, material, parameters (those of the `laws_cost` bench).
type Case = (&'static str, Box<dyn Material>, Vec<f64>);

fn cases() -> Vec<Case> {
    let pl = |h, r| Box::new(Plastic::new(h, r)) as Box<dyn Material>;
    let (e, nu, sy, k, m) = (1e5, 0.3, 500.0, 1500.0, 5.0);
    vec![
        (
            "norton_hoff",
            Box::new(LawMaterial(&NortonHoff)),
            vec![e, nu, k, m, sy],
        ),
        (
            "plastic_linear",
            pl(Hardening::Linear, Rate::Independent),
            vec![e, nu, sy, 1000.0],
        ),
        (
            "plastic_power",
            pl(Hardening::Power, Rate::Independent),
            vec![e, nu, sy, 0.2],
        ),
        (
            "plastic_voce",
            pl(Hardening::Voce, Rate::Independent),
            vec![e, nu, sy, 300.0, 20.0],
        ),
        (
            "plastic_linear_norton",
            pl(Hardening::Linear, Rate::Norton),
            vec![e, nu, sy, 1000.0, k, m],
        ),
        (
            "plastic_power_norton",
            pl(Hardening::Power, Rate::Norton),
            vec![e, nu, sy, 0.2, k, m],
        ),
        (
            "plastic_voce_norton",
            pl(Hardening::Voce, Rate::Norton),
            vec![e, nu, sy, 300.0, 20.0, k, m],
        ),
        (
            "prony2",
            Box::new(Prony::new(2).expect("prony")),
            vec![e, nu, 0.3, 0.2, 0.2, 2.0],
        ),
    ]
}

/// What one run is: the trapezoid by depth, the load and hold by depth, or by force.
#[derive(Clone, Copy, PartialEq)]
enum Control {
    Trapezoid,
    Depth,
    Load,
}

impl Control {
    fn name(self) -> &'static str {
        match self {
            Control::Trapezoid => "depth (trapezoid)",
            Control::Depth => "depth (load, hold)",
            Control::Load => "load (load, hold)",
        }
    }
}

fn rule_name(r: RefreshRule) -> &'static str {
    match r {
        RefreshRule::Auto => "auto",
        RefreshRule::Legacy => "legacy",
        RefreshRule::Adaptive => "adaptive",
    }
}

fn controls() -> Vec<Control> {
    let text = std::env::var("REFRESH_CONTROLS").unwrap_or_else(|_| "trapezoid,depth,load".into());
    let mut all: Vec<Control> = text
        .split(',')
        .map(|c| match c.trim() {
            "trapezoid" => Control::Trapezoid,
            "depth" => Control::Depth,
            "load" => Control::Load,
            other => {
                eprintln!("unknown control {other}: expected trapezoid, depth or load");
                std::process::exit(2);
            }
        })
        .collect();
    all.dedup();
    all
}

/// The CPU time of the process so far (s): every thread's run time (Linux), else the wall
/// clock since the first call.
fn cpu_seconds() -> f64 {
    static START: std::sync::OnceLock<Instant> = std::sync::OnceLock::new();
    let start = *START.get_or_init(Instant::now);
    let ns: Option<u64> = std::fs::read_dir("/proc/self/task").ok().map(|tasks| {
        tasks
            .filter_map(|t| {
                let text = std::fs::read_to_string(t.ok()?.path().join("schedstat")).ok()?;
                text.split_whitespace().next()?.parse::<u64>().ok()
            })
            .sum()
    });
    match ns {
        Some(ns) if ns > 0 => 1e-9 * ns as f64,
        _ => start.elapsed().as_secs_f64(),
    }
}

fn rules() -> Vec<RefreshRule> {
    let text = std::env::var("REFRESH_RULES").unwrap_or_else(|_| "legacy,adaptive".into());
    text.split(',')
        .map(|r| match r.trim() {
            "auto" => RefreshRule::Auto,
            "legacy" => RefreshRule::Legacy,
            "adaptive" => RefreshRule::Adaptive,
            other => {
                eprintln!("unknown rule {other}: expected auto, legacy or adaptive");
                std::process::exit(2);
            }
        })
        .collect()
}

/// One configuration of the table and its measurements.
struct Row {
    law: usize,
    control: Control,
    rule: RefreshRule,
    times: Vec<f64>,
    counts: String,
}

fn main() {
    let repeat: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(3);
    let filter = std::env::args().nth(2).unwrap_or_default();
    let mesh = CylinderMesher::REFERENCE.build().expect("reference mesh");
    let model = Model::new(
        mesh,
        Punch::Cone {
            half_angle_deg: 68.0,
        },
    )
    .expect("model");
    let trapezoid = Schedule::from_segments(&trapezoid(0.1, 1.0, 1.0, 1.0, 30)).expect("schedule");
    let seg = |depth| Segment {
        duration: 1.0,
        depth,
        steps: 30,
    };
    let load_hold = Schedule::from_segments(&[seg(0.1), seg(0.1)]).expect("schedule");
    let opts = SolverOptions {
        record_fields: false,
        ..SolverOptions::default()
    };
    let cases: Vec<Case> = cases()
        .into_iter()
        .filter(|c| c.0 == "norton_hoff" || c.0.contains(&filter))
        .collect();
    let mut solver = DirectSolver::new(&model).expect("solver");
    // each law's force history of the load and hold (the legacy rule's, for every rule)
    solver.set_refresh_rule(RefreshRule::Legacy);
    let histories: Vec<LoadHistory> = cases
        .iter()
        .map(|(_, mat, c)| {
            let t = solver.run(&**mat, c, &load_hold, &opts).expect("depth run");
            LoadHistory::from_force_record(&load_hold.t, &t.forces()).expect("history")
        })
        .collect();
    let mut rows = Vec::new();
    for law in 0..cases.len() {
        for control in controls() {
            for &rule in &rules() {
                rows.push(Row {
                    law,
                    control,
                    rule,
                    times: Vec::new(),
                    counts: String::new(),
                });
            }
        }
    }
    let log = std::env::var_os("REFRESH_LOG").is_some();
    for round in 0..repeat {
        for row in &mut rows {
            let (_, mat, c) = &cases[row.law];
            solver.set_refresh_rule(row.rule);
            solver.keep_pcg_log(log && round == 0);
            let t0 = cpu_seconds();
            let traj: Trajectory = match row.control {
                Control::Trapezoid => solver.run(&**mat, c, &trapezoid, &opts),
                Control::Depth => solver.run(&**mat, c, &load_hold, &opts),
                Control::Load => solver.run_history(&**mat, c, &histories[row.law], &opts),
            }
            .expect("run");
            row.times.push(cpu_seconds() - t0);
            if round == 0 {
                let tm = traj.timing;
                let cuts = traj.steps.iter().filter(|s| !s.on_schedule).count();
                row.counts = format!(
                    "{:>5} {:>4} {:>6} {:>6} {:>6} {:>6}",
                    traj.total_iterations(),
                    cuts,
                    tm.pcg_solves,
                    tm.cg_iterations,
                    tm.pcg_fallbacks,
                    tm.factorizations
                );
                if log {
                    let events: Vec<String> = solver
                        .system()
                        .pcg_log()
                        .iter()
                        .map(|e| {
                            format!(
                                "{}:{}{}",
                                e.newton,
                                e.iterations,
                                if e.converged { "" } else { "!" }
                            )
                        })
                        .collect();
                    println!(
                        "{} {} {}: {}",
                        cases[row.law].0,
                        row.control.name(),
                        rule_name(row.rule),
                        events.join(" ")
                    );
                }
            }
        }
    }
    println!(
        "{:<22} {:<19} {:<8} {:>5} {:>4} {:>6} {:>6} {:>6} {:>6} {:>9} {:>9} {:>7} {:>7}",
        "law",
        "control",
        "rule",
        "Newton",
        "cuts",
        "PCG",
        "CG its",
        "fallbk",
        "factor",
        "min cpu ms",
        "median",
        "/ NH",
        "/ depth"
    );
    let median = |t: &[f64]| {
        let mut v = t.to_vec();
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    for row in &rows {
        let nh = rows
            .iter()
            .find(|r| r.law == 0 && r.control == row.control && r.rule == row.rule)
            .map_or(f64::NAN, |r| median(&r.times));
        let depth = rows
            .iter()
            .find(|r| r.law == row.law && r.control == Control::Depth && r.rule == row.rule)
            .map_or(f64::NAN, |r| median(&r.times));
        let own = median(&row.times);
        let min = row.times.iter().copied().fold(f64::INFINITY, f64::min);
        println!(
            "{:<22} {:<19} {:<8} {} {:>9.1} {:>9.1} {:>7.3} {:>7}",
            cases[row.law].0,
            row.control.name(),
            rule_name(row.rule),
            row.counts,
            1e3 * min,
            1e3 * own,
            own / nh,
            if row.control == Control::Load {
                format!("{:.3}", own / depth)
            } else {
                "-".into()
            }
        );
    }
}
