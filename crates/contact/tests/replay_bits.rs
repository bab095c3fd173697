//! A checkpointed run's replay repeats it bit for bit: every checkpoint of a small
//! mesh's run, replayed to the end, gives the run's depths, forces and Newton iteration
//! counts to the last bit (`to_bits`), under load control (a trigger, then a Pdot/P
//! segment and a hold, Norton-Hoff), under depth control and through the compliant
//! frame (docs/solver.md, "The inexact solves and when their factor is refreshed").

use indentify_contact::{
    ContactKind, DirectSolver, Frame, Kinematics, LoadHistory, Model, Punch, Schedule, Segment,
    SegmentSpec, SolverOptions, Trajectory,
};
use indentify_laws::{LawMaterial, NortonHoff};
use indentify_mesh::CylinderMesher;

/// A 2 x 2 mm cylinder, 8 x 8 Q8 graded 1.3, under the 68 deg cone, vertical contact.
fn model() -> Model {
    let mesh = CylinderMesher {
        radius: 2.0,
        height: 2.0,
        nr: 8,
        nz: 8,
        grading_r: 1.3,
        grading_z: 1.3,
    }
    .build()
    .unwrap();
    Model::with_contact(
        mesh,
        Punch::Cone {
            half_angle_deg: 68.0,
        },
        ContactKind::Vertical,
    )
    .unwrap()
    .with_kinematics(Kinematics::Small)
    .unwrap()
}

/// R2's Norton-Hoff parameters (E MPa, nu, sigma_Y MPa, n, K MPa s^(1/n)).
const R2: [f64; 5] = [1e5, 0.3, 1500.0, 5.0, 500.0];

fn linear(duration: f64, force: f64, steps: usize) -> SegmentSpec {
    SegmentSpec {
        duration: Some(duration),
        depth: None,
        force: Some(force),
        pdot_over_p: None,
        steps,
    }
}

/// A trigger ramp to 4 N in 0.1 s, then to 64 N at Pdot/P = 0.5/s in 10 steps, a 1 s
/// hold in 4.
fn history() -> LoadHistory {
    let p0 = 4.0;
    LoadHistory::from_specs(&[
        linear(0.1, p0, 2),
        SegmentSpec {
            duration: None,
            depth: None,
            force: Some(16.0 * p0),
            pdot_over_p: Some(0.5),
            steps: 10,
        },
        linear(1.0, 16.0 * p0, 4),
    ])
    .unwrap()
}

fn opts(every: usize) -> SolverOptions {
    SolverOptions {
        record_fields: false,
        checkpoint_every: every,
        ..SolverOptions::default()
    }
}

/// Depth, force (their bits) and Newton iterations of every step.
fn bits(steps: &[indentify_contact::StepRecord]) -> Vec<(u64, u64, u32)> {
    steps
        .iter()
        .map(|s| (s.depth.to_bits(), s.force.to_bits(), s.iterations))
        .collect()
}

/// Asserts every checkpoint of `run` replays (by `replay`) to the run's bits.
fn check_replays(
    name: &str,
    run: &Trajectory,
    min_checkpoints: usize,
    mut replay: impl FnMut(&indentify_contact::Checkpoint) -> Trajectory,
) {
    assert!(
        run.checkpoints.len() >= min_checkpoints,
        "{name}: {} checkpoints",
        run.checkpoints.len()
    );
    for c in &run.checkpoints {
        let r = replay(c);
        let want = &run.steps[c.steps_done..];
        assert_eq!(r.steps.len(), want.len(), "{name}: steps from {c:?}");
        let (got, want) = (bits(&r.steps), bits(want));
        for (k, (g, w)) in got.iter().zip(&want).enumerate() {
            assert_eq!(
                g,
                w,
                "{name}: replay from {} differs at its step {k}: depth {:e} against {:e}, \
                 force {:e} against {:e}",
                c.schedule_index,
                f64::from_bits(g.0),
                f64::from_bits(w.0),
                f64::from_bits(g.1),
                f64::from_bits(w.1)
            );
        }
    }
}

#[test]
fn load_controlled_replays_repeat_the_run_bit_for_bit() {
    let m = model();
    let mat = LawMaterial(&NortonHoff);
    let history = history();
    let j_end = history.schedule.t.len() - 1;
    let mut solver = DirectSolver::new(&m).unwrap();
    for every in [2, 3] {
        let run = solver
            .run_history(&mat, &R2, &history, &opts(every))
            .unwrap();
        check_replays(&format!("load, every {every}"), &run, 4, |c| {
            solver
                .replay_history(&mat, &R2, &history, &opts(every), c, j_end)
                .unwrap()
        });
    }
}

/// A depth schedule: to 0.02 mm in 1 s (8 steps), a 1 s hold (4 steps).
fn depth_schedule() -> Schedule {
    Schedule::from_segments(&[
        Segment {
            duration: 1.0,
            depth: 0.02,
            steps: 8,
        },
        Segment {
            duration: 1.0,
            depth: 0.02,
            steps: 4,
        },
    ])
    .unwrap()
}

#[test]
fn depth_controlled_replays_repeat_the_run_bit_for_bit() {
    let m = model();
    let mat = LawMaterial(&NortonHoff);
    let schedule = depth_schedule();
    let j_end = schedule.t.len() - 1;
    let mut solver = DirectSolver::new(&m).unwrap();
    for every in [2, 3] {
        let run = solver.run(&mat, &R2, &schedule, &opts(every)).unwrap();
        check_replays(&format!("depth, every {every}"), &run, 4, |c| {
            solver
                .replay(&mat, &R2, &schedule, &opts(every), c, j_end)
                .unwrap()
        });
    }
}

#[test]
fn compliant_replays_repeat_the_run_bit_for_bit() {
    let m = model();
    let mat = LawMaterial(&NortonHoff);
    let schedule = depth_schedule();
    let frame = Frame {
        compliance: 2e-4,
        drift: 0.0,
        offset: 0.0,
    };
    let j_end = schedule.t.len() - 1;
    let mut solver = DirectSolver::new(&m).unwrap();
    for every in [2, 3] {
        let run = solver
            .run_compliant(&mat, &R2, &schedule, &frame, &opts(every))
            .unwrap();
        check_replays(&format!("compliant, every {every}"), &run, 4, |c| {
            solver
                .replay_compliant(&mat, &R2, &schedule, &frame, &opts(every), c, j_end)
                .unwrap()
        });
    }
}
