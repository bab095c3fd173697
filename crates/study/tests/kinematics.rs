//! The `kinematics` field: `--set kinematics=Finite` runs the finite-strain forward problem
//! with normal contact (frictionless or with Coulomb friction), is refused with vertical
//! contact, and `gradient`, `gradient-check` and `identify` run with its exact adjoint
//! (checked against central differences).

use indentify_study::ConfigSource;
use indentify_study::simulate::{self, SimulateOptions};

fn r1() -> ConfigSource {
    ConfigSource::Text {
        text: indentify_study::templates::template(indentify_study::config::Reference::R1Maxwell),
        name: "r1".into(),
    }
}

fn coarse(extra: &[&str]) -> Vec<String> {
    let mut v: Vec<String> = ["specimen.nr=6", "specimen.nz=6"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    v.extend(extra.iter().map(|s| s.to_string()));
    v
}

#[test]
fn finite_strain_runs_with_normal_contact_and_moves_the_force() {
    let peak = |sets: &[&str]| {
        let mut opts = SimulateOptions::new(r1());
        opts.sets = coarse(sets);
        let o = simulate::run(&opts).unwrap();
        assert!(o.failure.is_none());
        o.trajectory.forces().iter().copied().fold(0.0, f64::max)
    };
    let small = peak(&["contact=Normal"]);
    let finite = peak(&["contact=Normal", "kinematics=Finite"]);
    println!("R1 (6 x 6): small {small} N, finite {finite} N");
    assert!(finite.is_finite() && finite > 0.0);
    assert!(finite != small);
    assert!((finite / small - 1.0).abs() < 0.2, "{small} vs {finite}");
}

#[test]
fn finite_strain_with_vertical_contact_is_refused() {
    let mut opts = SimulateOptions::new(r1());
    opts.sets = coarse(&["kinematics=Finite"]);
    let err = format!("{:?}", simulate::run(&opts).unwrap_err());
    assert!(err.contains("kinematics"), "{err}");
    assert!(err.contains("contact: Normal"), "{err}");
}

/// `gradient-check` under finite strain (R1 Maxwell, 6 x 6, normal contact): the adjoint
/// against central differences of the whole-history cost (1e-6) and against `J^T rho`
/// (1e-8); `identify` runs on it too (three iterations).
#[test]
fn gradients_under_finite_strain_match_finite_differences() {
    let sets = coarse(&["contact=Normal", "kinematics=Finite"]);
    let mut c = indentify_study::check::CheckOptions::new(r1());
    c.sets = sets.clone();
    let report = indentify_study::check::run(&c).unwrap();
    for p in &report.checks {
        println!(
            "R1 finite {}: adjoint {:.10e} fd {:.10e} | rel fd {:.1e} sens {:.1e}",
            p.name, p.adjoint, p.fd, p.rel_diff_fd, p.rel_diff_sensitivity
        );
        assert!(p.rel_diff_fd < 1e-6, "{}: {p:?}", p.name);
        assert!(p.rel_diff_sensitivity < 1e-8, "{}: {p:?}", p.name);
    }
    assert_eq!(report.checks.len(), 3);
    assert!(report.passed, "{:?}", report.failures);
    // identify from the synthesized data: the cost goes down from its start
    let mut i = indentify_study::identify::IdentifyOptions::new(r1());
    i.sets = sets;
    i.sets.push("identify.stop.max_iterations=3".into());
    i.figures = false;
    i.refine = false;
    let out = indentify_study::identify::run(&i, &mut ()).unwrap();
    println!(
        "R1 finite identify: J {} -> {} in {} iterations",
        out.result.initial_cost, out.result.cost, out.result.iterations
    );
    assert!(
        out.result.cost < 0.5 * out.result.initial_cost,
        "{:?}",
        out.result
    );
}

/// `gradient-check` under finite strain with Coulomb friction (R1 Maxwell, 6 x 6,
/// `Normal(friction: 0.2)`): the adjoint against central differences of the
/// whole-history cost (1e-6) with every step's contact set and stick/slip statuses held
/// by the +-h runs, and against `J^T rho` (1e-8); the run's nodes stick (counted).
#[test]
fn gradients_under_finite_strain_with_friction_match_finite_differences() {
    let sets = coarse(&["contact=Normal(friction: 0.2)", "kinematics=Finite"]);
    let mut opts = SimulateOptions::new(r1());
    opts.sets = sets.clone();
    let o = simulate::run(&opts).unwrap();
    assert!(o.failure.is_none());
    let statuses: Vec<i8> = o
        .trajectory
        .steps
        .iter()
        .flat_map(|s| s.slip.clone())
        .collect();
    let (stick, slip) = (
        statuses.iter().filter(|&&s| s == 0).count(),
        statuses.iter().filter(|&&s| s != 0).count(),
    );
    println!("R1 finite, mu = 0.2: {stick} sticking, {slip} slipping node-steps");
    // on this coarse R1 every active node sticks (also at mu = 0.05): finite strain's
    // tangential forces stay inside the cone; slipping nodes are covered by
    // adjoint/tests/gradient_fd_finite_friction.rs
    assert!(stick > 0, "stick {stick}, slip {slip}");
    let mut c = indentify_study::check::CheckOptions::new(r1());
    c.sets = sets;
    let report = indentify_study::check::run(&c).unwrap();
    for p in &report.checks {
        println!(
            "R1 finite mu = 0.2 {}: adjoint {:.10e} fd {:.10e} | rel fd {:.1e} sens {:.1e} | \
             statuses held {:?}",
            p.name, p.adjoint, p.fd, p.rel_diff_fd, p.rel_diff_sensitivity, p.statuses_held
        );
        assert_eq!(p.statuses_held, Some(true), "{}", p.name);
        assert!(p.rel_diff_fd < 1e-6, "{}: {p:?}", p.name);
        assert!(p.rel_diff_sensitivity < 1e-8, "{}: {p:?}", p.name);
    }
    assert_eq!(report.checks.len(), 3);
    assert!(report.passed, "{:?}", report.failures);
}

/// `gradient-check` under finite strain on a measured history: the Berkovich record of
/// `examples/real/anon-nh.ron` (Norton-Hoff with yield, automatic specimen, Berkovich
/// punch) resampled to 20 points drives the depth; the forces are synthesized and the point
/// perturbed, as `indentify gradient-check` does without `--data`: adjoint vs central
/// differences (1e-6) and vs `J^T rho` (1e-8) for E, nu, K, m, sY.
#[test]
fn finite_strain_gradients_on_a_measured_history_match_finite_differences() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/real/anon-nh.ron");
    let mut c = indentify_study::check::CheckOptions::new(ConfigSource::Path(path));
    c.sets = [
        "data.preprocessing.resample.n=20",
        "contact=Normal",
        "kinematics=Finite",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let report = indentify_study::check::run(&c).unwrap();
    for p in &report.checks {
        println!(
            "anon-nh finite {}: adjoint {:.10e} fd {:.10e} | rel fd {:.1e} sens {:.1e}",
            p.name, p.adjoint, p.fd, p.rel_diff_fd, p.rel_diff_sensitivity
        );
        assert!(p.rel_diff_fd < 1e-6, "{}: {p:?}", p.name);
        assert!(p.rel_diff_sensitivity < 1e-8, "{}: {p:?}", p.name);
    }
    assert_eq!(report.checks.len(), 5);
    assert!(report.passed, "{:?}", report.failures);
}

/// The finite/small force ratios on R1 and R2 (sY = 0 and 500) at the reference mesh with
/// normal contact, and the forward run times back to back (a study, not a check: run with
/// `cargo test -p indentify-study --test kinematics -- --ignored --nocapture`).
#[test]
#[ignore]
fn finite_over_small_ratios_on_the_reference_problems() {
    use indentify_study::config::Reference;
    for (reference, extra) in [
        (Reference::R0Elastic, vec![]),
        (Reference::R1Maxwell, vec![]),
        (Reference::R2NortonHoff, vec!["law.sY=0"]),
        (Reference::R2NortonHoff, vec![]),
    ] {
        let source = || ConfigSource::Text {
            text: indentify_study::templates::template(reference),
            name: "ref".into(),
        };
        let run = |kin: &str| {
            let mut opts = SimulateOptions::new(source());
            opts.sets = extra.iter().map(|s| s.to_string()).collect();
            opts.sets.push("contact=Normal".into());
            opts.sets.push(format!("kinematics={kin}"));
            let t0 = std::time::Instant::now();
            let o = simulate::run(&opts).unwrap();
            let secs = t0.elapsed().as_secs_f64();
            assert!(o.failure.is_none());
            let traj = o.trajectory;
            let pts: Vec<(f64, f64)> = traj.schedule_steps().map(|s| (s.t, s.force)).collect();
            (pts, secs)
        };
        let (small, ts) = run("Small");
        let (finite, tf) = run("Finite");
        let at = |pts: &[(f64, f64)], t: f64| {
            pts.iter()
                .min_by(|a, b| (a.0 - t).abs().total_cmp(&(b.0 - t).abs()))
                .map(|p| p.1)
                .unwrap()
        };
        let ratios: Vec<String> = [0.2, 0.5, 1.0, 1.5, 2.0]
            .iter()
            .map(|&t| {
                format!(
                    "t={t}: {:+.1}%",
                    100.0 * (at(&finite, t) / at(&small, t) - 1.0)
                )
            })
            .collect();
        println!(
            "{reference:?} {extra:?}: {}; time small {ts:.2} s, finite {tf:.2} s (x{:.2})",
            ratios.join(", "),
            tf / ts
        );
    }
}
