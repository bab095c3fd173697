//! Messages on standard error through `tracing` (`--quiet`: errors only; default: progress
//! and summaries; `-v`: solver detail; `-vv`: everything; `RUST_LOG` overrides all but
//! `--quiet`), and the
//! progress bar of long runs, drawn only when standard error is a terminal and kept out of
//! the way of the messages (a message suspends the bar while it is written).

use std::io::{IsTerminal as _, Write};
use std::sync::Mutex;
use std::time::Duration;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use tracing_subscriber::EnvFilter;
use tracing_subscriber::fmt::MakeWriter;

/// The bar being drawn, if any: messages suspend it while they are written.
static BAR: Mutex<Option<ProgressBar>> = Mutex::new(None);

/// Whether `--quiet` was given (no progress bar either).
static QUIET: Mutex<bool> = Mutex::new(false);

/// Installs the subscriber: `quiet` keeps errors only, each `-v` one level more than info.
/// `RUST_LOG`, when set and valid, wins (e.g. `RUST_LOG=indentify_contact=debug`).
pub fn init(quiet: bool, verbose: u8) {
    let level = match (quiet, verbose) {
        (true, _) => "error",
        (false, 0) => "info",
        (false, 1) => "debug",
        (false, _) => "trace",
    };
    if let Ok(mut q) = QUIET.lock() {
        *q = quiet;
    }
    // --quiet wins over RUST_LOG
    let filter = std::env::var("RUST_LOG")
        .ok()
        .filter(|_| !quiet)
        .and_then(|s| EnvFilter::try_new(s).ok())
        .unwrap_or_else(|| EnvFilter::new(level));
    // a second call (tests) keeps the first subscriber
    let _ = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(Stderr)
        .without_time()
        .with_target(verbose > 0)
        .with_level(verbose > 0)
        .with_ansi(false)
        .try_init();
}

/// The writer of the messages: standard error, with the progress bar suspended.
#[derive(Clone, Copy, Debug)]
struct Stderr;

impl Write for Stderr {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let bar = BAR.lock().ok().and_then(|b| b.clone());
        match bar {
            Some(bar) => bar.suspend(|| std::io::stderr().lock().write_all(buf))?,
            None => std::io::stderr().lock().write_all(buf)?,
        }
        Ok(buf.len())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        std::io::stderr().flush()
    }
}

impl<'a> MakeWriter<'a> for Stderr {
    type Writer = Stderr;

    fn make_writer(&'a self) -> Self::Writer {
        Stderr
    }
}

/// A progress bar over `len` units (iterations, steps) with a message; hidden unless
/// standard error is a terminal and `--quiet` is off. Finished (and erased) on drop.
#[derive(Debug)]
pub struct Progress {
    bar: Option<ProgressBar>,
}

impl Progress {
    /// Starts a bar titled `prefix` over `len` units of `unit` (e.g. `iterations`).
    pub fn new(prefix: &str, len: u64, unit: &str) -> Progress {
        let quiet = QUIET.lock().map(|q| *q).unwrap_or(false);
        if quiet || !std::io::stderr().is_terminal() {
            return Progress { bar: None };
        }
        let template = format!(
            "{{prefix}} [{{elapsed_precise}}] {{bar:30}} {{pos}}/{{len}} {unit} (eta {{eta}}) {{msg}}"
        );
        let style = ProgressStyle::with_template(&template)
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> ");
        let bar = ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::stderr())
            .with_style(style)
            .with_prefix(prefix.to_string());
        bar.enable_steady_tick(Duration::from_millis(200));
        if let Ok(mut b) = BAR.lock() {
            *b = Some(bar.clone());
        }
        Progress { bar: Some(bar) }
    }

    /// Moves the bar to `pos` with `msg` beside it.
    pub fn set(&self, pos: u64, msg: String) {
        if let Some(bar) = &self.bar {
            bar.set_position(pos);
            bar.set_message(msg);
        }
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        if let Some(bar) = self.bar.take() {
            bar.finish_and_clear();
            if let Ok(mut b) = BAR.lock() {
                *b = None;
            }
        }
    }
}
