//! One whole Levenberg-Marquardt fit of a two-term Prony solid, timed (docs/performance.md,
//! "Prony's and load control's sensitivity pass all-nodal"): R2's reference mesh (20 x 20
//! Q8, cone 68 deg, vertical contact), exact data of the depth-controlled trapezoid (0.1
//! mm, 1 s load, hold, unload, 30 steps each) at `E = 20000` MPa, `nu = 0.3` (fixed),
//! `g = (0.3, 0.2)`, `tau = (0.2, 2.0)` s, or (`load`) of its force history up to the
//! unload's 0.3 of the peak, driven by force with the depths as data; started at `E =
//! 15000`, `g = (0.2, 0.3)`, `tau = (0.4, 1.0)`.
//!
//! `RAYON_NUM_THREADS=1 cargo run --release -p indentify-identify --example
//! prony_fit_cost -- [depth|load] [ROUNDS]` prints, per round, the fit's on-CPU time
//! (the process's, `/proc/self/stat`, 10 ms resolution), its forward and sensitivity
//! solves, iterations, the parameters found and the cost.
use std::sync::Arc;

use indentify_contact::{
    DirectSolver, LoadHistory, Model, Punch, Schedule, SolverOptions, trapezoid,
};
use indentify_identify::{ForceRecord, IdentifyConfig, Method, ParamSpec, Problem, Test, identify};
use indentify_laws::{Material, Prony};
use indentify_mesh::CylinderMesher;

/// The process's on-CPU time (s), every thread (`/proc/self/stat`, utime + stime in
/// clock ticks of 10 ms): the fit runs on a pool's worker.
fn cpu_s() -> f64 {
    std::fs::read_to_string("/proc/self/stat")
        .ok()
        .and_then(|s| {
            let rest = s.rsplit_once(')')?.1;
            let f: Vec<&str> = rest.split_whitespace().collect();
            Some((f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?) * 0.01)
        })
        .unwrap_or(0.0)
}

fn model() -> Model {
    let mesh = CylinderMesher::REFERENCE.build().expect("reference mesh");
    Model::new(
        mesh,
        Punch::Cone {
            half_angle_deg: 68.0,
        },
    )
    .expect("model")
}

fn main() {
    let load = std::env::args().nth(1).is_some_and(|s| s == "load");
    let rounds: usize = std::env::args()
        .nth(2)
        .and_then(|s| s.parse().ok())
        .unwrap_or(1);
    let mat: Arc<dyn Material> = Arc::new(Prony::new(2).expect("prony"));
    let truth = [20000.0, 0.3, 0.3, 0.2, 0.2, 2.0];
    let opts = SolverOptions::default();
    let schedule = Schedule::from_segments(&trapezoid(0.1, 1.0, 1.0, 1.0, 30)).expect("schedule");
    let m = model();
    let mut solver = DirectSolver::new(&m).expect("solver");
    let by_depth = solver.run(&*mat, &truth, &schedule, &opts).expect("run");
    let forces = by_depth.forces();
    let test = if load {
        let peak = forces.iter().fold(0.0f64, |a, f| a.max(*f));
        let at_peak = forces.iter().position(|f| *f == peak).expect("peak");
        let end = (at_peak..forces.len())
            .find(|&i| forces[i] < 0.3 * peak)
            .unwrap_or(forces.len());
        let history =
            LoadHistory::from_force_record(&schedule.t[..end], &forces[..end]).expect("history");
        let traj = solver
            .run_history(&*mat, &truth, &history, &opts)
            .expect("load run");
        let mut depths = vec![0.0];
        depths.extend(traj.steps.iter().filter(|s| s.on_schedule).map(|s| s.depth));
        let record = ForceRecord::new(history.schedule.t.clone(), depths).expect("record");
        Test::new_load(model(), history, &record, None, opts.clone(), 1.0).expect("test")
    } else {
        let record = ForceRecord::new(schedule.t.clone(), forces).expect("record");
        Test::new(model(), schedule, &record, None, opts.clone(), 1.0).expect("test")
    };
    let p = Problem::joint(mat, vec![test]).expect("problem");
    let mut cfg = IdentifyConfig::new(vec![
        ParamSpec::free("E", 15000.0, 1000.0, 1e6),
        ParamSpec::fixed("nu", 0.3),
        ParamSpec::free("g1", 0.2, 0.01, 0.9),
        ParamSpec::free("tau1", 0.4, 0.01, 100.0),
        ParamSpec::free("g2", 0.3, 0.01, 0.9),
        ParamSpec::free("tau2", 1.0, 0.01, 100.0),
    ]);
    cfg.method = Method::LevenbergMarquardt;
    for round in 0..rounds {
        let t0 = cpu_s();
        let r = identify(&p, &cfg, &mut |_| {}).expect("identify");
        let cpu = cpu_s() - t0;
        println!(
            "{} round {round}: CPU {cpu:.2} s; {} iterations, {} forward and {} sensitivity \
             solves; c = {:?}; J = {:.6e}; {}",
            if load { "load" } else { "depth" },
            r.iterations,
            r.forward_solves,
            r.sensitivity_solves,
            r.c,
            r.cost,
            r.stop_reason
        );
    }
}
