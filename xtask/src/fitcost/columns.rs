//! `cargo xtask fit-cost --columns`: one sensitivity pass of every parameter against one
//! of the free parameters only (what an identification forms), back to back on one
//! thread at the fit's start, with a forward run of the same point for the scale: the
//! time of each over the forward run's, and whether the free columns are the same bits.

use std::path::Path;
use std::time::Instant;

use anyhow::{Result, bail};
use indentify_identify::Evaluator;
use indentify_study::identify;
use serde_json::{Value, json};

/// One case: `rounds` rounds of (forward, all columns, free columns) at points 1e-6 apart,
/// the order of the two passes alternating between rounds; medians.
pub fn measure(root: &Path, case: &str, rounds: usize) -> Result<Value> {
    let opts = super::options(root, case)?;
    let resolved = identify::resolve(&opts)?;
    let mut s = identify::setup(resolved, &opts)?;
    s.problem.set_threads(1)?;
    s.problem.set_warm_start(false);
    let start: Vec<f64> = s
        .id_cfg
        .params
        .iter()
        .map(|p| p.value.unwrap_or(0.0))
        .collect();
    let free: Vec<usize> = s
        .id_cfg
        .params
        .iter()
        .filter(|p| p.free)
        .filter_map(|p| s.names.iter().position(|n| *n == p.name))
        .collect();
    let (mut fwd, mut all, mut part) = (Vec::new(), Vec::new(), Vec::new());
    let mut same = true;
    s.problem.install(|| -> Result<()> {
        let mut ev = Evaluator::new(&s.problem)?;
        for r in 0..rounds {
            let c: Vec<f64> = start
                .iter()
                .map(|v| v * (1.0 + 1e-6 * (r as f64 + 1.0)))
                .collect();
            let clock = Instant::now();
            ev.cost(&c)?;
            fwd.push(clock.elapsed().as_secs_f64());
            let mut pass = |cols: Option<Vec<usize>>| -> Result<(f64, Vec<Vec<f64>>)> {
                ev.set_jacobian_columns(cols);
                let clock = Instant::now();
                let j = ev.jacobian(&c)?;
                Ok((clock.elapsed().as_secs_f64(), j))
            };
            let (ja, jf) = if r % 2 == 0 {
                let a = pass(None)?;
                (a, pass(Some(free.clone()))?)
            } else {
                let f = pass(Some(free.clone()))?;
                (pass(None)?, f)
            };
            all.push(ja.0);
            part.push(jf.0);
            for (ra, rf) in ja.1.iter().zip(&jf.1) {
                same &= free.iter().all(|&k| ra[k].to_bits() == rf[k].to_bits());
            }
        }
        Ok(())
    })?;
    if !same {
        bail!("{case}: the free columns differ from the full Jacobian's");
    }
    let (f, a, p) = (
        super::median(&mut fwd),
        super::median(&mut all),
        super::median(&mut part),
    );
    Ok(json!({
        "case": case,
        "params": s.names.len(),
        "free": free.len(),
        "forward_s": f,
        "all_s": a,
        "free_s": p,
        "all_over_forward": a / f,
        "free_over_forward": p / f,
        "free_over_all": p / a,
        "same_bits": same,
    }))
}

/// `--columns`: [`measure`] of each case, printed as a table row as it finishes.
pub fn sweep(root: &Path, cases: &[&str], rounds: usize) -> Result<Vec<Value>> {
    println!(
        "| case | free / parameters | forward (s) | all columns / forward | free columns / forward | free / all |"
    );
    println!("|---|---|---|---|---|---|");
    let mut results = Vec::new();
    for case in cases {
        let m = measure(root, case, rounds)?;
        println!(
            "| {case} | {} / {} | {:.3} | {:.3} | {:.3} | {:.3} |",
            m["free"],
            m["params"],
            m["forward_s"].as_f64().unwrap_or(f64::NAN),
            m["all_over_forward"].as_f64().unwrap_or(f64::NAN),
            m["free_over_forward"].as_f64().unwrap_or(f64::NAN),
            m["free_over_all"].as_f64().unwrap_or(f64::NAN)
        );
        results.push(m);
    }
    Ok(results)
}
