//! The configuration's stop on the proposed step, `identify.stop.proposed_step`: on by
//! default in configurations (measured on every single-fit example and the map batch,
//! docs/performance.md "Seeded starts, the stop on the proposed step, the start curve
//! kept"), `false` or `step_sigma: None` turns it off, the library's own default stays off,
//! the templates write it and read it back, a value that is not a boolean is refused with
//! the field named. And through the study's whole identification: a noisy R1
//! Levenberg-Marquardt fit ends by it, says so in its stop reason, and lands within a
//! tenth of a standard deviation of the same fit with it off.
//!
//! Reference: the same fit with the rule off, and its Gauss-Newton deviations.

use indentify_identify::{StopCriteria, StopReason};
use indentify_study::config::{MethodName, Reference};
use indentify_study::identify::{self, IdentifyOptions};
use indentify_study::{ConfigSource, ErrorKind};

fn opts(sets: &[&str]) -> IdentifyOptions {
    let mut o = IdentifyOptions::new(ConfigSource::Default);
    o.sets = sets.iter().map(|s| s.to_string()).collect();
    o
}

#[test]
fn proposed_step_is_on_in_configurations_and_off_in_the_library() {
    assert!(!StopCriteria::default().proposed_step);
    let r = identify::resolve(&opts(&[])).unwrap_or_else(|e| panic!("{:?}", e.messages()));
    assert!(r.id_cfg.stop.proposed_step);
    assert_eq!(r.id_cfg.stop.step_sigma, Some(0.1));
    let r = identify::resolve(&opts(&["identify.stop.proposed_step=false"]))
        .unwrap_or_else(|e| panic!("{:?}", e.messages()));
    assert!(!r.id_cfg.stop.proposed_step);
}

#[test]
fn the_template_writes_proposed_step_and_reads_it_back() {
    let text = indentify_study::templates::annotated(&Reference::R2NortonHoff.config(), &[]);
    assert!(text.contains("proposed_step: true,"), "{text}");
    let dir = std::env::temp_dir().join(format!("proposed-step-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (shown, want) in [
        ("proposed_step: true,", true),
        ("proposed_step: false,", false),
    ] {
        let path = dir.join("c.ron");
        std::fs::write(&path, text.replace("proposed_step: true,", shown)).unwrap();
        let r = identify::resolve(&IdentifyOptions::new(ConfigSource::Path(path)))
            .unwrap_or_else(|e| panic!("{:?}", e.messages()));
        assert_eq!(r.id_cfg.stop.proposed_step, want, "{shown}");
    }
    // a configuration written before the field existed gets the default
    let path = dir.join("old.ron");
    std::fs::write(&path, text.replace("proposed_step: true,", "")).unwrap();
    let r = identify::resolve(&IdentifyOptions::new(ConfigSource::Path(path)))
        .unwrap_or_else(|e| panic!("{:?}", e.messages()));
    assert!(r.id_cfg.stop.proposed_step);
    // not a boolean: refused naming the field
    let path = dir.join("bad.ron");
    std::fs::write(
        &path,
        text.replace("proposed_step: true,", "proposed_step: 0.1,"),
    )
    .unwrap();
    let e = match identify::resolve(&IdentifyOptions::new(ConfigSource::Path(path))) {
        Err(e) => e,
        Ok(_) => panic!("proposed_step: 0.1 was accepted"),
    };
    assert_eq!(e.kind(), ErrorKind::Config);
    let msg = e.messages().join(" ");
    assert!(
        msg.contains("proposed_step") || msg.contains("bool"),
        "{msg}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// R1 (the embedded default, Maxwell on the 20 x 20 mesh) fitted by Levenberg-Marquardt
/// from its configuration's start to its curve with 2% noise (seed 3).
fn noisy_r1(proposed: bool) -> indentify_study::identify::IdentifyOutcome {
    let mut o = opts(&[if proposed {
        "identify.stop.proposed_step=true"
    } else {
        "identify.stop.proposed_step=false"
    }]);
    o.overrides.method = Some(MethodName::Lm);
    o.noise = Some((0.02, 3));
    o.refine = false;
    o.figures = false;
    identify::run(&o, &mut ()).unwrap_or_else(|e| panic!("{:?}", e.messages()))
}

#[test]
fn a_noisy_fit_ends_by_it_within_a_tenth_of_sigma_and_says_so() {
    let on = noisy_r1(true);
    let off = noisy_r1(false);
    println!(
        "on: {} it, {} forward, {} ({:?}); off: {} it, {} forward, {} ({:?})",
        on.result.iterations,
        on.result.forward_solves,
        on.result.stop_reason,
        on.result.c,
        off.result.iterations,
        off.result.forward_solves,
        off.result.stop_reason,
        off.result.c
    );
    assert!(
        matches!(on.result.stop_reason, StopReason::ProposedBelowSigma { .. }),
        "{}",
        on.result.stop_reason
    );
    assert!(on.converged() && off.converged());
    let text = on.result.stop_reason.to_string();
    assert!(text.contains("next Gauss-Newton step < 0.1 σ"), "{text}");
    assert!(on.result.forward_solves < off.result.forward_solves);
    for name in ["E", "eta"] {
        let sd = off.std_dev(name).unwrap();
        let shift = (on.value(name).unwrap() - off.value(name).unwrap()).abs() / sd;
        assert!(shift <= 0.1, "{name}: {shift} sigma");
    }
}
