//! The configuration's first Levenberg-Marquardt radius, `identify.stop.lm_radius`: a
//! length that is not finite and > 0 is refused before any solve with the field named; a
//! value reaches `StopCriteria::lm.first_radius`; the templates show it and it reads back.

mod common;

use common::default_with;
use indentify_study::identify::{self, IdentifyOptions};
use indentify_study::{ConfigSource, ErrorKind};

fn opts(set: &str) -> IdentifyOptions {
    default_with(&[set])
}

#[test]
fn bad_lm_radius_is_refused_with_the_field_named() {
    for bad in ["0", "-1", "1e400", "-1e400"] {
        let e = match identify::resolve(&opts(&format!("identify.stop.lm_radius={bad}"))) {
            Err(e) => e,
            Ok(_) => panic!("lm_radius = {bad} was accepted"),
        };
        assert_eq!(e.kind(), ErrorKind::Config, "{bad}");
        let text = e.messages().join(" ");
        assert!(text.contains("stop.lm_radius"), "{bad}: {text}");
    }
}

#[test]
fn lm_radius_reaches_the_strategy_and_reads_back_from_the_template() {
    let r = identify::resolve(&IdentifyOptions::new(ConfigSource::Default))
        .unwrap_or_else(|e| panic!("{:?}", e.messages()));
    let default = indentify_study::config::DEFAULT_LM_RADIUS;
    assert_eq!(r.id_cfg.stop.lm.first_radius, default);
    assert!(!r.id_cfg.stop.lm.line_model && !r.id_cfg.stop.lm.geodesic);
    let r = identify::resolve(&opts("identify.stop.lm_radius=0.5"))
        .unwrap_or_else(|e| panic!("{:?}", e.messages()));
    assert_eq!(r.id_cfg.stop.lm.first_radius, Some(0.5));
    let text = indentify_study::templates::annotated(
        &indentify_study::config::Reference::R2NortonHoff.config(),
        &[],
    );
    let shown = match default {
        Some(v) => format!("lm_radius: {v:?},"),
        None => "lm_radius: None,".to_string(),
    };
    assert!(text.contains(&shown), "{shown} in {text}");
    let two = text.replace(&shown, "lm_radius: 2.0,");
    let dir = std::env::temp_dir().join(format!("lm-radius-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("two.ron");
    std::fs::write(&path, two).unwrap();
    let r = identify::resolve(&IdentifyOptions::new(ConfigSource::Path(path)))
        .unwrap_or_else(|e| panic!("{:?}", e.messages()));
    assert_eq!(r.id_cfg.stop.lm.first_radius, Some(2.0));
    std::fs::remove_dir_all(&dir).ok();
}
