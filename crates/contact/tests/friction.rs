//! Coulomb friction on the normal contact (`ContactKind::NormalFriction`): Newton's
//! quadratic rate with sticking and slipping nodes, the Coulomb conditions at every
//! converged step, the force against the friction coefficient (mu -> 0: frictionless,
//! mu large: full stick), and the configuration's spellings and bad values.

mod common;

use common::{model_2mm, ramp, testkit::coulomb as friction, testkit::cylinder};
use indentify_contact::{
    ContactError, ContactKind, DirectSolver, Model, Punch, Schedule, SolverOptions, Trajectory,
    trapezoid,
};
use indentify_laws::{Elastic, Law, NortonHoff};
use indentify_mesh::CylinderMesher;

/// A 2 x 2 mm cylinder, 12 x 12 Q8 graded 1.3 towards the axis and the top.
fn model(punch: Punch, kind: ContactKind) -> Model {
    model_2mm(12, punch, kind)
}

fn norton() -> (NortonHoff, Vec<f64>) {
    (NortonHoff, vec![1e5, 0.3, 1500.0, 5.0, 500.0])
}

/// The internal force `f_int` (all dofs) of recorded state `i`, recomputed from its
/// stresses.
fn traj_force(model: &Model, traj: &Trajectory, i: usize) -> Vec<f64> {
    let mut f = vec![0.0; model.disc.n_dofs()];
    model.disc.internal_force(&traj.fields[i].sigma, &mut f);
    f
}

/// The solver shall converge quadratically with Coulomb friction (mu = 0.2) on a sphere,
/// elastic and Norton-Hoff: in the last step of a ramp, once the contact set and the
/// stick/slip partition are settled, each residual above round-off is at most 10 times
/// the square of the previous one; the Coulomb conditions hold at every step.
#[test]
fn newton_converges_quadratically_with_friction() {
    let (nh, cn) = norton();
    for (law, c, mu) in [
        (&Elastic as &dyn Law, vec![20000.0, 0.3], 0.02),
        (&nh as &dyn Law, cn, 0.2),
    ] {
        let model = model(Punch::Sphere { radius: 0.5 }, friction(mu));
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
        let last = traj.steps.last().unwrap();
        println!(
            "mu = {mu}, stick (0) / slip (+-1) in the last step: {:?}",
            last.slip
        );
        assert!(last.active.len() >= 4);
        assert!(last.slip.iter().any(|&s| s != 0), "no slipping node");
        // consecutive passes with the same sets (contact and stick/slip), after the first
        // pass (which precedes any solve), down to round-off (1e-13)
        let checked = common::quadratic_pairs(r);
        assert!(checked >= 1, "{r:?}");
        let (st, sl) = common::check_coulomb(&model, &traj, mu, |i| traj_force(&model, &traj, i));
        println!("{}: {st} sticking and {sl} slipping node-steps", law.name());
        assert!(st > 0, "no sticking node");
    }
}

/// Peak forces of a load-hold-unload history for several coefficients.
fn peaks(punch: &Punch, law: &dyn Law, c: &[f64], mus: &[f64]) -> Vec<f64> {
    let sched = Schedule::from_segments(&trapezoid(0.03, 1.0, 1.0, 1.0, 8)).unwrap();
    mus.iter()
        .map(|&mu| {
            let kind = if mu < 0.0 {
                ContactKind::Normal
            } else {
                friction(mu)
            };
            let m = model(punch.clone(), kind);
            let mut solver = DirectSolver::new(&m).unwrap();
            let traj = solver
                .run(
                    &indentify_laws::LawMaterial(law),
                    c,
                    &sched,
                    &SolverOptions::default(),
                )
                .unwrap();
            println!(
                "mu {mu}: {} steps (sub-steps included), {} iterations, {} set changes",
                traj.steps.len(),
                traj.total_iterations(),
                traj.steps.iter().map(|s| s.active_set_changes).sum::<u32>()
            );
            if mu > 0.0 {
                common::check_coulomb(&m, &traj, mu, |i| traj_force(&m, &traj, i));
            }
            traj.steps.iter().map(|s| s.force).fold(0.0, f64::max)
        })
        .collect()
}

/// The force shall grow with the friction coefficient and saturate at full stick; a
/// vanishing coefficient shall give the frictionless force (elastic, mu = 1e-9: to 1e-8;
/// Norton-Hoff to 2e-3, where a cut step (stick/slip cycling) changes the time steps of
/// the rate-dependent law), and `Normal(friction: 0)` is `Normal`. Over load-hold-unload
/// histories with contact growing and lost, cone and sphere, elastic and Norton-Hoff.
#[test]
fn force_grows_with_friction_and_saturates() {
    assert_eq!(friction(0.0), ContactKind::Normal);
    let (nh, cn) = norton();
    let mus = [-1.0, 1e-9, 0.1, 0.2, 0.5, 5.0, 50.0];
    for punch in [
        Punch::Cone {
            half_angle_deg: 68.0,
        },
        Punch::Sphere { radius: 0.5 },
    ] {
        for (law, c) in [
            (&Elastic as &dyn Law, vec![20000.0, 0.3]),
            (&nh as &dyn Law, cn.clone()),
        ] {
            let f = peaks(&punch, law, &c, &mus);
            let rel: Vec<f64> = f.iter().map(|x| x / f[0] - 1.0).collect();
            println!(
                "{} {}: peak {:.4} N frictionless; relative change at mu = {mus:?}: {rel:?}",
                punch.describe(),
                law.name(),
                f[0]
            );
            let tol0 = if law.name() == "elastic" { 1e-8 } else { 2e-3 };
            assert!(rel[1].abs() < tol0, "mu -> 0: {rel:?}");
            // increasing up to 1e-4 (the elastic sphere's full-stick force, path dependent,
            // sits 6e-5 under its mu = 0.5 force)
            for w in f[1..].windows(2) {
                assert!(w[1] >= w[0] * (1.0 - 1e-4), "not increasing: {f:?}");
            }
            assert!(rel[2] > 0.0, "mu = 0.1 adds nothing: {rel:?}");
            // full stick: mu = 5 and mu = 50 within 0.1%
            assert!((f[6] / f[5] - 1.0).abs() < 1e-3, "{f:?}");
        }
    }
}

/// Bad friction coefficients shall be refused with the field, the value and what is
/// allowed; the spellings `Vertical`, `Normal` and `Normal(friction: mu)` parse.
#[test]
fn bad_friction_is_refused() {
    for mu in [-0.1, f64::NAN, f64::INFINITY] {
        let e = ContactKind::normal_with_friction(mu).unwrap_err();
        let msg = e.to_string();
        assert!(
            msg.contains("contact.friction") && msg.contains(">= 0"),
            "{msg}"
        );
        let mesh = cylinder(1.0, 2, 1.0);
        let e = Model::with_contact(
            mesh,
            Punch::Sphere { radius: 0.5 },
            ContactKind::NormalFriction { friction: mu },
        )
        .unwrap_err();
        assert!(
            matches!(
                e,
                ContactError::Input {
                    field: "contact.friction",
                    ..
                }
            ),
            "{e}"
        );
    }
    assert_eq!(
        ContactKind::parse("Vertical").unwrap(),
        ContactKind::Vertical
    );
    assert_eq!(ContactKind::parse("Normal").unwrap(), ContactKind::Normal);
    assert_eq!(
        ContactKind::parse("Normal(friction: 0.25)").unwrap(),
        ContactKind::NormalFriction { friction: 0.25 }
    );
    let e = ContactKind::parse("Normal(friction: -1)").unwrap_err();
    assert!(e.to_string().contains("-1"), "{e}");
    let e = ContactKind::parse("Sideways").unwrap_err();
    assert!(e.to_string().contains("Normal(friction: mu)"), "{e}");
}

/// Study (ignored; prints, asserts nothing timed): the cost of R2 (docs/theory.md §11, reference
/// mesh, cone 68 deg, 30 steps per segment) with friction mu = 0.2 against frictionless
/// normal contact, run back to back, alternating, three times each.
/// `cargo test -p indentify-contact --release --test friction -- --ignored --nocapture`.
#[test]
#[ignore]
fn r2_cost_with_friction() {
    let schedule = Schedule::from_segments(&trapezoid(0.1, 1.0, 1.0, 1.0, 30)).unwrap();
    let (law, c) = norton();
    let cone = Punch::Cone {
        half_angle_deg: 68.0,
    };
    let models: Vec<(&str, Model)> = [("normal", ContactKind::Normal), ("mu = 0.2", friction(0.2))]
        .into_iter()
        .map(|(n, k)| {
            let mesh = CylinderMesher::REFERENCE.build().unwrap();
            (n, Model::with_contact(mesh, cone.clone(), k).unwrap())
        })
        .collect();
    let mut best = [f64::INFINITY; 2];
    for _ in 0..3 {
        for (j, (name, m)) in models.iter().enumerate() {
            let mut solver = DirectSolver::new(m).unwrap();
            let t0 = std::time::Instant::now();
            let t = solver
                .run(
                    &indentify_laws::LawMaterial(&law),
                    &c,
                    &schedule,
                    &SolverOptions::default(),
                )
                .unwrap();
            let s = t0.elapsed().as_secs_f64();
            best[j] = best[j].min(s);
            println!(
                "{name}: {:.3} s, {} steps, {} iterations, peak {:.2} N, {}",
                s,
                t.steps.len(),
                t.total_iterations(),
                t.steps.iter().map(|s| s.force).fold(0.0, f64::max),
                t.timing
            );
        }
    }
    println!("best of 3: friction / normal = {:.2}", best[1] / best[0]);
}
