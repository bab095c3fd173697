//! Back-to-back timing of the exact gradient under load control against its forward run
//! (docs/validation-load-control.md §4): R1 or R2 (docs/theory.md §11) on the reference
//! mesh, vertical contact; the load-controlled load and hold of the force history of the
//! depth-controlled trapezoid's first two segments; the forward run recording its fields,
//! then `Adjoint::gradient_load` of the depth cost and `Adjoint::sensitivities_load`.
//! Prints the fastest of REPEAT alternated runs of each and their ratios:
//! `cargo run --release -p indentify-adjoint --example load_adjoint -- r1 [REPEAT]`.
use std::time::Instant;

use indentify_adjoint::Adjoint;
use indentify_contact::{
    DirectSolver, LoadHistory, Model, Punch, Schedule, Segment, SolverOptions,
};
use indentify_laws::{Law, Maxwell, NortonHoff};
use indentify_mesh::CylinderMesher;

fn main() {
    let case = std::env::args().nth(1).unwrap_or_else(|| "r1".into());
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
    let plain = SolverOptions {
        record_fields: false,
        ..SolverOptions::default()
    };
    let opts = SolverOptions {
        record_fields: true,
        ..SolverOptions::default()
    };
    let mut solver = DirectSolver::new(&model).expect("solver");
    let by_depth = solver
        .run(
            &indentify_laws::LawMaterial(law),
            &params,
            &schedule,
            &plain,
        )
        .expect("depth run");
    let history =
        LoadHistory::from_force_record(&schedule.t, &by_depth.forces()).expect("force history");
    let mut adjoint = Adjoint::new(&model).expect("adjoint");
    let (mut best_f, mut best_g, mut best_s) = (f64::INFINITY, f64::INFINITY, f64::INFINITY);
    for _ in 0..repeat {
        let t0 = Instant::now();
        let traj = solver
            .run_history(&indentify_laws::LawMaterial(law), &params, &history, &opts)
            .expect("load run");
        best_f = best_f.min(t0.elapsed().as_secs_f64());
        let n = traj.steps.len();
        let dj_dh: Vec<f64> = traj.steps.iter().map(|s| s.depth).collect();
        let t0 = Instant::now();
        let g = adjoint
            .gradient_load(
                &indentify_laws::LawMaterial(law),
                &params,
                &traj,
                &history,
                &dj_dh,
                &vec![0.0; n],
            )
            .expect("gradient");
        best_g = best_g.min(t0.elapsed().as_secs_f64());
        let t0 = Instant::now();
        let s = adjoint
            .sensitivities_load(&indentify_laws::LawMaterial(law), &params, &traj, &history)
            .expect("sensitivities");
        best_s = best_s.min(t0.elapsed().as_secs_f64());
        std::hint::black_box((g, s));
    }
    println!(
        "{case}: load-controlled forward (fields recorded) {:.1} ms, gradient_load {:.1} ms \
         ({:.2}x), sensitivities_load {:.1} ms ({:.2}x)",
        best_f * 1e3,
        best_g * 1e3,
        best_g / best_f,
        best_s * 1e3,
        best_s / best_f
    );
}
