//! `indentify serve`: the toolkit in a browser. Maps its arguments onto
//! `indentify_server::ServeOptions`, prints the URL and serves until Ctrl-C.

use std::net::IpAddr;
use std::path::PathBuf;

use anyhow::Result;
use indentify_server::{DEFAULT_PORT, ServeOptions};

/// Arguments of `indentify serve`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The port (0: any free one).
    #[arg(long, default_value_t = DEFAULT_PORT)]
    pub port: u16,

    /// The workspace folder: uploaded records (records/) and every run's files (runs/{id}/,
    /// as the CLI writes them, with status.json); created if needed.
    #[arg(long, value_name = "DIR", default_value = "indentify-workspace")]
    pub workspace: PathBuf,

    /// Listen on this address instead of 127.0.0.1 (e.g. 0.0.0.0): every request then needs
    /// the token (printed in the URL).
    #[arg(long, value_name = "ADDR")]
    pub host: Option<IpAddr>,

    /// The token (at least 16 characters; default: drawn at random when --host is given;
    /// also read from INDENTIFY_TOKEN).
    #[arg(long)]
    pub token: Option<String>,

    /// Open the page in the default browser (xdg-open / open).
    #[arg(long)]
    pub open: bool,

    /// Runs executed at the same time (each uses every core for its own work); the others
    /// wait in the queue.
    #[arg(long, value_name = "N", default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=64))]
    pub jobs: u32,

    /// Runs that may wait in the queue (further submissions get 503).
    #[arg(long, value_name = "N", default_value_t = 100, value_parser = clap::value_parser!(u32).range(1..))]
    pub max_queue: u32,

    /// Largest upload in MB.
    #[arg(long, value_name = "MB", default_value_t = 100, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub max_upload_mb: u32,
}

/// Serves until Ctrl-C.
///
/// # Errors
/// A workspace that cannot be created, an address in use.
pub fn run(args: &Args) -> Result<()> {
    let mut opts = ServeOptions::new(args.workspace.clone());
    opts.port = args.port;
    if let Some(h) = args.host {
        opts.host = h;
    }
    opts.token = args.token.clone().or_else(|| {
        std::env::var("INDENTIFY_TOKEN")
            .ok()
            .filter(|t| !t.is_empty())
    });
    opts.workers = args.jobs as usize;
    opts.max_queue = args.max_queue as usize;
    opts.max_upload = args.max_upload_mb as usize * 1024 * 1024;
    let server = indentify_server::bind(&opts)?;
    tracing::info!(
        "indentify serve: {} (workspace `{}`, {} worker{}, uploads up to {} MB); Ctrl-C stops",
        server.url,
        args.workspace.display(),
        args.jobs,
        if args.jobs == 1 { "" } else { "s" },
        args.max_upload_mb
    );
    println!("{}", server.url);
    if args.open {
        let opener = if cfg!(target_os = "macos") {
            "open"
        } else {
            "xdg-open"
        };
        if let Err(e) = std::process::Command::new(opener).arg(&server.url).spawn() {
            tracing::warn!(
                "cannot open a browser ({opener}: {e}): open {} yourself",
                server.url
            );
        }
    }
    server.run_until(indentify_server::ctrl_c())
}
