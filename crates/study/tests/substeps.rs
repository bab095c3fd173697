//! `data.substeps`: the forward solve of a measured record takes equal sub-steps between
//! the record's points. Measured data default to 2 (docs/discretization.md); the fitted
//! points stay the record's; the gradient through the sub-steps is exact on a real record
//! (`gradient-check` against central differences); bad values are refused with the file,
//! line and the allowed range.

use indentify_study::ConfigSource;
use indentify_study::config::{DEFAULT_SUBSTEPS, MAX_DATA_SUBSTEPS, load, load_str};
use indentify_study::simulate::{self, SimulateOptions};
use std::path::{Path, PathBuf};

fn example(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples/real")
        .join(name)
}

/// Measured data take 2 sub-steps between points unless stated; a history has none.
#[test]
fn measured_records_default_to_two_substeps_and_histories_to_none() {
    assert_eq!(DEFAULT_SUBSTEPS, 2);
    let cfg = load(&example("anon-nh.ron"), &[]).unwrap();
    assert_eq!(cfg.data.as_ref().unwrap().substeps, 2);
    let p = cfg.prepare("anon-nh").unwrap();
    assert_eq!(p.schedule.n_steps(), 59);
    assert_eq!(p.schedule.n_solver_steps(), 118);
    assert_eq!(
        p.schedule.substeps_summary().as_deref(),
        Some("2 sub-steps per step")
    );
    let one = load(&example("anon-nh.ron"), &["data.substeps=1".into()]).unwrap();
    let p1 = one.prepare("anon-nh").unwrap();
    assert_eq!(
        (p1.schedule.n_solver_steps(), p1.schedule.substeps_summary()),
        (59, None)
    );
    // the record's points are the schedule's either way
    assert_eq!(p1.schedule.t, p.schedule.t);
    let r1 = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/r1-maxwell.ron");
    let h = load(&r1, &[]).unwrap().prepare("r1").unwrap();
    assert!(h.schedule.substeps.is_empty());
}

/// A simulation with sub-steps reports the force at the record's points only; the solver
/// took every sub-step (and the forces differ from those without sub-steps).
#[test]
fn the_curve_stays_on_the_record_points() {
    let run = |k: usize| {
        let mut o = SimulateOptions::new(ConfigSource::Path(example("anon-maxwell.ron")));
        o.sets = vec![
            "data.preprocessing.resample.n=12".into(),
            format!("data.substeps={k}"),
        ];
        let out = simulate::run(&o).unwrap();
        assert!(out.failure.is_none());
        out
    };
    let (a, b) = (run(1), run(3));
    assert_eq!(a.rows.len(), 12);
    assert_eq!(b.rows.len(), 12);
    assert!(
        a.rows
            .iter()
            .zip(&b.rows)
            .all(|(x, y)| x.t == y.t && x.h == y.h)
    );
    assert!(b.trajectory.steps.len() >= 3 * 11);
    assert_eq!(b.trajectory.schedule_steps().count(), 11);
    assert_eq!(b.substeps.as_deref(), Some("3 sub-steps per step"));
    assert_eq!(
        b.cut_substeps,
        b.trajectory.steps.len() - 33,
        "the sub-steps are not counted as cuts"
    );
    let moved = a
        .rows
        .iter()
        .zip(&b.rows)
        .map(|(x, y)| (x.f - y.f).abs())
        .fold(0.0, f64::max);
    assert!(moved > 1e-7, "sub-steps changed nothing ({moved} N)");
}

/// `gradient-check` on the Berkovich record (Norton-Hoff, finite strain, normal contact)
/// with 3 sub-steps between its 12 points: the adjoint through the sub-steps against
/// central differences of the forward solver's own cost (1e-6) and `J^T rho` (1e-8).
#[test]
fn the_gradient_through_substeps_on_a_real_record_matches_finite_differences() {
    let mut c =
        indentify_study::check::CheckOptions::new(ConfigSource::Path(example("anon-nh.ron")));
    c.sets = vec![
        "data.preprocessing.resample.n=12".into(),
        "data.substeps=3".into(),
    ];
    let report = indentify_study::check::run(&c).unwrap();
    for p in &report.checks {
        println!(
            "anon-nh, 3 sub-steps, {}: adjoint {:.10e} fd {:.10e} | rel fd {:.1e} sens {:.1e}",
            p.name, p.adjoint, p.fd, p.rel_diff_fd, p.rel_diff_sensitivity
        );
        assert!(p.rel_diff_fd < 1e-6, "{}: {p:?}", p.name);
        assert!(p.rel_diff_sensitivity < 1e-8, "{}: {p:?}", p.name);
    }
    assert_eq!(report.checks.len(), 5);
    assert!(report.passed, "{:?}", report.failures);
}

/// Zero, too many, negative or fractional sub-steps: refused while parsing, with the
/// file, line and column, the value and the allowed range; through `--set` too.
#[test]
fn bad_substep_counts_are_refused_with_the_line_and_the_range() {
    let text = std::fs::read_to_string(example("anon-nh.ron")).unwrap();
    let with = |v: &str| {
        text.replace(
            "preprocessing: (resample: (n: 60)),",
            &format!("preprocessing: (resample: (n: 60)),\n        substeps: {v},"),
        )
    };
    assert_ne!(with("2"), text, "the example's data section moved");
    let line = 1 + with("2")
        .lines()
        .position(|l| l.contains("substeps:"))
        .unwrap();
    for v in ["0", "101", "1000000"] {
        let e = format!("{:#}", load_str(&with(v), "x.ron", &[]).unwrap_err());
        assert!(
            e.contains(&format!("x.ron:{line}:"))
                && e.contains(&format!("data.substeps = {v} is not allowed"))
                && e.contains(&format!("[1, {MAX_DATA_SUBSTEPS}]")),
            "{v}: {e}"
        );
    }
    for v in ["2.5", "-1", "two"] {
        let e = format!("{:#}", load_str(&with(v), "x.ron", &[]).unwrap_err());
        assert!(
            e.contains(&format!("x.ron:{line}:")) && e.contains("data.substeps"),
            "{v}: {e}"
        );
    }
    assert_eq!(
        load_str(&with("5"), "x.ron", &[])
            .unwrap()
            .data
            .unwrap()
            .substeps,
        5
    );
    let e = format!(
        "{:#}",
        load_str(&text, "x.ron", &["data.substeps=0".into()]).unwrap_err()
    );
    assert!(e.contains("data.substeps = 0 is not allowed"), "{e}");
    let e = format!(
        "{:#}",
        load_str(&text, "x.ron", &["data.substeps=1.5".into()]).unwrap_err()
    );
    assert!(e.contains("data.substeps") && e.contains("integer"), "{e}");
}
