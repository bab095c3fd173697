//! The adequacy test under the noise `--noise` draws (multiplicative, uniform: its level
//! follows the force, zero at the ends of R2's curve and largest at the peak), on R2
//! (`examples/r2-norton-hoff.ron`, Norton-Hoff with a yield stress, its own law).
//!
//! - The false-alarm rate: the truth's curve plus the noise of 200 seeds, assessed with the
//!   truth as the "fit" (the residuals are the noise itself, 4 free parameters) and
//!   standardized by the stated multiplicative noise as the pipeline does (the size test
//!   over the 47 of 91 points at or above 0.25 F_max), is flagged systematic in 3 seeds
//!   (1.5%; at most 3% asserted); with the points below the floor held at it in the size
//!   test (before), in 20 (10%); assessed as if every point had one variance, in 55.
//!   `r2_table` (ignored) gives docs/adequacy.md's 1000-seed rows, with a 4-deviation bump.
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
use indentify_report::adequacy::RELATIVE_FLOOR;
use indentify_report::{Adequacy, Verdict};
use indentify_study::ConfigSource;
use indentify_study::identify::{self, IdentifyOptions};
use indentify_study::simulate::{self, SimulateOptions};

fn r2() -> ConfigSource {
    ConfigSource::Path(
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples/r2-norton-hoff.ron"),
    )
}

/// The standardized assessment before the points below the floor were left out: every
/// point divided by `max(|F_model|, 0.25 F_max)` (the "before" column of docs/adequacy.md).
fn floor_held(t: &[f64], y: &[f64], m: &[f64], free: usize) -> Adequacy {
    let floor = RELATIVE_FLOOR * y.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
    let s: Vec<f64> = m.iter().map(|v| v.abs().max(floor)).collect();
    let d: Vec<f64> = y.iter().zip(&s).map(|(v, s)| v / s).collect();
    let mm: Vec<f64> = m.iter().zip(&s).map(|(v, s)| v / s).collect();
    Adequacy::assess(t, &d, &mm, free).unwrap()
}

/// Counts over `seeds` seeds of R2's curve with multiplicative noise `a` at the truth
/// (4 free parameters): flagged systematic as the pipeline assesses it today, with the
/// points below the floor held at it (before), assessed with one variance, and by the
/// classical Ljung-Box `z > 3` alone with one variance, and as today with no free
/// parameter (`dof = n`: the residuals at the truth are the noise, nothing was fitted to
/// them); and the points left out.
fn r2_alarms(
    a: f64,
    bump: f64,
    seeds: std::ops::RangeInclusive<u64>,
) -> ([usize; 5], usize, usize) {
    let o = simulate::run(&SimulateOptions::new(r2())).unwrap();
    assert!(o.failure.is_none());
    let t: Vec<f64> = o.rows.iter().map(|r| r.t).collect();
    let f: Vec<f64> = o.rows.iter().map(|r| r.f).collect();
    // a bump of `bump` local noise deviations (a / sqrt(3) of the force) centred on the
    // peak force, 5% of the history wide
    let i_peak = (0..f.len()).fold(0, |m, i| if f[i] > f[m] { i } else { m });
    let width = 0.05 * t[t.len() - 1];
    let shape: Vec<f64> = t
        .iter()
        .zip(&f)
        .map(|(s, v)| bump * a / 3f64.sqrt() * v * (-((s - t[i_peak]) / width).powi(2)).exp())
        .collect();
    let mut count = [0usize; 5];
    let mut left_out = 0;
    for seed in seeds {
        let noisy: Vec<f64> = multiplicative_noise(&f, a, seed)
            .iter()
            .zip(&shape)
            .map(|(v, b)| v + b)
            .collect();
        // as the pipeline assesses a fit that states the noise of --noise
        let now = Adequacy::assess_relative(&t, &noisy, &f, 4).unwrap();
        if now.verdict == Verdict::Systematic {
            count[0] += 1;
            println!("seed {seed}: {}", now.message);
        }
        left_out = now.left_out;
        count[1] += usize::from(floor_held(&t, &noisy, &f, 4).verdict == Verdict::Systematic);
        let b = Adequacy::assess(&t, &noisy, &f, 4).unwrap();
        count[2] += usize::from(b.verdict == Verdict::Systematic);
        count[3] += usize::from(b.noisy_record && b.z_ljung_box > 3.0);
        // the residuals at the truth are the noise itself: no parameter was fitted to them
        let zero = Adequacy::assess_relative(&t, &noisy, &f, 0).unwrap();
        count[4] += usize::from(zero.verdict == Verdict::Systematic);
    }
    (count, left_out, t.len())
}

/// The false-alarm rate on R2 with 2% multiplicative noise at the truth, 200 seeds: at
/// most 3% (the nominal level of three one-sided tests at 3 deviations is about 0.4%,
/// 1.1-2.4% measured on the unit tests' record; 3% of 200 is 6 seeds, a binomial margin
/// over 2%). Before the points below the floor were left out: 20 of 200.
#[test]
fn r2_noise_at_the_truth_is_not_systematic() {
    let seeds = 200u64;
    let ([flagged, held, plain, classical, _], left_out, n) = r2_alarms(0.02, 0.0, 1..=seeds);
    println!(
        "R2, 2% noise at the truth, {seeds} seeds: systematic {flagged} ({left_out} of {n} \
         points below the floor left out; held at the floor: {held}; assessed with one \
         variance: {plain}; the classical Ljung-Box z > 3 alone: {classical})"
    );
    assert!(
        flagged as f64 <= 0.03 * seeds as f64,
        "{flagged} false alarms"
    );
    assert!(
        held > 2 * flagged.max(5),
        "holding the points below the floor was expected to over-reject ({held} vs {flagged})"
    );
    assert!(
        plain > 2 * flagged.max(5),
        "the one-variance assessment was expected to over-reject ({plain} vs {flagged})"
    );
}

/// The numbers of docs/adequacy.md's R2 table, 1000 seeds at 2% and 0.2% noise:
/// `cargo test -p indentify-study --test adequacy_noise -- --ignored --nocapture r2_table`.
#[test]
#[ignore]
fn r2_table() {
    for (a, bump) in [(0.02, 0.0), (0.002, 0.0), (0.02, 4.0), (0.002, 4.0)] {
        let ([now, held, plain, classical, zero], left_out, n) = r2_alarms(a, bump, 1..=1000);
        println!(
            "| R2 at the truth, a = {a}, bump {bump} σ | {:.1}% (dof = n: {:.1}%) | held at the floor {:.1}% \
             | one variance {:.1}% | classical Ljung-Box alone {:.1}% | {left_out} of {n} \
             left out |",
            now as f64 / 10.0,
            zero as f64 / 10.0,
            held as f64 / 10.0,
            plain as f64 / 10.0,
            classical as f64 / 10.0
        );
    }
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
