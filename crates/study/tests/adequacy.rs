//! Model adequacy through the identification pipeline: R1 (Maxwell) on a coarse mesh with
//! 31 noisy points. Fitted with its own law the residuals pass; fitted with the viscosity
//! held at three times its true value (a law that cannot describe the record: only E is
//! left to fit the relaxation) the fit still ends "converged" with R² near 1, and the
//! verdict, result.json and the caveats say the residuals are systematic.
//!
//! Reference: the truth that synthesized the data (R1: E = 20000 MPa, eta = 30000 MPa s).

use indentify_report::Verdict;
use indentify_study::ConfigSource;
use indentify_study::identify::{self, IdentifyOptions};

fn opts() -> IdentifyOptions {
    let mut o = IdentifyOptions::new(ConfigSource::Default);
    o.sets = [
        "specimen.nr=6",
        "specimen.nz=6",
        "history.segments.0.steps=10",
        "history.segments.1.steps=10",
        "history.segments.2.steps=10",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    o.noise = Some((0.01, 3));
    o.refine = false;
    o.figures = false;
    o.jobs = Some(1);
    o
}

#[test]
fn own_law_passes_and_a_wrong_viscosity_is_flagged_as_systematic() {
    let own = identify::run(&opts(), &mut ()).unwrap();
    assert!(own.converged());
    let a = own.adequacy().unwrap();
    println!("own law: {}", a.tests[0].adequacy.message);
    assert_eq!(a.tests.len(), 1);
    assert_eq!(a.tests[0].adequacy.n, 31);
    assert_ne!(
        a.verdict,
        Verdict::Systematic,
        "{}",
        a.tests[0].adequacy.message
    );
    assert!(own.caveats().is_empty(), "{:?}", own.caveats());
    assert!(own.adequacy_lines().contains("adequacy:"));

    let dir = tempfile::tempdir().unwrap();
    let mut o = opts();
    o.overrides.fixed = vec![("eta".into(), Some(90000.0))];
    o.out = Some(dir.path().to_path_buf());
    let wrong = identify::run(&o, &mut ()).unwrap();
    let a = wrong.adequacy().unwrap();
    let q = wrong.quality.unwrap();
    println!(
        "eta held 3x: R2 {:.5}, {}",
        q.r2, a.tests[0].adequacy.message
    );
    assert_eq!(a.verdict, Verdict::Systematic);
    assert!(wrong.caveats()[0].contains("systematic residuals"));
    assert!(wrong.headline_status().contains("caveats"));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("result.json")).unwrap())
            .unwrap();
    assert_eq!(json["adequacy"]["verdict"], "systematic");
    assert_eq!(json["adequacy"]["tests"][0]["n"], 31);
    assert!(
        json["caveats"][0]
            .as_str()
            .unwrap()
            .contains("the standard deviations assume")
    );
}
