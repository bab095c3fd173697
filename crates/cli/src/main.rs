//! `indentify`: simulate instrumented indentation tests (axisymmetric finite elements,
//! frictionless rigid punch) from RON configurations. Parsing and dispatch only.

mod commands;
mod config;
mod output;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Identifies constitutive-law parameters from instrumented indentation curves.
#[derive(Debug, Parser)]
#[command(
    name = "indentify",
    version,
    about = "Simulate instrumented indentation tests (axisymmetric FE, rigid frictionless punch) \
             and identify constitutive-law parameters from force-depth curves",
    long_about = None,
    after_help = "Units everywhere: N, mm, s, MPa.\n\n\
                  Examples:\n  \
                  indentify init elastic > r0.ron\n  \
                  indentify simulate r0.ron --out curve.csv\n  \
                  indentify simulate r0.ron --set law.E=25000 --set specimen.nr=10 --vtu fields/\n  \
                  indentify check r0.ron --set punch.half_angle_deg=70.3"
)]
struct Cli {
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
    #[command(after_help = "Example: indentify init norton-hoff > my-test.ron")]
    Init(commands::init::Args),
    /// Validate a configuration and its --set overrides without solving; print it resolved.
    Check(commands::check::Args),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Simulate(args) => commands::simulate::run(args),
        Command::Init(args) => commands::init::run(args),
        Command::Check(args) => commands::check::run(args),
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
