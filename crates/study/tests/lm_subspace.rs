//! The configuration's Levenberg-Marquardt steps in the determined subspace,
//! `identify.stop.lm_subspace`: off by default; a value that is not a boolean is refused
//! before any solve with the field named (from `--set` and from a file); `true` reaches
//! `StopCriteria::lm.subspace`.

use indentify_study::config::{DEFAULT_LM_SUBSPACE, Reference};
use indentify_study::identify::{self, IdentifyOptions};
use indentify_study::{ConfigSource, ErrorKind};

fn opts(set: &str) -> IdentifyOptions {
    let mut o = IdentifyOptions::new(ConfigSource::Default);
    o.sets = vec![set.to_string()];
    o
}

#[test]
fn malformed_lm_subspace_is_refused_with_the_field_named() {
    for bad in ["3", "yes", "Classic", "\"true\""] {
        let e = match identify::resolve(&opts(&format!("identify.stop.lm_subspace={bad}"))) {
            Err(e) => e,
            Ok(_) => panic!("lm_subspace = {bad} was accepted"),
        };
        assert_eq!(e.kind(), ErrorKind::Config, "{bad}");
        let text = e.messages().join(" ");
        assert!(text.contains("stop.lm_subspace"), "{bad}: {text}");
    }
    let text = indentify_study::templates::annotated(&Reference::R2NortonHoff.config(), &[]);
    let shown = "lm_damping: Classic,";
    assert!(text.contains(shown), "{text}");
    let dir = std::env::temp_dir().join(format!("lm-subspace-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("bad.ron");
    std::fs::write(
        &path,
        text.replace(shown, &format!("{shown} lm_subspace: 2,")),
    )
    .unwrap();
    let e = match identify::resolve(&IdentifyOptions::new(ConfigSource::Path(path.clone()))) {
        Err(e) => e,
        Ok(_) => panic!("lm_subspace: 2 was accepted"),
    };
    let msg = e.messages().join(" ");
    assert!(msg.contains("stop.lm_subspace"), "{msg}");
    // the same file with a boolean reads
    std::fs::write(
        &path,
        text.replace(shown, &format!("{shown} lm_subspace: true,")),
    )
    .unwrap();
    let r = identify::resolve(&IdentifyOptions::new(ConfigSource::Path(path)))
        .unwrap_or_else(|e| panic!("{:?}", e.messages()));
    assert!(r.id_cfg.stop.lm.subspace);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn lm_subspace_is_off_by_default_and_reaches_the_strategy() {
    let r = identify::resolve(&IdentifyOptions::new(ConfigSource::Default))
        .unwrap_or_else(|e| panic!("{:?}", e.messages()));
    assert_eq!(r.id_cfg.stop.lm.subspace, DEFAULT_LM_SUBSPACE);
    assert!(!r.id_cfg.stop.lm.subspace);
    let r = identify::resolve(&opts("identify.stop.lm_subspace=true"))
        .unwrap_or_else(|e| panic!("{:?}", e.messages()));
    assert!(r.id_cfg.stop.lm.subspace);
}
