//! The configuration's Levenberg-Marquardt damping update, `identify.stop.lm_damping`: an
//! unknown name is refused before any solve with the field named (from `--set` and from a
//! file); a name reaches `StopCriteria::lm.damping`; the templates show the default and
//! it reads back.

use indentify_identify::LmDamping;
use indentify_study::config::{DEFAULT_LM_DAMPING, LmDampingName, Reference};
use indentify_study::identify::{self, IdentifyOptions};
use indentify_study::{ConfigSource, ErrorKind};

fn opts(set: &str) -> IdentifyOptions {
    let mut o = IdentifyOptions::new(ConfigSource::Default);
    o.sets = vec![set.to_string()];
    o
}

fn with_damping(text: &str, name: &str) -> String {
    let shown = format!("lm_damping: {DEFAULT_LM_DAMPING:?},");
    assert!(text.contains(&shown), "{shown} in {text}");
    text.replace(&shown, &format!("lm_damping: {name},"))
}

#[test]
fn unknown_lm_damping_is_refused_with_the_field_named() {
    for bad in ["TrustRegion", "nielsen", "4"] {
        let e = match identify::resolve(&opts(&format!("identify.stop.lm_damping={bad}"))) {
            Err(e) => e,
            Ok(_) => panic!("lm_damping = {bad} was accepted"),
        };
        assert_eq!(e.kind(), ErrorKind::Config, "{bad}");
        let text = e.messages().join(" ");
        assert!(text.contains("stop.lm_damping"), "{bad}: {text}");
    }
    let text = indentify_study::templates::annotated(&Reference::R2NortonHoff.config(), &[]);
    let dir = std::env::temp_dir().join(format!("lm-damping-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("bad.ron");
    std::fs::write(&path, with_damping(&text, "Fletcher")).unwrap();
    let e = match identify::resolve(&IdentifyOptions::new(ConfigSource::Path(path))) {
        Err(e) => e,
        Ok(_) => panic!("lm_damping: Fletcher was accepted"),
    };
    let text = e.messages().join(" ");
    assert!(text.contains("stop.lm_damping"), "{text}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn lm_damping_reaches_the_strategy_and_reads_back_from_the_template() {
    let r = identify::resolve(&IdentifyOptions::new(ConfigSource::Default))
        .unwrap_or_else(|e| panic!("{:?}", e.messages()));
    assert_eq!(r.id_cfg.stop.lm.damping, DEFAULT_LM_DAMPING.damping());
    let r = identify::resolve(&opts("identify.stop.lm_damping=MarquardtFletcher"))
        .unwrap_or_else(|e| panic!("{:?}", e.messages()));
    assert_eq!(r.id_cfg.stop.lm.damping, LmDamping::MarquardtFletcher);
    let text = indentify_study::templates::annotated(&Reference::R2NortonHoff.config(), &[]);
    let dir = std::env::temp_dir().join(format!("lm-damping-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (name, want) in [
        ("Nielsen", LmDamping::Nielsen),
        ("GainCapped", LmDamping::GainCapped),
        ("Delayed", LmDamping::Delayed),
        ("Classic", LmDamping::Classic),
    ] {
        let path = dir.join(format!("{name}.ron"));
        std::fs::write(&path, with_damping(&text, name)).unwrap();
        let r = identify::resolve(&IdentifyOptions::new(ConfigSource::Path(path)))
            .unwrap_or_else(|e| panic!("{:?}", e.messages()));
        assert_eq!(r.id_cfg.stop.lm.damping, want, "{name}");
    }
    std::fs::remove_dir_all(&dir).ok();
    // every configuration name maps to the library's update of the same name
    for (n, d) in [
        (LmDampingName::Classic, LmDamping::Classic),
        (LmDampingName::Nielsen, LmDamping::Nielsen),
        (
            LmDampingName::MarquardtFletcher,
            LmDamping::MarquardtFletcher,
        ),
        (LmDampingName::GainCapped, LmDamping::GainCapped),
        (LmDampingName::Delayed, LmDamping::Delayed),
    ] {
        assert_eq!(n.damping(), d);
    }
}
