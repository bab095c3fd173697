//! Back-to-back timing of load control against depth control on the same history
//! (docs/validation-load-control.md, docs/solver.md): R1 or R2 (docs/theory.md §11) on the
//! reference mesh (or an `NR` x `NR` one), vertical contact; the depth-controlled load and
//! hold of the trapezoid, then the load-controlled run of its force history (one load
//! segment per step). Prints the fastest of REPEAT alternated runs of each (the process's
//! CPU time, `/proc/self/task/*/schedstat`, Linux; else the wall clock) and their ratio:
//! `cargo run --release -p indentify-contact --example load_vs_depth -- r2 [REPEAT] [NR]`
//! (then each run's steps and counts: Newton iterations, active-set changes,
//! factorizations, CG iterations; with `LVD_STEPS` set, every step's Newton iterations,
//! sub-steps of a cut marked `*`).
use std::time::Instant;

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

use indentify_contact::{
    DirectSolver, LoadHistory, Model, Punch, Schedule, Segment, SolverOptions,
};
use indentify_laws::{Law, Maxwell, NortonHoff};
use indentify_mesh::CylinderMesher;

fn main() {
    let case = std::env::args().nth(1).unwrap_or_else(|| "r2".into());
    let repeat: usize = std::env::args()
        .nth(2)
        .and_then(|s| s.parse().ok())
        .unwrap_or(3);
    let (law, params): (&dyn Law, Vec<f64>) = match case.as_str() {
        "r1" => (&Maxwell, vec![2e4, 0.3, 3e4]),
        _ => (&NortonHoff, vec![1e5, 0.3, 1500.0, 5.0, 500.0]),
    };
    let nr: usize = std::env::args()
        .nth(3)
        .and_then(|s| s.parse().ok())
        .unwrap_or(20);
    let mesh = CylinderMesher {
        nr,
        nz: nr,
        ..CylinderMesher::REFERENCE
    }
    .build()
    .expect("mesh");
    let model = Model::new(
        mesh,
        Punch::Cone {
            half_angle_deg: 68.0,
        },
    )
    .expect("model");
    let seg = |depth| Segment {
        duration: 1.0,
        depth,
        steps: 30,
    };
    let schedule = Schedule::from_segments(&[seg(0.1), seg(0.1)]).expect("schedule");
    let opts = SolverOptions {
        record_fields: false,
        ..SolverOptions::default()
    };
    let mut solver = DirectSolver::new(&model).expect("solver");
    let by_depth = solver
        .run(&indentify_laws::LawMaterial(law), &params, &schedule, &opts)
        .expect("depth run");
    let history =
        LoadHistory::from_force_record(&schedule.t, &by_depth.forces()).expect("force history");
    let (mut best_d, mut best_f) = (f64::INFINITY, f64::INFINITY);
    let (mut it_d, mut it_f) = (0, 0);
    let (mut timing_d, mut timing_f) = (String::new(), String::new());
    let (mut steps_d, mut steps_f) = (0, 0);
    let mut worst: f64 = 0.0;
    for _ in 0..repeat {
        let t0 = cpu_seconds();
        let d = solver
            .run(&indentify_laws::LawMaterial(law), &params, &schedule, &opts)
            .expect("depth run");
        best_d = best_d.min(cpu_seconds() - t0);
        let t0 = cpu_seconds();
        let f = solver
            .run_history(&indentify_laws::LawMaterial(law), &params, &history, &opts)
            .expect("load run");
        best_f = best_f.min(cpu_seconds() - t0);
        it_d = d.total_iterations();
        it_f = f.total_iterations();
        (steps_d, steps_f) = (d.steps.len(), f.steps.len());
        let changes = |t: &indentify_contact::Trajectory| {
            t.steps
                .iter()
                .map(|s| s.active_set_changes as u64)
                .sum::<u64>()
        };
        timing_d = format!("{} active-set changes; {}", changes(&d), d.timing);
        timing_f = format!("{} active-set changes; {}", changes(&f), f.timing);
        if std::env::var_os("LVD_STEPS").is_some() {
            let its = |t: &indentify_contact::Trajectory| {
                t.steps
                    .iter()
                    .map(|s| format!("{}{}", s.iterations, if s.on_schedule { "" } else { "*" }))
                    .collect::<Vec<_>>()
                    .join(" ")
            };
            println!("depth: {}\nload:  {}", its(&d), its(&f));
        }
        for (a, b) in d.schedule_steps().zip(f.schedule_steps()) {
            worst = worst.max((a.depth - b.depth).abs() / 0.1);
        }
    }
    println!(
        "{case}: depth control {:.1} ms ({it_d} Newton iterations), load control {:.1} ms \
         ({it_f}), ratio {:.3}; max |dh| / h_max = {worst:.1e}",
        1e3 * best_d,
        1e3 * best_f,
        best_f / best_d
    );
    println!("  depth control: {steps_d} steps; {timing_d}");
    println!("  load control: {steps_f} steps; {timing_f}");
}
