//! `indentify`: simulate instrumented indentation tests (axisymmetric finite elements,
//! rigid punch, frictionless or Coulomb contact) from RON configurations. Parsing and
//! dispatch only.

mod commands;
mod interrupt;
mod log;
mod print;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Identifies constitutive-law parameters from instrumented indentation curves.
#[derive(Debug, Parser)]
#[command(
    name = "indentify",
    version,
    about = "Simulate instrumented indentation tests (axisymmetric FE, rigid punch, frictionless \
             or Coulomb contact) and identify constitutive-law parameters from force-depth curves",
    long_about = None,
    after_help = "Units everywhere: N, mm, s, MPa.\n\n\
                  Examples:\n  \
                  indentify init elastic > r0.ron\n  \
                  indentify simulate r0.ron --out curve.csv\n  \
                  indentify simulate r0.ron --set law.E=25000 --set specimen.nr=10 --vtu fields/\n  \
                  indentify check r0.ron --set punch.half_angle_deg=70.3"
)]
struct Cli {
    /// Print nothing on standard error but errors (no progress, no summaries).
    #[arg(short, long, global = true, conflicts_with = "verbose")]
    quiet: bool,

    /// More detail on standard error: -v solver steps, cuts and line searches, -vv
    /// everything (RUST_LOG, when set, overrides).
    #[arg(short, long, global = true, action = clap::ArgAction::Count)]
    verbose: u8,

    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Run the direct problem of a configuration: force-depth curve (CSV), optional fields (VTU).
    #[command(
        after_help = "A summary (law, mesh, steps, Newton iterations, max force, wall time) \
                            goes to standard error. The exit status is non-zero for an invalid \
                            configuration, and for a step that fails even after cutting (the \
                            curve up to the failure is written all the same).\n\n\
                            Examples:\n  \
                            indentify simulate examples/r0-elastic.ron --out curve.csv\n  \
                            indentify simulate examples/r1-maxwell.ron --set law.eta=60000 --vtu fields/"
    )]
    Simulate(commands::simulate::Args),
    /// Print an annotated template configuration (the reference problem of the chosen law).
    #[command(
        after_help = "Examples:\n  indentify init norton-hoff > my-test.ron\n  \
                            indentify init maxwell --data examples/data/anton-paar-unht-berkovich/anonNI.TXT --out my-tests/anon.ron"
    )]
    Init(commands::init::Args),
    /// List every law with its parameters (--set law.NAME), units, ranges and kinds.
    #[command(after_help = "Examples:\n  indentify laws\n  indentify laws --json")]
    Laws(commands::laws::Args),
    /// Validate a configuration and its --set overrides without solving; print it resolved.
    Check(commands::check::Args),
    /// Misfit J to a measured curve and its exact gradient dJ/dc by the discrete adjoint.
    #[command(
        after_help = "J = 1/2 sum_i (F_i - F_exp,i)^2 over the schedule times t_i of the \
                            configuration (the initial state included, every weight 1), F_exp \
                            being the data interpolated linearly at t_i; the data must cover the \
                            simulated history. The gradient is taken at the configuration's law \
                            parameters. A law that is not differentiable there (Norton-Hoff with \
                            m <= 1) is an error.\n\n\
                            Examples:\n  \
                            indentify simulate examples/r1-maxwell.ron --out curve.csv\n  \
                            indentify gradient examples/r1-maxwell.ron --data curve.csv --set law.eta=25000\n  \
                            indentify gradient examples/r2-norton-hoff.ron --data curve.csv --checkpoint 10 --json"
    )]
    Gradient(commands::gradient::Args),
    /// Check the adjoint gradient against central finite differences and forward sensitivities.
    #[command(
        after_help = "Without --data, the data are the configuration's own curve and the \
                            check point is its law parameters multiplied by 1.1 (nu by 0.97), so \
                            that the misfit is non-zero; with --data, the check point is the \
                            configuration's law. The forward solves converge to a relative \
                            residual of at most 1e-12. The exit status is non-zero when, for any \
                            parameter, adjoint and central differences differ by more than --tol \
                            (relative) or adjoint and J^T rho (forward sensitivities) by more than \
                            1e-8.\n\n\
                            Examples:\n  \
                            indentify gradient-check examples/r1-maxwell.ron\n  \
                            indentify gradient-check examples/r2-norton-hoff.ron --scan --json"
    )]
    GradientCheck(commands::gradient_check::Args),
    /// Identify law parameters from a force curve (adjoint gradient, BFGS and others); write a report.
    #[command(after_help = "Without CONFIG, runs the embedded default: R1 \
                            (examples/r1-maxwell.ron), its curve simulated at E = 20000, nu = 0.3, \
                            eta = 30000 as the data, (E, eta) identified from the paper's first \
                            start (4000, 70000) with nu held. Without --data, the data are the \
                            configuration's curve at its `law` values (the truth, shown in the \
                            table). The configuration's optional `identify` section says what is \
                            free (start, bounds, scaling), what is held, the method and the \
                            stopping rules (`indentify init maxwell` shows one); --free, --fixed, \
                            --start, --method and --max-iter override it.\n\n\
                            Writes DIR/result.json (parameters with start, final value, bound hit; \
                            J, iterations, solves, stop reason, wall time, identifiability), \
                            DIR/history.csv (one line per iteration, written as it completes) and \
                            DIR/fit.csv (t, h, F_data, F_start, F_final). The table's std. dev. \
                            column says `undetermined` for a parameter the data do not \
                            determine (from the singular values of the scaled sensitivity \
                            matrix; see result.json `undetermined`).\n\n\
                            Exit status: 0 converged with every free parameter determined; 1 \
                            invalid input, a stall or the iteration limit (after the report is \
                            written); 2 a malformed command line; 3 a convergence criterion met \
                            but some free parameter undetermined by the data (a parameter at a \
                            bound where it has no effect, a combination the test cannot tell \
                            apart): the report is written and the message says what to do; \
                            130 interrupted (Ctrl-C).\n\n\
                            Examples:\n  \
                            indentify identify\n  \
                            indentify identify examples/r1-maxwell.ron --start E=60000,eta=10000 --out out/start2\n  \
                            indentify identify examples/r1-maxwell.ron --noise 0.1 --seed 2\n  \
                            indentify identify my-test.ron --data curve.csv --free E,eta --fixed nu=0.3 --method lbfgsb\n  \
                            indentify identify examples/r1-maxwell.ron --noise 0.02 --starts 8 --seed 1 --profiles\n  \
                            indentify identify examples/r2-norton-hoff.ron --max-iter 5 --out out/r2 && indentify identify examples/r2-norton-hoff.ron --out out/r2 --resume")]
    Identify(commands::identify::Args),
    /// Identify every indent of a manifest in parallel (a map); shards, Slurm arrays, merge.
    #[command(
        after_help = "The manifest is a CSV file with a header: `id` (unique; it names \
                            the folder OUT/indents/<id>/), `config` (optional with --config), \
                            `data` (a record or curve file), `test` (of a multi-test file), `x`, \
                            `y` (positions, for the maps) and any configuration path as a \
                            column (law.E, identify.params.E.start, ...). Relative paths are \
                            relative to the manifest. Each indent's result.json, fit.csv, \
                            history.csv and status.json are written into OUT/indents/<id>/; \
                            OUT/results.csv and OUT/maps/ (heat maps and histograms of every \
                            free parameter and R², SVG and PNG) are rebuilt at the end. A rerun \
                            skips finished indents; one indent's failure never stops the batch.\n\n\
                            Examples:\n  \
                            indentify batch map/manifest.csv --config map/base.ron --out out/map\n  \
                            indentify batch map/manifest.csv --config map/base.ron --out out/map --shard 1/4\n  \
                            indentify batch slurm map/manifest.csv --config map/base.ron --out /scratch/map --array 16 --time 02:00:00\n  \
                            indentify batch merge /scratch/map"
    )]
    Batch(commands::batch::Args),
    /// The cost J over a 2D slice of two free parameters (grid in parallel): CSV, JSON, contour figure.
    #[command(
        after_help = "The slice passes through the fit (--through fit, the default: the \
                            configuration is identified first), the configuration's law values \
                            (--through law) or the identification's start (--through start); \
                            the other parameters are held at the centre's values. The grid has \
                            --grid points per side, evenly spaced in the scaled variables (ln c \
                            for log-scaled parameters) over +-span around the centre, clipped to \
                            the bounds. Writes DIR/map.csv (one line per point: the two values \
                            and J), DIR/map.json (grid, J, centre, lowest point, threads, wall \
                            time) and DIR/map.svg/png (log10 J as colors and contour lines, axes \
                            in physical units, the centre marked). Grid points are independent \
                            forward solves: the map does not depend on the number of threads.\n\n\
                            Examples:\n  \
                            indentify map examples/r1-maxwell.ron --pair E,eta --grid 41\n  \
                            indentify map examples/r2-norton-hoff.ron --pair K,m --span 1.0,0.4 --through law --out out/km"
    )]
    Map(commands::map::Args),
    /// Rank candidate test protocols by the standard deviations they would give (before testing).
    #[command(
        after_help = "The configuration's `design` section states the noise (Relative(f): \
                            standard deviation f x |F|; Absolute(s): s in N) and lists \
                            candidates, each one test or several fitted jointly (entries as in \
                            a joint fit's `tests`). At the configuration's `law` values and for \
                            the free parameters of its `identify` section, each candidate's \
                            forward sensitivities give the covariance of its least-squares fit \
                            under that noise: the candidates are ranked by ln det of the \
                            information matrix (D-optimal) and by the largest relative standard \
                            deviation (worst parameter), and the parameters a candidate leaves \
                            undetermined are listed. Candidates run in parallel; the table does \
                            not depend on the number of threads. Writes DIR/design.json and \
                            DIR/design.md.\n\n\
                            Examples:\n  \
                            indentify design examples/r2-design.ron\n  \
                            indentify design examples/r2-design.ron --free K,m,sY --out out/design"
    )]
    Design(commands::design::Args),
    /// Serve the toolkit in a browser: records, runs with live progress, results (docs/web.md).
    Serve(commands::serve::Args),
    /// Oliver-Pharr (ISO 14577) analysis of every test and unloading: H, E, S, creep, work.
    #[command(
        after_help = "Reads the file (every test, or --test K), applies the zero point, the file's \
                            drift correction and the tip's (or the file's) frame compliance, fits \
                            F = alpha (h - h_f)^m over the fit range of each unloading and reports \
                            S, h_c, A_p, H_IT, E_r and E_IT per test (from its unloading at the \
                            largest force), the hold's creep and the work ratio. Method, defaults \
                            and sources: docs/analysis.md.\n\n\
                            Examples:\n  \
                            indentify analyze examples/data/anton-paar-sphere-creep/HT_V_100mN.TXT --tip sphere:10 --epsilon m\n  \
                            indentify calibrate examples/data/kla-fused-silica/FusedSilica.xlsx --modulus 72 --nu 0.17 --out tip.ron\n  \
                            indentify analyze examples/data/kla-fused-silica/FusedSilica.xlsx --tip-file tip.ron --nu 0.17 --out out/fs"
    )]
    Analyze(commands::analyze::Args),
    /// Calibrate the frame compliance and the tip's area function on a reference (fused silica); write a tip file.
    Calibrate(commands::analyze::CalibrateArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    log::init(cli.quiet, cli.verbose);
    let result = match &cli.command {
        Command::Simulate(args) => commands::simulate::run(args),
        Command::Init(args) => commands::init::run(args),
        Command::Laws(args) => commands::laws::run(args),
        Command::Check(args) => commands::check::run(args),
        Command::Gradient(args) => commands::gradient::run(args),
        Command::GradientCheck(args) => commands::gradient_check::run(args),
        Command::Identify(args) => commands::identify::run(args),
        Command::Batch(args) => commands::batch::run(args),
        Command::Map(args) => commands::map::run(args),
        Command::Design(args) => commands::design::run(args),
        Command::Serve(args) => commands::serve::run(args),
        Command::Analyze(args) => commands::analyze::run(args),
        Command::Calibrate(args) => commands::analyze::run_calibrate(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("error: {err}");
            for cause in err.chain().skip(1) {
                for line in cause.to_string().lines() {
                    eprintln!("  {line}");
                }
            }
            ExitCode::FAILURE
        }
    }
}
