//! Back-to-back cost of a constant-Pdot/P forward (docs/validation-load-control.md §12):
//! Norton-Hoff (R2's law) under the 68 deg cone, a trigger ramp to `p0`, Pdot/P = `r` to
//! `16 p0` in 12 steps and a 1 s hold (the consistency test's history,
//! `crates/contact/tests/pdotp.rs`), against
//! - a linear force ramp from `p0` to `16 p0` of the same duration and step count, and
//! - the depth-controlled runs of each one's depths at the times of every step it took
//!   (its cut sub-steps included: the same discrete problem stated the other way round).
//!
//! Prints the fastest of REPEAT alternated runs of each (CPU of the process's threads, wall), their
//! steps, cuts, Newton iterations, factorizations and CG iterations:
//! `cargo run --release -p indentify-contact --example pdotp_cost -- [MESH] [REPEAT]`
//! with MESH `small` (the test's 2 x 2 mm cylinder, 10 x 10 Q8, p0 = 4 N) or `reference`
//! (R2's 10 x 10 mm reference mesh, p0 = 32 N), REPEAT 3 by default.
//! With `PDOTP_STEPS` set, every step's Newton iterations (cut sub-steps marked `*`); with
//! `PDOTP_PCG` set, every PCG solve of the load-controlled runs.
use std::time::Instant;

use indentify_contact::{
    ContactKind, DirectSolver, Kinematics, LoadHistory, Model, Punch, Schedule, SegmentSpec,
    SolverOptions, Trajectory,
};
use indentify_laws::{LawMaterial, NortonHoff};
use indentify_mesh::CylinderMesher;

fn linear(duration: f64, force: f64, steps: usize) -> SegmentSpec {
    SegmentSpec {
        duration: Some(duration),
        depth: None,
        force: Some(force),
        pdot_over_p: None,
        steps,
    }
}

/// CPU seconds of every thread of this process (Linux: the sum of
/// `/proc/self/task/*/schedstat`, nanoseconds), or `None`.
fn process_cpu() -> Option<f64> {
    let mut ns = 0.0;
    for e in std::fs::read_dir("/proc/self/task").ok()? {
        let s = std::fs::read_to_string(e.ok()?.path().join("schedstat")).ok()?;
        ns += s.split_whitespace().next()?.parse::<f64>().ok()?;
    }
    Some(ns * 1e-9)
}

fn describe(name: &str, t: &Trajectory, cpu: f64, wall: f64) {
    let cuts = t.steps.iter().filter(|s| !s.on_schedule).count();
    println!(
        "  {name:<34} cpu {:8.1} ms  wall {:8.1} ms  {:3} steps ({cuts:2} off schedule)  \
         {:4} Newton  {}",
        1e3 * cpu,
        1e3 * wall,
        t.steps.len(),
        t.total_iterations(),
        t.timing
    );
    if std::env::var_os("PDOTP_STEPS").is_some() {
        let its: Vec<String> = t
            .steps
            .iter()
            .map(|s| format!("{}{}", s.iterations, if s.on_schedule { "" } else { "*" }))
            .collect();
        println!("    {}", its.join(" "));
    }
}

/// The depth schedule of every step `t` took.
fn depths_of(t: &Trajectory) -> Schedule {
    let ts: Vec<f64> = std::iter::once(0.0)
        .chain(t.steps.iter().map(|s| s.t))
        .collect();
    let hs: Vec<f64> = std::iter::once(0.0)
        .chain(t.steps.iter().map(|s| s.depth))
        .collect();
    Schedule::from_record(&ts, &hs).expect("depth schedule")
}

fn main() {
    let mesh_name = std::env::args().nth(1).unwrap_or_else(|| "small".into());
    let repeat: usize = std::env::args()
        .nth(2)
        .and_then(|s| s.parse().ok())
        .unwrap_or(3);
    let (mesh, p0) = match mesh_name.as_str() {
        "reference" => (CylinderMesher::REFERENCE, 32.0),
        _ => (
            CylinderMesher {
                radius: 2.0,
                height: 2.0,
                nr: 10,
                nz: 10,
                grading_r: 1.3,
                grading_z: 1.3,
            },
            4.0,
        ),
    };
    let model = Model::with_contact(
        mesh.build().expect("mesh"),
        Punch::Cone {
            half_angle_deg: 68.0,
        },
        ContactKind::Vertical,
    )
    .expect("model")
    .with_kinematics(Kinematics::Small)
    .expect("kinematics");
    let params = [1e5, 0.3, 1500.0, 5.0, 500.0];
    let mat = LawMaterial(&NortonHoff);
    let r = 0.5;
    let duration = 16f64.ln() / r;
    let pdotp = LoadHistory::from_specs(&[
        linear(0.1, p0, 2),
        SegmentSpec {
            duration: None,
            depth: None,
            force: Some(16.0 * p0),
            pdot_over_p: Some(r),
            steps: 12,
        },
        linear(1.0, 16.0 * p0, 4),
    ])
    .expect("Pdot/P history");
    let ramp = LoadHistory::from_specs(&[
        linear(0.1, p0, 2),
        linear(duration, 16.0 * p0, 12),
        linear(1.0, 16.0 * p0, 4),
    ])
    .expect("linear history");
    let opts = SolverOptions {
        record_fields: false,
        ..SolverOptions::default()
    };
    let mut solver = DirectSolver::new(&model).expect("solver");
    let by_pdotp = solver.run_history(&mat, &params, &pdotp, &opts).unwrap();
    let by_ramp = solver.run_history(&mat, &params, &ramp, &opts).unwrap();
    let depth_pdotp = depths_of(&by_pdotp);
    let depth_ramp = depths_of(&by_ramp);
    println!(
        "Norton-Hoff, {mesh_name} mesh: trigger to {p0} N, {duration:.4} s to {} N (Pdot/P = {r}/s \
         or linear), 1 s hold; fastest of {repeat} alternated runs",
        16.0 * p0
    );
    let names = [
        "Pdot/P (load control)",
        "linear ramp (load control)",
        "depths of the Pdot/P run",
        "depths of the linear run",
    ];
    let mut best = [(f64::INFINITY, f64::INFINITY); 4];
    let mut last: Vec<Option<Trajectory>> = vec![None, None, None, None];
    for _ in 0..repeat {
        for (k, slot) in last.iter_mut().enumerate() {
            let (c0, w0) = (process_cpu().unwrap_or(0.0), Instant::now());
            let t = match k {
                0 => solver.run_history(&mat, &params, &pdotp, &opts),
                1 => solver.run_history(&mat, &params, &ramp, &opts),
                2 => solver.run(&mat, &params, &depth_pdotp, &opts),
                _ => solver.run(&mat, &params, &depth_ramp, &opts),
            }
            .expect("run");
            let (cpu, wall) = (
                process_cpu().unwrap_or(0.0) - c0,
                w0.elapsed().as_secs_f64(),
            );
            best[k] = (best[k].0.min(cpu), best[k].1.min(wall));
            *slot = Some(t);
        }
    }
    for (k, name) in names.iter().enumerate() {
        describe(name, last[k].as_ref().unwrap(), best[k].0, best[k].1);
    }
    if std::env::var_os("PDOTP_PCG").is_some() {
        // every PCG solve of one more run of each load-controlled history: the Newton
        // solve of its step, CG iterations, `!` where it fell back
        solver.keep_pcg_log(true);
        for (name, h) in [("Pdot/P", &pdotp), ("linear", &ramp)] {
            solver.run_history(&mat, &params, h, &opts).expect("run");
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
            println!("  PCG solves, {name}: {}", events.join(" "));
        }
    }
    println!(
        "  CPU ratios: Pdot/P / its depths {:.2}, linear / its depths {:.2}, Pdot/P / linear {:.2}",
        best[0].0 / best[2].0,
        best[1].0 / best[3].0,
        best[0].0 / best[1].0
    );
}
