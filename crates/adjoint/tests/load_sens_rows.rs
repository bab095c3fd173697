//! Load control's and the frame's forward sensitivities with the force at the depth held
//! (which sets the depth's variation) and the depth-controlled steps' forces read from
//! the force dofs' rows of each step's tangent, `rhs_A - (K du)_A`, and a load-controlled
//! step's force variation taken as prescribed (the default), against the same passes
//! over the Gauss points (`Adjoint::set_fused(false)`: the code before the rows): every
//! `dU_i/dc_k` and every computed `dF_i/dc_k` within 1e-12 of its column's largest entry,
//! for stress-only laws (Norton-Hoff, Maxwell) and laws with internal variables (a
//! two-term Prony solid, J2 with power hardening and Norton overstress), small strain
//! under vertical, frictionless normal and Coulomb contact and finite strain
//! (frictionless and Coulomb), over a load-hold-unload, a depth-load-hold-depth history
//! and depth through the frame; and `dU_i/dc_k` (`dF_i/dc_k` through the frame) against
//! central differences of the direct solver's own runs, a reference this code did not
//! produce, with the contact set and stick/slip statuses of the +-h runs held.
//!
//! Without the rows (the passes the default took before) the first test fails: the pass
//! does not read the rows (`Adjoint::last_pass_reaction_rows`) and a load-controlled
//! step's force variation is the passes' round-off instead of its prescribed zero.

mod common;

use common::sphere_model as model;
use indentify_adjoint::{Adjoint, FrameIndex, LoadSensitivities};
use indentify_contact::{
    ContactKind, DirectSolver, Frame, Kinematics, LoadHistory, Model, Schedule, Target, Trajectory,
    trapezoid,
};
use indentify_laws::{Hardening, LawMaterial, Material, Maxwell, NortonHoff, Plastic, Prony, Rate};
use indentify_testkit::{depth, force, force_lhu, recording};

/// Depth to 0.03 mm, load to `p` N, hold, depth back to 0.03 mm.
fn mixed(p: f64) -> LoadHistory {
    LoadHistory::from_segments(&[
        depth(1.0, 0.03, 4),
        force(1.0, p, 5),
        force(1.0, p, 4),
        depth(1.0, 0.03, 4),
    ])
    .unwrap()
}

const NH: [f64; 5] = [1e5, 0.3, 1500.0, 5.0, 500.0];
const MAXWELL: [f64; 3] = [20000.0, 0.3, 30000.0];
const PRONY: [f64; 6] = [1e5, 0.3, 0.3, 0.2, 0.2, 2.0];
const POWER_NORTON: [f64; 6] = [1e5, 0.3, 500.0, 0.2, 1500.0, 5.0];

/// How a case drives the punch.
#[derive(Clone, Copy)]
enum Drive<'a> {
    Load(&'a LoadHistory),
    /// The trapezoid 0 -> 0.06 mm -> hold -> 0.024 mm of machine depths through
    /// `Cf = 1e-5` mm/N.
    Frame,
}

fn frame() -> Frame {
    Frame {
        compliance: 1e-5,
        ..Frame::default()
    }
}

fn machine() -> Schedule {
    let mut segs = trapezoid(0.06, 1.0, 1.0, 1.0, 5);
    if let Some(last) = segs.last_mut() {
        last.depth = 0.024;
    }
    Schedule::from_segments(&segs).unwrap()
}

fn run(m: &Model, mat: &dyn Material, c: &[f64], drive: Drive<'_>, record: bool) -> Trajectory {
    let mut solver = DirectSolver::new(m).unwrap();
    match drive {
        Drive::Load(h) => solver
            .run_history(mat, c, h, &recording(record, 1e-12))
            .unwrap(),
        Drive::Frame => solver
            .run_compliant(mat, c, &machine(), &frame(), &recording(record, 1e-12))
            .unwrap(),
    }
}

fn pass(
    adj: &mut Adjoint,
    mat: &dyn Material,
    c: &[f64],
    t: &Trajectory,
    drive: Drive<'_>,
) -> LoadSensitivities {
    match drive {
        Drive::Load(h) => adj.sensitivities_load(mat, c, t, h).unwrap(),
        Drive::Frame => adj
            .sensitivities_compliant(mat, c, t, (&machine(), &frame()), FrameIndex::default())
            .unwrap(),
    }
}

/// Whether step `i` of `t` prescribes its force.
fn load_step(drive: Drive<'_>, t: &Trajectory, i: usize) -> bool {
    match drive {
        Drive::Load(h) => matches!(h.segment_at(t.steps[i].t).1, Target::Force(_)),
        Drive::Frame => false,
    }
}

/// The rows' pass against the Gauss-point passes': the worst `dU/dc` and computed
/// `dF/dc` differences, relative to each column's largest entry (asserted 1e-12), and the
/// largest difference on the load-controlled steps (N per unit parameter), whose force
/// variation the rows' pass takes as prescribed (asserted exactly zero where the history
/// starts under load control, within 1e-12 of the computed steps' largest after a
/// depth-controlled start).
fn compare(m: &Model, mat: &dyn Material, c: &[f64], drive: Drive<'_>) -> (f64, f64, f64) {
    let t = run(m, mat, c, drive, true);
    let n = t.steps.len();
    let mut adj = Adjoint::new(m).unwrap();
    let rows = pass(&mut adj, mat, c, &t, drive);
    assert!(
        adj.last_pass_reaction_rows(),
        "the tangent rows were not read"
    );
    adj.set_fused(false);
    let points = pass(&mut adj, mat, c, &t, drive);
    assert!(!adj.last_pass_reaction_rows());
    let (mut w_dh, mut w_df, mut noise) = (0.0f64, 0.0f64, 0.0f64);
    for k in 0..c.len() {
        let col = |v: &[Vec<f64>], keep: &dyn Fn(usize) -> bool| {
            (0..n)
                .filter(|&i| keep(i))
                .fold(0.0f64, |s, i| s.max(v[i][k].abs()))
        };
        let all = |_: usize| true;
        let computed = |i: usize| !load_step(drive, &t, i);
        let (s_dh, s_df) = (col(&points.dh_dc, &all), col(&points.df_dc, &computed));
        for i in 0..n {
            if s_dh > 0.0 {
                let d = (rows.dh_dc[i][k] - points.dh_dc[i][k]).abs() / s_dh;
                assert!(d <= 1e-12, "{}: step {i} dU/dc_{k}: {d:.2e}", mat.name());
                w_dh = w_dh.max(d);
            }
            if computed(i) {
                if s_df > 0.0 {
                    let d = (rows.df_dc[i][k] - points.df_dc[i][k]).abs() / s_df;
                    assert!(d <= 1e-12, "{}: step {i} dF/dc_{k}: {d:.2e}", mat.name());
                    w_df = w_df.max(d);
                }
            } else {
                // the prescribed variation (a mixed history's start force's share) against
                // the passes' computed one: absolute (the prescribed steps' own scale is
                // zero from a start under load control), and relative to the computed
                // steps' where there are any
                let d = (rows.df_dc[i][k] - points.df_dc[i][k]).abs();
                noise = noise.max(d);
                if s_df > 0.0 {
                    assert!(
                        d <= 1e-12 * s_df,
                        "{}: step {i} dP/dc_{k}: {d:.2e}",
                        mat.name()
                    );
                }
            }
        }
        assert!(
            s_dh > 0.0 || k > 0,
            "{}: dU/dc_{k} is zero everywhere",
            mat.name()
        );
    }
    if let Drive::Load(h) = drive {
        // a segment prescribed from the start: dF_i = dP_i = 0, exactly
        let first_load = h
            .ends
            .first()
            .is_some_and(|e| matches!(e.1, Target::Force(_)));
        for i in (0..n).filter(|&i| first_load && load_step(drive, &t, i)) {
            assert!(
                rows.df_dc[i].iter().all(|v| *v == 0.0),
                "{}: step {i}: the prescribed force varies: {:?}",
                mat.name(),
                rows.df_dc[i]
            );
        }
    }
    (w_dh, w_df, noise)
}

#[test]
fn rows_equal_the_gauss_point_passes() {
    let friction = ContactKind::normal_with_friction(0.2).unwrap();
    let (h_nh, h_mx, h_pr) = (
        force_lhu(600.0, 5),
        force_lhu(300.0, 5),
        force_lhu(1500.0, 5),
    );
    let (m_nh, m_pr) = (mixed(600.0), mixed(1500.0));
    let prony = Prony::new(2).unwrap();
    let power = Plastic::new(Hardening::Power, Rate::Norton);
    let mut report = Vec::new();
    for (name, kind, kin) in [
        ("vertical", ContactKind::Vertical, Kinematics::Small),
        ("normal", ContactKind::Normal, Kinematics::Small),
        ("coulomb", friction, Kinematics::Small),
        ("finite normal", ContactKind::Normal, Kinematics::Finite),
        ("finite coulomb", friction, Kinematics::Finite),
    ] {
        let m = model(kind, kin);
        let small = kin == Kinematics::Small;
        let mut cases: Vec<(&str, &dyn Material, &[f64], Drive<'_>)> = vec![
            (
                "NH load",
                &LawMaterial(&NortonHoff),
                &NH,
                Drive::Load(&h_nh),
            ),
            ("Prony load", &prony, &PRONY, Drive::Load(&h_pr)),
            ("NH frame", &LawMaterial(&NortonHoff), &NH, Drive::Frame),
        ];
        if small {
            cases.push((
                "Maxwell load",
                &LawMaterial(&Maxwell),
                &MAXWELL,
                Drive::Load(&h_mx),
            ));
            cases.push((
                "NH mixed",
                &LawMaterial(&NortonHoff),
                &NH,
                Drive::Load(&m_nh),
            ));
            cases.push(("Prony mixed", &prony, &PRONY, Drive::Load(&m_pr)));
            cases.push((
                "J2 power+Norton load",
                &power,
                &POWER_NORTON,
                Drive::Load(&h_nh),
            ));
            cases.push(("Prony frame", &prony, &PRONY, Drive::Frame));
        }
        for (case, mat, c, drive) in cases {
            let (dh, df, noise) = compare(&m, mat, c, drive);
            report.push(format!(
                "{name}, {case}: dU/dc {dh:.1e}, dF/dc {df:.1e}; prescribed steps' dF/dc \
                 against the passes' up to {noise:.1e}"
            ));
        }
    }
    println!("{}", report.join("\n"));
}

/// The contact set and stick/slip statuses of every step.
fn statuses(t: &Trajectory) -> Vec<(Vec<u32>, Vec<i8>)> {
    t.steps
        .iter()
        .map(|s| (s.active.clone(), s.slip.clone()))
        .collect()
}

/// Columns `ks` of the rows' pass (`dU/dc` under load control, `dF/dc` through the frame)
/// against central differences of the direct solver's depths (forces), with every
/// status held in the +-h runs (the largest relative step of 1e-5, 1e-6, 1e-4 that holds
/// them); returns the worst difference relative to the column's largest entry.
fn against_differences(
    m: &Model,
    mat: &dyn Material,
    c: &[f64],
    drive: Drive<'_>,
    ks: &[usize],
) -> f64 {
    let t = run(m, mat, c, drive, true);
    let mut adj = Adjoint::new(m).unwrap();
    let s = pass(&mut adj, mat, c, &t, drive);
    assert!(adj.last_pass_reaction_rows());
    let base = statuses(&t);
    let observe = |t: &Trajectory| -> Vec<f64> {
        match drive {
            Drive::Load(_) => t.steps.iter().map(|s| s.depth).collect(),
            Drive::Frame => t.steps.iter().map(|s| s.force).collect(),
        }
    };
    let column = |k: usize| -> Vec<f64> {
        match drive {
            Drive::Load(_) => s.dh_dc.iter().map(|r| r[k]).collect(),
            Drive::Frame => s.df_dc.iter().map(|r| r[k]).collect(),
        }
    };
    let mut worst = 0.0f64;
    for &k in ks {
        let col = column(k);
        let scale = col.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        assert!(scale > 0.0);
        let mut fd = None;
        for rel in [1e-5, 1e-6, 1e-4] {
            let h = rel * c[k].abs();
            let at = |x: f64| {
                let mut p = c.to_vec();
                p[k] = x;
                run(m, mat, &p, drive, false)
            };
            let (tp, tm) = (at(c[k] + h), at(c[k] - h));
            if statuses(&tp) == base && statuses(&tm) == base {
                let (op, om) = (observe(&tp), observe(&tm));
                fd = Some(
                    op.iter()
                        .zip(&om)
                        .map(|(a, b)| (a - b) / (2.0 * h))
                        .collect::<Vec<_>>(),
                );
                break;
            }
        }
        let fd = fd.expect("no step holds every status");
        let d = col
            .iter()
            .zip(&fd)
            .fold(0.0f64, |a, (x, y)| a.max((x - y).abs() / scale));
        println!(
            "  {} column {k}: {d:.2e} of its largest {scale:.3e}",
            mat.name()
        );
        worst = worst.max(d);
    }
    worst
}

#[test]
fn rows_match_central_differences() {
    let friction = ContactKind::normal_with_friction(0.2).unwrap();
    let (h_nh, h_pr) = (force_lhu(600.0, 5), force_lhu(1500.0, 5));
    let prony = Prony::new(2).unwrap();
    let mut report = Vec::new();
    for (name, kind, kin) in [
        ("normal", ContactKind::Normal, Kinematics::Small),
        ("coulomb", friction, Kinematics::Small),
        ("finite normal", ContactKind::Normal, Kinematics::Finite),
        ("finite coulomb", friction, Kinematics::Finite),
    ] {
        let m = model(kind, kin);
        let nh = against_differences(
            &m,
            &LawMaterial(&NortonHoff),
            &NH,
            Drive::Load(&h_nh),
            &[0, 3, 4],
        );
        let pr = against_differences(&m, &prony, &PRONY, Drive::Load(&h_pr), &[0, 3]);
        let fr = against_differences(&m, &LawMaterial(&NortonHoff), &NH, Drive::Frame, &[0, 4]);
        report.push(format!(
            "{name}: NH load {nh:.1e}, Prony load {pr:.1e}, NH frame {fr:.1e}"
        ));
        for (what, d) in [("NH load", nh), ("Prony load", pr), ("NH frame", fr)] {
            assert!(
                d <= 1e-5,
                "{name}, {what}: {d:.2e} against central differences"
            );
        }
    }
    println!("{}", report.join("\n"));
}
