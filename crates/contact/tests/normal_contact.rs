//! Normal contact (`ContactKind::Normal`): Newton's quadratic rate with an active zone on
//! a sphere, the solver on every punch profile, clear errors beyond a surface's end, and
//! vertical contact left as it was.

mod common;

use common::{model_2mm, ramp, testkit::cylinder};
use indentify_contact::{
    ContactError, ContactKind, DirectSolver, Model, Punch, Schedule, SolverOptions, Trajectory,
    trapezoid,
};
use indentify_laws::{Elastic, Law, Maxwell, NortonHoff};
use indentify_mesh::CylinderMesher;

/// A 2 x 2 mm cylinder, 12 x 12 Q8 graded 1.3 towards the axis and the top.
fn model(punch: Punch, kind: ContactKind) -> Model {
    model_2mm(12, punch, kind)
}

/// At every converged step, active nodes sit on the surface (|g| <= 1e-12 mm) with a
/// compressive normal reaction, inactive ones off it, and the reactions sum to the
/// force through their vertical components.
fn check_complementarity(model: &Model, traj: &Trajectory) {
    for (i, s) in traj.steps.iter().enumerate() {
        let u = &traj.fields[i + 1].u;
        let mut fz = 0.0;
        for (&k, &lam) in s.active.iter().zip(&s.lambda) {
            let p = model.project(k as usize, u, s.depth).in_contact();
            assert!(p.gap.abs() <= 1e-12, "step {i} node {k}: gap {}", p.gap);
            assert!(
                lam >= -1e-9 * s.force.abs(),
                "step {i} node {k}: lambda {lam}"
            );
            fz += lam * p.m[1];
        }
        assert!(
            (fz - s.force).abs() <= 1e-8 * s.force.abs().max(1e-12),
            "step {i}: {fz} vs {}",
            s.force
        );
        for k in 0..model.candidates.len() {
            if !s.active.contains(&(k as u32)) {
                let g = model.project(k, u, s.depth).gap;
                assert!(g >= -1e-10 * s.depth.abs(), "step {i} node {k}: gap {g}");
            }
        }
    }
}

/// The solver shall converge quadratically with normal contact on a sphere: in the last
/// step of a ramp (an established contact zone, curved normals), each residual of the
/// final iterations is at most 10 times the square of the previous one.
#[test]
fn newton_converges_quadratically_on_a_sphere() {
    for (law, c) in [
        (&Elastic as &dyn Law, vec![20000.0, 0.3]),
        (&NortonHoff, vec![1e5, 0.3, 1500.0, 5.0, 500.0]),
    ] {
        let model = model(Punch::Sphere { radius: 0.5 }, ContactKind::Normal);
        let mut solver = DirectSolver::new(&model).unwrap();
        let opts = SolverOptions {
            residual_tol: 1e-13,
            ..Default::default()
        };
        let traj = solver
            .run(
                &indentify_laws::LawMaterial(law),
                &c,
                &ramp(0.05, 10),
                &opts,
            )
            .unwrap();
        let r = solver.last_residuals();
        println!("{}: residuals of the last step {r:?}", law.name());
        assert!(traj.steps.last().unwrap().active.len() >= 4);
        // the passes after the first solve with the final active set, down to round-off
        // (1e-13); the first pass precedes any solve (its residual does not see the gap)
        let settled = r.last().unwrap().1;
        let tail: Vec<f64> = r
            .iter()
            .skip(1)
            .filter(|p| p.1 == settled)
            .map(|p| p.0)
            .collect();
        let mut checked = 0;
        for w in tail.windows(2) {
            if w[1] > 1e-13 {
                assert!(w[1] <= 10.0 * w[0] * w[0], "{:e} -> {:e}", w[0], w[1]);
                checked += 1;
            }
        }
        assert!(checked >= 1, "{r:?}");
        check_complementarity(&model, &traj);
    }
}

/// The solver shall run normal contact for every punch profile over a load-unload
/// history, satisfy complementarity at every step, and stay within 10% of vertical
/// contact's force (the two formulations differ by a few percent at these depths).
#[test]
fn every_profile_runs_with_normal_contact() {
    let sphere_table = {
        let r: Vec<f64> = (0..=40).map(|i| 0.01 * i as f64).collect();
        let z = r.iter().map(|&x| 0.5 - (0.25 - x * x).sqrt()).collect();
        Punch::Tabulated { r, z }
    };
    let punches = [
        Punch::Cone {
            half_angle_deg: 68.0,
        },
        Punch::Sphere { radius: 0.5 },
        Punch::SpheroCone {
            radius: 0.05,
            half_angle_deg: 70.3,
        },
        Punch::Berkovich { tip_radius: None },
        Punch::Vickers {
            tip_radius: Some(0.02),
        },
        Punch::CubeCorner { tip_radius: None },
        sphere_table,
    ];
    let sched = Schedule::from_segments(&trapezoid(0.02, 1.0, 0.5, 1.0, 6)).unwrap();
    let c = [20000.0, 0.3];
    for punch in punches {
        let mut fmax = [0.0; 2];
        for (j, kind) in [ContactKind::Vertical, ContactKind::Normal]
            .into_iter()
            .enumerate()
        {
            let m = model(punch.clone(), kind);
            let mut solver = DirectSolver::new(&m).unwrap();
            let traj = solver
                .run(
                    &indentify_laws::LawMaterial(&Elastic),
                    &c,
                    &sched,
                    &SolverOptions::default(),
                )
                .unwrap_or_else(|e| panic!("{punch:?} {kind:?}: {e}"));
            fmax[j] = traj.forces().iter().fold(0.0f64, |a, &b| a.max(b));
            if kind == ContactKind::Normal {
                check_complementarity(&m, &traj);
            }
        }
        println!(
            "{}: vertical {:.4} N, normal {:.4} N",
            punch.describe(),
            fmax[0],
            fmax[1]
        );
        assert!(
            fmax[1] > 0.0 && (fmax[1] / fmax[0] - 1.0).abs() < 0.1,
            "{fmax:?}"
        );
    }
}

/// The flat punch's face carries nodes by their displaced radius; its rim node moves
/// inward and stays on the face, so normal and vertical contact solve the same equations
/// (a vertical normal on the face) and agree to round-off.
#[test]
fn flat_punch_with_normal_contact() {
    let mesh = CylinderMesher {
        radius: 2.0,
        height: 2.0,
        nr: 12,
        nz: 12,
        grading_r: 1.3,
        grading_z: 1.3,
    }
    .build_through(0.2)
    .unwrap()
    .0;
    let punch = Punch::Flat { radius: 0.2 };
    let mesh = indentify_contact::punch::treat_rim(mesh, &punch).unwrap().0;
    let mut f = [0.0; 2];
    for (j, kind) in [ContactKind::Vertical, ContactKind::Normal]
        .into_iter()
        .enumerate()
    {
        let m = Model::with_contact(mesh.clone(), punch.clone(), kind).unwrap();
        let mut solver = DirectSolver::new(&m).unwrap();
        let traj = solver
            .run(
                &indentify_laws::LawMaterial(&Elastic),
                &[20000.0, 0.3],
                &ramp(0.002, 4),
                &SolverOptions::default(),
            )
            .unwrap();
        if kind == ContactKind::Normal {
            check_complementarity(&m, &traj);
        }
        f[j] = traj.steps.last().unwrap().force;
    }
    println!("flat: vertical {} N, normal {} N", f[0], f[1]);
    assert!((f[1] / f[0] - 1.0).abs() < 1e-10, "{f:?}");
}

/// A node in normal contact beyond the last point of a tabulated profile shall stop the
/// run with an error naming the table's end (no silent force from an extrapolation).
#[test]
fn tabulated_profile_too_short_is_a_clear_error() {
    let punch = Punch::Tabulated {
        r: vec![0.0, 0.01, 0.02],
        z: vec![0.0, 0.004, 0.008],
    };
    let m = model(punch, ContactKind::Normal);
    let mut solver = DirectSolver::new(&m).unwrap();
    let err = solver
        .run(
            &indentify_laws::LawMaterial(&Elastic),
            &[20000.0, 0.3],
            &ramp(0.05, 5),
            &SolverOptions::default(),
        )
        .unwrap_err();
    let text = err.to_string();
    println!("{text}");
    assert!(matches!(err, ContactError::StepFailed { .. }));
    assert!(
        text.contains("last point of the tabulated profile (r = 0.02 mm)"),
        "{text}"
    );
}

/// `Model::new` is vertical contact, and `ContactKind` reads `Normal` and `Vertical`.
#[test]
fn vertical_is_the_default() {
    let m = Model::new(cylinder(1.0, 4, 1.0), Punch::Sphere { radius: 1.0 }).unwrap();
    assert_eq!(m.contact, ContactKind::Vertical);
    assert_eq!(ContactKind::default(), ContactKind::Vertical);
}

/// The solver shall run Norton-Hoff (sY > 0, plastic flow outward along the flanks) with
/// normal contact on curved, steep and flat profiles over load-hold-unload, with
/// complementarity at every step; a node of the flat punch that slides past the rim while
/// in contact stays on the face's plane, so the flat punch's force is vertical contact's.
#[test]
fn norton_hoff_runs_on_every_profile() {
    let sched = Schedule::from_segments(&trapezoid(0.03, 1.0, 1.0, 1.0, 6)).unwrap();
    let c = [1e5, 0.3, 1500.0, 5.0, 500.0];
    let flat_mesh = |punch: &Punch| {
        let mesh = CylinderMesher {
            radius: 2.0,
            height: 2.0,
            nr: 12,
            nz: 12,
            grading_r: 1.3,
            grading_z: 1.3,
        }
        .build_through(0.1)
        .unwrap()
        .0;
        indentify_contact::punch::treat_rim(mesh, punch).unwrap().0
    };
    for punch in [
        Punch::Sphere { radius: 0.5 },
        Punch::SpheroCone {
            radius: 0.05,
            half_angle_deg: 70.3,
        },
        Punch::CubeCorner { tip_radius: None },
        Punch::Flat { radius: 0.1 },
    ] {
        let mut fmax = [0.0; 2];
        for (j, kind) in [ContactKind::Vertical, ContactKind::Normal]
            .into_iter()
            .enumerate()
        {
            let m = match punch {
                Punch::Flat { .. } => {
                    Model::with_contact(flat_mesh(&punch), punch.clone(), kind).unwrap()
                }
                _ => model(punch.clone(), kind),
            };
            let mut solver = DirectSolver::new(&m).unwrap();
            let traj = solver
                .run(
                    &indentify_laws::LawMaterial(&NortonHoff),
                    &c,
                    &sched,
                    &SolverOptions::default(),
                )
                .unwrap_or_else(|e| panic!("{punch:?} {kind:?}: {e}"));
            if kind == ContactKind::Normal {
                check_complementarity(&m, &traj);
                if let Punch::Flat { radius } = punch {
                    // the rim node slides outward past the rim while in contact
                    let past = traj.steps.iter().enumerate().any(|(i, s)| {
                        s.active.iter().any(|&k| {
                            let n = m.candidates[k as usize];
                            m.mesh.nodes[n][0] + traj.fields[i + 1].u[2 * n] > radius
                        })
                    });
                    assert!(past, "no node in contact past the rim");
                }
            }
            fmax[j] = traj.forces().iter().fold(0.0f64, |a, &b| a.max(b));
        }
        println!(
            "{}: vertical {:.3} N, normal {:.3} N ({:+.1}%)",
            punch.describe(),
            fmax[0],
            fmax[1],
            100.0 * (fmax[1] / fmax[0] - 1.0)
        );
        assert!(fmax[1] > 0.0);
        if let Punch::Flat { .. } = punch {
            assert!((fmax[1] / fmax[0] - 1.0).abs() < 1e-9, "{fmax:?}");
        }
    }
}

/// A normal-contact run shall repeat bit for bit with the same solver (its caches warm)
/// and with a fresh one, and the stretch between two checkpoints, replayed, shall repeat
/// the recorded steps bit for bit (Maxwell: capacitance with frames; Norton-Hoff: inexact
/// solves on rotated systems).
#[test]
fn normal_contact_runs_repeat_bit_for_bit() {
    let sched = Schedule::from_segments(&trapezoid(0.03, 1.0, 1.0, 1.0, 5)).unwrap();
    let cases: [(&dyn Law, Vec<f64>); 2] = [
        (&Maxwell, vec![20000.0, 0.3, 30000.0]),
        (&NortonHoff, vec![1e5, 0.3, 1500.0, 5.0, 500.0]),
    ];
    for (law, c) in cases {
        let m = model(Punch::Sphere { radius: 0.5 }, ContactKind::Normal);
        let opts = SolverOptions {
            checkpoint_every: 4,
            ..SolverOptions::default()
        };
        let mut solver = DirectSolver::new(&m).unwrap();
        let first = solver
            .run(&indentify_laws::LawMaterial(law), &c, &sched, &opts)
            .unwrap();
        let again = solver
            .run(&indentify_laws::LawMaterial(law), &c, &sched, &opts)
            .unwrap();
        let fresh = DirectSolver::new(&m)
            .unwrap()
            .run(&indentify_laws::LawMaterial(law), &c, &sched, &opts)
            .unwrap();
        for other in [&again, &fresh] {
            assert_eq!(first.steps, other.steps, "{}", law.name());
            assert_eq!(first.fields, other.fields, "{}", law.name());
        }
        // the stretch between two checkpoints, as the adjoint replays it
        let (cp, next) = (&first.checkpoints[1], &first.checkpoints[2]);
        let seg = solver
            .replay(
                &indentify_laws::LawMaterial(law),
                &c,
                &sched,
                &opts,
                cp,
                next.schedule_index,
            )
            .unwrap();
        let steps = &first.steps[cp.steps_done..next.steps_done];
        assert_eq!(seg.steps[..], steps[..], "{}", law.name());
        let again = solver
            .replay(
                &indentify_laws::LawMaterial(law),
                &c,
                &sched,
                &opts,
                cp,
                next.schedule_index,
            )
            .unwrap();
        assert_eq!(seg.fields, again.fields, "{}", law.name());
    }
}
