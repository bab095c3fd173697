//! Back-to-back timing of a fit's forward sensitivity pass against its forward run
//! (docs/performance.md, "A cheaper sensitivity pass"): R1 (Maxwell) or R2 (Norton-Hoff)
//! of docs/theory.md §11 on the reference mesh, vertical contact, the depth-controlled
//! trapezoid (0.1 mm, 1 s load, hold, unload, 30 steps each), the free parameters of an
//! identification (R1: `E`, `eta`; R2: `E`, `K`, `m`, `sY`). Each round runs at new
//! parameters (changed in their last bits, as a fit's new point), records the fields,
//! then times, on one thread (on-CPU time):
//! - `fwd`: the forward run;
//! - `take`: `Adjoint::sensitivities_of` with the forward's factor handed over
//!   (`Adjoint::take_factor`, as `identify` does);
//! - `fresh`: the same pass without it;
//! - `gauss`: the pass with the all-nodal recursion off (`Adjoint::set_fused(false)`;
//!   for R2 the Gauss-point pass with its third pass over the points for `dF_i/dc_k`
//!   instead of the force dofs' rows of the tangent), the forward's factor taken from a
//!   second forward run at the same point (not timed);
//! - `full`: `fresh` with the finite-strain operators `B_L` and `P` formed per point
//!   (`Adjoint::set_compact_finite(false)`, the pass before the compact `G = P L(F)`),
//!   run before or after `fresh` by turns (under small strain the same pass as `fresh`).
//!
//! `r2f` is R2 under finite strain (frictionless normal contact).
//!
//! `cargo run --release -p indentify-adjoint --example sens_cost -- r1 [ROUNDS]`
//! prints the median of each and its ratio to the forward, the numeric factorizations of
//! each pass, and the largest difference of the columns against the Gauss-point pass's,
//! relative to each column's largest entry. `... -- r1 ROUNDS gauss|nodal|forward` runs
//! that alone ROUNDS times (the sensitivity passes on one trajectory, without the
//! forward's factor), for `perf record`.
use std::time::Instant;

use indentify_adjoint::Adjoint;
use indentify_contact::{
    ContactKind, DirectSolver, Kinematics, Model, Punch, Schedule, SolverOptions, trapezoid,
};
use indentify_laws::{Law, LawMaterial, Maxwell, NortonHoff};
use indentify_mesh::CylinderMesher;

/// The time the calling thread spent on a CPU (`/proc/thread-self/schedstat`), or the
/// wall time where that file cannot be read.
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
    fn elapsed(self) -> f64 {
        match (self.cpu, Clock::cpu_ns()) {
            (Some(a), Some(b)) => (b - a) as f64 * 1e-9,
            _ => self.wall.elapsed().as_secs_f64(),
        }
    }
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let case = std::env::args().nth(1).unwrap_or_else(|| "r1".into());
    let rounds: usize = std::env::args()
        .nth(2)
        .and_then(|s| s.parse().ok())
        .unwrap_or(5);
    let (law, base, free): (&dyn Law, Vec<f64>, Vec<usize>) = match case.as_str() {
        "r1" => (&Maxwell, vec![2e4, 0.3, 3e4], vec![0, 2]),
        _ => (
            &NortonHoff,
            vec![1e5, 0.3, 1500.0, 5.0, 500.0],
            vec![0, 2, 3, 4],
        ),
    };
    let mesh = CylinderMesher::REFERENCE.build().expect("reference mesh");
    let cone = Punch::Cone {
        half_angle_deg: 68.0,
    };
    // `r2f`: R2 under finite strain (frictionless normal contact, as finite strain needs)
    let model = if case == "r2f" {
        Model::with_contact(mesh, cone, ContactKind::Normal)
            .and_then(|m| m.with_kinematics(Kinematics::Finite))
            .expect("model")
    } else {
        Model::new(mesh, cone).expect("model")
    };
    let schedule = Schedule::from_segments(&trapezoid(0.1, 1.0, 1.0, 1.0, 30)).expect("schedule");
    let opts = SolverOptions {
        record_fields: true,
        ..SolverOptions::default()
    };
    let mat = LawMaterial(law);
    // the size of one factorization of the model's tangent (what a pass keeping one per
    // step would store)
    if let Ok(ch) = indentify_fe::SparseCholesky::analyse(&model.pattern) {
        println!(
            "{case}: {} equations, {} Gauss points, factor {} nonzeros ({:.2} MB)",
            model.dofs.n_eq,
            model.disc.n_qp(),
            ch.factor_nnz(),
            8.0 * ch.factor_nnz() as f64 / 1e6
        );
    }
    let mut solver = DirectSolver::new(&model).expect("solver");
    let mut adjoint = Adjoint::new(&model).expect("adjoint");
    // `sens_cost r1 N gauss|nodal|forward`: that alone, N times (for `perf record`)
    if let Some(only) = std::env::args().nth(3) {
        let traj = solver.run(&mat, &base, &schedule, &opts).expect("forward");
        adjoint.set_fused(only != "gauss");
        adjoint.set_compact_finite(only != "full");
        let t0 = Clock::now();
        for _ in 0..rounds {
            if only == "forward" {
                std::hint::black_box(solver.run(&mat, &base, &schedule, &opts).expect("forward"));
            } else {
                std::hint::black_box(
                    adjoint
                        .sensitivities_of(&mat, &base, &traj, &free)
                        .expect("sensitivities"),
                );
            }
        }
        println!("{only}: {:.2} ms each", 1e3 * t0.elapsed() / rounds as f64);
        return;
    }
    let mut t = [Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new()];
    let mut full_worst = 0.0f64;
    let mut facts = [0usize; 3];
    let mut worst = 0.0f64;
    for round in 0..=rounds {
        let mut c = base.clone();
        for v in c.iter_mut() {
            *v *= 1.0 + 1e-13 * (round + 1) as f64;
        }
        let t0 = Clock::now();
        let traj = solver.run(&mat, &c, &schedule, &opts).expect("forward");
        let fwd = t0.elapsed();
        let f0 = adjoint.factorizations();
        let t0 = Clock::now();
        adjoint.take_factor(&mut solver);
        let take = adjoint
            .sensitivities_of(&mat, &c, &traj, &free)
            .expect("sensitivities");
        let t_take = t0.elapsed();
        let f1 = adjoint.factorizations();
        // `fresh` and `full` by turns first
        let mut timed = |compact: bool| {
            adjoint.set_compact_finite(compact);
            let f = adjoint.factorizations();
            let t0 = Clock::now();
            let out = adjoint
                .sensitivities_of(&mat, &c, &traj, &free)
                .expect("sensitivities");
            let t = t0.elapsed();
            adjoint.set_compact_finite(true);
            (out, t, adjoint.factorizations() - f)
        };
        let ((fresh, t_fresh, n_fresh), (full, t_full, _)) = if round % 2 == 0 {
            let a = timed(true);
            (a, timed(false))
        } else {
            let b = timed(false);
            (timed(true), b)
        };
        let f2 = f1 + n_fresh;
        let f2b = adjoint.factorizations();
        solver.run(&mat, &c, &schedule, &opts).expect("forward");
        adjoint.set_fused(false);
        let t0 = Clock::now();
        adjoint.take_factor(&mut solver);
        let gauss = adjoint
            .sensitivities_of(&mat, &c, &traj, &free)
            .expect("sensitivities");
        let t_gauss = t0.elapsed();
        adjoint.set_fused(true);
        let f3 = adjoint.factorizations();
        facts = [f1 - f0, f2 - f1, f3 - f2b];
        for &k in &free {
            let scale = gauss.df_dc.iter().fold(0.0f64, |m, r| m.max(r[k].abs()));
            for ((a, b), g) in take.df_dc.iter().zip(&fresh.df_dc).zip(&gauss.df_dc) {
                worst = worst
                    .max((a[k] - g[k]).abs() / scale)
                    .max((b[k] - g[k]).abs() / scale);
            }
            for (a, b) in fresh.df_dc.iter().zip(&full.df_dc) {
                full_worst = full_worst.max((a[k] - b[k]).abs() / scale);
            }
        }
        if round > 0 {
            // the first round warms the caches up
            for (v, x) in t.iter_mut().zip([fwd, t_take, t_fresh, t_gauss, t_full]) {
                v.push(x);
            }
        }
    }
    let m: Vec<f64> = t.iter_mut().map(|v| median(v)).collect();
    println!(
        "{case}: forward {:.1} ms; sensitivities of {} parameters: with the forward's factor \
         {:.1} ms ({:.3}x, {} factorizations), fresh {:.1} ms ({:.3}x, {}), Gauss-point pass \
         {:.1} ms ({:.3}x, {}); columns against the Gauss-point pass's: {worst:.1e}; \
         B_L and P {:.1} ms ({:.3}x; compact / B_L and P {:.3}; columns apart by \
         {full_worst:.1e})",
        1e3 * m[0],
        free.len(),
        1e3 * m[1],
        m[1] / m[0],
        facts[0],
        1e3 * m[2],
        m[2] / m[0],
        facts[1],
        1e3 * m[3],
        m[3] / m[0],
        facts[2],
        1e3 * m[4],
        m[4] / m[0],
        m[2] / m[4],
    );
}
