//! The adequacy test under the noise `--noise` draws (multiplicative, uniform: its level
//! follows the force, zero at the ends of R2's curve and largest at the peak), on R2
//! (`examples/r2-norton-hoff.ron`, Norton-Hoff with a yield stress, its own law).
//!
//! - The false-alarm rate: the truth's curve plus the noise of 200 seeds, assessed with the
//!   truth as the "fit" (the residuals are the noise itself, 4 free parameters) and
//!   standardized by the stated multiplicative noise as the pipeline does, is flagged
//!   systematic in 10% of the seeds (at most 12% asserted: not yet the nominal 1-2%, see
//!   the test); assessed as if every point had one variance (before), in 27.5%.
//! - The case that raised the false alarm: R2 fitted with 2% noise, seed 3 (RMS 0.91
//!   σ_rec, runs z -0.33, yet "systematic residuals") is not systematic.
//! - Power: the same data fitted with E held at 60000 MPa (the truth is 1e5, a law that
//!   cannot describe the record) is flagged, and the caveat names the statistic that fired.
//!   (Held at m = 3 instead of 5 the other parameters compensate to within the noise:
//!   RMS 1.20 σ_rec, runs z -1.19, adequate; no residual test can see a misfit below the
//!   noise.)
//!
//! Reference: the truth that synthesized the data (R2: E = 1e5 MPa, K = 1500, m = 5,
//! sY = 500 MPa) and the distribution of the statistics under independent noise.

use std::path::PathBuf;

use indentify_identify::multiplicative_noise;
use indentify_report::{Adequacy, Verdict};
use indentify_study::ConfigSource;
use indentify_study::identify::{self, IdentifyOptions};
use indentify_study::simulate::{self, SimulateOptions};

fn r2() -> ConfigSource {
    ConfigSource::Path(
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples/r2-norton-hoff.ron"),
    )
}

#[test]
fn r2_noise_at_the_truth_is_not_systematic() {
    let o = simulate::run(&SimulateOptions::new(r2())).unwrap();
    assert!(o.failure.is_none());
    let t: Vec<f64> = o.rows.iter().map(|r| r.t).collect();
    let f: Vec<f64> = o.rows.iter().map(|r| r.f).collect();
    let seeds = 200u64;
    let (mut flagged, mut plain, mut classical) = (0, 0, 0);
    for seed in 1..=seeds {
        let noisy = multiplicative_noise(&f, 0.02, seed);
        // as the pipeline assesses a fit that states the noise of --noise
        let a = Adequacy::assess_relative(&t, &noisy, &f, 4).unwrap();
        if a.verdict == Verdict::Systematic {
            flagged += 1;
            println!("seed {seed}: {}", a.message);
        }
        // as it was assessed before: one variance for every point
        let b = Adequacy::assess(&t, &noisy, &f, 4).unwrap();
        plain += usize::from(b.verdict == Verdict::Systematic);
        classical += usize::from(b.noisy_record && b.z_ljung_box > 3.0);
    }
    println!(
        "R2, 2% noise at the truth, {seeds} seeds: systematic {flagged} (assessed with one \
         variance: {plain}; the classical Ljung-Box z > 3 alone: {classical})"
    );
    // measured 2026-11-27: 20 of 200 (10%) against 55 (27.5%) before. Still above the
    // nominal 1-2%: the points below the floor (0.25 F_max, about 40% of R2's points: the
    // early loading and the zero force after contact is lost) keep a smaller standardized
    // variance, the noise estimate's trim then cuts the peak's largest windows and the size
    // test fires (z 3.0-4.5). Not yet fixed; this pins the improvement and fails on a
    // regression.
    assert!(
        flagged as f64 <= 0.12 * seeds as f64,
        "{flagged} false alarms"
    );
    assert!(
        plain > 2 * flagged.max(5),
        "the one-variance assessment was expected to over-reject ({plain} vs {flagged})"
    );
}

fn fit(fixed_e: Option<f64>) -> indentify_study::identify::IdentifyOutcome {
    let mut o = IdentifyOptions::new(r2());
    o.noise = Some((0.02, 3));
    o.refine = false;
    o.figures = false;
    o.jobs = Some(1);
    if let Some(e) = fixed_e {
        o.overrides.fixed = vec![("E".into(), Some(e))];
    }
    identify::run(&o, &mut ()).unwrap()
}

#[test]
fn r2_with_two_percent_noise_seed_3_is_adequate_and_a_wrong_modulus_is_not() {
    let own = fit(None);
    let a = own.adequacy().unwrap();
    let t = &a.tests[0].adequacy;
    println!("own law: {}", t.message);
    println!(
        "  classical Ljung-Box z {:.2}, robust {:.2}",
        t.z_ljung_box, t.z_ljung_box_robust
    );
    assert!(t.noisy_record, "{}", t.message);
    assert_ne!(a.verdict, Verdict::Systematic, "{}", t.message);
    assert!(
        !own.caveats().iter().any(|c| c.contains("systematic")),
        "{:?}",
        own.caveats()
    );

    let wrong = fit(Some(60000.0));
    let a = wrong.adequacy().unwrap();
    let t = &a.tests[0].adequacy;
    println!("E held at 60000: {}", t.message);
    assert_eq!(a.verdict, Verdict::Systematic, "{}", t.message);
    let caveat = &wrong.caveats()[0];
    println!("caveat: {caveat}");
    let fired = t.fired();
    assert!(!fired.is_empty());
    for f in &fired {
        assert!(caveat.contains(&f.statistic), "{caveat}");
    }
}
