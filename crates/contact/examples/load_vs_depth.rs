//! Back-to-back timing of load control against depth control on the same history
//! (docs/validation-load-control.md, docs/solver.md): R1 or R2 (docs/theory.md §11) on the
//! reference mesh, vertical contact; the depth-controlled load and hold of the trapezoid,
//! then the load-controlled run of its force history (one load segment per step). Prints
//! the fastest of REPEAT alternated runs of each and their ratio:
//! `cargo run --release -p indentify-contact --example load_vs_depth -- r2 [REPEAT]`
//! (then each run's steps and counts: factorizations, CG iterations; with `LVD_STEPS`
//! set, every step's Newton iterations, sub-steps of a cut marked `*`).
use std::time::Instant;

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
    let mesh = CylinderMesher::REFERENCE.build().expect("reference mesh");
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
        let t0 = Instant::now();
        let d = solver
            .run(&indentify_laws::LawMaterial(law), &params, &schedule, &opts)
            .expect("depth run");
        best_d = best_d.min(t0.elapsed().as_secs_f64());
        let t0 = Instant::now();
        let f = solver
            .run_history(&indentify_laws::LawMaterial(law), &params, &history, &opts)
            .expect("load run");
        best_f = best_f.min(t0.elapsed().as_secs_f64());
        it_d = d.total_iterations();
        it_f = f.total_iterations();
        (steps_d, steps_f) = (d.steps.len(), f.steps.len());
        timing_d = format!("{}", d.timing);
        timing_f = format!("{}", f.timing);
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
