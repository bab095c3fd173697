//! `cargo xtask multi-rate`: the joint fit of `examples/r2-multi-rate.ron` (R2 Norton-Hoff,
//! three loading rates held 10 s) from the paper's eight Table III starts with
//! Levenberg-Marquardt and with BFGS (are E, K, m, sY within 1% of the truth in at most 25
//! iterations?), and the coverage of the 2-sigma intervals with 2% multiplicative noise
//! over 20 seeds. The coverage fits run with `identify.noise = RelativeEstimated` (the
//! deviations of a multiplicative noise whose level is estimated from the residuals,
//! sandwich covariance); the table also gives the z-scores for the stated level
//! `a / sqrt(3)` (the same covariance scaled by the ratio of the levels). `--sigma
//! residual` runs them with the classical one-variance deviations instead. Prints a
//! Markdown report (docs/joint-fits.md quotes it).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Result, bail};
use indentify_study::ConfigSource;
use indentify_study::config::{BfgsStartName, MethodName, NoiseSetting, Overrides};
use indentify_study::identify::{self, IdentifyOptions, IdentifyOutcome};
use xtask::paper::{PAPER_III, R2_TRUTH};

/// The free parameters and their truth.
const FREE: [(&str, f64); 4] = [
    ("E", R2_TRUTH[0]),
    ("K", R2_TRUTH[2]),
    ("m", R2_TRUTH[3]),
    ("sY", R2_TRUTH[4]),
];

/// Options of the study.
struct Options {
    config: PathBuf,
    sets: Vec<String>,
    max_iterations: usize,
    seeds: u64,
    noise: f64,
    methods: Vec<MethodName>,
    starts: Vec<usize>,
    jobs: Option<usize>,
    coverage: bool,
    /// The coverage fits' noise model: `RelativeEstimated` (true) or `Residual` (false).
    relative: bool,
    /// First seed of the coverage.
    first_seed: u64,
    /// BFGS's initial inverse Hessian (default: the configuration's).
    bfgs_start: Option<BfgsStartName>,
}

/// `cargo xtask multi-rate [--max-iter 25] [--seeds 20] [--noise 0.02] [--methods lm,bfgs]
/// [--starts 1,..,8] [--jobs N] [--coarse] [--no-coverage] [--no-starts] [--set K=V]
/// [--bfgs-start scaled|gauss-newton]`.
pub fn run(args: &[String]) -> Result<()> {
    let o = parse_options(args)?;
    let clock = Instant::now();
    println!(
        "## Joint fit of `{}` ({} iterations at most){}\n",
        o.config.display(),
        o.max_iterations,
        if o.sets.is_empty() {
            String::new()
        } else {
            format!(", --set {}", o.sets.join(" --set "))
        }
    );
    println!("Exact data; truth E = 100000 MPa, K = 1500 MPa s^(1/m), m = 5, sY = 500 MPa.\n");
    starts_table(&o)?;
    if o.coverage {
        coverage(&o)?;
    }
    println!(
        "\n(cargo xtask multi-rate, {:.0} s wall time)",
        clock.elapsed().as_secs_f64()
    );
    Ok(())
}

/// The options of `cargo xtask multi-rate`.
fn parse_options(args: &[String]) -> Result<Options> {
    let mut o = Options {
        config: PathBuf::from("examples/r2-multi-rate.ron"),
        sets: Vec::new(),
        max_iterations: 25,
        seeds: 20,
        noise: 0.02,
        methods: vec![MethodName::Lm, MethodName::Bfgs],
        starts: (1..=PAPER_III.len()).collect(),
        jobs: None,
        coverage: true,
        relative: true,
        first_seed: 1,
        bfgs_start: None,
    };
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut val = || it.next().cloned().unwrap_or_default();
        match a.as_str() {
            "--max-iter" => o.max_iterations = val().parse()?,
            "--seeds" => o.seeds = val().parse()?,
            "--noise" => o.noise = val().parse()?,
            "--jobs" => o.jobs = Some(val().parse()?),
            "--no-coverage" => o.coverage = false,
            "--first-seed" => o.first_seed = val().parse()?,
            "--sigma" => {
                o.relative = match val().as_str() {
                    "relative" => true,
                    "residual" => false,
                    other => bail!("--sigma {other}: expected relative or residual"),
                }
            }
            "--no-starts" => o.methods.clear(),
            "--bfgs-start" => {
                o.bfgs_start = Some(match val().as_str() {
                    "scaled" => BfgsStartName::Scaled,
                    "gauss-newton" => BfgsStartName::GaussNewton,
                    other => bail!("--bfgs-start {other}: expected scaled or gauss-newton"),
                })
            }
            "--set" => o.sets.push(val()),
            "--coarse" => {
                for k in 0..3 {
                    o.sets.push(format!("tests.{k}.history.segments.0.steps=8"));
                    o.sets.push(format!("tests.{k}.history.segments.1.steps=4"));
                    o.sets.push(format!("tests.{k}.history.segments.2.steps=4"));
                }
                o.sets.push("specimen.nr=10".into());
                o.sets.push("specimen.nz=10".into());
                o.sets.push("specimen.grading_r=1.6".into());
                o.sets.push("specimen.grading_z=1.6".into());
            }
            "--methods" => {
                o.methods = val()
                    .split(',')
                    .map(|m| match m {
                        "lm" => Ok(MethodName::Lm),
                        "bfgs" => Ok(MethodName::Bfgs),
                        "lbfgs" => Ok(MethodName::Lbfgs),
                        "lbfgsb" => Ok(MethodName::Lbfgsb),
                        other => bail!("unknown method {other}"),
                    })
                    .collect::<Result<_>>()?;
            }
            "--starts" => {
                o.starts = val().split(',').map(str::parse).collect::<Result<_, _>>()?;
                if o.starts.iter().any(|&s| s == 0 || s > PAPER_III.len()) {
                    bail!("--starts: rows 1 to {}", PAPER_III.len());
                }
            }
            other => bail!("unknown option {other}"),
        }
    }
    Ok(o)
}

/// The joint fit from each of Table III's starts by each method, a table row each.
fn starts_table(o: &Options) -> Result<()> {
    println!(
        "| method | start (E, K, m, sY) | iterations | stop | E | K | m | sY | all within 1% |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    let mut ok_counts = Vec::new();
    for &method in &o.methods {
        let mut ok = 0;
        for &row in &o.starts {
            let start = PAPER_III[row - 1].0;
            let out = fit(o, method, &start, None)?;
            let errs = rel_errors(&out);
            let within = errs.iter().all(|e| e.abs() <= 0.01);
            ok += usize::from(within);
            println!(
                "| {:?} | {} ({}, {}, {}, {}) | {} | {} | {} | {} |",
                method,
                row,
                start[0],
                start[1],
                start[2],
                start[3],
                out.result.iterations,
                out.result.stop_reason,
                errs.iter()
                    .map(|e| format!("{:+.2e}", e))
                    .collect::<Vec<_>>()
                    .join(" | "),
                if within { "yes" } else { "no" }
            );
        }
        ok_counts.push((method, ok));
    }
    println!();
    for (m, ok) in &ok_counts {
        println!(
            "- {m:?}: {ok} of {} starts end with all four parameters within 1% of the truth.",
            o.starts.len()
        );
    }
    Ok(())
}

/// The noise coverage: LM from Table III's start 1 on noisy data, one row per seed, the
/// 2-sigma intervals' coverage of the truth.
fn coverage(o: &Options) -> Result<()> {
    println!(
        "\n### Coverage: {}% multiplicative noise, {} seeds, LM from Table III start 1\n",
        100.0 * o.noise,
        o.seeds
    );
    let stated = o.noise / 3f64.sqrt();
    if o.relative {
        println!(
            "Deviations: `identify.noise = RelativeEstimated` (multiplicative noise, level \
             estimated from the residuals, sandwich covariance); z = (value - truth) / \
             sigma with that level, z_stated with the stated level a/sqrt(3) = {:.4}%.\n",
            100.0 * stated
        );
        println!(
            "| seed | iterations | stop | E | K | m | sY | estimated level | z (E, K, m, sY) | z_stated |"
        );
        println!("|---|---|---|---|---|---|---|---|---|---|");
    } else {
        println!("Deviations: `identify.noise = Residual` (one variance, 2J/(n-p)).\n");
        println!("| seed | iterations | stop | E | K | m | sY | z (E, K, m, sY) |");
        println!("|---|---|---|---|---|---|---|---|");
    }
    let mut covered_all = [0usize; 2];
    let mut covered = [[0usize; 4]; 2];
    for seed in o.first_seed..o.first_seed + o.seeds {
        let out = fit(o, MethodName::Lm, &PAPER_III[0].0, Some((o.noise, seed)))?;
        let errs = rel_errors(&out);
        let level = out
            .result
            .identifiability
            .as_ref()
            .map_or(f64::NAN, |i| i.noise_level);
        let z: Vec<f64> = FREE
            .iter()
            .map(|&(n, t)| {
                let v = out.value(n).unwrap_or(f64::NAN);
                out.std_dev(n).map_or(f64::INFINITY, |s| (v - t) / s)
            })
            .collect();
        // the sandwich covariance scales with the square of the level
        let z_stated: Vec<f64> = z.iter().map(|z| z * level / stated).collect();
        for (k, zs) in [&z, &z_stated].into_iter().enumerate() {
            let cov: Vec<bool> = zs.iter().map(|z| z.abs() <= 2.0).collect();
            for (c, &b) in covered[k].iter_mut().zip(&cov) {
                *c += usize::from(b);
            }
            covered_all[k] += usize::from(cov.iter().all(|&b| b));
        }
        let show = |z: &[f64]| {
            z.iter()
                .map(|z| format!("{z:+.2}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let errs = errs
            .iter()
            .map(|e| format!("{:+.2e}", e))
            .collect::<Vec<_>>()
            .join(" | ");
        if o.relative {
            println!(
                "| {seed} | {} | {} | {errs} | {:.3}% | {} | {} |",
                out.result.iterations,
                out.result.stop_reason,
                100.0 * level,
                show(&z),
                show(&z_stated)
            );
        } else {
            println!(
                "| {seed} | {} | {} | {errs} | {} |",
                out.result.iterations,
                out.result.stop_reason,
                show(&z)
            );
        }
    }
    let c = &covered[0];
    println!(
        "\n- 2-sigma intervals cover the truth: all four parameters in {} of {} seeds; per \
         parameter E {}, K {}, m {}, sY {}.",
        covered_all[0], o.seeds, c[0], c[1], c[2], c[3]
    );
    if o.relative {
        let c = &covered[1];
        println!(
            "- With the stated level: all four in {} of {} seeds; per parameter E {}, K {}, \
             m {}, sY {}.",
            covered_all[1], o.seeds, c[0], c[1], c[2], c[3]
        );
    }
    Ok(())
}

/// One joint fit from `start` (E, K, m, sY).
fn fit(
    o: &Options,
    method: MethodName,
    start: &[f64; 4],
    noise: Option<(f64, u64)>,
) -> Result<IdentifyOutcome> {
    let mut opts = IdentifyOptions::new(ConfigSource::Path(o.config.clone()));
    opts.sets = o.sets.clone();
    opts.refine = false;
    opts.figures = false;
    opts.noise = noise;
    opts.jobs = o.jobs;

    opts.overrides = Overrides {
        starts: FREE
            .iter()
            .zip(start)
            .map(|(&(n, _), &v)| (n.to_string(), v))
            .collect(),
        method: Some(method),
        max_iterations: Some(o.max_iterations),
        // stated either way: without it, synthesized noise makes the default Relative(a/sqrt 3)
        noise: noise.map(|_| {
            if o.relative {
                NoiseSetting::RelativeEstimated
            } else {
                NoiseSetting::Residual
            }
        }),
        bfgs_start: o.bfgs_start,
        ..Overrides::default()
    };
    Ok(identify::run(&opts, &mut ())?)
}

/// `(value - truth) / truth` of E, K, m, sY.
fn rel_errors(out: &IdentifyOutcome) -> Vec<f64> {
    FREE.iter()
        .map(|&(n, t)| (out.value(n).unwrap_or(f64::NAN) - t) / t)
        .collect()
}
