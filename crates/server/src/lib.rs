//! `indentify serve`: the study pipelines behind a local HTTP API and a browser page.
//!
//! One process: an axum server on tokio answers the page (HTML, JS and CSS compiled in,
//! no third-party code) and the API of docs/web.md; runs (`identify`, `simulate`,
//! `analyze`, `calibrate`, `design`, `batch`, `map`; joint fits of tests of one or several
//! records) are checked when submitted, exactly as the CLI checks its configuration, then
//! executed by a fixed pool of worker threads calling `indentify_study` (the same options,
//! observer and cancellation as the CLI). Everything a run writes goes into `WORKSPACE/runs/<id>/`: the
//! files the CLI writes (config.ron, result.json, report.md, history.csv, fit.csv,
//! figures) and `status.json`, so runs survive a restart and open in the CLI and Python.
//!
//! Safe by default: loopback only (and the Host header must name it), a token when
//! listening elsewhere, uploads size-limited and stored only under `records/`, request
//! paths validated name by name, state-changing requests need a custom header and a
//! same-origin `Origin` (cross-site request forgery), one failing run never stops the
//! server, and runs queue behind a bounded number of workers.

pub mod api;
pub mod calibrate;
mod jobs;
mod page;
pub mod records;
pub mod runs;
pub mod tips;
pub mod workspace;

use std::net::{IpAddr, SocketAddr};
use std::path::PathBuf;
use std::sync::Arc;

use anyhow::{Context as _, Result, bail};

pub use api::{AppState, CSRF_HEADER, router};
pub use runs::{RunRequest, Runs, Status};
pub use workspace::Workspace;

/// The default port.
pub const DEFAULT_PORT: u16 = 8765;

/// The default upload limit: 100 MB.
pub const DEFAULT_MAX_UPLOAD: usize = 100 * 1024 * 1024;

/// How to serve.
#[derive(Clone, Debug)]
pub struct ServeOptions {
    /// The address to listen on (default 127.0.0.1).
    pub host: IpAddr,
    /// The port (0: any free one).
    pub port: u16,
    /// The workspace folder.
    pub workspace: PathBuf,
    /// The token required beyond loopback (`None`: one is generated there).
    pub token: Option<String>,
    /// Worker threads executing runs (each run uses the rayon pool for its own work).
    pub workers: usize,
    /// Runs that may wait in the queue.
    pub max_queue: usize,
    /// Largest upload, bytes.
    pub max_upload: usize,
}

impl ServeOptions {
    /// Loopback, the default port, `workspace`, one worker, 100 queued runs, 100 MB.
    pub fn new(workspace: PathBuf) -> ServeOptions {
        ServeOptions {
            host: IpAddr::from([127, 0, 0, 1]),
            port: DEFAULT_PORT,
            workspace,
            token: None,
            workers: 1,
            max_queue: 100,
            max_upload: DEFAULT_MAX_UPLOAD,
        }
    }
}

/// A server bound to its address, not yet answering.
pub struct Server {
    listener: tokio::net::TcpListener,
    app: axum::Router,
    runtime: tokio::runtime::Runtime,
    /// The address it listens on.
    pub addr: SocketAddr,
    /// The URL to open (with the token, if any).
    pub url: String,
    /// The runs (for tests and the CLI's summary).
    pub runs: Arc<Runs>,
}

/// A random token: 32 hex digits from the system's random source.
fn random_token() -> Result<String> {
    use std::io::Read as _;
    let mut b = [0u8; 16];
    std::fs::File::open("/dev/urandom")
        .and_then(|mut f| f.read_exact(&mut b))
        .context("cannot read /dev/urandom for a token: give one with --token")?;
    Ok(b.iter().map(|x| format!("{x:02x}")).collect())
}

/// Opens the workspace, starts the workers and binds the address.
///
/// # Errors
/// A workspace that cannot be created, an address in use, a token that cannot be drawn.
pub fn bind(opts: &ServeOptions) -> Result<Server> {
    if opts.max_upload == 0 || opts.workers == 0 || opts.max_queue == 0 {
        bail!("the upload limit, the workers and the queue length must be at least 1");
    }
    let loopback = opts.host.is_loopback();
    let token = match (&opts.token, loopback) {
        (Some(t), _) if t.len() < 16 => bail!("--token must have at least 16 characters"),
        (Some(t), _) => Some(t.clone()),
        (None, false) => Some(random_token()?),
        (None, true) => None,
    };
    let ws = Workspace::open(&opts.workspace)?;
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .context("cannot start the server's runtime")?;
    let addr = SocketAddr::new(opts.host, opts.port);
    let listener = runtime
        .block_on(tokio::net::TcpListener::bind(addr))
        .with_context(|| format!("cannot listen on {addr}"))?;
    let addr = listener.local_addr().context("no local address")?;
    let runs = Runs::start(ws, opts.workers, opts.max_queue);
    let state = Arc::new(AppState {
        runs: Arc::clone(&runs),
        token: token.clone(),
        loopback,
        max_upload: opts.max_upload,
    });
    let shown = if loopback {
        format!("127.0.0.1:{}", addr.port())
    } else {
        addr.to_string()
    };
    let url = match &token {
        Some(t) => format!("http://{shown}/?token={t}"),
        None => format!("http://{shown}/"),
    };
    Ok(Server {
        listener,
        app: router(state),
        runtime,
        addr,
        url,
        runs,
    })
}

impl Server {
    /// Answers requests until `stop` resolves (the CLI: Ctrl-C).
    ///
    /// # Errors
    /// The listener failing.
    pub fn run_until(
        self,
        stop: impl std::future::Future<Output = ()> + Send + 'static,
    ) -> Result<()> {
        let Server {
            listener,
            app,
            runtime,
            ..
        } = self;
        runtime
            .block_on(async move {
                axum::serve(listener, app)
                    .with_graceful_shutdown(stop)
                    .await
            })
            .context("the server stopped")
    }

    /// Answers requests on a background thread until the process ends (tests).
    pub fn spawn(self) -> (SocketAddr, Arc<Runs>) {
        let addr = self.addr;
        let runs = Arc::clone(&self.runs);
        std::thread::spawn(move || {
            let _ = self.run_until(std::future::pending());
        });
        (addr, runs)
    }
}

/// Resolves when Ctrl-C is pressed.
pub async fn ctrl_c() {
    let _ = tokio::signal::ctrl_c().await;
}
