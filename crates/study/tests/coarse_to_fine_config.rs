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
