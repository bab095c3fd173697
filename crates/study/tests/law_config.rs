//! The `law` of a configuration read through the laws registry: every shipped example
//! (old laws and new) loads, the old laws keep their bits through RON, JSON and `--set`,
//! the new laws' parameters are reached by their registry names, and bad specifications are
//! refused naming the field, the allowed range and, in RON text, the line and column.

use std::path::Path;

use indentify_study::config::{self, IdentifySection, LawSpec, Overrides};

fn examples() -> Vec<std::path::PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples");
    let mut files = Vec::new();
    for dir in [root.clone(), root.join("real")] {
        for e in std::fs::read_dir(&dir).unwrap() {
            let p = e.unwrap().path();
            if p.extension().is_some_and(|x| x == "ron") {
                files.push(p);
            }
        }
    }
    files.sort();
    files
}

/// A small configuration around the law text `law`.
fn with_law(law: &str) -> String {
    format!(
        "(\n    specimen: Cylinder(radius: 10.0, height: 10.0, nr: 4, nz: 4, grading_r: 1.0, \
         grading_z: 1.0),\n    punch: Cone(half_angle_deg: 68.0),\n    law: {law},\n    \
         history: (segments: [(duration: 1.0, depth: 0.05, steps: 2)]),\n)"
    )
}

fn load(law: &str, sets: &[&str]) -> anyhow::Result<config::Config> {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    config::load_str(&with_law(law), "t.ron", &sets)
}

fn err(law: &str) -> String {
    format!("{:#}", load(law, &[]).unwrap_err())
}

/// The system shall load every shipped example (`indentify check` validates them),
/// the examples of the new laws included, and name at least one of each new law.
#[test]
fn every_shipped_example_loads() {
    let mut variants = Vec::new();
    for p in examples() {
        let cfg = config::load(&p, &[]).unwrap_or_else(|e| panic!("{}: {e:#}", p.display()));
        variants.push(cfg.law.variant());
    }
    for v in ["Elastic", "Maxwell", "NortonHoff", "Plastic", "Prony"] {
        assert!(variants.contains(&v), "no example of {v}: {variants:?}");
    }
    let names: Vec<String> = examples()
        .iter()
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    assert!(names.iter().any(|n| n.starts_with("prony-")), "{names:?}");
    assert!(
        names.iter().any(|n| n.ends_with("-plastic.ron")),
        "{names:?}"
    );
}

/// The system shall give the old laws the same law and the same parameter bits as the
/// hand-written configuration did (the library law, parameters in its order), after a
/// RON round trip and through a `--set` of another field (a JSON round trip).
#[test]
fn old_laws_keep_their_bits() {
    let cases: [(&str, &str, &[f64]); 3] = [
        ("Elastic(E: 20000.0, nu: 0.3)", "elastic", &[20000.0, 0.3]),
        (
            "Maxwell(E: 20000.0, nu: 0.3, eta: 30000.0)",
            "maxwell",
            &[20000.0, 0.3, 30000.0],
        ),
        (
            // written in another field order than the library's
            "NortonHoff(sY: 500.0, E: 1e5, nu: 0.3, m: 5.0, K: 1500.1)",
            "norton-hoff",
            &[1e5, 0.3, 1500.1, 5.0, 500.0],
        ),
    ];
    for (text, name, params) in cases {
        let cfg = load(text, &[]).unwrap();
        let (law, p) = cfg.law.build().unwrap();
        assert_eq!(law.name(), name);
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&p), bits(params), "{text}");
        let lib: Vec<&str> = law.params().iter().map(|i| i.name).collect();
        let named: Vec<&str> = cfg.law.named_params().iter().map(|(n, _)| *n).collect();
        assert_eq!(named, lib);
        let ron_text = ron::to_string(&cfg.law).unwrap();
        let back: LawSpec = ron::from_str(&ron_text).unwrap();
        assert_eq!(back, cfg.law, "{ron_text}");
        let set = load(text, &["solver.max_iterations=7"]).unwrap();
        assert_eq!(bits(&set.law.build().unwrap().1), bits(params));
    }
}

/// The system shall parse `Plastic` with each hardening form, with and without a rate,
/// and `Prony` with its terms, with the registry's parameter names in its order; RON and
/// JSON round trips keep the nested variant names.
#[test]
fn new_laws_parse_with_registry_names() {
    let cases: [(&str, &[&str]); 6] = [
        (
            "Plastic(E: 7e4, nu: 0.3, sY: 300.0, hardening: Linear(H: 2000.0))",
            &["E", "nu", "sY", "H"],
        ),
        (
            "Plastic(E: 7e4, nu: 0.3, sY: 300.0, hardening: Power(n: 0.2), \
             rate: Norton(K: 200.0, m: 3.0))",
            &["E", "nu", "sY", "n", "K", "m"],
        ),
        (
            "Plastic(E: 7e4, nu: 0.3, sY: 300.0, hardening: Voce(Q: 150.0, b: 40.0))",
            &["E", "nu", "sY", "Q", "b"],
        ),
        (
            "Plastic(E: 7e4, nu: 0.3, sY: 300.0, hardening: Swift(eps0: 0.01, n: 0.3))",
            &["E", "nu", "sY", "eps0", "n"],
        ),
        (
            "Plastic(E: 7e4, nu: 0.3, sY: 300.0, \
             hardening: Table(points: [(0.0, 300.0), (0.1, 400.0), (1.0, 450.0)]))",
            &["E", "nu", "sY"],
        ),
        (
            "Prony(E: 3000.0, nu: 0.35, terms: [(g: 0.3, tau: 0.1), (g: 0.2, tau: 2.0)])",
            &["E", "nu", "g1", "tau1", "g2", "tau2"],
        ),
    ];
    for (text, names) in cases {
        let cfg = load(text, &[]).unwrap_or_else(|e| panic!("{text}: {e:#}"));
        let got: Vec<&str> = cfg.law.named_params().iter().map(|(n, _)| *n).collect();
        assert_eq!(got, names, "{text}");
        let ron_text = ron::to_string(&cfg.law).unwrap();
        let back: LawSpec = ron::from_str(&ron_text).unwrap();
        assert_eq!(back, cfg.law, "{ron_text}");
        let json = serde_json::to_value(&cfg.law).unwrap();
        let back: LawSpec = serde_json::from_value(json.clone()).unwrap();
        assert_eq!(back, cfg.law, "{json}");
        // every parameter can be set by its registry name
        for (n, v) in cfg.law.named_params() {
            let moved = if n == "nu" { 0.25 } else { v * 1.01 };
            let set = load(text, &[&format!("law.{n}={moved}")])
                .unwrap_or_else(|e| panic!("--set law.{n} on {text}: {e:#}"));
            let after = set.law.named_params();
            for (m, w) in after {
                let want = if m == n {
                    moved
                } else {
                    cfg.law.named_params().iter().find(|p| p.0 == m).unwrap().1
                };
                assert_eq!(w.to_bits(), want.to_bits(), "--set law.{n}: {m}");
            }
        }
    }
    let cfg = load(cases[5].0, &["law.tau2=3.5"]).unwrap();
    assert_eq!(cfg.law.param_path("tau2").as_deref(), Some("terms.1.tau"));
    assert_eq!(cfg.law.named_params()[5], ("tau2", 3.5));
    let cfg = load(cases[1].0, &["law.hardening.n=0.25"]).unwrap();
    assert_eq!(cfg.law.named_params()[3], ("n", 0.25));
}

/// The system shall refuse bad law specifications naming the field and the allowed range,
/// with the RON line and column: a negative or non-finite hardening parameter, sum g >= 1,
/// tau <= 0, a decreasing table, unknown hardening or rate kinds, unknown or missing fields.
#[test]
fn bad_law_specifications_name_field_range_and_position() {
    let p = "Plastic(E: 7e4, nu: 0.3, sY: 300.0, hardening: ";
    let t = err(&format!("{p}Linear(H: -5.0))"));
    assert!(t.contains("law.H = -5") && t.contains("[0, inf)"), "{t}");
    assert!(t.contains("t.ron:4:"), "{t}");
    let t = err(&format!("{p}Power(n: NaN))"));
    assert!(t.contains("law.n") && t.contains("NaN"), "{t}");
    let t = err(&format!("{p}Voce(Q: 100.0, b: -1.0))"));
    assert!(t.contains("law.b = -1"), "{t}");
    let t = err(&format!("{p}Ludwik(k: 1.0))"));
    assert!(
        t.contains("law.hardening")
            && t.contains("Ludwik")
            && t.contains("Linear, Power, Voce, Swift, Table"),
        "{t}"
    );
    assert!(t.contains("t.ron:4:"), "{t}");
    let t = err(&format!("{p}Linear(H: 1.0), rate: Perzyna(eta: 1.0))"));
    assert!(
        t.contains("law.rate") && t.contains("Perzyna") && t.contains("Norton"),
        "{t}"
    );
    let t = err(&format!("{p}Table(points: [(0.0, 300.0), (0.1, 250.0)]))"));
    assert!(
        t.contains("law.hardening.points[1]") && t.contains("non-decreasing"),
        "{t}"
    );
    let t = err(&format!("{p}Linear(H: 1.0, Q: 2.0))"));
    assert!(
        t.contains("law.hardening.Q") && t.contains("unknown field"),
        "{t}"
    );
    let t = err("Plastic(E: 7e4, nu: 0.3, hardening: Linear(H: 1.0))");
    assert!(t.contains("law.sY") && t.contains("missing"), "{t}");
    let t = err("Prony(E: 3000.0, nu: 0.3, terms: [(g: 0.6, tau: 1.0), (g: 0.5, tau: 2.0)])");
    assert!(t.contains("g") && t.contains("1"), "{t}");
    assert!(t.to_lowercase().contains("sum"), "{t}");
    let t = err("Prony(E: 3000.0, nu: 0.3, terms: [(g: 0.3, tau: 0.0)])");
    assert!(t.contains("tau1 = 0") && t.contains("(0, inf)"), "{t}");
    let t = err("Prony(E: 3000.0, nu: 0.3, terms: [(g: 0.3, tau: 1.0, beta: 2.0)])");
    assert!(
        t.contains("law.terms.0.beta") && t.contains("accepted: g, tau"),
        "{t}"
    );
    let t = err("Hooke(E: 1.0)");
    assert!(t.contains("Hooke") && t.contains("Prony"), "{t}");
    let t = format!("{:#}", load(cases_plastic(), &["law.eta=3"]).unwrap_err());
    assert!(t.contains("eta"), "{t}");
}

fn cases_plastic() -> &'static str {
    "Plastic(E: 7e4, nu: 0.3, sY: 300.0, hardening: Power(n: 0.2))"
}

/// The system shall take `free`, `fixed` and starts by the registry's parameter names,
/// and refuse a name the law does not have, listing its parameters.
#[test]
fn identify_settings_use_registry_names() {
    let cfg = load(
        "Plastic(E: 7e4, nu: 0.3, sY: 300.0, hardening: Voce(Q: 150.0, b: 40.0), \
         rate: Norton(K: 200.0, m: 3.0))",
        &[],
    )
    .unwrap();
    let built = cfg.law.material().unwrap();
    let ov = Overrides {
        free: Some(vec!["sY".into(), "Q".into(), "b".into()]),
        fixed: vec![("K".into(), Some(250.0))],
        ..Overrides::default()
    };
    let s = IdentifySection::settings(None, built.material.as_ref(), &ov).unwrap();
    let names: Vec<&str> = s.iter().map(|(n, _)| *n).collect();
    assert_eq!(names, ["E", "nu", "sY", "Q", "b", "K", "m"]);
    let free: Vec<&str> = s
        .iter()
        .filter(|(_, p)| matches!(p, config::ParamSetting::Free { .. }))
        .map(|(n, _)| *n)
        .collect();
    assert_eq!(free, ["sY", "Q", "b"]);
    let ov = Overrides {
        free: Some(vec!["eta".into()]),
        ..Overrides::default()
    };
    let e = IdentifySection::settings(None, built.material.as_ref(), &ov)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("eta") && e.contains("E, nu, sY, Q, b, K, m"),
        "{e}"
    );
}

/// The system shall write an `init` template for every hardening form and for Prony that
/// loads back to the law it was written from.
#[test]
fn init_templates_of_registry_laws_load() {
    use indentify_study::templates::{LAW_TEMPLATES, law_template};
    for (kind, text) in LAW_TEMPLATES {
        let t = law_template(kind).unwrap();
        let cfg = config::load_str(&t, kind, &[]).unwrap_or_else(|e| panic!("{kind}: {e:#}\n{t}"));
        let want: LawSpec = ron::from_str(text).unwrap();
        assert_eq!(cfg.law, want, "{kind}");
        assert!(cfg.identify.is_some(), "{kind}");
    }
    for hardening in ["Linear", "Power", "Voce", "Swift", "Table"] {
        assert!(
            LAW_TEMPLATES.iter().any(|(_, t)| t.contains(hardening)),
            "{hardening}"
        );
    }
    assert!(
        law_template("hooke")
            .unwrap_err()
            .to_string()
            .contains("plastic-voce")
    );
}
