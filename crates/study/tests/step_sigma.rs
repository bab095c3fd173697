//! The configuration's statistical stop, `identify.stop.step_sigma`: a fraction that is
//! not finite and > 0 is refused before any solve with the field named; `None` turns it
//! off; the default (0.1) is what `indentify check` and the templates show.

mod common;

use common::default_with;
use indentify_study::identify::{self, IdentifyOptions};
use indentify_study::{ConfigSource, ErrorKind};

fn opts(set: &str) -> IdentifyOptions {
    default_with(&[set])
}

#[test]
fn bad_step_sigma_is_refused_with_the_field_named() {
    for bad in ["0", "-0.1", "1e400", "-1e400"] {
        let e = match identify::resolve(&opts(&format!("identify.stop.step_sigma={bad}"))) {
            Err(e) => e,
            Ok(_) => panic!("step_sigma = {bad} was accepted"),
        };
        assert_eq!(e.kind(), ErrorKind::Config, "{bad}");
        let text = e.messages().join(" ");
        assert!(text.contains("stop.step_sigma"), "{bad}: {text}");
    }
}

#[test]
fn step_sigma_defaults_to_a_tenth_and_can_be_turned_off() {
    let r = identify::resolve(&IdentifyOptions::new(ConfigSource::Default))
        .unwrap_or_else(|e| panic!("{:?}", e.messages()));
    assert_eq!(r.id_cfg.stop.step_sigma, Some(0.1));
    let r = identify::resolve(&opts("identify.stop.step_sigma=0.25"))
        .unwrap_or_else(|e| panic!("{:?}", e.messages()));
    assert_eq!(r.id_cfg.stop.step_sigma, Some(0.25));
    let text = indentify_study::templates::annotated(
        &indentify_study::config::Reference::R2NortonHoff.config(),
        &[],
    );
    assert!(text.contains("step_sigma: 0.1,"), "{text}");
    let off = text.replace("step_sigma: 0.1,", "step_sigma: None,");
    let dir = std::env::temp_dir().join(format!("step-sigma-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("off.ron");
    std::fs::write(&path, off).unwrap();
    let r = identify::resolve(&IdentifyOptions::new(ConfigSource::Path(path)))
        .unwrap_or_else(|e| panic!("{:?}", e.messages()));
    assert_eq!(r.id_cfg.stop.step_sigma, None);
    std::fs::remove_dir_all(&dir).ok();
}
