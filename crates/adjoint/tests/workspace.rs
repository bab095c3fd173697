//! A reused [`Adjoint`] workspace gives the same bits as a new one: the gradient and the
//! forward sensitivities at a point do not depend on what the workspace computed before
//! (the other of the two at the same point, or either at another point). The joint
//! evaluator computes a test's adjoint ahead of a request on an idle core, so which of
//! the two runs first at a point depends on timing; its results must not.
//!
//! Reference: the same computation on a new workspace. Cases: Maxwell (a reusable
//! tangent: the capacitance factorization whose columns and Schur factor would otherwise
//! carry over) and Norton-Hoff with yield, vertical, normal and Coulomb contact, small and
//! finite strain, on the 4 x 4 mm cylinder (8 x 8 Q8) under a cone, load-hold-unload.

mod common;

use indentify_adjoint::Adjoint;
use indentify_contact::{
    ContactKind, DirectSolver, Model, Schedule, SolverOptions, Trajectory, trapezoid,
};
use indentify_laws::{Law, Maxwell, NortonHoff};
use indentify_testkit::cone68 as cone;

fn run(model: &Model, law: &dyn Law, c: &[f64]) -> Trajectory {
    let schedule = Schedule::from_segments(&trapezoid(0.1, 0.5, 0.5, 0.5, 6)).unwrap();
    DirectSolver::new(model)
        .unwrap()
        .run(
            &indentify_laws::LawMaterial(law),
            c,
            &schedule,
            &SolverOptions::default(),
        )
        .unwrap()
}

/// The bits of the gradient (for `rho = F`) and of every sensitivity.
fn gradient_bits(a: &mut Adjoint, law: &dyn Law, c: &[f64], t: &Trajectory) -> Vec<u64> {
    let rho: Vec<f64> = t.steps.iter().map(|s| s.force).collect();
    let g = a
        .gradient(&indentify_laws::LawMaterial(law), c, t, &rho)
        .unwrap();
    g.dj_dc.iter().map(|v| v.to_bits()).collect()
}

fn sensitivity_bits(a: &mut Adjoint, law: &dyn Law, c: &[f64], t: &Trajectory) -> Vec<u64> {
    let s = a
        .sensitivities(&indentify_laws::LawMaterial(law), c, t)
        .unwrap();
    s.df_dc.iter().flatten().map(|v| v.to_bits()).collect()
}

/// Gradient and sensitivities, in both orders and after a computation at another point,
/// equal a new workspace's, bit for bit.
#[test]
fn a_reused_workspace_gives_a_new_ones_bits() {
    let maxwell = [20000.0, 0.3, 30000.0];
    let norton = [1e5, 0.3, 1500.0, 5.0, 500.0];
    let models = [
        (
            "vertical",
            common::small_model(cone(), ContactKind::Vertical),
        ),
        ("normal", common::small_model(cone(), ContactKind::Normal)),
        (
            "friction 0.2",
            common::small_model(cone(), ContactKind::normal_with_friction(0.2).unwrap()),
        ),
        ("finite", common::finite_model(cone())),
    ];
    for (name, model) in &models {
        for (law, c) in [
            (&Maxwell as &dyn Law, &maxwell[..]),
            (&NortonHoff, &norton[..]),
        ] {
            let other: Vec<f64> = c.iter().map(|v| v * 1.1).collect();
            let t = run(model, law, c);
            let t_other = run(model, law, &other);
            let g_new = gradient_bits(&mut Adjoint::new(model).unwrap(), law, c, &t);
            let s_new = sensitivity_bits(&mut Adjoint::new(model).unwrap(), law, c, &t);
            let case = format!("{name}, {}", law.name());
            // sensitivities after the gradient at the same point, and the reverse
            let mut a = Adjoint::new(model).unwrap();
            assert_eq!(gradient_bits(&mut a, law, c, &t), g_new, "{case}");
            assert_eq!(
                sensitivity_bits(&mut a, law, c, &t),
                s_new,
                "{case}: sensitivities after the gradient"
            );
            assert_eq!(
                gradient_bits(&mut a, law, c, &t),
                g_new,
                "{case}: gradient after the sensitivities"
            );
            // the sequence of a line search with the adjoint computed ahead: the gradient
            // at the previous point, the gradient here, then the sensitivities here
            let mut d = Adjoint::new(model).unwrap();
            gradient_bits(&mut d, law, &other, &t_other);
            assert_eq!(gradient_bits(&mut d, law, c, &t), g_new, "{case}");
            assert_eq!(
                sensitivity_bits(&mut d, law, c, &t),
                s_new,
                "{case}: sensitivities after two gradients"
            );
            // an optimizer's sequence: the sensitivities at one point, the gradient at the
            // next, then the gradient (computed ahead) and the sensitivities at a third
            let third: Vec<f64> = c.iter().map(|v| v * 0.95).collect();
            let t_third = run(model, law, &third);
            let s_third =
                sensitivity_bits(&mut Adjoint::new(model).unwrap(), law, &third, &t_third);
            let mut e = Adjoint::new(model).unwrap();
            sensitivity_bits(&mut e, law, c, &t);
            gradient_bits(&mut e, law, &other, &t_other);
            gradient_bits(&mut e, law, &third, &t_third);
            assert_eq!(
                sensitivity_bits(&mut e, law, &third, &t_third),
                s_third,
                "{case}: an optimizer's sequence"
            );
            // after either at another point
            let mut b = Adjoint::new(model).unwrap();
            sensitivity_bits(&mut b, law, &other, &t_other);
            assert_eq!(
                gradient_bits(&mut b, law, c, &t),
                g_new,
                "{case}: gradient after another point"
            );
            gradient_bits(&mut b, law, &other, &t_other);
            assert_eq!(
                sensitivity_bits(&mut b, law, c, &t),
                s_new,
                "{case}: sensitivities after another point"
            );
        }
    }
}

/// The forward sensitivities run their parameters in parallel on a pool with threads:
/// the same bits on 1 and 3 threads (each parameter's solve has its own work space and
/// the same arithmetic), Coulomb friction included (its slipping rows' solve shares the
/// factorized system, and each parameter keeps its own previous-step variation for the
/// sticking ties). With `pinned.rs` (1 thread) this pins the parallel bits too.
#[test]
fn sensitivities_do_not_depend_on_the_thread_count() {
    let norton = [1e5, 0.3, 1500.0, 5.0, 500.0];
    let maxwell = [20000.0, 0.3, 30000.0];
    let models = [
        (
            "vertical",
            common::small_model(cone(), ContactKind::Vertical),
        ),
        ("normal", common::small_model(cone(), ContactKind::Normal)),
        ("finite", common::finite_model(cone())),
        (
            "friction 0.2",
            common::small_model(cone(), ContactKind::normal_with_friction(0.2).unwrap()),
        ),
        (
            "finite, friction 0.2",
            common::finite_model_with_friction(cone(), 0.2),
        ),
    ];
    for (name, model) in &models {
        for (law, c) in [
            (&Maxwell as &dyn Law, &maxwell[..]),
            (&NortonHoff, &norton[..]),
        ] {
            let t = run(model, law, c);
            if name.contains("friction") {
                let slipping = t.steps.iter().flat_map(|s| &s.slip).any(|&s| s != 0);
                assert!(slipping, "{name}: the run has slipping node-steps");
            }
            let on = |threads: usize| {
                rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap()
                    .install(|| sensitivity_bits(&mut Adjoint::new(model).unwrap(), law, c, &t))
            };
            let one = on(1);
            assert!(one.iter().any(|&b| f64::from_bits(b) != 0.0), "{name}");
            assert_eq!(on(3), one, "{name}, {}", law.name());
        }
    }
}
