//! End-to-end tests of the `indentify` binary: the shipped examples, the CSV curve, `--set`
//! overrides, VTU output, `init` templates, and bad input rejected with a message naming
//! the field (never a panic).

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::{
    COARSE, assert_ok, assert_rejected, examples, indentify, parse_curve, stderr, stdout,
};

/// A copy of `examples/r0-elastic.ron` with `from` replaced by `to` (which must occur).
fn r0_variant(dir: &Path, name: &str, from: &str, to: &str) -> PathBuf {
    let src = std::fs::read_to_string(examples().join("r0-elastic.ron")).unwrap();
    assert!(src.contains(from), "`{from}` is not in r0-elastic.ron");
    let path = dir.join(name);
    std::fs::write(&path, src.replacen(from, to, 1)).unwrap();
    path
}

#[test]
fn r0_matches_sneddon_within_two_percent_and_writes_91_rows() {
    // Reference: Sneddon (1965), rigid cone on an elastic half-space,
    // F = (2/pi) tan(alpha) E/(1-nu^2) h^2; docs/theory.md §11 puts the 10 x 10 mm cylinder
    // about 1% above the half-space.
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("curve.csv");
    let o = indentify(&[
        "simulate",
        examples().join("r0-elastic.ron").to_str().unwrap(),
        "--out",
        csv.to_str().unwrap(),
    ]);
    assert_ok(&o);
    let text = std::fs::read_to_string(&csv).unwrap();
    assert_eq!(text.lines().count(), 92, "91 rows + header");
    let rows = parse_curve(&text);
    assert_eq!(rows[0], [0.0, 0.0, 0.0, 0.0]);
    let [t, h, f, a] = rows[30];
    assert!((t - 1.0).abs() < 1e-12 && (h - 0.1).abs() < 1e-12);
    let (e, nu) = (20000.0_f64, 0.3_f64);
    let sneddon =
        2.0 / std::f64::consts::PI * 68f64.to_radians().tan() * e / (1.0 - nu * nu) * h * h * 1.01;
    assert!(
        (f - sneddon).abs() < 0.02 * sneddon,
        "F(h_max) = {f} N, Sneddon x 1.01 = {sneddon} N"
    );
    assert!(a > 0.0 && a < 0.3, "contact radius {a}");
    assert!(rows[90][1].abs() < 1e-12 && rows[90][2].abs() < 1e-6 * f);
    let err = stderr(&o);
    assert!(
        err.contains("max force") && err.contains("wall time"),
        "{err}"
    );
}

#[test]
fn curve_goes_to_stdout_without_out() {
    let mut args = vec!["simulate", "../../examples/r0-elastic.ron"];
    args.extend(COARSE);
    let o = Command::new(env!("CARGO_BIN_EXE_indentify"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(&args)
        .output()
        .unwrap();
    assert_ok(&o);
    assert_eq!(parse_curve(&stdout(&o)).len(), 13);
}

#[test]
fn set_doubling_e_doubles_the_force() {
    // Linear elasticity with a frictionless rigid punch: the contact set does not depend on
    // E, and the force is proportional to E.
    let r0 = examples().join("r0-elastic.ron");
    let run = |extra: &[&str]| {
        let mut args = vec!["simulate", r0.to_str().unwrap()];
        args.extend(COARSE);
        args.extend(extra);
        let o = indentify(&args);
        assert_ok(&o);
        parse_curve(&stdout(&o))
    };
    let base = run(&[]);
    let doubled = run(&["--set", "law.E=40000"]);
    assert_eq!(base.len(), doubled.len());
    assert!(base[4][2] > 0.0);
    for (b, d) in base.iter().zip(&doubled) {
        assert!(
            (d[2] - 2.0 * b[2]).abs() <= 1e-8 * b[2].abs().max(1.0),
            "{b:?} {d:?}"
        );
        assert_eq!(b[3], d[3], "contact radius");
    }
}

#[test]
fn set_rejects_unknown_paths_listing_the_available_keys() {
    let r0 = examples().join("r0-elastic.ron");
    let r0 = r0.to_str().unwrap();
    let cases: [(&str, &[&str]); 6] = [
        ("law.G=1", &["`G`", "E, nu"]),
        (
            "speciman.nr=3",
            &[
                "`speciman`",
                "history, identify, kinematics, law, punch, solver, specimen",
            ],
        ),
        ("specimen.nr=2.5", &["specimen.nr", "integer"]),
        ("history.segments.5.depth=1", &["index 5", "0..3"]),
        ("punch.radius=1", &["`radius`", "half_angle_deg"]),
        ("law.E", &["key.path=value"]),
    ];
    for (set, needles) in cases {
        let o = indentify(&["simulate", r0, "--set", set]);
        assert_rejected(&o, needles, set);
    }
}

#[test]
fn bad_inputs_are_rejected_naming_the_field() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // (case, text in r0-elastic.ron, replacement, what the message must contain)
    let cases: [(&str, &str, &str, &[&str]); 14] = [
        (
            "mistyped field",
            "nu: 0.3,",
            "nuu: 0.3,",
            &["law.nuu", ":47:"],
        ),
        ("missing field", "nu: 0.3,", "", &["law.nu", "required"]),
        (
            "missing section",
            "punch: Cone(half_angle_deg: 68.0),",
            "",
            &["punch"],
        ),
        (
            "non-positive modulus",
            "E: 20000.0,",
            "E: 0.0,",
            &["law.E", "(0, inf)"],
        ),
        (
            "nu too large",
            "nu: 0.3,",
            "nu: 0.5,",
            &["law.nu", "0.5", "(-1, 0.5)"],
        ),
        (
            "nu too small",
            "nu: 0.3,",
            "nu: -1.0,",
            &["law.nu", "(-1, 0.5)"],
        ),
        (
            "non-positive size",
            "radius: 10.0,",
            "radius: -10.0,",
            &["specimen.radius", "-10"],
        ),
        (
            "zero elements",
            "nz: 20,",
            "nz: 0,",
            &["specimen.nz", "= 0", "[1, 2000]"],
        ),
        ("negative count", "nr: 20,", "nr: -3,", &["specimen.nr"]),
        (
            "zero duration",
            "(duration: 1.0, depth: 0.1",
            "(duration: 0.0, depth: 0.1",
            &["duration", "> 0"],
        ),
        (
            "unknown punch",
            "punch: Cone(",
            "punch: Pyramid(",
            &["Pyramid", "punch", "Cone", "Sphere"],
        ),
        (
            "unknown law",
            "law: Elastic(",
            "law: Hooke(",
            &["Hooke", "law", "Elastic", "Maxwell", "NortonHoff"],
        ),
        (
            "string for a number",
            "E: 20000.0,",
            "E: \"stiff\",",
            &["law.E"],
        ),
        (
            "bad solver field",
            "max_cuts: 8,",
            "max_cut: 8,",
            &["solver.max_cut", "max_cuts"],
        ),
    ];
    for (i, (case, from, to, needles)) in cases.iter().enumerate() {
        let path = r0_variant(d, &format!("bad{i}.ron"), from, to);
        let o = indentify(&["simulate", path.to_str().unwrap(), "--out", "/dev/null"]);
        assert_rejected(&o, needles, case);
        assert!(
            stderr(&o).contains(&format!("bad{i}.ron")),
            "{case}: file name"
        );
    }
    let o = indentify(&["simulate", d.join("absent.ron").to_str().unwrap()]);
    assert_rejected(&o, &["absent.ron"], "missing file");
}

#[test]
fn law_parameter_ranges_are_enforced_by_set() {
    let r1 = examples().join("r1-maxwell.ron");
    let r2 = examples().join("r2-norton-hoff.ron");
    let cases: [(&Path, &str, &[&str]); 4] = [
        (&r1, "law.eta=0", &["law.eta", "0"]),
        (&r2, "law.K=-1", &["law.K", "-1"]),
        (&r2, "law.sY=-5", &["law.sY", "-5"]),
        (&r2, "law.m=0.5", &["law.m", "0.5"]),
    ];
    for (file, set, needles) in cases {
        let o = indentify(&["check", file.to_str().unwrap(), "--set", set]);
        assert_rejected(&o, needles, set);
    }
}

#[test]
fn init_templates_round_trip_and_are_the_examples() {
    let dir = tempfile::tempdir().unwrap();
    for (law, file) in [
        ("elastic", "r0-elastic.ron"),
        ("maxwell", "r1-maxwell.ron"),
        ("norton-hoff", "r2-norton-hoff.ron"),
    ] {
        let o = indentify(&["init", law]);
        assert_ok(&o);
        let text = stdout(&o);
        assert_eq!(
            text,
            std::fs::read_to_string(examples().join(file)).unwrap(),
            "examples/{file} differs from `indentify init {law}`"
        );
        let path = dir.path().join(file);
        std::fs::write(&path, &text).unwrap();
        let o = indentify(&["check", path.to_str().unwrap()]);
        assert_ok(&o);
        // the resolved output of `check` is itself a valid configuration
        let again = dir.path().join(format!("resolved-{file}"));
        std::fs::write(&again, stdout(&o)).unwrap();
        assert_ok(&indentify(&["check", again.to_str().unwrap()]));
    }
    assert_rejected(
        &indentify(&["init", "hooke"]),
        &["hooke", "elastic"],
        "init hooke",
    );
}

#[test]
fn viscous_examples_simulate_on_a_coarse_mesh() {
    for file in ["r1-maxwell.ron", "r2-norton-hoff.ron"] {
        let mut args = vec![
            "simulate".to_string(),
            examples().join(file).display().to_string(),
        ];
        args.extend(COARSE.iter().map(|s| s.to_string()));
        let o = Command::new(env!("CARGO_BIN_EXE_indentify"))
            .args(&args)
            .output()
            .unwrap();
        assert_ok(&o);
        let rows = parse_curve(&stdout(&o));
        assert_eq!(rows.len(), 13);
        // relaxation during the hold at h_max (rows 4..8)
        assert!(
            rows[4][2] > 0.0 && rows[8][2] < rows[4][2],
            "{file}: {rows:?}"
        );
    }
}

#[test]
fn vtu_series_has_every_state_and_elastic_eps_p_vanishes() {
    let dir = tempfile::tempdir().unwrap();
    let vtu = dir.path().join("fields");
    let mut args = vec![
        "simulate".to_string(),
        examples().join("r0-elastic.ron").display().to_string(),
        "--vtu".into(),
        vtu.display().to_string(),
        "--out".into(),
        dir.path().join("c.csv").display().to_string(),
    ];
    args.extend(COARSE.iter().map(|s| s.to_string()));
    let o = Command::new(env!("CARGO_BIN_EXE_indentify"))
        .args(&args)
        .output()
        .unwrap();
    assert_ok(&o);
    let pvd = std::fs::read_to_string(vtu.join("steps.pvd")).unwrap();
    assert_eq!(pvd.matches("<DataSet").count(), 2 * 13);
    assert!(pvd.contains("file=\"step_0012.vtu\"") && pvd.contains("file=\"gauss_0012.vtu\""));
    let mesh = std::fs::read_to_string(vtu.join("step_0004.vtu")).unwrap();
    for name in [
        "displacement",
        "contact_pressure",
        "stress",
        "von_mises",
        "eps_p",
        "eps_p_eq",
    ] {
        assert!(mesh.contains(&format!("Name=\"{name}\"")), "{name}");
    }
    // eps - S sigma is zero for an elastic law: only round-off remains
    let gauss = std::fs::read_to_string(vtu.join("gauss_0004.vtu")).unwrap();
    let values = |name: &str| -> Vec<f64> {
        let start = gauss.find(&format!("Name=\"{name}\"")).unwrap();
        let body = &gauss[start..];
        let body = &body[body.find('>').unwrap() + 1..body.find("</DataArray>").unwrap()];
        body.split_whitespace()
            .map(|x| x.parse().unwrap())
            .collect()
    };
    let eps_p = values("eps_p");
    let stress = values("stress");
    assert_eq!(eps_p.len(), 4 * 9 * 36);
    let smax = stress.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    assert!(smax > 1.0, "loaded state");
    let emax = eps_p.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    assert!(
        emax < 1e-9 * smax / 20000.0,
        "eps_p {emax} vs elastic strain {}",
        smax / 20000.0
    );
}

/// A law with internal variables writes them: J2 plasticity's accumulated plastic strain `p`
/// beside `eps_p_eq`, the equivalent of `eps - S sigma`. At small strain `eps - S sigma` is
/// the plastic strain tensor, so `eps_p_eq <= p` everywhere (the length of a path's end
/// against its length), with equality after the first plastic step from a stress-free
/// state (one radial return: the plastic strain is `Delta p n`, `n` of unit equivalent).
#[test]
fn vtu_writes_the_accumulated_plastic_strain_of_j2() {
    let dir = tempfile::tempdir().unwrap();
    let vtu = dir.path().join("fields");
    let args: Vec<String> = [
        "simulate",
        &examples()
            .join("plastic-power-cone.ron")
            .display()
            .to_string(),
        "--vtu",
        &vtu.display().to_string(),
        "--out",
        &dir.path().join("c.csv").display().to_string(),
        "--set",
        "specimen.nr=8",
        "--set",
        "specimen.nz=8",
        "--set",
        "history.segments.0.steps=6",
        "--set",
        "history.segments.1.steps=4",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let o = Command::new(env!("CARGO_BIN_EXE_indentify"))
        .args(&args)
        .output()
        .unwrap();
    assert_ok(&o);
    let values = |file: &str, name: &str| -> Vec<f64> {
        let doc = std::fs::read_to_string(vtu.join(file)).unwrap();
        let start = doc
            .find(&format!("Name=\"{name}\""))
            .unwrap_or_else(|| panic!("{file}: no field {name}"));
        let body = &doc[start..];
        let body = &body[body.find('>').unwrap() + 1..body.find("</DataArray>").unwrap()];
        body.split_whitespace()
            .map(|x| x.parse().unwrap())
            .collect()
    };
    assert!(
        std::fs::read_to_string(vtu.join("step_0003.vtu"))
            .unwrap()
            .contains("Name=\"internal_p\""),
        "cell averages of p"
    );
    let mut first = true;
    for k in 1..=10 {
        let file = format!("gauss_{k:04}.vtu");
        let (p, eq) = (values(&file, "internal_p"), values(&file, "eps_p_eq"));
        assert_eq!(p.len(), eq.len());
        let pmax = p.iter().fold(0.0_f64, |m, v| m.max(*v));
        if pmax == 0.0 {
            continue;
        }
        for (a, b) in p.iter().zip(&eq) {
            assert!(
                *b <= a * (1.0 + 1e-9) + 1e-12 * pmax,
                "{file}: eps_p_eq {b} > p {a}"
            );
            if first {
                assert!(
                    (a - b).abs() <= 1e-9 * pmax,
                    "{file}: first plastic step: p {a}, eps_p_eq {b}"
                );
            }
        }
        first = false;
    }
    assert!(!first, "the cone yields");
}

#[test]
fn a_failing_step_writes_the_partial_curve_and_fails_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("partial.csv");
    let o = indentify(&[
        "simulate",
        examples().join("r2-norton-hoff.ron").to_str().unwrap(),
        "--out",
        csv.to_str().unwrap(),
        "--set",
        "solver.max_iterations=1",
        "--set",
        "solver.max_cuts=0",
    ]);
    assert_rejected(&o, &["stopped", "max_cuts"], "max_iterations = 1");
    let rows = parse_curve(&std::fs::read_to_string(&csv).unwrap());
    assert!(!rows.is_empty() && rows.len() < 91, "{} rows", rows.len());
}

#[test]
fn help_describes_commands_and_options() {
    let o = indentify(&["--help"]);
    assert_ok(&o);
    let h = stdout(&o);
    for w in [
        "simulate",
        "init",
        "check",
        "gradient",
        "gradient-check",
        "identify",
        "N, mm, s, MPa",
    ] {
        assert!(h.contains(w), "{w} in {h}");
    }
    let o = indentify(&["simulate", "--help"]);
    let h = stdout(&o);
    for w in ["--out", "--vtu", "--set", "t,h,F,a", "law.E=25000"] {
        assert!(h.contains(w), "{w} in {h}");
    }
    let h = stdout(&indentify(&["init", "--help"]));
    assert!(h.contains("norton-hoff"), "{h}");
    let h = stdout(&indentify(&["simulate", "--help"]));
    for w in ["--noise", "--seed", "SplitMix64"] {
        assert!(h.contains(w), "{w} in {h}");
    }
    let h = stdout(&indentify(&["gradient", "--help"]));
    for w in ["--data", "--json", "--checkpoint", "t_i", "m <= 1"] {
        assert!(h.contains(w), "{w} in {h}");
    }
    let h = stdout(&indentify(&["gradient-check", "--help"]));
    for w in ["--rel-step", "--tol", "--scan", "1.1", "0.97", "1e-8"] {
        assert!(h.contains(w), "{w} in {h}");
    }
    let h = stdout(&indentify(&["identify", "--help"]));
    for w in [
        "--data",
        "--out",
        "--method",
        "--free",
        "--fixed",
        "--start",
        "--max-iter",
        "--resume",
        "--quiet",
        "result.json",
        "history.csv",
        "fit.csv",
        "(4000, 70000)",
    ] {
        assert!(h.contains(w), "{w} in {h}");
    }
}
