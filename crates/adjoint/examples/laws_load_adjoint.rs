//! Every law of R2 under load control, its exact gradient against its forward run, back
//! to back in one process (docs/validation-load-control.md §6, "Every law under load
//! control"): R2's reference mesh (20 x 20 Q8, cone 68 deg, vertical contact), the force
//! history of the depth-controlled trapezoid (0.1 mm, 30 steps per segment) run of each
//! law, kept from the start to the last step before the unload drops under 0.3 of the
//! peak force, driven by force; the depth cost `J = sum U_i^2 / 2` (`dJ/dU_i = U_i`).
//! Per law and round: the depth-controlled forward (for the load / depth ratio), the
//! load-controlled forward recording its fields, then `Adjoint::gradient_load` with the
//! forward's factorization taken (`Adjoint::take_factor`, as `identify` does), the same
//! sweep fresh, and the sweep with `Adjoint::set_fused(false)` (for a material with
//! internal variables the Gauss-point sweep, for a stress-only law the two-pass one).
//! Every round runs at parameters changed in their last bits (a fit's new point), so that
//! no forward finds the factor of the round before. Prints the mean of REPEAT rounds
//! (on-CPU time of the thread) and the ratios to the load-controlled forward:
//! `RAYON_NUM_THREADS=1 cargo run --release -p indentify-adjoint --example
//! laws_load_adjoint -- [FILTER] [REPEAT] [frame]` (`FILTER`: the cases whose name
//! contains it). With `frame`, the second drive is depth through the instrument's frame
//! instead of load control: `DirectSolver::run_compliant` of the trapezoid's machine
//! depths with `Cf = 1e-4` mm/N, `Adjoint::gradient_compliant` of the force cost
//! `J = sum F_i^2 / 2` (the "load" columns are then the compliant drive's).
//! With `LAWS_LOAD_BITS` set in the environment, each round's gradient (the forward's
//! factor taken) is printed to stderr as its bits, to compare two builds.

use std::time::Instant;

use indentify_adjoint::Adjoint;
use indentify_contact::{
    ContactKind, DirectSolver, Frame, LoadHistory, Model, Punch, Schedule, SolverOptions,
    Trajectory, trapezoid,
};
use indentify_laws::{
    Elastic, Hardening, LawMaterial, Material, Maxwell, NortonHoff, Plastic, Prony, Rate,
};
use indentify_mesh::CylinderMesher;

/// The time the calling thread spent on a CPU (`/proc/thread-self/schedstat`, Linux;
/// nanoseconds), or the wall time where that file cannot be read.
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

/// Every law of R2 (`benches/laws_cost.rs`'s cases): name, material, parameters.
fn cases() -> Vec<(&'static str, Box<dyn Material>, Vec<f64>)> {
    let pl = |h, r| Box::new(Plastic::new(h, r)) as Box<dyn Material>;
    let prony = |n| Box::new(Prony::new(n).expect("prony")) as Box<dyn Material>;
    let (e, nu, sy, k, m) = (1e5, 0.3, 500.0, 1500.0, 5.0);
    vec![
        ("elastic", Box::new(LawMaterial(&Elastic)), vec![e, nu]),
        (
            "maxwell",
            Box::new(LawMaterial(&Maxwell)),
            vec![20000.0, 0.3, 30000.0],
        ),
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
        ("prony1", prony(1), vec![e, nu, 0.3, 0.2]),
        ("prony2", prony(2), vec![e, nu, 0.3, 0.2, 0.2, 2.0]),
        (
            "prony3",
            prony(3),
            vec![e, nu, 0.3, 0.2, 0.2, 2.0, 0.1, 20.0],
        ),
    ]
}

/// The load-controlled history of a depth-controlled run's forces (`forces[0]` the
/// start's, as [`indentify_contact::Trajectory::forces`] gives them beside `schedule.t`):
/// from the start to the last step before the force drops under 0.3 of its peak.
fn force_history(schedule: &Schedule, forces: &[f64]) -> LoadHistory {
    let peak = forces.iter().fold(0.0f64, |m, f| m.max(*f));
    let at_peak = forces
        .iter()
        .position(|f| *f == peak)
        .expect("a largest force");
    let end = (at_peak..forces.len())
        .find(|&i| forces[i] < 0.3 * peak)
        .unwrap_or(forces.len());
    LoadHistory::from_force_record(&schedule.t[..end], &forces[..end]).expect("force history")
}

fn main() {
    let only = std::env::args().nth(1).unwrap_or_default();
    let repeat: usize = std::env::args()
        .nth(2)
        .and_then(|s| s.parse().ok())
        .unwrap_or(3);
    let through_frame = std::env::args().nth(3).is_some_and(|s| s == "frame");
    let frame = Frame {
        compliance: 1e-4,
        ..Frame::default()
    };
    let mesh = CylinderMesher::REFERENCE.build().expect("reference mesh");
    let model = Model::with_contact(
        mesh,
        Punch::Cone {
            half_angle_deg: 68.0,
        },
        ContactKind::Vertical,
    )
    .expect("model");
    let schedule = Schedule::from_segments(&trapezoid(0.1, 1.0, 1.0, 1.0, 30)).expect("schedule");
    let plain = SolverOptions {
        record_fields: false,
        ..SolverOptions::default()
    };
    let opts = SolverOptions {
        record_fields: true,
        ..SolverOptions::default()
    };
    let mut solver = DirectSolver::new(&model).expect("solver");
    let mut adjoint = Adjoint::new(&model).expect("adjoint");
    println!(
        "| law | steps | depth forward (ms) | load forward (ms) | load / depth | gradient, \
         forward's factor (ms) | / load forward | fresh | set_fused(false) | nodal |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for (name, mat, base) in cases().into_iter().filter(|c| c.0.contains(&only)) {
        let mat = &*mat;
        let by_depth = solver
            .run(mat, &base, &schedule, &plain)
            .expect("depth run");
        let history = force_history(&schedule, &by_depth.forces());
        // [depth forward, load forward, gradient with the factor, fresh, unfused]
        let mut t = [0.0; 5];
        let mut steps = 0;
        let mut nodal = false;
        let time = |slot: &mut f64, t0: Clock| *slot += t0.elapsed() / repeat as f64;
        for round in 0..repeat {
            let point = |k: usize| {
                let mut p = base.clone();
                *p.last_mut().expect("parameters") *= 1.0 + 1e-13 * (4 * round + k + 1) as f64;
                p
            };
            let params = point(0);
            let t0 = Clock::now();
            let d = solver.run(mat, &params, &schedule, &plain).expect("run");
            time(&mut t[0], t0);
            std::hint::black_box(d);
            let params = point(1);
            let t0 = Clock::now();
            let traj = if through_frame {
                solver.run_compliant(mat, &params, &schedule, &frame, &opts)
            } else {
                solver.run_history(mat, &params, &history, &opts)
            }
            .expect("second run");
            time(&mut t[1], t0);
            steps = traj.steps.len();
            let dj_dh: Vec<f64> = traj.steps.iter().map(|s| s.depth).collect();
            let dj_df: Vec<f64> = traj.steps.iter().map(|s| s.force).collect();
            let zero = vec![0.0; steps];
            let gradient = |adjoint: &mut Adjoint, traj: &Trajectory| {
                if through_frame {
                    adjoint
                        .gradient_compliant(mat, &params, traj, (&schedule, &frame), &dj_df)
                        .expect("gradient")
                        .dj_dc
                } else {
                    adjoint
                        .gradient_load(mat, &params, traj, &history, &dj_dh, &zero)
                        .expect("gradient")
                        .dj_dc
                }
            };
            let t0 = Clock::now();
            adjoint.take_factor(&mut solver);
            let with_factor = gradient(&mut adjoint, &traj);
            time(&mut t[2], t0);
            if std::env::var_os("LAWS_LOAD_BITS").is_some() {
                // the gradient's bits, to compare two builds
                let bits: Vec<String> = with_factor
                    .iter()
                    .map(|g| format!("{:016x}", g.to_bits()))
                    .collect();
                eprintln!("{name} round {round}: {}", bits.join(" "));
            }
            nodal = if mat.as_law().is_some() {
                adjoint.last_sweep_was_nodal()
            } else {
                adjoint.last_material_sweep_was_nodal()
            };
            for (slot, fused) in [(3, true), (4, false)] {
                adjoint.set_fused(fused);
                let t0 = Clock::now();
                let g = gradient(&mut adjoint, &traj);
                time(&mut t[slot], t0);
                // the three sweeps give one gradient (to round-off)
                let big = g
                    .iter()
                    .zip(&params)
                    .fold(0.0f64, |m, (g, c)| m.max((g * c).abs()));
                let off = (0..params.len()).fold(0.0f64, |m, k| {
                    m.max((g[k] - with_factor[k]).abs() * params[k].abs() / big)
                });
                assert!(off < 1e-9, "{name}: the sweeps differ by {off:e}");
            }
            adjoint.set_fused(true);
        }
        println!(
            "| {name} | {steps} | {:.1} | {:.1} | {:.2} | {:.1} | **{:.2}** | {:.2} | {:.2} | {} |",
            t[0] * 1e3,
            t[1] * 1e3,
            t[1] / t[0],
            t[2] * 1e3,
            t[2] / t[1],
            t[3] / t[1],
            t[4] / t[1],
            if nodal { "yes" } else { "-" }
        );
    }
}
