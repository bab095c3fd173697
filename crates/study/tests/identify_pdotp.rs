//! `identify` of a load-controlled record loaded at a constant Pdot/P
//! (`examples/pdotp-maxwell.ron`; docs/validation-load-control.md §12): a trigger ramp to
//! 5 N, Pdot/P = 1/s to 100 N, a 2 s hold and an unload to 10 N, the force prescribed and
//! the depth fitted, Maxwell's E and eta free from a start 40% and 167% off the truth.
//!
//! References: the law values that generated the data. Exact synthesized depths: the
//! identified (E, eta) equal them to 1e-6 relative. 1% multiplicative noise on the depth
//! (three seeded draws): the fit converges and lands within 2.5 of its own standard
//! deviations of the truth, deviations below 10% of the values. The fitted record carries
//! the exponential force of the Pdot/P segment.
//!
//! ```text
//!   the example on an 8 x 8 mesh (10 x 10 in the file)
//! ```

use indentify_study::identify::{self, IdentifyOptions};
use indentify_study::source::ConfigSource;

const TRUTH: [(&str, f64); 2] = [("E", 20000.0), ("eta", 30000.0)];

fn options() -> IdentifyOptions {
    let mut o = IdentifyOptions::new(ConfigSource::Path(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/pdotp-maxwell.ron"),
    ));
    o.sets = vec!["specimen.nr=8".into(), "specimen.nz=8".into()];
    o.refine = false;
    o.figures = false;
    o
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// Exact synthesized depths: the fit from the example's start converges on the truth.
#[test]
fn pdotp_record_exact_depths_give_back_the_truth() {
    let o = identify::run(&options(), &mut ()).unwrap();
    println!(
        "{} after {} iterations: E = {:?}, eta = {:?}",
        o.result.stop_reason,
        o.result.iterations,
        o.value("E"),
        o.value("eta")
    );
    assert!(o.converged(), "{}", o.result.stop_reason);
    assert_eq!(o.fit.observable, indentify_study::Observable::Depth);
    for (name, truth) in TRUTH {
        let v = o.value(name).unwrap();
        assert!(rel(v, truth) < 1e-6, "{name} = {v}, truth {truth}");
    }
    // the prescribed series is the force: the trigger ramp to 5 N, then on the Pdot/P
    // rows P = 5 exp(1.0 (t - 0.1)) N up to 100 N at t = 0.1 + ln 20 s
    let (t, f) = (&o.fit.t, &o.fit.h);
    let t_end = 0.1 + 20f64.ln();
    let mut on_exp = 0;
    for (&ti, &fi) in t.iter().zip(f) {
        if ti > 0.1 + 1e-9 && ti < t_end + 1e-9 {
            let p = 5.0 * (ti - 0.1).exp();
            assert!((fi - p).abs() < 1e-7 * p, "t = {ti}: {fi} vs {p}");
            on_exp += 1;
        }
    }
    assert_eq!(on_exp, 10, "{t:?}");
    // the hold creeps: the depth at the end of the hold beyond the depth at its start
    let h = &o.fit.f_data;
    let k = t.iter().position(|&ti| (ti - t_end).abs() < 1e-9).unwrap();
    assert!(h[k + 6] > 1.05 * h[k], "{} -> {}", h[k], h[k + 6]);
}

/// 1% noise on the depth, three seeded draws: converged, within 2.5 sigma of the truth.
#[test]
fn pdotp_record_with_noisy_depths_lands_within_its_deviations() {
    for seed in [1, 2, 3] {
        let mut o = options();
        o.noise = Some((0.01, seed));
        let out = identify::run(&o, &mut ()).unwrap();
        println!(
            "seed {seed}: {} after {} iterations",
            out.result.stop_reason, out.result.iterations
        );
        assert!(out.converged(), "seed {seed}: {}", out.result.stop_reason);
        for (name, truth) in TRUTH {
            let v = out.value(name).unwrap();
            let s = out.std_dev(name).expect("a standard deviation");
            println!(
                "  {name} = {v:.2} (truth {truth}), sigma {s:.2} ({:.3}%), |v - truth| / sigma = {:.2}",
                100.0 * s / truth,
                (v - truth).abs() / s
            );
            assert!(s > 0.0 && s < 0.1 * truth, "{name}: sigma {s}");
            assert!(
                (v - truth).abs() <= 2.5 * s,
                "seed {seed}: {name} = {v}, truth {truth}, sigma {s}"
            );
        }
    }
}
