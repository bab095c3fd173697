//! The discretization error of a fit (`identify::run` with `refine`): the force change on
//! the 2x refined mesh with halved steps, and the parameter shift it implies, checked
//! against a second identification made with the refined discretization.

mod common;

use common::{coarse as coarse_opts, examples};
use std::path::Path;

use indentify_contact::DirectSolver;
use indentify_study::identify::{self, IdentifyOptions};
use indentify_study::solve::forward;
use indentify_study::{ConfigSource, discretization};

/// An `n x n` mesh graded `g`, `steps` per segment.
fn sets(n: usize, g: f64, steps: usize) -> Vec<String> {
    let mut s = vec![
        format!("specimen.nr={n}"),
        format!("specimen.nz={n}"),
        format!("specimen.grading_r={g}"),
        format!("specimen.grading_z={g}"),
    ];
    s.extend((0..3).map(|i| format!("history.segments.{i}.steps={steps}")));
    s
}

fn result_json(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("result.json")).unwrap()).unwrap()
}

#[test]
fn a_coarse_maxwell_fit_reports_a_force_change_and_finite_shifts() {
    let tmp = tempfile::tempdir().unwrap();
    let mut o = coarse_opts();
    o.out = Some(tmp.path().to_path_buf());
    let outcome = identify::run(&o, &mut ()).unwrap();
    assert!(outcome.converged());
    let d = outcome
        .discretization
        .as_ref()
        .expect("a discretization result");
    assert_eq!(d.elements, (36, 144));
    assert_eq!(d.n_steps, (12, 24));
    assert_eq!(d.delta_f.len(), 13);
    assert_eq!(d.delta_f[0], 0.0);
    assert!(d.rms_rel > 1e-3, "force change {}", d.rms_rel);
    // E and eta free (shifted), nu held (no shift)
    assert!(d.shift[0].is_some_and(f64::is_finite), "{:?}", d.shift);
    assert_eq!(d.shift[1], None);
    assert!(d.shift[2].is_some_and(f64::is_finite), "{:?}", d.shift);
    assert!(d.undetermined.is_empty());
    // the data are this coarse model's own: the fit is exact, its deviations round-off,
    // and the discretization moves both parameters by more
    assert!(
        outcome
            .warnings
            .iter()
            .any(|w| w.contains("discretization moves E by") && w.contains("refine the mesh")),
        "{:?}",
        outcome.warnings
    );
    let json = result_json(tmp.path());
    let disc = &json["discretization"];
    assert!(disc["rms_rel"].as_f64().unwrap() > 1e-3, "{disc}");
    assert!(disc["shift"]["E"].as_f64().unwrap().is_finite(), "{disc}");
    assert!(disc["shift"]["eta"].as_f64().unwrap().is_finite(), "{disc}");
    assert!(disc["shift"].get("nu").is_none(), "{disc}");
    assert!(disc["mesh"].as_str().unwrap().contains("12 x 12"), "{disc}");
    assert!(
        json["warnings"]
            .as_array()
            .unwrap()
            .iter()
            .any(|w| w.as_str().unwrap().contains("discretization moves")),
        "{json}"
    );
    // and the report shows it
    let md = std::fs::read_to_string(tmp.path().join("report.md")).unwrap();
    assert!(md.contains("## Discretization error"), "{md}");
    assert!(md.contains("discretization moves E by"), "{md}");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(tmp.path().join("report.json")).unwrap())
            .unwrap();
    assert!(report["discretization"]["rms_rel"].as_f64().is_some());
    indentify_report::Report::from_json(&report.to_string()).unwrap();
}

/// The shift agrees with reality: data simulated on the refined discretization at
/// `(E, eta) = (20000, 30000)` (2n x 2n elements, gradings square-rooted, 2 steps per
/// segment); the fit on n x n (`steps`) misses them by its discretization error;
/// `c_fit + delta_c` lands within `tol` of that miss from what the refined discretization
/// identifies from the same data (a wrong sign or scale would land farther).
fn check_shift_against_refined_identification(n: usize, steps: usize, tol: f64) {
    let g = 1.3_f64.sqrt();
    let tmp = tempfile::tempdir().unwrap();
    // the data: the refined model's curve at the truth
    let cfg = ConfigSource::Default
        .load(&sets(2 * n, g, 2 * steps))
        .unwrap();
    let prepared = identify::prepare(&cfg, "refined").unwrap();
    let (law, truth) = cfg.law.build().unwrap();
    let mut solver = DirectSolver::new(&prepared.model).unwrap();
    let traj = forward(
        &mut solver,
        &*law,
        &truth,
        &prepared.schedule,
        &cfg.solver.options(false),
        "refined",
    )
    .unwrap();
    let mut csv = String::from("t,F\n");
    for (t, f) in prepared.schedule.t.iter().zip(traj.forces()) {
        csv.push_str(&format!("{t:e},{f:e}\n"));
    }
    let data = tmp.path().join("refined.csv");
    std::fs::write(&data, csv).unwrap();

    let mut coarse = IdentifyOptions::new(ConfigSource::Default);
    coarse.sets = sets(n, 1.3, steps);
    coarse.data = Some(data.clone());
    let fit = identify::run(&coarse, &mut ()).unwrap();
    assert!(fit.converged());
    let d = fit.discretization.as_ref().unwrap();

    let mut fine = IdentifyOptions::new(ConfigSource::Default);
    fine.sets = sets(2 * n, g, 2 * steps);
    fine.data = Some(data);
    fine.refine = false;
    let reference = identify::run(&fine, &mut ()).unwrap();
    assert!(reference.converged());

    for (k, name) in [(0, "E"), (2, "eta")] {
        let c_fit = fit.result.c[k];
        let c_ref = reference.result.c[k];
        let predicted = c_fit + d.shift[k].unwrap();
        let miss_before = (c_fit - c_ref).abs();
        let miss_after = (predicted - c_ref).abs();
        assert!(
            miss_before > 1e-3 * c_ref,
            "{name}: the coarse fit {c_fit} is already the refined one {c_ref}"
        );
        eprintln!(
            "{n} x {n}, {steps} steps: {name}: c_fit {c_fit}, shift {:?}, refined {c_ref}: \
             miss {miss_before} -> {miss_after}",
            d.shift[k]
        );
        assert!(
            miss_after < tol * miss_before,
            "{name}: c_fit {c_fit}, shift {:?} -> {predicted}, refined identification {c_ref}",
            d.shift[k]
        );
    }
}

/// 10 x 10 elements, 4 steps per segment: E off by a few percent, the shift takes most of
/// it back.
#[test]
fn the_shift_predicts_the_refined_identification() {
    check_shift_against_refined_identification(10, 4, 0.15);
}

/// 6 x 6 elements: one element across the contact, E off by half; the linear estimate
/// still takes half of it back, in the right direction.
#[test]
fn on_a_very_coarse_mesh_the_shift_still_points_to_the_refined_identification() {
    check_shift_against_refined_identification(6, 4, 0.6);
}

#[test]
fn refine_false_gives_none() {
    let tmp = tempfile::tempdir().unwrap();
    let mut o = coarse_opts();
    o.refine = false;
    o.figures = false;
    o.out = Some(tmp.path().to_path_buf());
    let outcome = identify::run(&o, &mut ()).unwrap();
    assert!(outcome.discretization.is_none());
    assert!(result_json(tmp.path()).get("discretization").is_none());
}

#[test]
fn a_measured_record_gets_a_discretization_result() {
    let tmp = tempfile::tempdir().unwrap();
    let mut o = IdentifyOptions::new(ConfigSource::Path(examples().join("real/anon-maxwell.ron")));
    o.sets = vec![
        "data.preprocessing.resample.n=16".into(),
        "specimen.elements_in_contact=4".into(),
    ];
    o.overrides.max_iterations = Some(4);
    o.figures = false;
    o.out = Some(tmp.path().to_path_buf());
    let outcome = identify::run(&o, &mut ()).unwrap();
    let d = outcome
        .discretization
        .as_ref()
        .expect("a discretization result");
    let n = outcome.fit.t.len();
    assert_eq!(d.delta_f.len(), n);
    // solver steps: the record's n - 1 steps in the default 2 sub-steps each
    // (data.substeps), then twice as many with the midpoints inserted
    assert_eq!(d.n_steps, (2 * (n - 1), 4 * (n - 1)));
    assert!(d.steps.contains("midpoints"), "{}", d.steps);
    assert!(d.elements.1 > 2 * d.elements.0, "{:?}", d.elements);
    assert!(d.rms_rel.is_finite() && d.rms_rel > 0.0, "{}", d.rms_rel);
    assert!(d.shift[0].is_some_and(f64::is_finite), "{:?}", d.shift);
    assert!(d.shift[2].is_some_and(f64::is_finite), "{:?}", d.shift);
    assert!(result_json(tmp.path())["discretization"]["shift"]["E"].is_number());
}

#[test]
fn refined_schedules_keep_the_original_times_at_even_indices() {
    use indentify_contact::{Schedule, Segment};
    let segments = vec![
        Segment {
            duration: 0.3,
            depth: 0.1,
            steps: 3,
        },
        Segment {
            duration: 0.7,
            depth: 0.05,
            steps: 5,
        },
    ];
    let s = Schedule::from_segments(&segments).unwrap();
    let h = indentify_study::config::History {
        segments: segments.into_iter().map(Into::into).collect(),
    };
    let (fine, _) = discretization::refine_schedule(Some(&h), &s).unwrap();
    let r = Schedule::from_record(&s.t, &s.depth).unwrap();
    let (mid, text) = discretization::refine_schedule(None, &r).unwrap();
    assert!(text.contains("midpoints"));
    for (i, (&t, &d)) in s.t.iter().zip(&s.depth).enumerate() {
        assert_eq!(fine.t[2 * i], t);
        assert_eq!(mid.t[2 * i], t);
        assert_eq!(mid.depth[2 * i], d);
        assert!((fine.depth[2 * i] - d).abs() < 1e-15);
    }
    assert_eq!(fine.t.len(), 2 * s.t.len() - 1);
    assert_eq!(mid.t.len(), 2 * s.t.len() - 1);
}
