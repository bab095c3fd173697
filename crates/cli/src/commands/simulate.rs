//! `indentify simulate`: runs the direct problem of a configuration and writes the
//! force-depth curve (CSV) and, on request, the fields of every step (VTU + PVD).

use std::path::PathBuf;

use anyhow::{Result, bail};
use indentify_study::ConfigSource;
use indentify_study::output;
use indentify_study::simulate::{self, SimulateOptions};

/// Arguments of `indentify simulate`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Configuration file (RON); `indentify init elastic` prints an annotated one.
    pub config: PathBuf,

    /// Write the curve here instead of standard output: CSV with header `t,h,F,a`
    /// (s, mm, N, mm), one row per schedule time from the initial state (0,0,0,0).
    #[arg(short, long, value_name = "CURVE.csv")]
    pub out: Option<PathBuf>,

    /// Also write the fields of every step for ParaView into DIR: `step_NNNN.vtu` (mesh:
    /// displacement (u_r, u_z, 0) and contact pressure at the nodes; element averages of
    /// stress [rr, zz, tt, rz], von_mises, viscoplastic strain eps_p = eps - S sigma
    /// [rr, zz, tt, rz] and eps_p_eq), `gauss_NNNN.vtu` (the same at the Gauss points,
    /// unsmoothed) and `steps.pvd` (both, by time).
    #[arg(long, value_name = "DIR")]
    pub vtu: Option<PathBuf>,

    /// Perturb the written force multiplicatively, F_i (1 + A xi_i) with xi_i uniform in
    /// [-1, 1) drawn in row order (the initial row included) from SplitMix64 seeded with
    /// --seed: the same curve on every machine. 0.1 is the paper's 10% noise.
    #[arg(long, value_name = "A", allow_negative_numbers = true)]
    pub noise: Option<f64>,

    /// Write the constrained tangent of step N (see --at-step) into DIR as Matrix Market
    /// (K_step_N.mtx, full symmetric, through sprs; scipy.io.mmread reads it) with
    /// equations.csv (equation, node, component, r, z, constrained).
    #[arg(long, value_name = "DIR", requires = "at_step")]
    pub matrix_market: Option<PathBuf>,

    /// The schedule step (from 1) whose tangent --matrix-market writes.
    #[arg(long, value_name = "N", requires = "matrix_market")]
    pub at_step: Option<usize>,

    /// Seed of the noise generator (with --noise).
    #[arg(
        long,
        value_name = "N",
        default_value_t = 1,
        requires = "noise",
        allow_negative_numbers = true,
        value_parser = super::parse_count
    )]
    pub seed: u64,

    /// Override a scalar of the configuration by its dotted path (repeatable), e.g.
    /// `--set law.E=25000 --set specimen.nr=10 --set punch.half_angle_deg=70.3
    /// --set history.segments.0.depth=0.2 --set solver.max_cuts=4`.
    #[arg(long = "set", value_name = "KEY.PATH=VALUE")]
    pub sets: Vec<String>,

    /// The test (from 1) of a joint configuration (`tests: [...]`) to work on.
    #[arg(long, value_name = "K")]
    pub test: Option<usize>,
}

/// Runs the simulation and writes its outputs; a summary goes to standard error.
///
/// # Errors
/// An invalid configuration, an output that cannot be written, or a step that fails even
/// after cutting (the curve up to the last converged step is still written).
pub fn run(args: &Args) -> Result<()> {
    let o = simulate::run(&SimulateOptions {
        config: ConfigSource::Path(args.config.clone()),
        sets: args.sets.clone(),
        test: args.test,
        noise: args.noise.map(|a| (a, args.seed)),
        out: args.out.clone(),
        vtu: args.vtu.clone(),
        matrix_market: args.matrix_market.clone().zip(args.at_step),
    })?;
    if args.out.is_none() {
        output::write_curve(None, &o.rows)?;
    }
    let rows = &o.rows;
    // first row of largest force
    let peak = rows
        .iter()
        .copied()
        .fold(rows[0], |best, r| if r.f > best.f { r } else { best });
    let tm = &o.trajectory.timing;
    tracing::info!(
        "indentify simulate {name}\n  \
         law {} ({}), punch {}\n  \
         mesh: {} ({} nodes, {} elements)\n  \
         {} of {} schedule steps{} ({} sub-steps from cuts), {} Newton iterations, {} factorizations\n  \
         max force {:.6} N at t = {} s, h = {} mm (contact radius {:.6} mm)\n  \
         wall time {:.3} s (solver {:.3} s: local {:.3}, assembly {:.3}, factorization {:.3}, solve {:.3})",
        o.law,
        o.params.join(", "),
        o.punch,
        o.mesher.describe(),
        o.size.0,
        o.size.1,
        rows.len() - 1,
        o.schedule_steps,
        o.substeps
            .as_ref()
            .map_or(String::new(), |s| format!(", {s}")),
        o.cut_substeps,
        o.trajectory.total_iterations(),
        tm.factorizations,
        peak.f,
        peak.t,
        peak.h,
        peak.a,
        o.seconds,
        tm.total,
        tm.local,
        tm.assembly,
        tm.factorization,
        tm.solve,
        name = o.config,
    );
    let curve_to = args
        .out
        .as_ref()
        .map_or("standard output".to_string(), |p| {
            format!("`{}`", p.display())
        });
    let plural = if rows.len() == 1 { "" } else { "s" };
    if let Some(a) = args.noise {
        tracing::info!(
            "  force perturbed: F (1 + {a} xi), xi uniform in [-1, 1) from SplitMix64 seed {}",
            args.seed
        );
    }
    if let Some(m) = &o.measured {
        tracing::info!("  depth history from the data: {}", m.summary());
    }
    tracing::info!("  curve ({} row{plural}) written to {curve_to}", rows.len());
    if let (Some(dir), Some(n)) = (&args.vtu, o.vtu_states) {
        tracing::info!(
            "  {n} states written to `{}` (open steps.pvd in ParaView)",
            dir.display()
        );
    }
    if let Some((path, n, nnz)) = &o.matrix {
        tracing::info!(
            "  tangent of step {} ({n} equations, {nnz} non-zeros) written to `{}`",
            args.at_step.unwrap_or(0),
            path.display()
        );
    }
    if let Some(why) = o.failure {
        bail!(
            "the simulation of `{}` stopped: {why}; the curve up to t = {} s was written \
             (try smaller steps in `history.segments` or a larger `solver.max_cuts`)",
            o.config,
            rows.last().map_or(0.0, |r| r.t)
        );
    }
    Ok(())
}
