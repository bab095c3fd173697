//! Back-to-back timing of the exact gradient under load control against its forward run
//! (docs/validation-load-control.md §4): R1 or R2 (docs/theory.md §11) on the reference
//! mesh, vertical contact; the load-controlled load and hold of the force history of the
//! depth-controlled trapezoid's first two segments; the forward run recording its fields,
//! then `Adjoint::gradient_load` of the depth cost (with the one-pass sweep of an affine
//! law and with the general two-pass one, `Adjoint::set_fused`) and
//! `Adjoint::sensitivities_load`; then the same under depth control (the trapezoid's load
//! and hold, `Adjoint::gradient` of a force cost), and through the instrument's frame
//! (`DirectSolver::run_compliant` of the same machine depths with `Cf = 1e-4` mm/N,
//! `Adjoint::gradient_compliant` of a force cost). Prints the mean of REPEAT alternated
//! runs of each (on-CPU time) and their ratios to the forward:
//! `cargo run --release -p indentify-adjoint --example load_adjoint -- r1 [REPEAT] [NR] [cold]`
//! (`NR`: elements along the radius and the height, 20 the reference mesh). Each gradient
//! is also timed with the forward's factorization handed over (`Adjoint::take_factor`
//! after the forward run). With `cold`, every round runs at parameters changed in their
//! last bits (a fit's new point), so that no run finds its factor from the round before.
use std::time::Instant;

/// The time the calling thread spent on a CPU (`/proc/thread-self/schedstat`, Linux;
/// nanoseconds), or the wall time where that file cannot be read: on a shared machine
/// the on-CPU time of a one-thread run is far less noisy than its wall time.
#[derive(Clone, Copy)]
struct Clock {
    cpu: Option<u64>,
    wall: Instant,
}

impl Clock {
    fn cpu_ns() -> Option<u64> {
        let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
        s.split_whitespace().next()?.parse().ok()
    }
    fn now() -> Clock {
        Clock {
            cpu: Clock::cpu_ns(),
            wall: Instant::now(),
        }
    }
    /// Seconds since `self`.
    fn elapsed(self) -> f64 {
        match (self.cpu, Clock::cpu_ns()) {
            (Some(a), Some(b)) => (b - a) as f64 * 1e-9,
            _ => self.wall.elapsed().as_secs_f64(),
        }
    }
}

use indentify_adjoint::Adjoint;
use indentify_contact::{
    DirectSolver, Frame, LoadHistory, Model, Punch, Schedule, Segment, SolverOptions,
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
    let nr: usize = std::env::args()
        .nth(3)
        .and_then(|s| s.parse().ok())
        .unwrap_or(20);
    let cold = std::env::args().nth(4).is_some_and(|s| s == "cold");
    let mesh = CylinderMesher {
        nr,
        nz: nr,
        ..CylinderMesher::REFERENCE
    }
    .build()
    .expect("reference mesh");
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
    let mat = indentify_laws::LawMaterial(law);
    // mean of `repeat` alternated runs: [forward, gradient (one pass), gradient (two
    // passes), sensitivities] under load control, then the same under depth control
    let mut best = [[0.0; 4]; 3];
    // the one-pass gradients with the forward's factor handed over
    let mut reused = [0.0; 3];
    let mut facts_reused = [0; 3];
    // the largest difference of the load-controlled gradients with and without it,
    // relative to the largest component
    let mut worst = 0.0f64;
    // the last load-controlled forward's own split, Newton iterations, largest contact
    let mut split = None;
    let frame = Frame {
        compliance: 1e-4,
        ..Frame::default()
    };
    // numeric factorizations of the last sweeps: one pass, two passes
    let mut facts = [0; 2];
    let time = |slot: &mut f64, t0: Clock| *slot += t0.elapsed() / repeat as f64;
    let base = params.clone();
    // with `cold`, another point for every run: the last parameter's bits changed
    let point = |run: usize| {
        let mut p = base.clone();
        if cold {
            *p.last_mut().expect("parameters") *= 1.0 + 1e-13 * (run + 1) as f64;
        }
        p
    };
    for round in 0..repeat {
        let params = point(3 * round);
        let t0 = Clock::now();
        let traj = solver
            .run_history(&mat, &params, &history, &opts)
            .expect("load run");
        time(&mut best[0][0], t0);
        split = Some((
            traj.timing,
            traj.total_iterations(),
            traj.steps.iter().map(|s| s.active.len()).max().unwrap_or(0),
        ));

        let n = traj.steps.len();
        let dj_dh: Vec<f64> = traj.steps.iter().map(|s| s.depth).collect();
        let zero = vec![0.0; n];
        let t0 = Clock::now();
        adjoint.take_factor(&mut solver);
        let g = adjoint
            .gradient_load(&mat, &params, &traj, &history, &dj_dh, &zero)
            .expect("gradient");
        time(&mut reused[0], t0);
        facts_reused[0] = g.factorizations;
        let with_factor = g.dj_dc;
        for (k, fused) in [(1, true), (2, false)] {
            adjoint.set_fused(fused);
            let t0 = Clock::now();
            let g = adjoint
                .gradient_load(&mat, &params, &traj, &history, &dj_dh, &zero)
                .expect("gradient");
            time(&mut best[0][k], t0);
            facts[usize::from(k == 2)] = g.factorizations;
            if k == 1 {
                // the gradient with the forward's factor against the fresh one
                let scale = g.dj_dc.iter().fold(0.0f64, |m, x| m.max(x.abs()));
                for (a, b) in g.dj_dc.iter().zip(&with_factor) {
                    worst = worst.max((a - b).abs() / scale);
                }
            }
            std::hint::black_box(g);
        }
        adjoint.set_fused(true);
        let t0 = Clock::now();
        let s = adjoint
            .sensitivities_load(&mat, &params, &traj, &history)
            .expect("sensitivities");
        time(&mut best[0][3], t0);
        std::hint::black_box(s);
        // depth control: the trapezoid's load and hold
        let params = point(3 * round + 1);
        let t0 = Clock::now();
        let traj = solver
            .run(&mat, &params, &schedule, &opts)
            .expect("depth run");
        time(&mut best[1][0], t0);
        let rho: Vec<f64> = traj.steps.iter().map(|s| s.force).collect();
        let t0 = Clock::now();
        adjoint.take_factor(&mut solver);
        let g = adjoint
            .gradient(&mat, &params, &traj, &rho)
            .expect("gradient");
        time(&mut reused[1], t0);
        facts_reused[1] = g.factorizations;
        std::hint::black_box(g);
        for (k, fused) in [(1, true), (2, false)] {
            adjoint.set_fused(fused);
            let t0 = Clock::now();
            let g = adjoint
                .gradient(&mat, &params, &traj, &rho)
                .expect("gradient");
            time(&mut best[1][k], t0);
            facts[usize::from(k == 2)] = g.factorizations;
            std::hint::black_box(g);
        }
        adjoint.set_fused(true);
        let t0 = Clock::now();
        let s = adjoint
            .sensitivities(&mat, &params, &traj)
            .expect("sensitivities");
        time(&mut best[1][3], t0);
        std::hint::black_box(s);
        // through the frame: the same machine depths, a force cost
        let params = point(3 * round + 2);
        let t0 = Clock::now();
        let traj = solver
            .run_compliant(&mat, &params, &schedule, &frame, &opts)
            .expect("compliant run");
        time(&mut best[2][0], t0);
        let rho: Vec<f64> = traj.steps.iter().map(|s| s.force).collect();
        let t0 = Clock::now();
        adjoint.take_factor(&mut solver);
        let g = adjoint
            .gradient_compliant(&mat, &params, &traj, (&schedule, &frame), &rho)
            .expect("compliant gradient");
        time(&mut reused[2], t0);
        facts_reused[2] = g.factorizations;
        std::hint::black_box(g);
        for (k, fused) in [(1, true), (2, false)] {
            adjoint.set_fused(fused);
            let t0 = Clock::now();
            let g = adjoint
                .gradient_compliant(&mat, &params, &traj, (&schedule, &frame), &rho)
                .expect("compliant gradient");
            time(&mut best[2][k], t0);
            std::hint::black_box(g);
        }
        adjoint.set_fused(true);
    }
    println!(
        "{case}: factorizations per sweep (one pass, two passes) {facts:?}; with the \
         forward's factor (load, depth, compliant) {facts_reused:?}, load control's \
         gradient {worst:.1e} from the fresh one"
    );
    if let Some((t, iterations, active)) = &split {
        println!(
            "{case} load control, the last forward: {iterations} Newton iterations, at most \
             {active} active nodes, {} factorizations; wall ms: local {:.1}, assembly {:.1}, \
             factorization {:.1}, solves {:.1}, total {:.1}",
            t.factorizations,
            t.local * 1e3,
            t.assembly * 1e3,
            t.factorization * 1e3,
            t.solve * 1e3,
            t.total * 1e3
        );
    }
    for (k, (name, b, g, s)) in [
        ("load", best[0], "gradient_load", "sensitivities_load"),
        ("depth", best[1], "gradient", "sensitivities"),
        ("compliant", best[2], "gradient_compliant", "(not timed)"),
    ]
    .into_iter()
    .enumerate()
    {
        println!(
            "{case} {name} control: {g} with the forward's factor {:.1} ms ({:.2}x)",
            reused[k] * 1e3,
            reused[k] / b[0]
        );
        println!(
            "{case} {name} control: forward (fields recorded) {:.1} ms, {g} {:.1} ms ({:.2}x; \
             two passes per step {:.1} ms, {:.2}x), {s} {:.1} ms ({:.2}x)",
            b[0] * 1e3,
            b[1] * 1e3,
            b[1] / b[0],
            b[2] * 1e3,
            b[2] / b[0],
            b[3] * 1e3,
            b[3] / b[0]
        );
    }
}
