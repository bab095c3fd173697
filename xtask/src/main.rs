//! `cargo xtask`: project automation. `cargo xtask paper-tables` regenerates
//! docs/paper-tables.md and its figures (docs/figures/*.svg) from the reference problems.

use anyhow::{Context, Result, bail};
use indentify_identify::Method;
use xtask::paper::{self, Data, Options, Setup, Stopwatch, Table};

mod fitcost;
mod fuzz;
mod jointcost;
mod map;
mod multirate;
mod newcomer;
mod reallaws;
mod slurm;

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        Some("paper-tables") => paper_tables(&args[1..]),
        Some("compare-methods") => compare_methods(),
        Some("fuzz-readers") => fuzz::run(&args[1..]),
        Some("make-map") => map::run(&args[1..]),
        Some("fuzz-configs") => fuzz_configs(&args[1..]),
        Some("slurm-check") => slurm::run(&args[1..]),
        Some("calculix") => calculix(&args[1..]),
        Some("mesh-study") => mesh_study(&args[1..]),
        Some("multi-rate") => multirate::run(&args[1..]),
        Some("joint-cost") => jointcost::run(&args[1..]),
        Some("fit-cost") => fitcost::run(&args[1..]),
        Some("tidy") => tidy(),
        Some("newcomer-walk") => newcomer::run(&args[1..]),
        Some("doc-numbers") => newcomer::doc_numbers(&args[1..]),
        Some("real-laws") => reallaws::run(&args[1..]),
        Some("dao") => xtask::dao::run(&args[1..]),
        _ => {
            eprintln!(
                "usage: cargo xtask paper-tables [--only I,II,III] [--rows 1,2,..] [--threads N] [--max-iter-r2 N] [--method-r2 bfgs|lbfgs|lbfgsb|lm] [--coarse] [--print]\n       cargo xtask compare-methods   (R1 from the paper's four starts with each method)\n       cargo xtask fuzz-readers [--cases N] [--seed S]   (records readers and preprocessing on random and mutated files)\n       cargo xtask make-map [DIR] [--n 10] [--noise 0.02] [--seed 1] [--coarse] [--run] [--jobs N]   (a synthetic two-phase Maxwell map for indentify batch)\n       cargo xtask fuzz-configs [--cases N] [--seed S]   (mutated configurations and --set values through check and simulate)\n       cargo xtask slurm-check [--keep] [--array N] [--timeout SECONDS] [--indentify PATH]   (indentify batch slurm on a real one-node Slurm started here, as root)\n       cargo xtask calculix [--out DIR] [--cases r0,r1,r2,r2-sy0,r0-nu049,r2-j2-linear,r2-j2-power] [--friction 0,0.1,0.2] [--kinematics small,nlgeom] [--penalty K] [--contact node-to-surface|surface-to-surface] [--decks-only] [--reuse] [--no-ccx] [--split-load] [--elastic neo-hooke|mooney-rivlin|hencky-umat] [--ccx PATH] [--load-substeps N] [--drive depth|force]   (CalculiX referee of normal contact, friction and finite strain; needs ccx)\n       cargo xtask mesh-study [--configs A.ron,B.ron] [--levels 1|2|3] [--set path=value ...] [--auto N:K:G[:C],...] [--no-candidate-fine-steps] [--additive-reference] [--steps-only] [--reference F1,F2,F3,F4]   (force vs meshes and steps refined 2x, 4x; Auto() candidates)\n       cargo xtask multi-rate [--max-iter 25] [--seeds 20] [--noise 0.02] [--methods lm,bfgs] [--starts 1,..,8] [--jobs N] [--coarse] [--no-coverage] [--no-starts]   (joint fit of examples/r2-multi-rate.ron from Table III's starts; 2-sigma coverage with noise; --sigma relative|residual, --first-seed S)\n       cargo xtask joint-cost [--rounds 5] [--threads 2] [--config FILE] [--set K=V]   (one joint cost + gradient vs the slowest single test, back to back)\n       cargo xtask fit-cost [--only r1-map,r2,r2-noisy,ht-nh,anon-nh,ht-nh-joint] [--quick] [--rounds 3] [--json FILE] [--compare FILE] [--no-chi2] [--valley [--valley-steps N] [--valley-chi2 X]] [--columns] [--lm-radius R] [--line-model] [--geodesic] [--c2f N [--c2f-tight] [--c2f-space F] [--c2f-keep-time] [--c2f-correct K] [--c2f-fine-radius R]] [--batch [--jobs 2] [--map-n 10] [--profile] [--op]] [--proposed-step [--both]] [--no-proposed-step] [--no-stop-rejected] [--lm-damping classic|nielsen|marquardt-fletcher|gain-capped|delayed] [--lm-subspace]   (a whole fit's wall and CPU time over one forward run's, one thread, back to back; --compare: before/after and |shift| / sigma; --batch: the 100-indent map through the batch path from the base start, closed-form starts with their own calibration, seeded, each without and with proposed_step (--op: and O&P first guesses); --profile: one indent's stages; --proposed-step: each case with the stop on the proposed step and, where it fired, without it, shifts and outcomes, the LM examples too)\n       cargo xtask newcomer-walk [--skip SUBSTRING,...] [--timeout SECONDS] [--keep] [--list]   (every README and docs/tutorial*.md command, in order, in a fresh clone of HEAD: exit status and time of each)\n       cargo xtask doc-numbers [--cheap]   (every number the docs quote from the tool, the long runs included, against a release build's output: crates/cli/tests/doc_numbers.rs)\n       cargo xtask tidy   (the repository's rules: layers, unused dependencies, //! lines, no outside references, function lengths)\n       cargo xtask real-laws [--only CASES] [--out DIR] [--refine] [--jobs N] [--table]   (Plastic and Prony on the real records, the mystical sY-n pairs, design of hardening tests: docs/tutorial-real-data.md)\n       cargo xtask dao [--ratios 50,200,1000] [--n 0,0.2,0.4] [--meshes 12,24] [--load-steps 30] [--friction 0.15] [--jobs N]   (J2 with power-law hardening under a 70.3-degree cone against Dao et al.'s dimensionless functions: docs/validation-laws.md §9)"
            );
            bail!("unknown or missing command")
        }
    }
}

/// `cargo xtask tidy`: every finding on its own line, exit 1 when there is any.
fn tidy() -> Result<()> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .context("workspace root")?;
    let found = xtask::tidy::run(root).context("reading the workspace")?;
    for f in &found {
        println!("{f}");
    }
    if found.is_empty() {
        println!(
            "tidy: layers, dependencies, //! lines, references and function lengths all clean"
        );
        Ok(())
    } else {
        bail!("tidy: {} finding(s)", found.len())
    }
}

fn paper_tables(args: &[String]) -> Result<()> {
    let clock = Stopwatch::start();
    let mut only: Option<Vec<Table>> = None;
    let mut rows: Option<Vec<usize>> = None;
    let mut opts = Options {
        setup: Setup::REFERENCE,
        threads: std::thread::available_parallelism().map_or(2, |n| n.get()),
        max_iterations_r1: 60,
        max_iterations_r2: 60,
        valleys: true,
        method_r2: Method::LevenbergMarquardt,
        max_iterations_bfgs_r2: 70,
    };
    let mut write = true;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut val = || it.next().cloned().unwrap_or_default();
        match a.as_str() {
            "--only" => {
                only = Some(
                    val()
                        .split(',')
                        .filter_map(|t| match t {
                            "I" => Some(Table::I),
                            "II" => Some(Table::II),
                            "III" => Some(Table::III),
                            _ => None,
                        })
                        .collect(),
                );
                write = false;
            }
            "--rows" => {
                rows = Some(val().split(',').filter_map(|r| r.parse().ok()).collect());
                write = false;
            }
            "--threads" => opts.threads = val().parse()?,
            "--max-iter-r2" => opts.max_iterations_r2 = val().parse()?,
            "--coarse" => {
                opts.setup = Setup::COARSE;
                write = false;
            }
            "--print" => write = false,
            "--method-r2" => {
                opts.method_r2 =
                    Method::from_name(&val()).ok_or_else(|| anyhow::anyhow!("unknown method"))?;
            }
            other => bail!("unknown option {other}"),
        }
    }
    let mut jobs: Vec<_> = paper::all_jobs();
    if opts.method_r2 != Method::Bfgs {
        jobs.push(paper::bfgs_reference_job());
    }
    let jobs: Vec<_> = jobs
        .into_iter()
        .filter(|j| only.as_ref().is_none_or(|o| o.contains(&j.table)))
        .filter(|j| rows.as_ref().is_none_or(|r| r.contains(&j.row)))
        .collect();
    let need_r2 = jobs.iter().any(|j| j.table == Table::III);
    let data = Data::new(&opts.setup, need_r2)?;
    eprintln!("data synthesized in {:.1} s", clock.seconds());
    let outcomes = paper::run_jobs(&opts, &data, &jobs)?;
    let total = clock.seconds();
    println!("{}", paper::render_tables(&outcomes, true));
    println!("{}", paper::render_bfgs_reference(&outcomes, true));
    println!("{}", paper::render_valleys(&outcomes));
    if write {
        // xtask lives in <root>/xtask: the workspace root is its parent
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .parent()
            .map(std::path::Path::to_path_buf)
            .unwrap_or_default();
        xtask::doc::write(&root, &opts, &data, &outcomes, total)?;
        eprintln!("wrote {}", root.join("docs/paper-tables.md").display());
    }
    eprintln!("paper-tables: {:.1} s", clock.seconds());
    Ok(())
}

/// Runs R1 (reference set-up, exact data) from the paper's four starts with each method and
/// prints iterations, solves, accuracy and time: the measurement behind the choice of
/// methods (BFGS-Armijo, L-BFGS/More-Thuente, L-BFGS-B, LM).
fn compare_methods() -> Result<()> {
    let setup = Setup::REFERENCE;
    let data = Data::new(&setup, false)?;
    let record = indentify_identify::ForceRecord::new(data.schedule.t.clone(), data.r1.clone())?;
    let problem = indentify_identify::Problem::new(
        setup.model()?,
        &indentify_laws::Maxwell,
        data.schedule.clone(),
        &record,
        None,
        indentify_contact::SolverOptions::default(),
    )?;
    println!("| method | start | iter | fwd | adj | sens | max rel. err | stop | time (s) |");
    println!("|---|---|---|---|---|---|---|---|---|");
    for method in [
        Method::Bfgs,
        Method::Lbfgs { memory: 5 },
        Method::Lbfgsb { memory: 5 },
        Method::LevenbergMarquardt,
    ] {
        for (start, _) in paper::PAPER_I {
            let mut cfg = paper::config(Table::I, &start, 100);
            cfg.method = method;
            cfg.identifiability = false;
            let r = indentify_identify::identify(&problem, &cfg, &mut |_| {})?;
            let err = paper::rel_errors(Table::I, &r.free_values())
                .iter()
                .fold(0.0f64, |m, e| m.max(e.abs()));
            println!(
                "| {} | ({}, {}) | {} | {} | {} | {} | {:.1e} | {} | {:.1} |",
                method.name(),
                start[0],
                start[1],
                r.iterations,
                r.forward_solves,
                r.adjoint_solves,
                r.sensitivity_solves,
                err,
                r.stop_reason,
                r.seconds
            );
        }
    }
    Ok(())
}

/// `cargo xtask fuzz-configs [--cases N] [--seed S]`: mutated configurations and random
/// `--set` values through loading, set-up and simulation (indentify_study::fuzzing).
fn fuzz_configs(args: &[String]) -> Result<()> {
    let (mut cases, mut seed) = (20_000usize, 1u64);
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut val = || it.next().cloned().unwrap_or_default();
        match a.as_str() {
            "--cases" => cases = val().parse()?,
            "--seed" => seed = val().parse()?,
            other => bail!("unknown option {other}"),
        }
    }
    let t0 = std::time::Instant::now();
    let c = indentify_study::fuzzing::run(seed, cases);
    println!(
        "fuzz-configs: {} cases in {:.1} s: {} configuration errors, {} data errors, {} solver \
         errors, {} simulated, {} too large to simulate; {} panics, {} non-finite forces",
        c.cases,
        t0.elapsed().as_secs_f64(),
        c.config_errors,
        c.data_errors,
        c.solver_errors,
        c.simulated,
        c.too_large,
        c.panics,
        c.non_finite
    );
    if c.panics > 0 || c.non_finite > 0 {
        bail!("{} panics and {} non-finite forces", c.panics, c.non_finite);
    }
    Ok(())
}

/// `cargo xtask calculix`: CalculiX decks of R0, R1, R2 (sY = 500 and 0) with our mesh and
/// a rigid cone in node-to-surface penalty contact, small strain and `NLGEOM`, frictionless
/// and with Coulomb friction, run by `ccx`, compared with our `Normal` contact,
/// `Normal(friction: mu)` and `kinematics: Finite` (xtask::calculix).
fn calculix(args: &[String]) -> Result<()> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map(std::path::Path::to_path_buf)
        .unwrap_or_default();
    let mut o = xtask::calculix::RunOptions {
        out: root.join("validation/calculix"),
        root,
        cases: xtask::calculix::CASES
            .iter()
            .filter(|c| c.name != "r0-nu049" && xtask::calculix::j2_case(c.name).is_none())
            .map(|c| c.name.to_string())
            .collect(),
        frictions: vec![0.0, 0.1, 0.2],
        kinematics: vec![false, true],
        deck: xtask::calculix::DeckOptions::default(),
        decks_only: false,
        reuse: false,
        no_ccx: false,
        ccx: "ccx".into(),
    };
    let mut force = false;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut val = || it.next().cloned().unwrap_or_default();
        match a.as_str() {
            "--out" => o.out = val().into(),
            "--cases" => o.cases = val().split(',').map(str::to_string).collect(),
            "--friction" => {
                o.frictions = val()
                    .split(',')
                    .map(|x| {
                        x.parse::<f64>()
                            .ok()
                            .filter(|m| m.is_finite() && *m >= 0.0)
                            .ok_or_else(|| {
                                anyhow::anyhow!("--friction: `{x}` is not a coefficient >= 0")
                            })
                    })
                    .collect::<Result<_>>()?;
            }
            "--kinematics" => {
                o.kinematics = val()
                    .split(',')
                    .map(|x| match x {
                        "small" => Ok(false),
                        "nlgeom" => Ok(true),
                        _ => bail!("--kinematics: `{x}` is not small or nlgeom"),
                    })
                    .collect::<Result<_>>()?;
            }
            "--penalty" => {
                let v = val();
                o.deck.penalty = v
                    .parse::<f64>()
                    .ok()
                    .filter(|k| k.is_finite() && *k > 0.0)
                    .ok_or_else(|| {
                        anyhow::anyhow!("--penalty: `{v}` is not a slope > 0 (MPa/mm)")
                    })?;
                o.deck.stick_slope = o.deck.penalty / 10.0;
            }
            "--contact" => o.deck.contact = xtask::calculix::ContactType::from_name(&val())?,
            "--decks-only" => o.decks_only = true,
            "--reuse" => o.reuse = true,
            "--no-ccx" => o.no_ccx = true,
            "--split-load" => o.deck.split_load = true,
            "--ccx" => {
                let v = val();
                if v.is_empty() {
                    bail!("--ccx: expected the path of a CalculiX executable");
                }
                // a path (not a bare name looked up on PATH) is made absolute: ccx runs
                // in a scratch folder
                let p = std::path::PathBuf::from(&v);
                o.ccx = if p.components().count() > 1 {
                    std::path::absolute(&p).map_err(|e| anyhow::anyhow!("--ccx: `{v}`: {e}"))?
                } else {
                    p
                };
            }
            "--elastic" => {
                o.deck.finite_elastic = xtask::calculix::FiniteElastic::from_name(&val())?;
            }
            "--load-substeps" => {
                let v = val();
                o.deck.load_substeps =
                    v.parse::<usize>().ok().filter(|n| *n >= 1).ok_or_else(|| {
                        anyhow::anyhow!("--load-substeps: `{v}` is not a count >= 1")
                    })?;
            }
            "--drive" => {
                force = match val().as_str() {
                    "depth" => false,
                    "force" => true,
                    other => bail!("--drive: `{other}` is not depth or force"),
                };
            }
            other => bail!("unknown option {other}"),
        }
    }
    let table = if force {
        xtask::calculix::force::run(&o)?
    } else {
        xtask::calculix::run(&o)?
    };
    println!("{table}");
    Ok(())
}

/// `cargo xtask mesh-study`: the force of R2 and of the real `Auto()` examples against
/// their meshes and steps refined 2x and 4x, and candidate `Auto()` options
/// (xtask::mesh_study; docs/discretization.md).
fn mesh_study(args: &[String]) -> Result<()> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map(std::path::Path::to_path_buf)
        .unwrap_or_default();
    let mut configs = vec![
        "examples/r2-norton-hoff.ron".to_string(),
        "examples/real/anon-nh.ron".to_string(),
        "examples/real/ht-nh.ron".to_string(),
    ];
    let mut levels = 3;
    let mut sets: Vec<String> = Vec::new();
    let mut candidates: Vec<xtask::mesh_study::Candidate> = ["12:48:1.5", "16:48:1.5", "16:48:1.3"]
        .iter()
        .map(|x| xtask::mesh_study::Candidate::parse(x))
        .collect::<Result<_>>()?;
    let mut fine_steps = true;
    let mut additive = false;
    let mut mesh_series = true;
    let mut reference: Option<Vec<f64>> = None;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut val = || it.next().cloned().unwrap_or_default();
        match a.as_str() {
            "--configs" => configs = val().split(',').map(str::to_string).collect(),
            "--levels" => levels = val().parse()?,
            "--set" => sets.push(val()),
            "--auto" => {
                candidates = val()
                    .split(',')
                    .filter(|x| !x.is_empty())
                    .map(xtask::mesh_study::Candidate::parse)
                    .collect::<Result<_>>()?;
            }
            "--no-candidate-fine-steps" => fine_steps = false,
            "--additive-reference" => additive = true,
            "--steps-only" => mesh_series = false,
            "--reference" => {
                reference = Some(
                    val()
                        .split(',')
                        .map(str::parse)
                        .collect::<Result<_, _>>()
                        .context("--reference: forces (N) separated by commas")?,
                )
            }
            other => bail!("unknown option {other}"),
        }
    }
    for c in &configs {
        let path = root.join(c);
        let cfg = indentify_study::config::load(&path, &sets)?;
        let st = xtask::mesh_study::study(
            &cfg,
            c,
            &xtask::mesh_study::StudyOptions {
                levels,
                candidates: candidates.clone(),
                candidates_fine_steps: fine_steps,
                additive_reference: additive,
                reference: reference.clone(),
                mesh_series,
            },
        )?;
        println!("{}", xtask::mesh_study::render(&st));
    }
    Ok(())
}
