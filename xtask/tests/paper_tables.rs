//! Snapshot of the paper's tables on a coarse set-up: the documented CI subset of
//! `cargo xtask paper-tables` (which regenerates docs/paper-tables.md on the reference
//! set-up, all runs).
//!
//! Reference: Constantinescu & Tardieu (2001), Tables I-III; truth R1 = (E, nu, eta) =
//! (20000, 0.3, 30000), R2 = (E, nu, K, m, sY) = (1e5, 0.3, 1500, 5, 500).
//! Goal: the identification pipeline (data synthesis, noise, BFGS-Armijo, LM, rendering)
//! gives the same tables to 4-5 significant digits.
//!
//! ```text
//!      cone 68 deg, depth 0 -> 0.1 mm -> hold -> 0, 1 s each, 8 steps per segment
//!        \   /
//!   z=0 --\-/--------------  top: contact candidates
//!        |                |  4 x 4 mm cylinder, 8 x 8 Q8 graded 1.45
//!  u_r=0 |                |  (reference: 10 x 10 mm, 20 x 20, 1.3, 30 steps)
//!        +----------------+  u_z = 0
//! ```
//!
//! Subset: all four starts of Tables I and II (BFGS-Armijo), Table III tests 2, 5 and 7
//! with Levenberg-Marquardt. It lives in xtask, beside the renderer
//! it pins, and runs in CI (`cargo test --workspace`). Accept a deliberate change with
//! `INSTA_UPDATE=always cargo test -p xtask --test paper_tables`.

use indentify_identify::Method;
use xtask::paper::{self, Data, Options, Setup, Table};

/// The system shall regenerate the coarse subset of Tables I-III identically (to the
/// rendered digits) and recover the truth from exact data.
#[test]
fn paper_tables_coarse_subset() {
    let opts = Options {
        setup: Setup::COARSE,
        threads: 2,
        max_iterations_r1: 60,
        max_iterations_r2: 60,
        valleys: false,
        method_r2: Method::LevenbergMarquardt,
        max_iterations_bfgs_r2: 70,
    };
    let jobs: Vec<_> = paper::all_jobs()
        .into_iter()
        .filter(|j| j.table != Table::III || [2, 5, 7].contains(&j.row))
        .collect();
    assert_eq!(jobs.len(), 11);
    let data = Data::new(&opts.setup, true).unwrap();
    let outcomes = paper::run_jobs(&opts, &data, &jobs).unwrap();
    for o in &outcomes {
        let r = o.result.as_ref().unwrap();
        assert!(
            r.stop_reason.is_converged(),
            "{:?}: {}",
            o.job,
            r.stop_reason
        );
        if o.job.table != Table::II {
            for e in paper::rel_errors(o.job.table, &r.free_values()) {
                assert!(e.abs() < 1e-5, "{:?}: {e}", o.job);
            }
        }
    }
    let text = format!(
        "Set-up: {}\n\n{}",
        opts.setup.describe(),
        paper::render_tables(&outcomes, false)
    );
    insta::assert_snapshot!("paper_tables_coarse", text);
}
