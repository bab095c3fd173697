//! `indentify_study::design`: candidate protocols ranked by the standard deviations they
//! would give at nominal parameters.
//!
//! References the design code did not produce: for an elastic law the force is
//! proportional to E (depth-controlled, rigid frictionless punch), so `dF/d ln E = F` and
//! the least-squares deviation of E has a closed form in the forces alone, which a plain
//! forward run gives (`relative_noise_closed_form_for_elastic_e`); and an identification
//! with `identify.noise` set to the design's noise, started at the nominal parameters,
//! reports the same deviations (`design_sigmas_agree_with_an_identification`).

use indentify_study::config::NoiseSetting;
use indentify_study::design::{self, DesignOptions};
use indentify_study::identify::{self, IdentifyOptions};
use indentify_study::simulate::{self, SimulateOptions};
use indentify_study::{ConfigSource, ErrorKind};

const MESH: &str =
    "specimen: Cylinder(radius: 10.0, height: 10.0, nr: 6, nz: 6, grading_r: 1.3, grading_z: 1.3),
     punch: Cone(half_angle_deg: 68.0),";

/// A history loading to `depth` in `load` s, held `hold` s.
fn history(load: f64, hold: f64, depth: f64) -> String {
    format!(
        "history: (segments: [(duration: {load}, depth: {depth}, steps: 4), \
         (duration: {hold}, depth: {depth}, steps: 4)])"
    )
}

fn text(law: &str, identify: &str, noise: &str, candidates: &[(&str, Vec<String>)]) -> String {
    let cands: Vec<String> = candidates
        .iter()
        .map(|(name, tests)| {
            let t: Vec<String> = tests.iter().map(|h| format!("({h})")).collect();
            format!("(name: \"{name}\", tests: [{}])", t.join(", "))
        })
        .collect();
    format!(
        "({MESH} law: {law}, {}, identify: ({identify}), design: (noise: {noise}, candidates: [{}]))",
        history(1.0, 1.0, 0.1),
        cands.join(", ")
    )
}

fn source(t: String) -> ConfigSource {
    ConfigSource::Text {
        text: t,
        name: "design-test".into(),
    }
}

const MAXWELL: &str = "Maxwell(E: 20000.0, nu: 0.3, eta: 30000.0)";
const MAXWELL_ID: &str = "params: {\"E\": Free(lower: 1000.0, upper: 1e6), \"nu\": Fixed(value: 0.3), \
                          \"eta\": Free(lower: 1000.0, upper: 1e7)}, method: Lm";

fn maxwell_candidates() -> Vec<(&'static str, Vec<String>)> {
    vec![
        ("one rate", vec![history(1.0, 1.0, 0.1)]),
        (
            "two rates",
            vec![history(0.1, 1.0, 0.1), history(10.0, 1.0, 0.1)],
        ),
    ]
}

/// The deviations of a candidate shall be those of an identification of its tests at the
/// nominal parameters with `identify.noise` set to the same noise (exact synthesized
/// data, LM started at the truth: the summary is computed there), to 1e-9.
#[test]
fn design_sigmas_agree_with_an_identification() {
    let cands = maxwell_candidates();
    let d = design::run(&DesignOptions::new(source(text(
        MAXWELL,
        MAXWELL_ID,
        "Relative(0.01)",
        &cands,
    ))))
    .unwrap();
    println!("{}", d.summary());
    assert_eq!(d.candidates.len(), 2);
    for (k, (_, tests)) in cands.iter().enumerate() {
        let t: Vec<String> = tests.iter().map(|h| format!("({h})")).collect();
        let cfg = format!(
            "({MESH} law: {MAXWELL}, tests: [{}], identify: ({MAXWELL_ID}, noise: Relative(0.01)))",
            t.join(", ")
        );
        let mut o = IdentifyOptions::new(source(cfg));
        o.refine = false;
        o.figures = false;
        let out = identify::run(&o, &mut ()).unwrap();
        let id = out.result.identifiability.as_ref().unwrap();
        // the summary is taken at the nominal parameters (exact data: the fit stays there)
        assert_eq!(
            id.values,
            vec![20000.0, 30000.0],
            "{}",
            out.result.stop_reason
        );
        for p in &d.candidates[k].params {
            let j = id.names.iter().position(|n| *n == p.name).unwrap();
            println!(
                "{} {}: design {} identification {}",
                d.candidates[k].name, p.name, p.std_dev, id.std_dev[j]
            );
            assert!(
                (p.std_dev - id.std_dev[j]).abs() <= 1e-9 * id.std_dev[j],
                "{} {}: {} vs {}",
                d.candidates[k].name,
                p.name,
                p.std_dev,
                id.std_dev[j]
            );
        }
    }
    // the two-rate candidate determines eta better than the one-rate one
    let rel = |k: usize, n: &str| {
        d.candidates[k]
            .params
            .iter()
            .find(|p| p.name == n)
            .unwrap()
            .rel_std_dev
    };
    println!(
        "eta: one rate {}, two rates {}",
        rel(0, "eta"),
        rel(1, "eta")
    );
}

/// Elastic, E alone: F = E g(h), so dF/d ln E = F and, under unit point weights (one
/// test), the deviation of ln E is `f sqrt(sum F^4) / sum F^2` for relative noise `f` and
/// `s / sqrt(sum F^2)` for absolute noise `s`; the forces come from `simulate`. The deeper
/// test (larger forces) ranks first under absolute noise by both criteria.
#[test]
fn closed_form_deviations_and_ranking_for_elastic_e() {
    let law = "Elastic(E: 20000.0, nu: 0.3)";
    let id = "params: {\"E\": Free(lower: 1000.0, upper: 1e6), \"nu\": Fixed(value: 0.3)}";
    let cands = vec![
        ("shallow", vec![history(1.0, 1.0, 0.05)]),
        ("deep", vec![history(1.0, 1.0, 0.1)]),
    ];
    let forces = |depth: f64| -> Vec<f64> {
        let cfg = format!("({MESH} law: {law}, {})", history(1.0, 1.0, depth));
        let mut o = SimulateOptions::new(source(cfg));
        o.out = None;
        simulate::run(&o)
            .unwrap()
            .rows
            .iter()
            .map(|r| r.f)
            .collect()
    };
    for noise in [NoiseSetting::Relative(0.02), NoiseSetting::Absolute(0.5)] {
        let n = match noise {
            NoiseSetting::Relative(f) => format!("Relative({f})"),
            NoiseSetting::Absolute(s) => format!("Absolute({s})"),
            _ => unreachable!(),
        };
        let d = design::run(&DesignOptions::new(source(text(law, id, &n, &cands)))).unwrap();
        println!("{}", d.summary());
        for (k, depth) in [(0, 0.05), (1, 0.1)] {
            let f = forces(depth);
            let s2: f64 = f.iter().map(|v| v * v).sum();
            let want = match noise {
                NoiseSetting::Relative(r) => {
                    r * f.iter().map(|v| v.powi(4)).sum::<f64>().sqrt() / s2
                }
                NoiseSetting::Absolute(s) => s / s2.sqrt(),
                _ => unreachable!(),
            };
            let got = d.candidates[k].params[0].rel_std_dev;
            println!("{n} depth {depth}: design {got}, closed form {want}");
            assert!((got - want).abs() <= 1e-6 * want, "{got} vs {want}");
            // ln det I = -2 ln(sigma of ln E)
            let ld = d.candidates[k].log_det;
            assert!((ld + 2.0 * got.ln()).abs() < 1e-6, "{ld}");
        }
        if let NoiseSetting::Absolute(_) = noise {
            assert_eq!(d.rank_d, vec![1, 0]);
            assert_eq!(d.rank_worst, vec![1, 0]);
        }
    }
}

/// The design shall not depend on the number of threads, bit for bit.
#[test]
fn design_is_bit_identical_for_one_and_two_threads() {
    let t = text(MAXWELL, MAXWELL_ID, "Relative(0.01)", &maxwell_candidates());
    let run = |jobs| {
        let mut o = DesignOptions::new(source(t.clone()));
        o.jobs = Some(jobs);
        design::run(&o).unwrap()
    };
    let (a, b) = (run(1), run(2));
    for (x, y) in a.candidates.iter().zip(&b.candidates) {
        for (p, q) in x.params.iter().zip(&y.params) {
            assert_eq!(p.std_dev.to_bits(), q.std_dev.to_bits());
        }
        assert_eq!(x.log_det.to_bits(), y.log_det.to_bits());
    }
    assert_eq!(a.rank_d, b.rank_d);
}

/// Bad design input shall be refused before any solve, naming the field and what is
/// allowed.
#[test]
fn bad_design_input_is_refused_naming_the_field() {
    let err = |t: String| {
        let e = design::run(&DesignOptions::new(source(t))).unwrap_err();
        let text = e.messages().join(": ");
        assert_eq!(e.kind(), ErrorKind::Config, "{text}");
        text
    };
    let c = maxwell_candidates();
    let e = err(text(MAXWELL, MAXWELL_ID, "Relative(0.01)", &[]));
    assert!(e.contains("design.candidates is empty"), "{e}");
    let e = err(text(MAXWELL, MAXWELL_ID, "Relative(0.0)", &c));
    assert!(e.contains("design.noise") && e.contains("> 0"), "{e}");
    let e = err(text(MAXWELL, MAXWELL_ID, "Absolute(-1.0)", &c));
    assert!(e.contains("design.noise"), "{e}");
    let e = err(text(MAXWELL, MAXWELL_ID, "Residual", &c));
    assert!(e.contains("stated noise level"), "{e}");
    let e = err(text(
        MAXWELL,
        MAXWELL_ID,
        "Relative(0.01)",
        &[("a", vec![])],
    ));
    assert!(
        e.contains("design.candidates[0].tests") && e.contains("empty"),
        "{e}"
    );
    let twice = vec![c[0].clone(), ("one rate", c[1].1.clone())];
    let e = err(text(MAXWELL, MAXWELL_ID, "Relative(0.01)", &twice));
    assert!(e.contains("also the name"), "{e}");
    // an unknown field in the section
    let t = text(MAXWELL, MAXWELL_ID, "Relative(0.01)", &c).replace("noise:", "noize:");
    let e = err(t);
    assert!(e.contains("noize"), "{e}");
    // no design section at all
    let t = format!("({MESH} law: {MAXWELL}, {})", history(1.0, 1.0, 0.1));
    let e = err(t);
    assert!(e.contains("no `design` section"), "{e}");
}
