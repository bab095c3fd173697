//! The line search on load control's bordered Newton update (`Newton::backtrack` and
//! `Newton::shorten`, docs/solver.md "The line search"): rate-independent J2 laws under
//! load control, whose Newton iterations cycled between two iterates until the step was
//! cut while the update moved the displacement and the depth together without one,
//! converge without cutting a step and in few iterations per step; the force history of
//! a depth-controlled run still drives the load-controlled run back to its depths (the
//! load-controlled run with the line search active against the depth-controlled one,
//! whose backtracking predates it); and the first load-controlled step from the trigger
//! joins the nodes its depth makes penetrate as the depth moves (`Newton::
//! join_penetrating`). Counts only, no timing.

mod common;

use common::testkit::cylinder;
use indentify_contact::{
    DirectSolver, LoadHistory, Model, Punch, Schedule, Segment, SolverOptions, Trajectory,
};
use indentify_laws::{Hardening, LawMaterial, Material, Maxwell, Plastic, Rate};
use indentify_mesh::CylinderMesher;

/// A 2 x 2 mm cylinder, 10 x 10 Q8 graded 1.3 towards the axis and the top, a 68 deg
/// cone, vertical contact, small strain.
fn model() -> Model {
    let mesh = cylinder(2.0, 10, 1.3);
    Model::new(
        mesh,
        Punch::Cone {
            half_angle_deg: 68.0,
        },
    )
    .unwrap()
}

fn opts() -> SolverOptions {
    SolverOptions {
        record_fields: false,
        ..SolverOptions::default()
    }
}

/// Load to 0.1 mm and hold, 15 steps each (R2's history, docs/theory.md §11, on the
/// small specimen).
fn load_hold() -> Schedule {
    let seg = |depth| Segment {
        duration: 1.0,
        depth,
        steps: 15,
    };
    Schedule::from_segments(&[seg(0.1), seg(0.1)]).unwrap()
}

/// The rate-independent J2 laws (R2's elasticity and yield stress).
fn laws() -> Vec<(&'static str, Plastic, Vec<f64>)> {
    vec![
        (
            "linear",
            Plastic::new(Hardening::Linear, Rate::Independent),
            vec![1e5, 0.3, 500.0, 1000.0],
        ),
        (
            "power",
            Plastic::new(Hardening::Power, Rate::Independent),
            vec![1e5, 0.3, 500.0, 0.2],
        ),
        (
            "voce",
            Plastic::new(Hardening::Voce, Rate::Independent),
            vec![1e5, 0.3, 500.0, 300.0, 20.0],
        ),
    ]
}

/// The depth-controlled run and the load-controlled run of its force history (one load
/// segment per step).
fn round_trip(model: &Model, mat: &dyn Material, c: &[f64]) -> (Trajectory, Trajectory) {
    let schedule = load_hold();
    let mut solver = DirectSolver::new(model).unwrap();
    let by_depth = solver.run(mat, c, &schedule, &opts()).unwrap();
    let history = LoadHistory::from_force_record(&schedule.t, &by_depth.forces()).unwrap();
    let by_force = solver.run_history(mat, c, &history, &opts()).unwrap();
    (by_depth, by_force)
}

/// Sub-steps a failed step was cut into.
fn cuts(t: &Trajectory) -> usize {
    t.steps.iter().filter(|s| !s.on_schedule).count()
}

/// Every rate-independent hardening under load control converges without cutting a step
/// (before the line search: 4, 1 and 4 cut sub-steps after failed steps of 60 cycling
/// iterations, 99, 40 and 111 factorizations; the depth-controlled runs cut none), with
/// at most 25 Newton iterations in a step and fewer than twice the depth-controlled run's
/// factorizations.
#[test]
fn rate_independent_load_control_converges_without_cuts() {
    let m = model();
    for (name, mat, c) in laws() {
        let (d, f) = round_trip(&m, &mat, &c);
        let max_it = f.steps.iter().map(|s| s.iterations).max().unwrap_or(0);
        println!(
            "{name}: depth control {} Newton iterations, {} cuts, {} factorizations; load \
             control {} iterations (at most {max_it} in a step), {} cuts, {} factorizations",
            d.total_iterations(),
            cuts(&d),
            d.timing.factorizations,
            f.total_iterations(),
            cuts(&f),
            f.timing.factorizations
        );
        assert_eq!(cuts(&d), 0, "{name}");
        assert_eq!(cuts(&f), 0, "{name}: the load-controlled run cut steps");
        assert!(max_it <= 25, "{name}: {max_it} iterations in a step");
        assert!(
            f.timing.factorizations < 2 * d.timing.factorizations,
            "{name}: {} factorizations against {}",
            f.timing.factorizations,
            d.timing.factorizations
        );
    }
}

/// With the line search active (the same runs), the force history of the
/// depth-controlled run drives the load-controlled run back to its depths, to the
/// solver's tolerance, and to the prescribed forces (before the line search: 9.8e-3 of the
/// largest depth for Linear, whose cut sub-steps made it another discrete problem).
#[test]
fn rate_independent_force_history_drives_back_to_the_depths() {
    let m = model();
    for (name, mat, c) in laws() {
        let (d, f) = round_trip(&m, &mat, &c);
        let a: Vec<_> = d.schedule_steps().collect();
        let b: Vec<_> = f.schedule_steps().collect();
        assert_eq!(a.len(), b.len());
        let h_max = a.iter().map(|s| s.depth).fold(0.0, f64::max);
        let mut worst: f64 = 0.0;
        for (x, y) in a.iter().zip(&b) {
            assert!((x.t - y.t).abs() < 1e-12);
            assert!(
                (y.force - x.force).abs() <= 1e-8 * x.force.abs().max(1.0),
                "{name}, t = {}: force {} for {}",
                x.t,
                y.force,
                x.force
            );
            worst = worst.max((x.depth - y.depth).abs() / h_max);
        }
        println!("{name}: max |dh| / h_max = {worst:.2e}");
        assert!(worst < 1e-7, "{name}: {worst:e}");
    }
}

/// R1 (Maxwell, docs/theory.md §11) on a 40 x 40 mesh of the reference specimen: the
/// first load-controlled step, from the trigger, takes at most 12 Newton iterations (35
/// before the nodes joined as the depth moved: one node's small stiffness threw the depth
/// to 0.62 mm for a step to 3.3e-3 mm, then 23 iterations released two nodes each), the
/// whole run at most 1.15x the depth-controlled run's iterations (101 against 70 before,
/// 77 after), and the depths are the depth-controlled run's.
#[test]
fn first_load_step_from_the_trigger_joins_the_contact_as_the_depth_moves() {
    let mesh = CylinderMesher {
        nr: 40,
        nz: 40,
        ..CylinderMesher::REFERENCE
    }
    .build()
    .unwrap();
    let m = Model::new(
        mesh,
        Punch::Cone {
            half_angle_deg: 68.0,
        },
    )
    .unwrap();
    let seg = |depth| Segment {
        duration: 1.0,
        depth,
        steps: 30,
    };
    let schedule = Schedule::from_segments(&[seg(0.1), seg(0.1)]).unwrap();
    let mat = LawMaterial(&Maxwell);
    let c = [2e4, 0.3, 3e4];
    let mut solver = DirectSolver::new(&m).unwrap();
    let d = solver.run(&mat, &c, &schedule, &opts()).unwrap();
    let history = LoadHistory::from_force_record(&schedule.t, &d.forces()).unwrap();
    let f = solver.run_history(&mat, &c, &history, &opts()).unwrap();
    let (first, total_d, total_f) = (
        f.steps[0].iterations,
        d.total_iterations(),
        f.total_iterations(),
    );
    println!(
        "first load step {first} iterations; runs {total_d} (depth) and {total_f} (load) \
         iterations, {} and {} active-set changes",
        d.steps.iter().map(|s| s.active_set_changes).sum::<u32>(),
        f.steps.iter().map(|s| s.active_set_changes).sum::<u32>()
    );
    assert_eq!(cuts(&f), 0);
    assert!(first <= 12, "{first} iterations in the first load step");
    assert!(
        total_f as f64 <= 1.15 * total_d as f64,
        "{total_f} against {total_d}"
    );
    let worst = d
        .schedule_steps()
        .zip(f.schedule_steps())
        .map(|(a, b)| (a.depth - b.depth).abs() / 0.1)
        .fold(0.0, f64::max);
    assert!(worst < 1e-7, "{worst:e}");
}
