//! The all-nodal forward sensitivities of a linear material with isotropic blocks
//! (`Prony`, `crates/adjoint/src/material/nodal/sens.rs`) and the bordered all-nodal
//! pass of a law with one isotropic tangent (Maxwell, `nodal_sens.rs`), under depth
//! control, load control and through the frame:
//! - the columns `dF_i/dc_k` and `dU_i/dc_k` equal the Gauss-point pass's
//!   (`Adjoint::set_fused(false)`) to 1e-12 of each column's largest entry, Prony with
//!   one to three terms and Maxwell, depth control (a history of three step lengths),
//!   load-hold-unload under load control, a depth-load-load-depth history and depth
//!   through the frame, every column and a subset; the pass asserted all-nodal (without
//!   it, `Adjoint::last_pass_nodal` is false for every case but Maxwell's depth control);
//! - against central differences of the direct solver's own runs (forces under depth
//!   control and through the frame, depths under load control), with the contact set of
//!   the +-h runs held;
//! - the same bits on one and two threads, and with the parameters' solves together
//!   (`Adjoint::set_multi_solve`) or one after the other;
//! - normal contact and finite strain keep the Gauss-point pass.

mod common;

use common::{column_rel, prony, small_model, sphere_model};
use indentify_adjoint::{Adjoint, FrameIndex, LoadSensitivities};
use indentify_contact::{
    ContactKind, DirectSolver, Frame, Kinematics, LoadHistory, Model, Schedule, Segment,
    SolverOptions, Target, Trajectory, trapezoid,
};
use indentify_laws::{LawMaterial, Material, Maxwell};
use indentify_testkit::{cone68 as cone, depth, force};

const MAXWELL: [f64; 3] = [20000.0, 0.3, 30000.0];

/// How a case drives the punch.
#[derive(Clone, Copy, Debug)]
enum Drive {
    /// Load to 0.08 mm, hold, partial unload and reload, unload to 0.02 mm, step lengths
    /// 1/6, 1/4, 1/10 and 1/10 s.
    Depth,
    /// Load to `p`, hold, unload to 0.4 `p` (1/6, 1/2, 1/5 s).
    Load,
    /// Depth to 0.03 mm, load to `p`, hold, depth back to 0.03 mm.
    Mixed,
    /// The trapezoid 0 -> 0.1 mm -> hold -> 0.04 mm of machine depths through
    /// `Cf = 5e-6` mm/N.
    Frame,
}

const DRIVES: [Drive; 4] = [Drive::Depth, Drive::Load, Drive::Mixed, Drive::Frame];

fn seg(duration: f64, depth: f64, steps: usize) -> Segment {
    Segment {
        duration,
        depth,
        steps,
    }
}

fn depth_schedule() -> Schedule {
    Schedule::from_segments(&[
        seg(1.0, 0.08, 6),
        seg(1.0, 0.08, 4),
        seg(0.5, 0.05, 5),
        seg(0.5, 0.07, 5),
        seg(1.0, 0.02, 10),
    ])
    .unwrap()
}

fn history(drive: Drive, p: f64) -> LoadHistory {
    match drive {
        Drive::Mixed => LoadHistory::from_segments(&[
            depth(1.0, 0.03, 4),
            force(1.0, p, 6),
            force(1.0, p, 4),
            depth(1.0, 0.03, 5),
        ]),
        _ => LoadHistory::from_segments(&[
            force(1.0, p, 6),
            force(1.0, p, 2),
            force(1.0, 0.4 * p, 5),
        ]),
    }
    .unwrap()
}

fn frame() -> Frame {
    Frame {
        compliance: 5e-6,
        ..Frame::default()
    }
}

fn machine() -> Schedule {
    let mut segs = trapezoid(0.1, 1.0, 1.0, 1.0, 5);
    if let Some(last) = segs.last_mut() {
        last.depth = 0.04;
    }
    Schedule::from_segments(&segs).unwrap()
}

fn opts(record: bool) -> SolverOptions {
    SolverOptions {
        record_fields: record,
        residual_tol: 1e-11,
        ..SolverOptions::default()
    }
}

/// The peak force of the load-controlled histories (N): about 0.08 mm under the cone
/// for the solid, 0.06 mm for Maxwell.
fn peak(mat: &dyn Material) -> f64 {
    if mat.name() == "maxwell" {
        300.0
    } else {
        1000.0
    }
}

fn run(m: &Model, mat: &dyn Material, c: &[f64], drive: Drive, record: bool) -> Trajectory {
    let mut solver = DirectSolver::new(m).unwrap();
    match drive {
        Drive::Depth => solver.run(mat, c, &depth_schedule(), &opts(record)),
        Drive::Load | Drive::Mixed => {
            solver.run_history(mat, c, &history(drive, peak(mat)), &opts(record))
        }
        Drive::Frame => solver.run_compliant(mat, c, &machine(), &frame(), &opts(record)),
    }
    .unwrap()
}

/// The pass of `drive` (`cols`: `Adjoint::sensitivities_of`, depth control only).
fn pass(
    adj: &mut Adjoint,
    mat: &dyn Material,
    c: &[f64],
    t: &Trajectory,
    drive: Drive,
    cols: Option<&[usize]>,
) -> LoadSensitivities {
    match drive {
        Drive::Depth => {
            let s = match cols {
                Some(cols) => adj.sensitivities_of(mat, c, t, cols),
                None => adj.sensitivities(mat, c, t),
            }
            .unwrap();
            LoadSensitivities {
                dh_dc: vec![vec![0.0; c.len()]; s.df_dc.len()],
                df_dc: s.df_dc,
                seconds: s.seconds,
            }
        }
        Drive::Load | Drive::Mixed => adj
            .sensitivities_load(mat, c, t, &history(drive, peak(mat)))
            .unwrap(),
        Drive::Frame => adj
            .sensitivities_compliant(mat, c, t, (&machine(), &frame()), FrameIndex::default())
            .unwrap(),
    }
}

/// The materials of the comparison: Prony with one to three terms and Maxwell.
fn materials() -> Vec<(Box<dyn Material>, Vec<f64>)> {
    let mut out: Vec<(Box<dyn Material>, Vec<f64>)> = (1..=3)
        .map(|n| {
            let (p, c) = prony(n);
            (Box::new(p) as Box<dyn Material>, c)
        })
        .collect();
    out.push((Box::new(LawMaterial(&Maxwell)), MAXWELL.to_vec()));
    out
}

#[test]
fn nodal_columns_equal_the_gauss_point_pass() {
    let m = small_model(cone(), ContactKind::Vertical);
    let mut report = Vec::new();
    for (mat, c) in materials() {
        let mat = mat.as_ref();
        for drive in DRIVES {
            let t = run(&m, mat, &c, drive, true);
            let most = t.steps.iter().map(|s| s.active.len()).max().unwrap_or(0);
            assert!(
                most > 2,
                "{} {drive:?}: {most} nodes in contact",
                mat.name()
            );
            // every column; under depth control also a subset
            let subset = [0, c.len() - 1];
            let subsets: &[Option<&[usize]>] = match drive {
                Drive::Depth => &[None, Some(&subset)],
                _ => &[None],
            };
            for &cols in subsets {
                let mut adj = Adjoint::new(&m).unwrap();
                let nodal = pass(&mut adj, mat, &c, &t, drive, cols);
                assert!(
                    adj.last_pass_nodal(),
                    "{} {drive:?}: the all-nodal pass did not run",
                    mat.name()
                );
                adj.set_fused(false);
                let gauss = pass(&mut adj, mat, &c, &t, drive, cols);
                assert!(!adj.last_pass_nodal());
                // the load-controlled steps' forces are prescribed (the nodal pass's, as
                // the rows' pass, exactly; the Gauss-point pass's to round-off)
                let computed = |v: &[Vec<f64>]| -> Vec<Vec<f64>> {
                    v.iter()
                        .zip(&t.steps)
                        .map(
                            |(r, s)| match (drive, history(drive, 1.0).segment_at(s.t).1) {
                                (Drive::Load | Drive::Mixed, Target::Force(_)) => {
                                    vec![0.0; r.len()]
                                }
                                _ => r.clone(),
                            },
                        )
                        .collect()
                };
                let (df, dh) = (
                    column_rel(&computed(&gauss.df_dc), &computed(&nodal.df_dc)),
                    column_rel(&gauss.dh_dc, &nodal.dh_dc),
                );
                report.push(format!(
                    "{} {drive:?} {cols:?}: dF/dc {df:.1e}, dU/dc {dh:.1e}",
                    mat.name()
                ));
                assert!(df <= 1e-12 && dh <= 1e-12, "{}", report.last().unwrap());
                if let Some(cols) = cols {
                    for k in (0..c.len()).filter(|k| !cols.contains(k)) {
                        assert!(nodal.df_dc.iter().all(|r| r[k] == 0.0), "column {k}");
                    }
                }
                if matches!(drive, Drive::Load) {
                    // a history prescribed from the start: dF_i = dP_i = 0, exactly
                    assert!(nodal.df_dc.iter().flatten().all(|v| *v == 0.0));
                }
            }
        }
    }
    println!("{}", report.join("\n"));
}

/// The contact set of every step.
fn contact_sets(t: &Trajectory) -> Vec<Vec<u32>> {
    t.steps.iter().map(|s| s.active.clone()).collect()
}

#[test]
fn nodal_columns_match_central_differences() {
    let m = small_model(cone(), ContactKind::Vertical);
    let (mat, c) = prony(2);
    let mut report = Vec::new();
    for drive in DRIVES {
        let t = run(&m, &mat, &c, drive, true);
        let mut adj = Adjoint::new(&m).unwrap();
        let s = pass(&mut adj, &mat, &c, &t, drive, None);
        assert!(adj.last_pass_nodal());
        // the observable: the depth under load control, the force otherwise
        let load = matches!(drive, Drive::Load);
        let observe = |t: &Trajectory| -> Vec<f64> {
            t.steps
                .iter()
                .map(|s| if load { s.depth } else { s.force })
                .collect()
        };
        let mut worst = 0.0f64;
        for k in [0, 1, 3, 5] {
            let col: Vec<f64> = (if load { &s.dh_dc } else { &s.df_dc })
                .iter()
                .map(|r| r[k])
                .collect();
            let scale = col.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            assert!(scale > 0.0, "{drive:?} column {k} is zero");
            let mut fd = None;
            for relh in [1e-6, 1e-5, 1e-7] {
                let h = relh * c[k].abs();
                let at = |x: f64| {
                    let mut p = c.clone();
                    p[k] = x;
                    run(&m, &mat, &p, drive, false)
                };
                let (tp, tm) = (at(c[k] + h), at(c[k] - h));
                if contact_sets(&tp) == contact_sets(&t) && contact_sets(&tm) == contact_sets(&t) {
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
            let fd = fd.expect("no step holds the contact sets");
            let d = col
                .iter()
                .zip(&fd)
                .fold(0.0f64, |a, (x, y)| a.max((x - y).abs() / scale));
            worst = worst.max(d);
        }
        report.push(format!("{drive:?}: {worst:.1e}"));
        assert!(worst <= 1e-5, "{drive:?}: {worst:.2e}");
    }
    println!("central differences: {}", report.join(", "));
}

#[test]
fn one_and_two_threads_give_the_same_bits() {
    let m = small_model(cone(), ContactKind::Vertical);
    for (mat, c) in materials() {
        let mat = mat.as_ref();
        for drive in DRIVES {
            let t = run(&m, mat, &c, drive, true);
            let on = |threads: usize, multi: bool| {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                let mut adj = Adjoint::new(&m).unwrap();
                adj.set_multi_solve(multi);
                let s = pool.install(|| pass(&mut adj, mat, &c, &t, drive, None));
                assert!(adj.last_pass_nodal());
                assert_eq!(adj.last_pass_multi_solve(), multi);
                (s.df_dc.iter().chain(&s.dh_dc))
                    .flatten()
                    .map(|x| x.to_bits())
                    .collect::<Vec<_>>()
            };
            let one = on(1, true);
            assert_eq!(one, on(2, true), "{} {drive:?}", mat.name());
            // the parameters' solves together or one after the other: the same bits
            assert_eq!(one, on(1, false), "{} {drive:?}", mat.name());
        }
    }
}

#[test]
fn normal_contact_and_finite_strain_keep_the_gauss_point_pass() {
    let (mat, c) = prony(2);
    for (kind, kin) in [
        (ContactKind::Normal, Kinematics::Small),
        (ContactKind::Normal, Kinematics::Finite),
    ] {
        let m = sphere_model(kind, kin);
        for drive in [Drive::Depth, Drive::Load] {
            let t = run(&m, &mat, &c, drive, true);
            let mut adj = Adjoint::new(&m).unwrap();
            pass(&mut adj, &mat, &c, &t, drive, None);
            assert!(!adj.last_pass_nodal(), "{kind:?} {kin:?} {drive:?}");
            let t = run(&m, &LawMaterial(&Maxwell), &MAXWELL, drive, true);
            pass(&mut adj, &LawMaterial(&Maxwell), &MAXWELL, &t, drive, None);
            assert!(!adj.last_pass_nodal(), "Maxwell {kind:?} {kin:?} {drive:?}");
        }
    }
}
