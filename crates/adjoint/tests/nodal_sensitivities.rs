//! The forward sensitivities of a law with one isotropic tangent, all-nodal
//! (`crates/adjoint/src/nodal_sens.rs`), and every sensitivity pass with the forward's
//! factorization taken (`Adjoint::take_factor`, as `identify` calls it before every
//! Jacobian):
//! - the all-nodal columns equal the Gauss-point pass's (`Adjoint::set_fused(false)`) to
//!   1e-12 of each column's largest entry, Maxwell and elasticity, histories of one and of
//!   three step lengths with a partial unload and reload, every column or a subset; the
//!   pass stays off under normal contact;
//! - against central differences of the direct solver's forces (an independent
//!   reference: the solver alone), to 1e-6;
//! - with the forward's factor taken, the columns equal a fresh workspace's (bit for bit
//!   here, asserted 1e-12) and the pass makes no factorization where the history has one
//!   step length; a solver whose last run had other parameters hands a factor that is
//!   not used; vertical and normal contact, depth and load control;
//! - the same bits on one and two threads.

mod common;

use common::{column_rel, small_model};
use indentify_adjoint::{Adjoint, Sensitivities};
use indentify_contact::{
    ContactKind, DirectSolver, HistorySegment, LoadHistory, Model, Schedule, Segment,
    SolverOptions, Trajectory,
};
use indentify_laws::{Elastic, Law, LawMaterial, Maxwell};
use indentify_testkit::cone68 as cone;

fn opts() -> SolverOptions {
    SolverOptions {
        record_fields: true,
        residual_tol: 1e-11,
        ..SolverOptions::default()
    }
}

fn seg(duration: f64, depth: f64, steps: usize) -> Segment {
    Segment {
        duration,
        depth,
        steps,
    }
}

/// Load, hold, unload of one step length (1/12 s); and of three (1/6, 1/4, 1/10 s) with
/// a partial unload and a reload before the last unload. Each unloads to 0.02 mm: an
/// elastic run unloaded to rest keeps no stress against which the nodal form is checked,
/// and takes the Gauss-point pass (Maxwell's keeps a residual stress).
fn schedules() -> [Schedule; 2] {
    [
        Schedule::from_segments(&[seg(0.5, 0.1, 6), seg(0.5, 0.1, 6), seg(0.5, 0.02, 6)]).unwrap(),
        Schedule::from_segments(&[
            seg(1.0, 0.1, 6),
            seg(1.0, 0.1, 4),
            seg(0.5, 0.06, 5),
            seg(0.5, 0.09, 5),
            seg(1.0, 0.02, 10),
        ])
        .unwrap(),
    ]
}

/// A law, its parameters and the column subset asked for (`None`: every column).
type Case = (&'static dyn Law, Vec<f64>, Option<Vec<usize>>);

/// The laws, their parameters and the column subsets asked for.
fn cases() -> Vec<Case> {
    vec![
        (&Maxwell, vec![20000.0, 0.3, 30000.0], None),
        (&Maxwell, vec![20000.0, 0.3, 30000.0], Some(vec![0, 2])),
        (&Elastic, vec![20000.0, 0.3], None),
        (&Elastic, vec![20000.0, 0.3], Some(vec![0])),
    ]
}

fn pass(
    adj: &mut Adjoint,
    law: &dyn Law,
    c: &[f64],
    traj: &Trajectory,
    cols: &Option<Vec<usize>>,
) -> Sensitivities {
    match cols {
        Some(cols) => adj.sensitivities_of(&LawMaterial(law), c, traj, cols),
        None => adj.sensitivities(&LawMaterial(law), c, traj),
    }
    .unwrap()
}

fn bits(s: &Sensitivities) -> Vec<u64> {
    s.df_dc.iter().flatten().map(|x| x.to_bits()).collect()
}

#[test]
fn nodal_sensitivities_equal_the_gauss_point_pass() {
    let model = small_model(cone(), ContactKind::Vertical);
    let mut solver = DirectSolver::new(&model).unwrap();
    let mut adj = Adjoint::new(&model).unwrap();
    for schedule in &schedules() {
        for (law, c, cols) in cases() {
            let traj = solver
                .run(&LawMaterial(law), &c, schedule, &opts())
                .unwrap();
            assert!(traj.steps.iter().any(|s| s.active.len() > 2));
            adj.set_fused(true);
            let nodal = pass(&mut adj, law, &c, &traj, &cols);
            assert!(adj.last_pass_nodal());
            adj.set_fused(false);
            let gauss = pass(&mut adj, law, &c, &traj, &cols);
            assert!(!adj.last_pass_nodal());
            adj.set_fused(true);
            let d = column_rel(&gauss.df_dc, &nodal.df_dc);
            println!("{} {cols:?}: nodal vs Gauss-point pass {d:.1e}", law.name());
            assert!(d <= 1e-12, "{d:e}");
            // the skipped columns stay exactly zero, the others are not
            for k in 0..c.len() {
                let asked = cols.as_ref().is_none_or(|cl| cl.contains(&k));
                let zero = nodal.df_dc.iter().all(|r| r[k] == 0.0);
                assert_eq!(zero, !asked, "column {k}");
            }
        }
    }
}

#[test]
fn nodal_sensitivities_stay_off_under_normal_contact() {
    let model = small_model(cone(), ContactKind::Normal);
    let mut solver = DirectSolver::new(&model).unwrap();
    let mut adj = Adjoint::new(&model).unwrap();
    let c = [20000.0, 0.3, 30000.0];
    let traj = solver
        .run(&LawMaterial(&Maxwell), &c, &schedules()[1], &opts())
        .unwrap();
    let s = adj
        .sensitivities(&LawMaterial(&Maxwell), &c, &traj)
        .unwrap();
    assert!(!adj.last_pass_nodal());
    // the Gauss-point pass, with `dF_i/dc_k` from the tangent's rows (`reaction_rows.rs`)
    assert!(adj.last_pass_reaction_rows());
    adj.set_fused(false);
    let g = adj
        .sensitivities(&LawMaterial(&Maxwell), &c, &traj)
        .unwrap();
    for k in 0..c.len() {
        let scale = g.df_dc.iter().fold(0.0f64, |m, r| m.max(r[k].abs()));
        for (a, b) in s.df_dc.iter().zip(&g.df_dc) {
            assert!((a[k] - b[k]).abs() <= 1e-12 * scale, "{} vs {}", a[k], b[k]);
        }
    }
}

#[test]
fn nodal_sensitivities_match_central_differences() {
    let model = small_model(cone(), ContactKind::Vertical);
    let mut solver = DirectSolver::new(&model).unwrap();
    let mut adj = Adjoint::new(&model).unwrap();
    let schedule = &schedules()[1];
    let c = [20000.0, 0.3, 30000.0];
    let mat = LawMaterial(&Maxwell);
    let traj = solver.run(&mat, &c, schedule, &opts()).unwrap();
    let s = adj.sensitivities(&mat, &c, &traj).unwrap();
    assert!(adj.last_pass_nodal());
    let plain = SolverOptions {
        record_fields: false,
        ..opts()
    };
    let mut worst = 0.0f64;
    for k in 0..c.len() {
        let h = 1e-6 * c[k];
        let mut forces = |sign: f64| {
            let mut p = c;
            p[k] += sign * h;
            solver.run(&mat, &p, schedule, &plain).unwrap().forces()
        };
        // the forces at the schedule's times after t = 0 (no step was cut)
        let (fp, fm) = (forces(1.0), forces(-1.0));
        assert_eq!(fp.len(), s.df_dc.len() + 1);
        let (fp, fm) = (&fp[1..], &fm[1..]);
        let scale = s.df_dc.iter().fold(0.0f64, |m, r| m.max(r[k].abs()));
        for ((a, b), r) in fp.iter().zip(fm).zip(&s.df_dc) {
            let fd = (a - b) / (2.0 * h);
            worst = worst.max((fd - r[k]).abs() / scale);
        }
    }
    println!("nodal sensitivities vs central differences: {worst:.1e}");
    assert!(worst <= 1e-6, "{worst:e}");
}

/// Forward at `c_forward`, then the sensitivities of the trajectory at `c` with the
/// solver's factor taken, against a fresh workspace's: (largest relative difference,
/// bit for bit, factorizations with, without).
fn taken_vs_fresh(
    model: &Model,
    law: &dyn Law,
    (c, c_forward): (&[f64], &[f64]),
    schedule: &Schedule,
    cols: &Option<Vec<usize>>,
) -> (f64, bool, usize, usize) {
    let mut solver = DirectSolver::new(model).unwrap();
    let mat = LawMaterial(law);
    let traj = solver.run(&mat, c, schedule, &opts()).unwrap();
    if c_forward != c {
        solver.run(&mat, c_forward, schedule, &opts()).unwrap();
    }
    let mut adj = Adjoint::new(model).unwrap();
    let f0 = adj.factorizations();
    assert!(adj.take_factor(&mut solver));
    let taken = pass(&mut adj, law, c, &traj, cols);
    let f_taken = adj.factorizations() - f0;
    let mut fresh_adj = Adjoint::new(model).unwrap();
    let fresh = pass(&mut fresh_adj, law, c, &traj, cols);
    let f_fresh = fresh_adj.factorizations();
    (
        column_rel(&fresh.df_dc, &taken.df_dc),
        bits(&fresh) == bits(&taken),
        f_taken,
        f_fresh,
    )
}

#[test]
fn depth_controlled_sensitivities_with_the_forward_factor_equal_the_fresh_ones() {
    for kind in [ContactKind::Vertical, ContactKind::Normal] {
        let model = small_model(cone(), kind);
        for (j, schedule) in schedules().iter().enumerate() {
            for (law, c, cols) in cases() {
                let (d, same, with, without) =
                    taken_vs_fresh(&model, law, (&c, &c), schedule, &cols);
                println!(
                    "{kind:?} schedule {j} {} {cols:?}: {d:.1e} (bits {same}), factorizations {with} against {without}",
                    law.name()
                );
                assert!(d <= 1e-12, "{d:e}");
                if j == 0 {
                    // one step length: the forward's factor serves every step
                    assert_eq!(with, 0);
                    assert!(without >= 1);
                } else {
                    assert!(with <= without);
                }
            }
        }
    }
}

#[test]
fn a_factor_of_other_parameters_is_not_used() {
    let model = small_model(cone(), ContactKind::Vertical);
    let c = [20000.0, 0.3, 30000.0];
    let other = [20000.0, 0.3, 30000.0 * (1.0 + 1e-9)];
    let schedule = &schedules()[0];
    let (d, same, with, without) =
        taken_vs_fresh(&model, &Maxwell, (&c, &other), schedule, &Some(vec![0, 2]));
    assert!(same, "{d:e}");
    assert_eq!(with, without);
}

#[test]
fn load_controlled_sensitivities_with_the_forward_factor_equal_the_fresh_ones() {
    let seg =
        |duration: f64, depth: Option<f64>, force: Option<f64>, steps: usize| HistorySegment {
            duration,
            depth,
            force,
            steps,
        };
    let h = LoadHistory::from_segments(&[
        seg(1.0, Some(0.02), None, 4),
        seg(1.0, None, Some(40.0), 6),
        seg(2.0, None, Some(40.0), 4),
        seg(1.0, Some(0.01), None, 5),
    ])
    .unwrap();
    for kind in [ContactKind::Vertical, ContactKind::Normal] {
        let model = small_model(cone(), kind);
        let c = [20000.0, 0.3, 30000.0];
        let mat = LawMaterial(&Maxwell);
        let mut solver = DirectSolver::new(&model).unwrap();
        let traj = solver.run_history(&mat, &c, &h, &opts()).unwrap();
        let mut adj = Adjoint::new(&model).unwrap();
        assert!(adj.take_factor(&mut solver));
        let taken = adj.sensitivities_load(&mat, &c, &traj, &h).unwrap();
        let fresh = Adjoint::new(&model)
            .unwrap()
            .sensitivities_load(&mat, &c, &traj, &h)
            .unwrap();
        let (dh, df) = (
            column_rel(&fresh.dh_dc, &taken.dh_dc),
            column_rel(&fresh.df_dc, &taken.df_dc),
        );
        println!("{kind:?} load control: dh {dh:.1e}, dF {df:.1e}");
        assert!(dh <= 1e-12 && df <= 1e-12, "{dh:e} {df:e}");
    }
}

#[test]
fn one_and_two_threads_give_the_same_bits() {
    let model = small_model(cone(), ContactKind::Vertical);
    let c = [20000.0, 0.3, 30000.0];
    let mat = LawMaterial(&Maxwell);
    let traj = DirectSolver::new(&model)
        .unwrap()
        .run(&mat, &c, &schedules()[1], &opts())
        .unwrap();
    let on = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let mut adj = Adjoint::new(&model).unwrap();
        let s = pool.install(|| adj.sensitivities(&mat, &c, &traj).unwrap());
        assert!(adj.last_pass_nodal());
        bits(&s)
    };
    assert_eq!(on(1), on(2));
}
