//! `cargo xtask`: project automation. `cargo xtask paper-tables` regenerates
//! docs/paper-tables.md and its figures (docs/figures/*.svg) from the reference problems.

use anyhow::{Result, bail};
use indentify_identify::Method;
use xtask::paper::{self, Data, Options, Setup, Stopwatch, Table};

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        Some("paper-tables") => paper_tables(&args[1..]),
        _ => {
            eprintln!(
                "usage: cargo xtask paper-tables [--only I,II,III] [--rows 1,2,..] [--threads N] [--max-iter-r2 N] [--coarse] [--print]"
            );
            bail!("unknown or missing command")
        }
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
        max_iterations_bfgs_r2: 80,
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
