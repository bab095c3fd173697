//! Meaningless set-ups are refused before any solve with the size they would need, and a
//! model stretched beyond small strain says so.

use indentify_study::ConfigSource;
use indentify_study::identify::prepare;

fn prepared(sets: &[&str]) -> Result<indentify_study::config::Prepared, indentify_study::Error> {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    let cfg = ConfigSource::Default.load(&sets)?;
    prepare(&cfg, "r1")
}

#[test]
fn depths_beyond_the_specimen_and_contact_at_its_edge_are_refused() {
    let too_deep = ["history.segments.0.depth=50", "history.segments.1.depth=50"];
    let e = prepared(&too_deep).map(|_| ()).unwrap_err();
    let all = e.messages().join("\n");
    assert!(
        all.contains("50 mm deep into a specimen 10 mm high"),
        "{all}"
    );
    assert!(all.contains("specimen.height >= 1000 mm"), "{all}");
    let absurd = [
        "history.segments.0.depth=1e12",
        "history.segments.1.depth=1e12",
    ];
    assert!(prepared(&absurd).is_err());
    // a wide contact on a narrow specimen
    let e = prepared(&["specimen.radius=0.25"]).map(|_| ()).unwrap_err();
    let all = e.messages().join("\n");
    assert!(all.contains("would reach its outer edge"), "{all}");
    assert!(all.contains("specimen.radius >="), "{all}");
    // the reference problem itself is fine and silent
    assert!(prepared(&[]).unwrap().warnings.is_empty());
}

#[test]
fn deep_spheres_are_refused_or_warned() {
    let sphere = |depth: &str| {
        let text = indentify_study::DEFAULT_CONFIG.replace(
            "punch: Cone(half_angle_deg: 68.0)",
            "punch: Sphere(radius: 0.2)",
        );
        let sets: Vec<String> = [
            format!("history.segments.0.depth={depth}"),
            format!("history.segments.1.depth={depth}"),
        ]
        .into();
        let cfg = ConfigSource::Text {
            text,
            name: "sphere".into(),
        }
        .load(&sets)
        .unwrap();
        prepare(&cfg, "sphere")
    };
    let e = sphere("2.0").map(|_| ()).unwrap_err().messages().join("\n");
    assert!(e.contains("past its own radius"), "{e}");
    let w = sphere("0.1").unwrap().warnings;
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].contains("0.5 R deep") && w[0].contains("small-strain"),
        "{}",
        w[0]
    );
    assert!(sphere("0.02").unwrap().warnings.is_empty());
    // a cube corner's representative strain is beyond small strain
    let text = indentify_study::DEFAULT_CONFIG
        .replace("punch: Cone(half_angle_deg: 68.0)", "punch: CubeCorner()");
    let cfg = ConfigSource::Text {
        text,
        name: "cc".into(),
    }
    .load(&[])
    .unwrap();
    let w = prepare(&cfg, "cc").unwrap().warnings;
    assert!(
        w.iter().any(|w| w.contains("representative strain of 22%")),
        "{w:?}"
    );
}

#[test]
fn a_truncated_record_and_up_sampling_are_said() {
    let tmp = tempfile::tempdir().unwrap();
    // 37 samples of loading only (2 um in 37 s, a linear force), as a generic CSV
    let mut csv = String::from("Time (s),Depth (nm),Load (mN)\n");
    for i in 0..37 {
        let t = i as f64;
        csv.push_str(&format!(
            "{t},{},{}\n",
            2000.0 * t / 36.0,
            10.0 * (t / 36.0).powi(2)
        ));
    }
    let file = tmp.path().join("cut.csv");
    std::fs::write(&file, csv).unwrap();
    let cfg = ConfigSource::Path(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../examples/real/anon-maxwell.ron"),
    )
    .load(&[
        format!("data.file={}", file.display()),
        "data.format=Auto".into(),
    ])
    .unwrap();
    let p = prepare(&cfg, "cut").unwrap();
    let all = p.warnings.join("\n");
    assert!(
        all.contains("37 samples") && all.contains("60 points"),
        "{all}"
    );
    assert!(all.contains("no unloading"), "{all}");
}

#[test]
fn a_record_with_a_plastic_imprint_is_not_taken_for_a_truncated_one() {
    // anonNI.TXT unloads to zero force and ends at about 60% of its maximum depth (the
    // residual imprint): the unloading is there and no warning may say otherwise.
    let cfg = ConfigSource::Path(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../examples/real/anon-maxwell.ron"),
    )
    .load(&[])
    .unwrap();
    let p = prepare(&cfg, "anon").unwrap();
    let m = p.measured.as_ref().unwrap();
    let (h_end, h_max) = (*m.raw.h.last().unwrap(), m.raw.h_max());
    assert!(
        h_end > 0.5 * h_max,
        "the record's final depth {h_end} of {h_max}"
    );
    assert!(
        !p.warnings.iter().any(|w| w.contains("no unloading")),
        "{:?}",
        p.warnings
    );
}

#[test]
fn a_poisson_ratio_the_elements_cannot_solve_is_refused_with_the_range() {
    let load = |nu: &str| {
        ConfigSource::Path(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/r0-elastic.ron"),
        )
        .load(&[format!("law.nu={nu}")])
    };
    let err = load("0.49999").unwrap_err();
    let mut e = err.to_string();
    let mut src = std::error::Error::source(&err);
    while let Some(s) = src {
        e.push_str(&format!(": {s}"));
        src = s.source();
    }
    assert!(
        e.contains("law.nu = 0.49999") && e.contains("(-1, 0.499]"),
        "{e}"
    );
    load("0.499").unwrap();
}
