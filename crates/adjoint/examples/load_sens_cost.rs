//! Back-to-back timing of the forward sensitivity pass under load control and through the
//! instrument's frame against its forward run (docs/performance.md, "Load control's
//! sensitivity pass from the tangent's rows"): R2's reference mesh (20 x 20 Q8, cone 68
//! deg, vertical contact; with `finite`, frictionless normal contact and finite strain),
//! a law of `benches/laws_cost.rs`, the force history of the law's own depth-controlled
//! trapezoid (0.1 mm, 30 steps per segment) from the start to the last step before the
//! unload drops under 0.3 of the peak force, driven by force (`load`), or the trapezoid's
//! machine depths through `Cf = 1e-4` mm/N (`frame`), or the trapezoid itself by depth
//! (`depth`, `Adjoint::sensitivities`). Each round runs at parameters
//! changed in their last bits (a fit's new point), records the fields, then times, on one
//! thread (on-CPU time), in an order alternated from round to round:
//! - `rows`: `Adjoint::sensitivities_load` / `sensitivities_compliant` as they run by
//!   default (the force at the depth held and the steps' forces from the force dofs'
//!   rows of each step's tangent; a load-controlled step's force prescribed);
//! - `passes`: the same with `Adjoint::set_fused(false)`, the passes over the Gauss
//!   points per parameter and step that the rows replace (the code before them).
//!
//! `RAYON_NUM_THREADS=1 cargo run --release -p indentify-adjoint --example load_sens_cost
//! -- LAW [ROUNDS] [load|frame|depth] [finite]` prints the median of each and its ratio to the
//! forward, and the largest difference of the columns (`dh/dc`, `dF/dc`) against the
//! passes', relative to each column's largest entry (the `dF/dc` rows of load-controlled
//! steps apart: their force is prescribed, the passes give it to round-off). With
//! `LOAD_SENS_BITS` set, the first round's columns (both passes) are hashed to stderr, to
//! compare two builds.
use std::time::Instant;

use indentify_adjoint::{Adjoint, FrameIndex, LoadSensitivities};
use indentify_contact::{
    ContactKind, DirectSolver, Frame, Kinematics, LoadHistory, Model, Punch, Schedule,
    SolverOptions, trapezoid,
};
use indentify_laws::{Hardening, LawMaterial, Material, Maxwell, NortonHoff, Plastic, Prony, Rate};
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

/// The largest difference of `a`'s columns from `b`'s, relative to each column's largest
/// entry of `b`, over the rows `keep` selects.
fn worst(a: &[Vec<f64>], b: &[Vec<f64>], keep: impl Fn(usize) -> bool) -> f64 {
    let np = b.first().map_or(0, Vec::len);
    let mut out = 0.0f64;
    for k in 0..np {
        let rows = || (0..b.len()).filter(|&i| keep(i));
        let scale = rows().fold(0.0f64, |m, i| m.max(b[i][k].abs()));
        if scale == 0.0 {
            continue;
        }
        for i in rows() {
            out = out.max((a[i][k] - b[i][k]).abs() / scale);
        }
    }
    out
}

fn main() {
    let name = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "norton_hoff".into());
    let rounds: usize = std::env::args()
        .nth(2)
        .and_then(|s| s.parse().ok())
        .unwrap_or(5);
    let frame_drive = std::env::args().nth(3).is_some_and(|s| s == "frame");
    let depth_drive = std::env::args().nth(3).is_some_and(|s| s == "depth");
    let finite = std::env::args().nth(4).is_some_and(|s| s == "finite");
    let (e, nu, sy, k, m) = (1e5, 0.3, 500.0, 1500.0, 5.0);
    let (mat, base): (Box<dyn Material>, Vec<f64>) = match name.as_str() {
        "maxwell" => (Box::new(LawMaterial(&Maxwell)), vec![20000.0, 0.3, 30000.0]),
        "norton_hoff" => (Box::new(LawMaterial(&NortonHoff)), vec![e, nu, k, m, sy]),
        "prony1" => (
            Box::new(Prony::new(1).expect("prony")),
            vec![e, nu, 0.3, 0.2],
        ),
        "prony2" => (
            Box::new(Prony::new(2).expect("prony")),
            vec![e, nu, 0.3, 0.2, 0.2, 2.0],
        ),
        "prony3" => (
            Box::new(Prony::new(3).expect("prony")),
            vec![e, nu, 0.3, 0.2, 0.2, 2.0, 0.1, 0.05],
        ),
        "plastic_power_norton" => (
            Box::new(Plastic::new(Hardening::Power, Rate::Norton)),
            vec![e, nu, sy, 0.2, k, m],
        ),
        other => panic!(
            "unknown law {other}: maxwell, norton_hoff, prony1, prony2, prony3, \
             plastic_power_norton"
        ),
    };
    let mat = mat.as_ref();
    let mesh = CylinderMesher::REFERENCE.build().expect("reference mesh");
    let cone = Punch::Cone {
        half_angle_deg: 68.0,
    };
    let model = if finite {
        Model::with_contact(mesh, cone, ContactKind::Normal)
            .and_then(|m| m.with_kinematics(Kinematics::Finite))
            .expect("model")
    } else {
        Model::new(mesh, cone).expect("model")
    };
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
    let by_depth = solver
        .run(mat, &base, &schedule, &plain)
        .expect("depth run");
    let forces = by_depth.forces();
    let peak = forces.iter().fold(0.0f64, |m, f| m.max(*f));
    let at_peak = forces.iter().position(|f| *f == peak).expect("peak");
    let end = (at_peak..forces.len())
        .find(|&i| forces[i] < 0.3 * peak)
        .unwrap_or(forces.len());
    let history =
        LoadHistory::from_force_record(&schedule.t[..end], &forces[..end]).expect("history");
    let frame = Frame {
        compliance: 1e-4,
        ..Frame::default()
    };
    let at = FrameIndex::default();
    let mut adjoint = Adjoint::new(&model).expect("adjoint");
    let mut t = [Vec::new(), Vec::new(), Vec::new()];
    let (mut w_dh, mut w_df, mut df_noise) = (0.0f64, 0.0f64, 0.0f64);
    let mut steps = 0;
    for round in 0..=rounds {
        let mut c = base.clone();
        for v in c.iter_mut() {
            *v *= 1.0 + 1e-13 * (round + 1) as f64;
        }
        let t0 = Clock::now();
        let traj = if frame_drive {
            solver.run_compliant(mat, &c, &schedule, &frame, &opts)
        } else if depth_drive {
            solver.run(mat, &c, &schedule, &opts)
        } else {
            solver.run_history(mat, &c, &history, &opts)
        }
        .expect("forward");
        let fwd = t0.elapsed();
        steps = traj.steps.len();
        let pass = |adjoint: &mut Adjoint<'_>, fused: bool| -> (LoadSensitivities, f64) {
            adjoint.set_fused(fused);
            let t0 = Clock::now();
            let s = if frame_drive {
                adjoint.sensitivities_compliant(mat, &c, &traj, (&schedule, &frame), at)
            } else if depth_drive {
                adjoint
                    .sensitivities(mat, &c, &traj)
                    .map(|s| LoadSensitivities {
                        dh_dc: vec![vec![0.0; c.len()]; s.df_dc.len()],
                        df_dc: s.df_dc,
                        seconds: s.seconds,
                    })
            } else {
                adjoint.sensitivities_load(mat, &c, &traj, &history)
            }
            .expect("sensitivities");
            let dt = t0.elapsed();
            adjoint.set_fused(true);
            (s, dt)
        };
        let ((rows, t_rows), (passes, t_passes)) = if round % 2 == 0 {
            let r = pass(&mut adjoint, true);
            (r, pass(&mut adjoint, false))
        } else {
            let p = pass(&mut adjoint, false);
            (pass(&mut adjoint, true), p)
        };
        // a load-controlled step's force is prescribed: those rows apart
        let load_step = |i: usize| {
            !frame_drive
                && !depth_drive
                && matches!(
                    history.segment_at(traj.steps[i].t).1,
                    indentify_contact::Target::Force(_)
                )
        };
        w_dh = w_dh.max(worst(&rows.dh_dc, &passes.dh_dc, |_| true));
        w_df = w_df.max(worst(&rows.df_dc, &passes.df_dc, |i| !load_step(i)));
        // the passes' force variation on the load-controlled steps against the force
        // scale of their depth variation (`s dU`: the passes' own round-off)
        for (i, row) in passes
            .df_dc
            .iter()
            .enumerate()
            .filter(|(i, _)| load_step(*i))
        {
            for (kk, v) in row.iter().enumerate() {
                df_noise = df_noise.max((v - rows.df_dc[i][kk]).abs());
            }
        }
        if round == 0 && std::env::var_os("LOAD_SENS_BITS").is_some() {
            // FNV-1a of the columns' bits (both passes), to compare two builds
            let mut h: u64 = 0xcbf2_9ce4_8422_2325;
            for s in [&rows, &passes] {
                for v in s.dh_dc.iter().chain(&s.df_dc).flatten() {
                    for b in v.to_bits().to_le_bytes() {
                        h ^= u64::from(b);
                        h = h.wrapping_mul(0x0100_0000_01b3);
                    }
                }
            }
            eprintln!("{name}: columns' bits {h:016x}");
        }
        if round > 0 {
            for (v, x) in t.iter_mut().zip([fwd, t_rows, t_passes]) {
                v.push(x);
            }
        }
    }
    let m: Vec<f64> = t.iter_mut().map(|v| median(v)).collect();
    let drive = if frame_drive {
        "frame"
    } else if depth_drive {
        "depth"
    } else {
        "load"
    };
    let kin = if finite { " finite" } else { "" };
    println!(
        "{name} {drive}{kin} ({steps} steps, {rounds} rounds): forward {:.1} ms; sensitivities \
         from the rows {:.1} ms ({:.3}x), with the passes {:.1} ms ({:.3}x), rows / passes \
         {:.3}; columns against the passes': dh {w_dh:.1e}, dF {w_df:.1e} (of each column's \
         largest), load steps' dF {df_noise:.1e} N (absolute)",
        1e3 * m[0],
        1e3 * m[1],
        m[1] / m[0],
        1e3 * m[2],
        m[2] / m[0],
        m[1] / m[2],
    );
}
