//! Load control at a constant `Pdot/P` (`indentify_contact::pdotp`; docs/validation-load-control.md
//! §12): the run carries the prescribed exponential force at every step, and the depths
//! of the run, prescribed to a depth-controlled run, give back that force history (the
//! same discrete problem stated the other way round), for every law, Norton-Hoff's
//! nonlinear predictor included.

mod common;

use common::testkit::cylinder;
use indentify_contact::{
    ContactKind, DirectSolver, Kinematics, LoadHistory, Model, Punch, Schedule, SegmentSpec,
    SolverOptions,
};
use indentify_laws::{Elastic, Law, LawMaterial, Maxwell, NortonHoff};
use std::time::Instant;

/// A 2 x 2 mm cylinder, 10 x 10 Q8 graded 1.3, under the 68 deg cone.
fn model() -> Model {
    let mesh = cylinder(2.0, 10, 1.3);
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

fn opts() -> SolverOptions {
    SolverOptions {
        record_fields: false,
        ..SolverOptions::default()
    }
}

const R0: [f64; 2] = [20000.0, 0.3];
const R1: [f64; 3] = [20000.0, 0.3, 30000.0];
const R2: [f64; 5] = [1e5, 0.3, 1500.0, 5.0, 500.0];

/// A trigger ramp to `p0` in 0.1 s, constant Pdot/P = `r` to `16 p0` in 12 steps, a 1 s
/// hold.
fn specs(p0: f64, r: f64) -> Vec<SegmentSpec> {
    let linear = |duration: f64, force: f64, steps| SegmentSpec {
        duration: Some(duration),
        depth: None,
        force: Some(force),
        pdot_over_p: None,
        steps,
    };
    vec![
        linear(0.1, p0, 2),
        SegmentSpec {
            duration: None,
            depth: None,
            force: Some(16.0 * p0),
            pdot_over_p: Some(r),
            steps: 12,
        },
        linear(1.0, 16.0 * p0, 4),
    ]
}

#[test]
fn pdotp_run_carries_the_exponential_and_its_depths_give_it_back() {
    let m = model();
    let mut solver = DirectSolver::new(&m).unwrap();
    let (p0, r) = (4.0, 0.5);
    let history = LoadHistory::from_specs(&specs(p0, r)).unwrap();
    let laws: [(&dyn Law, &[f64]); 3] = [(&Elastic, &R0), (&Maxwell, &R1), (&NortonHoff, &R2)];
    for (law, c) in laws {
        let mat = LawMaterial(law);
        let by_force = solver.run_history(&mat, c, &history, &opts()).unwrap();
        let steps: Vec<_> = by_force.schedule_steps().cloned().collect();
        assert_eq!(steps.len(), 18);
        // the Pdot/P steps (3 to 14) carry P0 exp(r (t - 0.1)) (ln P linear in time)
        for s in &steps[2..14] {
            let p = p0 * (r * (s.t - 0.1)).exp();
            assert!(
                (s.force - p).abs() <= 1e-8 * p,
                "t = {}: {} vs {p}",
                s.t,
                s.force
            );
        }
        // the depths, prescribed at the times of every step the run took (its cut steps'
        // too: the two runs then solve the same discrete problem), give back the forces
        let all = &by_force.steps;
        let t: Vec<f64> = std::iter::once(0.0)
            .chain(all.iter().map(|s| s.t))
            .collect();
        let h: Vec<f64> = std::iter::once(0.0)
            .chain(all.iter().map(|s| s.depth))
            .collect();
        let by_depth = solver
            .run(&mat, c, &Schedule::from_record(&t, &h).unwrap(), &opts())
            .unwrap();
        let back = &by_depth.steps;
        assert_eq!(back.len(), all.len());
        let mut worst: f64 = 0.0;
        for (a, b) in all.iter().zip(back) {
            worst = worst.max((a.force - b.force).abs() / (16.0 * p0));
        }
        println!(
            "{}: depth-controlled forces vs the Pdot/P run's: max |dF| / F_max = {worst:.2e} \
             ({} / {} Newton iterations)",
            law.name(),
            by_force.total_iterations(),
            by_depth.total_iterations()
        );
        assert!(worst < 1e-7, "{}: {worst:e}", law.name());
        // the cost, back to back (the fastest of 3 alternated runs; printed, not asserted)
        let schedule = Schedule::from_record(&t, &h).unwrap();
        let (mut t_load, mut t_depth) = (f64::INFINITY, f64::INFINITY);
        for _ in 0..3 {
            let clock = Instant::now();
            solver.run_history(&mat, c, &history, &opts()).unwrap();
            t_load = t_load.min(clock.elapsed().as_secs_f64());
            let clock = Instant::now();
            solver.run(&mat, c, &schedule, &opts()).unwrap();
            t_depth = t_depth.min(clock.elapsed().as_secs_f64());
        }
        println!(
            "{}: Pdot/P forward {:.2} ms, the depth-controlled forward of its depths {:.2} ms \
             (ratio {:.2})",
            law.name(),
            1e3 * t_load,
            1e3 * t_depth,
            t_load / t_depth
        );
    }
}
