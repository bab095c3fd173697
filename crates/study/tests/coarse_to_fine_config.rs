//! The configuration's fidelity schedule, `identify.coarse_to_fine: Some((iterations: N))`,
//! through the study's whole identification: a noisy R1 Levenberg-Marquardt fit runs its
//! first iterations on the 2x coarser model, says so, reports the configuration's start,
//! takes fewer full-fidelity forward solves than the fit at full fidelity throughout and
//! lands within a tenth of a standard deviation of it. A schedule that cannot be honoured
//! (a coarse mesh below the contact resolution, a count of 0) is refused before any solve
//! with the field named; a coarse phase that fails falls back to full fidelity from the
//! configuration's start and says so.
//!
//! Reference: the same fit at full fidelity, and its Gauss-Newton deviations.

use indentify_study::config::{MethodName, Reference};
use indentify_study::identify::{self, IdentifyOptions, IdentifyOutcome};
use indentify_study::{ConfigSource, ErrorKind};

/// R1's annotated configuration (Maxwell on the 20 x 20 mesh) with `schedule` after
/// `identifiability`, written to a fresh folder.
fn config_with(schedule: &str, tag: &str) -> std::path::PathBuf {
    let text = indentify_study::templates::annotated(&Reference::R1Maxwell.config(), &[]);
    let anchor = "identifiability: true,";
    assert!(text.contains(anchor), "{text}");
    let dir = std::env::temp_dir().join(format!("c2f-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("c.ron");
    std::fs::write(
        &path,
        text.replace(anchor, &format!("{anchor}\n        {schedule}")),
    )
    .unwrap();
    path
}

/// The noisy (2%, seed 3) Levenberg-Marquardt fit of `path` with `sets`.
fn fit(path: &std::path::Path, sets: &[&str]) -> Result<IdentifyOutcome, indentify_study::Error> {
    let mut o = IdentifyOptions::new(ConfigSource::Path(path.to_path_buf()));
    o.sets = sets.iter().map(|s| s.to_string()).collect();
    o.overrides.method = Some(MethodName::Lm);
    o.noise = Some((0.02, 3));
    o.refine = false;
    o.figures = false;
    identify::run(&o, &mut ())
}

#[test]
fn a_fit_runs_coarse_to_fine_within_a_tenth_of_sigma_and_says_so() {
    let path = config_with("coarse_to_fine: Some((iterations: 20)),", "run");
    let c2f = fit(&path, &[]).unwrap_or_else(|e| panic!("{:?}", e.messages()));
    let full_path = config_with("coarse_to_fine: None,", "full");
    let full = fit(&full_path, &[]).unwrap_or_else(|e| panic!("{:?}", e.messages()));
    let phase = c2f.coarse.as_ref().expect("the coarse phase is reported");
    assert!(phase.fallback.is_none(), "{:?}", phase.fallback);
    let coarse = phase.result.as_ref().expect("the coarse fit ran");
    println!(
        "coarse: {} it, {} forward ({}); fine: {} it, {} forward ({}); full: {} it, {} forward",
        coarse.iterations,
        coarse.forward_solves,
        coarse.stop_reason,
        c2f.result.iterations,
        c2f.result.forward_solves,
        c2f.result.stop_reason,
        full.result.iterations,
        full.result.forward_solves
    );
    assert!(full.coarse.is_none());
    assert!(
        c2f.result.stop_reason.is_converged(),
        "{}",
        c2f.result.stop_reason
    );
    // the coarse model is the 10 x 10 mesh on every second time
    let model = phase.model.as_deref().unwrap_or("");
    assert!(model.contains("10 x 10"), "{model}");
    assert!(model.contains("every second time"), "{model}");
    let summary = phase.summary();
    assert!(summary.contains("ran coarse to fine"), "{summary}");
    // the full-fidelity phase starts near the end: fewer of its forward solves
    assert!(
        c2f.result.forward_solves < full.result.forward_solves,
        "{} against {}",
        c2f.result.forward_solves,
        full.result.forward_solves
    );
    // the reported start is the configuration's, not the coarse optimum
    for (a, b) in c2f.result.params.iter().zip(&full.result.params) {
        assert_eq!(a.start, b.start, "{}", a.name);
    }
    assert_eq!(c2f.fit.f_start, full.fit.f_start);
    // the same result within a tenth of a standard deviation
    let id = full.result.identifiability.as_ref().expect("deviations");
    for (k, name) in id.names.iter().enumerate() {
        let (a, b) = (
            c2f.value(name).expect("value"),
            full.value(name).expect("value"),
        );
        let shift = (a - b).abs() / id.std_dev[k];
        println!("{name}: {a} against {b}, {shift:.4} sigma");
        assert!(shift < 0.1, "{name}: {a} against {b} ({shift} sigma)");
    }
    for p in [path, full_path] {
        std::fs::remove_dir_all(p.parent().unwrap()).ok();
    }
}

#[test]
fn a_schedule_that_cannot_be_honoured_is_refused_naming_the_field() {
    // 8 x 8 elements: the 4 x 4 coarse mesh has 1 element under the contact radius
    let path = config_with("coarse_to_fine: Some((iterations: 5)),", "coarse");
    let e = fit(&path, &["specimen.nr=8", "specimen.nz=8"]).expect_err("refused");
    assert_eq!(e.kind(), ErrorKind::Config);
    let text = e.messages().join(" ");
    assert!(text.contains("identify.coarse_to_fine"), "{text}");
    assert!(text.contains("contact resolution"), "{text}");
    assert!(text.contains("specimen"), "{text}");
    let zero = config_with("coarse_to_fine: Some((iterations: 0)),", "zero");
    let e = match identify::resolve(&IdentifyOptions::new(ConfigSource::Path(zero.clone()))) {
        Err(e) => e,
        Ok(_) => panic!("iterations: 0 was accepted"),
    };
    assert_eq!(e.kind(), ErrorKind::Config);
    let text = e.messages().join(" ");
    assert!(text.contains("coarse_to_fine.iterations"), "{text}");
    for p in [path, zero] {
        std::fs::remove_dir_all(p.parent().unwrap()).ok();
    }
}

#[test]
fn a_coarse_phase_that_fails_falls_back_to_the_configured_start_and_says_so() {
    let path = config_with("coarse_to_fine: Some((iterations: 5)),", "fallback");
    let o = IdentifyOptions::new(ConfigSource::Path(path.clone()));
    let s = identify::setup(
        identify::resolve(&o).unwrap_or_else(|e| panic!("{:?}", e.messages())),
        &o,
    )
    .unwrap_or_else(|e| panic!("{:?}", e.messages()));
    let (cfg, phase) = indentify_study::coarse_to_fine::coarse_phase(
        &s,
        Err(anyhow::anyhow!("no coarse model for this test")),
        &s.id_cfg,
        5,
        &mut |_| {},
    );
    assert_eq!(cfg, s.id_cfg, "the start is the configuration's");
    assert!(phase.result.is_none());
    let summary = phase.summary();
    assert!(summary.contains("ran at full fidelity"), "{summary}");
    assert!(
        summary.contains("no coarse model for this test"),
        "{summary}"
    );
    std::fs::remove_dir_all(path.parent().unwrap()).ok();
}

/// The set-up noisy R1 fit of `path` (as `fit` runs it), on one thread.
fn setup(path: &std::path::Path) -> identify::Setup {
    let mut o = IdentifyOptions::new(ConfigSource::Path(path.to_path_buf()));
    o.overrides.method = Some(MethodName::Lm);
    o.noise = Some((0.02, 3));
    o.jobs = Some(1);
    identify::setup(
        identify::resolve(&o).unwrap_or_else(|e| panic!("{:?}", e.messages())),
        &o,
    )
    .unwrap_or_else(|e| panic!("{:?}", e.messages()))
}

#[test]
fn an_output_correction_makes_the_coarse_model_reproduce_the_fine_forces_at_its_start() {
    use indentify_identify::Evaluator;
    use indentify_study::coarse_to_fine::{self as c2f, Coarsening};
    let path = config_with("coarse_to_fine: None,", "corrected");
    let s = setup(&path);
    let (_, phase) = s.problem.install(|| {
        c2f::coarse_phase_corrected(
            &s,
            c2f::coarse_problem_with(&s, Coarsening::default()),
            &s.id_cfg,
            (20, 1),
            &mut |_| {},
        )
    });
    assert!(phase.fallback.is_none(), "{:?}", phase.fallback);
    let first = phase.result.as_ref().expect("the coarse fit");
    assert_eq!(phase.corrections.len(), 1, "one correction ran");
    let corrected = &phase.corrections[0].result;
    // the corrected coarse fit starts at the coarse end point, where its model is the fine
    // model on the coarse rows: its cost there is the fine forces' misfit on those rows,
    // with the coarse weights (every second time, twice the weight)
    let fine = s
        .problem
        .install(|| Evaluator::new(&s.problem)?.forces(&first.c))
        .expect("fine forces");
    let (coarse, _) = c2f::coarse_problem(&s).expect("coarse problem");
    assert_eq!(2 * (coarse.target.len() - 1), s.problem.target.len() - 1);
    let j: f64 = (0..coarse.target.len())
        .map(|i| {
            let r = fine[2 * i] - s.problem.target[2 * i];
            0.5 * coarse.weights[i] * r * r
        })
        .sum();
    let rel = (corrected.initial_cost - j).abs() / j;
    println!(
        "corrected start cost {:.9e}, fine misfit on the coarse rows {j:.9e} ({rel:.1e}); \
         discrepancy {:.3e}; coarse end {:?}, corrected end {:?}",
        corrected.initial_cost, phase.corrections[0].discrepancy, first.c, corrected.c
    );
    assert!(rel < 1e-6, "{rel}");
    // and the uncorrected coarse model's cost there is not: the correction did something
    let rel0 = (first.cost - j).abs() / j;
    assert!(rel0 > 1e-3, "{rel0}");
    let d = phase.corrections[0].discrepancy;
    assert!(d > 0.0 && d < 0.5, "relative discrepancy {d}");
    let (it, fw, se, _, fine_runs) = phase.totals();
    assert_eq!(fine_runs, 1);
    assert_eq!(it, first.iterations + corrected.iterations);
    assert_eq!(fw, first.forward_solves + corrected.forward_solves);
    assert_eq!(se, first.sensitivity_solves + corrected.sensitivity_solves);
    assert_eq!(phase.end().map(|r| &r.c), Some(&corrected.c));
    let summary = phase.summary();
    assert!(summary.contains("1 output correction"), "{summary}");
    std::fs::remove_dir_all(path.parent().unwrap()).ok();
}

#[test]
fn the_discrepancy_of_a_coarse_model_that_is_the_fine_one_is_zero() {
    use indentify_study::coarse_to_fine::{self as c2f, Coarsening};
    let path = config_with("coarse_to_fine: None,", "same");
    let s = setup(&path);
    let same = Coarsening {
        space: 1.0,
        time: false,
    };
    let (_, phase) = s.problem.install(|| {
        c2f::coarse_phase_corrected(
            &s,
            c2f::coarse_problem_with(&s, same),
            &s.id_cfg,
            (3, 1),
            &mut |_| {},
        )
    });
    assert!(phase.fallback.is_none(), "{:?}", phase.fallback);
    let model = phase.model.as_deref().unwrap_or("");
    assert!(model.contains("20 x 20"), "{model}");
    assert!(model.contains("time steps kept"), "{model}");
    assert_eq!(phase.corrections.len(), 1);
    // the same model at the same point: the forces agree to the Newton tolerance
    let d = phase.corrections[0].discrepancy;
    println!("relative discrepancy {d:.3e}");
    assert!(d < 1e-8, "relative discrepancy {d}");
    std::fs::remove_dir_all(path.parent().unwrap()).ok();
}
