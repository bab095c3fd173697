//! Ctrl-C (SIGINT) during `identify`: the first ends the run after the iteration in
//! progress (its history line written, the partial report written, exit status 130); a
//! second one ends the process at once.

use indentify_study::Cancel;

/// A stop flag raised by the first Ctrl-C. Installs the handler once per process; where
/// no handler can be installed, the flag is never raised (Ctrl-C then ends the process as
/// usual).
pub fn cancel_on_ctrl_c() -> Cancel {
    let cancel = Cancel::default();
    let flag = cancel.clone();
    let installed = ctrlc::set_handler(move || {
        if flag.is_raised() {
            std::process::exit(130);
        }
        eprintln!(
            "\ninterrupt: stopping after the current iteration, or skipping the discretization \
             check if it runs (press Ctrl-C again to quit now)"
        );
        flag.raise();
    });
    if let Err(e) = installed {
        tracing::debug!("no Ctrl-C handler: {e}");
    }
    cancel
}
