//! `indentify batch`: identification of every indent of a manifest in parallel
//! (`indentify_study::batch`), with `slurm` (a job-array script over shards) and `merge`
//! (results.csv and maps from the shards of a shared folder).

use std::path::PathBuf;

use anyhow::{Result, bail};
use indentify_study::batch::{
    self, BatchObserver, BatchOptions, BatchSummary, IndentStatus, Shard, SlurmOptions, State,
};
use indentify_study::config::MethodName;

/// Arguments of `indentify batch`.
#[derive(Debug, clap::Args)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct Args {
    #[command(subcommand)]
    pub action: Option<Action>,

    #[command(flatten)]
    pub run: RunArgs,
}

/// `batch slurm` and `batch merge`.
#[derive(Debug, clap::Subcommand)]
pub enum Action {
    /// Write a Slurm job-array script running one shard per array task, and print the
    /// sbatch command.
    Slurm(SlurmArgs),
    /// Gather the statuses of every shard in DIR into results.csv and the maps.
    Merge {
        /// The batch's output folder.
        dir: PathBuf,
    },
}

/// Running a batch (or one shard of it).
#[derive(Debug, clap::Args)]
pub struct RunArgs {
    /// The manifest (CSV): id, config, data, test, x, y, start (oliver-pharr: start from the
    /// analysis of the indent's record; closed-form: from the closed-form pre-fit of its
    /// curve) and configuration paths as columns.
    #[arg(required = true)]
    pub manifest: Option<PathBuf>,

    /// Output folder: indents/{id}/, results.csv, maps/.
    #[arg(long, value_name = "DIR", required = true)]
    pub out: Option<PathBuf>,

    /// Base configuration for rows without a `config` column.
    #[arg(long, value_name = "BASE.ron")]
    pub config: Option<PathBuf>,

    /// Indents identified at once (default: every core).
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub jobs: usize,

    /// Run only shard K of N (rows i with i mod N = K - 1), e.g. --shard 2/8.
    #[arg(long, value_name = "K/N", value_parser = parse_shard)]
    pub shard: Option<Shard>,

    /// Redo the indents that failed (finished ones are always skipped).
    #[arg(long)]
    pub retry_failed: bool,

    /// The optimizer of every indent: bfgs, lbfgs, lbfgsb or lm.
    #[arg(long, value_parser = parse_method)]
    pub method: Option<MethodName>,

    /// Iteration limit of every indent.
    #[arg(long, value_name = "N", allow_negative_numbers = true, value_parser = super::parse_usize)]
    pub max_iter: Option<usize>,

    /// Also draw each indent's figures and report.md (slower).
    #[arg(long)]
    pub figures: bool,

    /// Where every indent's fit starts: `config` (the configuration's starts, or the
    /// manifest's `start` column), `closed-form` (the parameters a closed form covers
    /// from the pre-fit of the indent's own curve, corrected by one forward run; each
    /// indent's start depends on its own curve only: docs/analysis.md) or `seeded` (each
    /// configuration's first indent in manifest order fitted first from its closed form;
    /// the others from their own half-space closed form times its fitted / half-space
    /// ratio, without a calibration run: the same bits for any `--jobs`, order and shard).
    #[arg(long, value_name = "START", default_value = "config", value_parser = ["config", "closed-form", "seeded"])]
    pub start: String,

    /// Memory for the recorded runs of all workers together (MB): an indent whose
    /// recording would exceed its share checkpoints instead.
    #[arg(long, value_name = "MB", default_value_t = 1024)]
    pub memory_budget: usize,

    /// Oliver-Pharr analysis of every indent instead of FE fits: OUT/analysis.csv and the
    /// H_IT and E_IT maps (reads only the id, data, test, x and y columns).
    #[arg(long)]
    pub analyze: bool,

    /// The tip of --analyze: berkovich, cone:HALF_ANGLE_DEG, sphere:RADIUS_UM, flat:RADIUS_UM.
    #[arg(long, default_value = "berkovich", conflicts_with = "tip_file")]
    pub tip: String,

    /// A tip file of `indentify calibrate` for --analyze.
    #[arg(long, value_name = "TIP.ron")]
    pub tip_file: Option<PathBuf>,

    /// Poisson's ratio of the sample for --analyze.
    #[arg(long, default_value_t = 0.3)]
    pub nu: f64,
}

/// `batch slurm`.
#[derive(Debug, clap::Args)]
pub struct SlurmArgs {
    /// The manifest.
    pub manifest: PathBuf,
    /// The output folder, on a filesystem every node shares.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Base configuration.
    #[arg(long, value_name = "BASE.ron")]
    pub config: Option<PathBuf>,
    /// Array tasks (shards).
    #[arg(long, value_name = "N")]
    pub array: usize,
    /// Slurm partition.
    #[arg(long)]
    pub partition: Option<String>,
    /// Time limit per task (e.g. 02:00:00).
    #[arg(long)]
    pub time: Option<String>,
    /// Memory per task (e.g. 4G).
    #[arg(long)]
    pub mem: Option<String>,
    /// CPUs per task: each task identifies that many indents at once.
    #[arg(long, value_name = "C", default_value_t = 1)]
    pub cpus_per_task: usize,
}

fn parse_shard(text: &str) -> Result<Shard, String> {
    Shard::parse(text).map_err(|e| e.to_string())
}

fn parse_method(text: &str) -> Result<MethodName, String> {
    MethodName::parse(text).map_err(|e| e.to_string())
}

/// Progress bar and one log line per failed indent.
struct Console {
    bar: std::sync::Mutex<Option<crate::log::Progress>>,
}

impl BatchObserver for Console {
    fn started(&self, pending: usize, skipped: usize) {
        tracing::info!(
            "indentify batch: {pending} indents to identify, {skipped} already finished"
        );
        if let Ok(mut b) = self.bar.lock() {
            *b = Some(crate::log::Progress::new(
                "batch",
                pending as u64,
                "indents",
            ));
        }
    }

    fn finished(&self, s: &IndentStatus, done: usize, _pending: usize) {
        if let Ok(b) = self.bar.lock() {
            if let Some(b) = b.as_ref() {
                b.set(done as u64, format!("{} {}", s.id, s.state.name()));
            }
        }
        match s.state {
            State::Failed => tracing::warn!("  {} failed: {}", s.id, s.message),
            _ => tracing::debug!("  {} {} ({:.1} s)", s.id, s.state.name(), s.seconds),
        }
    }
}

/// Runs the command.
///
/// # Errors
/// Invalid manifest or options, an output folder that cannot be written or holds another
/// batch; a batch with failed indents exits non-zero after writing everything.
pub fn run(args: &Args) -> Result<()> {
    match &args.action {
        Some(Action::Slurm(s)) => slurm(s),
        Some(Action::Merge { dir }) => {
            let summary = batch::merge(dir)?;
            report(&summary);
            Ok(())
        }
        None => run_batch(&args.run),
    }
}

fn run_batch(a: &RunArgs) -> Result<()> {
    let (Some(manifest), Some(out)) = (&a.manifest, &a.out) else {
        bail!("give a manifest and --out DIR (indentify batch MANIFEST.csv --out DIR)");
    };
    if a.analyze {
        return analyze_batch(a, manifest, out);
    }
    let mut opts = BatchOptions::new(manifest.clone(), out.clone());
    opts.config = a.config.clone();
    opts.jobs = a.jobs;
    opts.shard = a.shard;
    opts.retry_failed = a.retry_failed;
    opts.overrides.method = a.method;
    opts.overrides.max_iterations = a.max_iter;
    opts.figures = a.figures;
    opts.memory_budget = a.memory_budget.saturating_mul(1 << 20);
    opts.closed_form_start = a.start != "config";
    opts.seeded = a.start == "seeded";
    opts.cancel = crate::interrupt::cancel_on_ctrl_c();
    let console = Console {
        bar: std::sync::Mutex::new(None),
    };
    let summary = batch::run(&opts, &console)?;
    if let Ok(mut b) = console.bar.lock() {
        b.take();
    }
    report(&summary);
    if opts.cancel.is_raised() {
        tracing::warn!("interrupted: rerun the same command to finish the remaining indents");
        std::process::exit(130);
    }
    let failed = summary.counts.get("failed").copied().unwrap_or(0);
    if failed > 0 {
        bail!(
            "{failed} of {} indents failed (their errors are in `{}`; fix them and rerun with \
             --retry-failed)",
            summary.total,
            summary.results.display()
        );
    }
    Ok(())
}

/// `batch --analyze`: the Oliver-Pharr analysis of every indent
/// (`indentify_study::batch_analysis`).
fn analyze_batch(a: &RunArgs, manifest: &std::path::Path, out: &std::path::Path) -> Result<()> {
    use indentify_study::batch_analysis::{self as ba, BatchAnalysisOptions};
    let mut o = BatchAnalysisOptions::new(manifest, out);
    o.tip = match &a.tip_file {
        Some(p) => indentify_study::analyze::read_tip(p)?,
        None => indentify_study::analyze::tip_from_name(&a.tip)?,
    };
    o.nu = a.nu;
    o.jobs = a.jobs;
    let r = ba::run(&o)?;
    println!(
        "batch --analyze: {} indents, {} analysed, {} without values; tip {}, nu {}; {:.2} s",
        r.indents.len(),
        r.analysed,
        r.failed,
        o.tip.area.describe(),
        o.nu,
        r.seconds
    );
    for i in r.indents.iter().filter(|i| i.error.is_some()).take(8) {
        println!("  ! {}: {}", i.id, i.error.as_deref().unwrap_or(""));
    }
    for p in &r.written {
        println!("  wrote {}", p.display());
    }
    Ok(())
}

fn report(s: &BatchSummary) {
    let counts: Vec<String> = s.counts.iter().map(|(k, v)| format!("{v} {k}")).collect();
    let mut text = format!(
        "batch: {} indents in the manifest ({} in this shard: {} run now, {} already finished); \
         statuses: {}\n",
        s.total,
        s.in_shard,
        s.ran,
        s.skipped,
        if counts.is_empty() {
            "none".to_string()
        } else {
            counts.join(", ")
        }
    );
    if !s.missing.is_empty() {
        text.push_str(&format!(
            "  {} indents have no result yet (other shards, or interrupted): {}{}\n",
            s.missing.len(),
            s.missing
                .iter()
                .take(8)
                .cloned()
                .collect::<Vec<_>>()
                .join(", "),
            if s.missing.len() > 8 { ", ..." } else { "" }
        ));
    }
    text.push_str(&format!("  results: {}\n", s.results.display()));
    if !s.figures.is_empty() {
        text.push_str(&format!(
            "  maps: {} figures (SVG and PNG) in {}\n",
            s.figures.len(),
            s.figures[0]
                .parent()
                .map_or(String::new(), |p| p.display().to_string())
        ));
    }
    if let Some(note) = &s.maps_note {
        text.push_str(&format!("  maps: {note}\n"));
    }
    text.push_str(&format!("  wall time {:.1} s\n", s.seconds));
    print!("{text}");
}

fn slurm(a: &SlurmArgs) -> Result<()> {
    // the manifest and every indent's configuration must be valid before a job is queued
    let manifest = batch::read_manifest(&a.manifest, a.config.as_deref())?;
    batch::validate(&manifest, a.config.as_deref(), &Default::default())?;
    let script = batch::slurm_script(&SlurmOptions {
        manifest: a.manifest.clone(),
        out: a.out.clone(),
        config: a.config.clone(),
        array: a.array,
        partition: a.partition.clone(),
        time: a.time.clone(),
        mem: a.mem.clone(),
        cpus_per_task: a.cpus_per_task,
        executable: std::env::current_exe()?,
    })?;
    std::fs::create_dir_all(&a.out)?;
    let path = a.out.join("batch.sbatch");
    indentify_study::atomic::write(&path, script)?;
    println!(
        "wrote {}: {} array tasks; submit it with\n  sbatch {}\nthen, when every task is done:\n  \
         indentify batch merge {}",
        path.display(),
        a.array,
        path.display(),
        a.out.display()
    );
    Ok(())
}
