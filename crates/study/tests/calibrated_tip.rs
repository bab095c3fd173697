//! `punch: Calibrated(file: "TIP.ron")`: an ideal-Berkovich area function (C0 = 24.5 alone)
//! runs as its area-equivalent cone to round-off (vertical and normal contact), a sphere's
//! area function is the sphere punch, the tip's frame compliance reaches the record's
//! preprocessing, and bad tip files are named with the field.

use std::path::{Path, PathBuf};

use indentify_study::ConfigSource;
use indentify_study::Punch;
use indentify_study::simulate::{self, SimulateOptions};

fn dir(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("calibrated-tip-{name}"));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The R1 template with `punch` replaced, written as `config.ron` in `d`.
fn config_with_punch(d: &Path, punch: &str) -> PathBuf {
    let text = indentify_study::templates::template(indentify_study::config::Reference::R1Maxwell);
    let replaced: Vec<String> = text
        .lines()
        .map(|l| {
            if l.trim_start().starts_with("punch:") {
                format!("    punch: {punch},")
            } else {
                l.to_string()
            }
        })
        .collect();
    assert!(replaced.iter().any(|l| l.contains(punch)));
    let path = d.join("config.ron");
    std::fs::write(&path, replaced.join("\n")).unwrap();
    path
}

fn forces(config: &Path, sets: &[&str]) -> (Vec<f64>, f64) {
    let mut opts = SimulateOptions::new(ConfigSource::Path(config.to_path_buf()));
    opts.sets = ["specimen.nr=6", "specimen.nz=6"]
        .iter()
        .chain(sets)
        .map(|s| s.to_string())
        .collect();
    let o = simulate::run(&opts).unwrap();
    assert!(o.failure.is_none(), "{:?}", o.failure);
    (o.trajectory.forces(), o.seconds)
}

#[test]
fn an_ideal_berkovich_area_runs_as_its_cone() {
    let d = dir("berkovich");
    std::fs::write(d.join("tip.ron"), "(area: Iso(coefficients: [24.5]))").unwrap();
    let calibrated = config_with_punch(&d, "Calibrated(file: \"tip.ron\")");
    let d2 = dir("cone");
    let theta = (24.5 / std::f64::consts::PI).sqrt().atan().to_degrees();
    let cone = config_with_punch(&d2, &format!("Cone(half_angle_deg: {theta:?})"));
    for (sets, tol) in [(&[][..], 1e-12), (&["contact=Normal"][..], 1e-9)] {
        // back to back, twice each (timings printed, not asserted)
        let (_, t_cone0) = forces(&cone, sets);
        let (_, t_cal0) = forces(&calibrated, sets);
        let ((a, t_cal), (b, t_cone)) = (forces(&calibrated, sets), forces(&cone, sets));
        println!(
            "{sets:?}: forward {:.3} / {:.3} s calibrated, {:.3} / {:.3} s cone",
            t_cal0, t_cal, t_cone0, t_cone
        );
        assert_eq!(a.len(), b.len());
        let fmax = b.iter().copied().fold(0.0, f64::max);
        assert!(fmax > 0.0);
        let worst = a
            .iter()
            .zip(&b)
            .map(|(x, y)| (x - y).abs() / fmax)
            .fold(0.0, f64::max);
        println!("{sets:?}: F_max {fmax} N, largest difference {worst:e} of F_max");
        assert!(worst < tol, "{sets:?}: {worst:e}");
    }
}

#[test]
fn a_sphere_area_function_is_the_sphere() {
    use indentify_study::config::tip::area_profile;
    let radius = 0.01;
    let p = area_profile(&indentify_analysis::AreaFunction::Sphere { radius }).unwrap();
    let sphere = Punch::Sphere { radius };
    for h in [1e-6, 1e-5, 1e-4, 1e-3, 5e-3, 9e-3] {
        let a = sphere.intersection_radius(h);
        assert!((p.radius(h) / a - 1.0).abs() < 1e-13, "{h}");
        assert!((p.height(a) / sphere.profile(a) - 1.0).abs() < 1e-10, "{h}");
    }
    // a calibrated Berkovich: the projected area at sampled depths is the area function
    let area = indentify_analysis::AreaFunction::Iso {
        coefficients: vec![23.79, 0.0, 2.69e4 * 1e-9],
    };
    let p = area_profile(&area).unwrap();
    for h in [1e-6, 1e-5, 1e-4, 1e-3] {
        let r = p.radius(h);
        assert!((std::f64::consts::PI * r * r / area.area(h) - 1.0).abs() < 1e-13);
        assert!((p.height(r) / h - 1.0).abs() < 1e-12);
    }
}

#[test]
fn the_tips_frame_compliance_is_applied_to_the_record() {
    let d = dir("compliance");
    let tip = d.join("tip.ron");
    std::fs::write(
        &tip,
        "(area: Iso(coefficients: [24.5]), frame_compliance: Some(0.5))",
    )
    .unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/real/anon-nh.ron");
    let mut cfg = indentify_study::config::load(&root, &[]).unwrap();
    cfg.punch = Punch::Calibrated {
        file: tip.display().to_string(),
        area: None,
    };
    let prepared = cfg.prepare("anon-nh").unwrap();
    let applied = &prepared.measured.unwrap().applied;
    let step = applied.iter().find(|a| a.step == "compliance").unwrap();
    assert!(step.description.contains("500"), "{}", step.description);
    assert!(matches!(
        prepared.model.punch,
        Punch::Calibrated { area: Some(_), .. }
    ));
}

#[test]
fn bad_tip_files_name_the_file_and_the_field() {
    let d = dir("bad");
    let err = |body: Option<&str>| {
        let tip = d.join("tip.ron");
        let _ = std::fs::remove_file(&tip);
        if let Some(b) = body {
            std::fs::write(&tip, b).unwrap();
        }
        let config = config_with_punch(&d, "Calibrated(file: \"tip.ron\")");
        let opts = SimulateOptions::new(ConfigSource::Path(config));
        format!("{:?}", simulate::run(&opts).unwrap_err())
    };
    let missing = err(None);
    assert!(
        missing.contains("tip.ron") && missing.contains("punch.file"),
        "{missing}"
    );
    let negative = err(Some("(area: Iso(coefficients: [-1.0]))"));
    assert!(
        negative.contains("tip.ron") && negative.contains("tip.area.coefficients[0]"),
        "{negative}"
    );
    let syntax = err(Some("(area: Iso(coefficients: [24.5]),\n modulus: x)"));
    assert!(syntax.contains("tip.ron:2"), "{syntax}");
    let flat = err(Some("(area: Flat(radius: 0.01))"));
    assert!(
        flat.contains("tip.ron") && flat.contains("tip.area") && flat.contains("Flat"),
        "{flat}"
    );
    let shrinking = err(Some("(area: Iso(coefficients: [24.5, -1.0]))"));
    assert!(
        shrinking.contains("tip.ron") && shrinking.contains("grows with the depth"),
        "{shrinking}"
    );
}
