//! Finite-strain kinematics (`Kinematics::Finite`): homogeneous compression of a cylinder
//! against the closed form (elastic Hencky) and the log-strain ODE (Norton-Hoff, integrated
//! here by RK4), Newton's quadratic rate under a cone, the small-depth limit equal to small
//! strain, the refusal of vertical contact, and the parallel Gauss-point passes giving the
//! same bits for any number of threads.

mod common;

use common::testkit::{cylinder, small_cylinder};
use indentify_contact::{
    ContactError, ContactKind, DirectSolver, Kinematics, Model, Punch, Schedule, Segment,
    SolverOptions, Trajectory, trapezoid,
};
use indentify_laws::{Elastic, NortonHoff};

/// A cylinder of radius 1 mm and height 1 mm, 2 x 2 Q8, under a flat punch wider than it
/// (frictionless top and bottom, free side: homogeneous uniaxial compression).
fn block() -> Model {
    let mesh = cylinder(1.0, 2, 1.0);
    Model::with_contact(mesh, Punch::Flat { radius: 3.0 }, ContactKind::Normal)
        .unwrap()
        .with_kinematics(Kinematics::Finite)
        .unwrap()
}

fn ramp(duration: f64, depth: f64, steps: usize) -> Schedule {
    Schedule::from_segments(&[Segment {
        duration,
        depth,
        steps,
    }])
    .unwrap()
}

/// Elastic Hencky material in uniaxial compression to 40% (stretch 0.6): `T_zz = E ln
/// lambda`, the Cauchy stress `T_zz / J` on the current area `pi R^2 lambda_r^2`, so
/// `F = pi R^2 E |ln lambda| / lambda` at every step, independent of nu (to the solver's
/// tolerance: the homogeneous field is in the element's space).
#[test]
fn elastic_compression_matches_the_hencky_closed_form() {
    let model = block();
    let (e, nu) = (1000.0, 0.3);
    let traj = DirectSolver::new(&model)
        .unwrap()
        .run(
            &indentify_laws::LawMaterial(&Elastic),
            &[e, nu],
            &ramp(1.0, 0.4, 20),
            &SolverOptions::default(),
        )
        .unwrap();
    for s in traj.schedule_steps() {
        let lam = 1.0 - s.depth;
        let exact = std::f64::consts::PI * e * (-lam.ln()) / lam;
        assert!(
            (s.force - exact).abs() < 1e-8 * exact,
            "depth {}: {} vs {exact}",
            s.depth,
            s.force
        );
    }
    // the lateral stretch: ln(lambda_r) = -nu ln(lambda_z)
    let u = &traj.fields.last().unwrap().u;
    let outer = model
        .mesh
        .nodes
        .iter()
        .position(|x| (x[0] - 1.0).abs() < 1e-12 && x[1].abs() < 1e-12)
        .unwrap();
    let lr = 1.0 + u[2 * outer];
    assert!((lr.ln() + nu * 0.6f64.ln()).abs() < 1e-9, "{lr}");
}

/// Norton-Hoff in uniaxial compression at a constant punch speed to a stretch of 0.5:
/// `dT/dt = E (d ln(lambda)/dt - sign(T) <(|T| - sY)/K>^m)`, integrated by RK4 with
/// 20000 steps, and `F = pi R^2 |T| / lambda` (plastic incompressibility does not enter:
/// the current area is `pi R^2 J / lambda`). The finite-element run is backward Euler
/// with 400 steps; their difference is the time discretization's (it halves with twice
/// the steps, checked below).
#[test]
fn norton_hoff_compression_matches_the_log_strain_ode() {
    let model = block();
    let c = [1000.0, 0.3, 200.0, 3.0, 20.0];
    let (duration, depth) = (2.0, 0.5);
    let ode = |t_end: f64| -> f64 {
        let n = 20000;
        let h = t_end / n as f64;
        let rate = |t: f64, s: f64| {
            let lam = 1.0 - depth * t / duration;
            let eps_rate = -(depth / duration) / lam;
            let x = ((s.abs() - c[4]) / c[2]).max(0.0);
            c[0] * (eps_rate - s.signum() * x.powf(c[3]))
        };
        let mut s = 0.0;
        for i in 0..n {
            let t = i as f64 * h;
            let k1 = rate(t, s);
            let k2 = rate(t + h / 2.0, s + h / 2.0 * k1);
            let k3 = rate(t + h / 2.0, s + h / 2.0 * k2);
            let k4 = rate(t + h, s + h * k3);
            s += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
        }
        let lam = 1.0 - depth * t_end / duration;
        std::f64::consts::PI * s.abs() / lam
    };
    let errors: Vec<f64> = [200, 400]
        .iter()
        .map(|&steps| {
            let traj = DirectSolver::new(&model)
                .unwrap()
                .run(
                    &indentify_laws::LawMaterial(&NortonHoff),
                    &c,
                    &ramp(duration, depth, steps),
                    &SolverOptions::default(),
                )
                .unwrap();
            let mut worst: f64 = 0.0;
            for s in traj.schedule_steps().filter(|s| s.t > 0.2) {
                let exact = ode(s.t);
                worst = worst.max((s.force - exact).abs() / exact);
            }
            println!("{steps} steps: worst relative error {worst:.3e}");
            worst
        })
        .collect();
    assert!(errors[1] < 3e-3, "{errors:?}");
    // first order in time: twice the steps, about half the error
    let ratio = errors[0] / errors[1];
    assert!((1.6..2.4).contains(&ratio), "{errors:?}");
}

fn cone_model(kin: Kinematics) -> Model {
    let mesh = cylinder(2.0, 10, 1.3);
    Model::with_contact(
        mesh,
        Punch::Cone {
            half_angle_deg: 68.0,
        },
        ContactKind::Normal,
    )
    .unwrap()
    .with_kinematics(kin)
    .unwrap()
}

/// Newton converges quadratically under finite strain (material and geometric tangent,
/// the contact's rotation): in the last step of a Norton-Hoff indentation to 0.1 mm
/// (strains of tens of percent under the tip), each residual between 1e-2 and 1e-12 is
/// at most a modest multiple of the square of the previous one.
#[test]
fn newton_is_quadratic_under_finite_strain() {
    let model = cone_model(Kinematics::Finite);
    let mut solver = DirectSolver::new(&model).unwrap();
    let opts = SolverOptions {
        residual_tol: 1e-13,
        ..Default::default()
    };
    solver
        .run(
            &indentify_laws::LawMaterial(&NortonHoff),
            &[1e5, 0.3, 1500.0, 5.0, 0.0],
            &ramp(1.0, 0.1, 10),
            &opts,
        )
        .unwrap();
    let res: Vec<f64> = solver.last_residuals().iter().map(|r| r.0).collect();
    println!("{res:?}");
    let pairs: Vec<[f64; 2]> = res
        .windows(2)
        .filter(|w| w[0] < 1e-2 && w[0] > 1e-12)
        .map(|w| [w[0], w[1]])
        .collect();
    assert!(!pairs.is_empty(), "{res:?}");
    for [a, b] in pairs {
        assert!(b < 1e3 * a * a || b < 1e-13, "{a:e} -> {b:e} in {res:?}");
    }
}

/// At a depth of 1e-5 mm finite strain and small strain (both with normal contact) give
/// the same force to 1e-3 relative (the difference is of the order of the strains).
#[test]
fn the_small_depth_limit_is_small_strain() {
    let sched = ramp(1.0, 1e-5, 4);
    let c = [1e5, 0.3, 1500.0, 5.0, 0.0];
    let force = |kin| {
        let model = cone_model(kin);
        let traj = DirectSolver::new(&model)
            .unwrap()
            .run(
                &indentify_laws::LawMaterial(&NortonHoff),
                &c,
                &sched,
                &SolverOptions::default(),
            )
            .unwrap();
        traj.forces()
    };
    let (small, finite) = (force(Kinematics::Small), force(Kinematics::Finite));
    for (a, b) in small.iter().zip(&finite).skip(1) {
        assert!((a - b).abs() < 1e-3 * a.abs(), "{small:?} vs {finite:?}");
    }
    // and they do differ at a depth of 0.1 mm (the test is not blind)
    let sched = ramp(1.0, 0.1, 10);
    let deep = |kin| {
        let model = cone_model(kin);
        DirectSolver::new(&model)
            .unwrap()
            .run(
                &indentify_laws::LawMaterial(&NortonHoff),
                &c,
                &sched,
                &SolverOptions::default(),
            )
            .unwrap()
            .forces()
    };
    let (s, f) = (deep(Kinematics::Small), deep(Kinematics::Finite));
    println!("at 0.1 mm: small {} N, finite {} N", s[10], f[10]);
    assert!((s[10] - f[10]).abs() > 0.01 * s[10]);
}

/// Finite strain with vertical contact is refused, naming the field and the fix; with
/// normal contact and friction it is accepted.
#[test]
fn finite_strain_needs_normal_contact() {
    let mesh = cylinder(1.0, 2, 1.0);
    let err = Model::new(mesh.clone(), Punch::Flat { radius: 3.0 })
        .unwrap()
        .with_kinematics(Kinematics::Finite)
        .unwrap_err();
    let text = err.to_string();
    assert!(matches!(
        err,
        ContactError::Input {
            field: "kinematics",
            ..
        }
    ));
    assert!(text.contains("contact: Normal"), "{text}");
    // normal contact with Coulomb friction takes finite strain (tests/finite_friction.rs)
    let friction = ContactKind::NormalFriction { friction: 0.2 };
    let model = Model::with_contact(mesh, Punch::Flat { radius: 3.0 }, friction)
        .unwrap()
        .with_kinematics(Kinematics::Finite)
        .unwrap();
    assert_eq!(model.kinematics, Kinematics::Finite);
}

/// An element squashed towards inversion stops the run (inverted, or its tangent no longer
/// positive definite first) with the element, the step and the depth, and the advice to
/// refine or reduce the depth; the converged part is kept, no NaN.
#[test]
fn an_inverted_element_is_reported() {
    // a 1 x 1 block of a single element squashed to 1% of its height
    let mesh = cylinder(1.0, 1, 1.0);
    let model = Model::with_contact(mesh, Punch::Flat { radius: 3.0 }, ContactKind::Normal)
        .unwrap()
        .with_kinematics(Kinematics::Finite)
        .unwrap();
    let opts = SolverOptions {
        max_cuts: 3,
        ..Default::default()
    };
    let err = DirectSolver::new(&model)
        .unwrap()
        .run(
            &indentify_laws::LawMaterial(&Elastic),
            &[1000.0, 0.3],
            &ramp(1.0, 1.2, 4),
            &opts,
        )
        .unwrap_err();
    let text = err.to_string();
    println!("{text}");
    match err {
        ContactError::StepFailed { partial, .. } => {
            assert!(partial.steps.iter().all(|s| s.force.is_finite()));
        }
        other => panic!("{other}"),
    }
    assert!(text.contains("element 0"), "{text}");
    assert!(text.contains("depth"), "{text}");
    assert!(text.contains("refine"), "{text}");
}

/// The finite-strain Gauss-point passes run on rayon over fixed chunks of elements and
/// assemble in element order: a load-hold-unload history (Norton-Hoff sY = 500, cone,
/// frictionless and with Coulomb friction mu = 0.2) gives bit for bit the same steps,
/// forces, reactions, displacements and stresses on 1, 2 and 4 threads.
#[test]
fn the_finite_forward_is_the_same_for_any_number_of_threads() {
    let sched = Schedule::from_segments(&trapezoid(0.1, 1.0, 1.0, 1.0, 6)).unwrap();
    let c = [1e5, 0.3, 1500.0, 5.0, 500.0];
    for contact in [
        ContactKind::Normal,
        ContactKind::NormalFriction { friction: 0.2 },
    ] {
        let model = Model::with_contact(
            cone_model(Kinematics::Small).mesh,
            Punch::Cone {
                half_angle_deg: 68.0,
            },
            contact,
        )
        .unwrap()
        .with_kinematics(Kinematics::Finite)
        .unwrap();
        let run = |threads: usize| -> Trajectory {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                DirectSolver::new(&model)
                    .unwrap()
                    .run(
                        &indentify_laws::LawMaterial(&NortonHoff),
                        &c,
                        &sched,
                        &SolverOptions::default(),
                    )
                    .unwrap()
            })
        };
        let bits = |t: &Trajectory| -> Vec<u64> {
            let mut b: Vec<u64> = Vec::new();
            for s in &t.steps {
                b.extend([s.t, s.force].map(f64::to_bits));
                b.extend(s.lambda.iter().map(|v| v.to_bits()));
            }
            for f in &t.fields {
                b.extend(f.u.iter().map(|v| v.to_bits()));
                b.extend(f.sigma.iter().flat_map(|v| v.0).map(f64::to_bits));
            }
            b
        };
        let one = run(1);
        assert!(one.steps.iter().any(|s| s.active.len() >= 3));
        let reference = bits(&one);
        for threads in [2, 4] {
            let other = run(threads);
            assert_eq!(one.steps.len(), other.steps.len(), "{threads} threads");
            assert!(
                bits(&other) == reference,
                "{contact:?}: {threads} threads differ"
            );
        }
    }
}

/// At the end of an elastic load-unload back to depth 0 the contact is released to
/// round-off (every force ~ 0), and the release must not depend on round-off: with the
/// penetration tolerance relative to the depth alone (zero at depth 0) a node released
/// with a gap of -1e-17 mm was re-activated, the set cycled and the step was cut in one
/// of two runs that differ only in round-off (here: with and without checkpoints, whose
/// segments start from a fresh factorization). With the tolerance floored at the first
/// element's width under the punch (`Model::gap_length`), both runs take the schedule's
/// 18 steps, uncut. (The mesh and history of `adjoint/tests/gradient_fd_finite.rs`, where
/// the cut broke the checkpointed gradient; without the floor this test fails: 19 steps
/// for `E = 17000, nu = 0.27`.)
#[test]
fn the_release_at_depth_zero_does_not_depend_on_round_off() {
    let mesh = small_cylinder();
    let sched = Schedule::from_segments(&trapezoid(0.1, 1.0, 1.0, 1.0, 6)).unwrap();
    let opts = SolverOptions {
        residual_tol: 1e-12,
        ..Default::default()
    };
    let ck_opts = SolverOptions {
        record_fields: false,
        checkpoint_every: 5,
        ..opts.clone()
    };
    for punch in [
        Punch::Cone {
            half_angle_deg: 68.0,
        },
        Punch::Sphere { radius: 1.0 },
    ] {
        let model = Model::with_contact(mesh.clone(), punch, ContactKind::Normal)
            .unwrap()
            .with_kinematics(Kinematics::Finite)
            .unwrap();
        // the first element's width under the punch: the graded mesh's first radial size
        let width = model.mesh.nodes[model.candidates[2]][0];
        assert!(width > 0.0 && width < 0.2, "{width}");
        assert_eq!(model.gap_length(), width);
        let mut solver = DirectSolver::new(&model).unwrap();
        for c in [[17000.0, 0.27], [20000.0, 0.3]] {
            let plain = solver
                .run(&indentify_laws::LawMaterial(&Elastic), &c, &sched, &opts)
                .unwrap();
            let ck = solver
                .run(&indentify_laws::LawMaterial(&Elastic), &c, &sched, &ck_opts)
                .unwrap();
            for t in [&plain, &ck] {
                let n: Vec<usize> = t.steps.iter().map(|s| s.active.len()).collect();
                assert_eq!(t.steps.len(), 18, "{c:?}: {n:?}");
                assert!(t.steps.iter().all(|s| s.on_schedule), "{c:?}: a cut step");
                assert!(*n.iter().max().unwrap() >= 3, "{n:?}");
            }
        }
    }
}
