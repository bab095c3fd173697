//! Set-ups shared by the identify crate's test targets: the small Maxwell and Norton-Hoff
//! problems with noisy data on the cone model, the load-hold-unload histories, forces
//! through an instrument's frame, and the pieces of the gradient checks through the
//! `Evaluator` (a central difference of its own cost, `J^T r` of its Jacobian). Each test
//! keeps its own tolerances and relative difference; the model itself is
//! `indentify_testkit::cone_model`.

// Each test target uses a part of this module.
#![allow(dead_code)]

use indentify_contact::{
    DirectSolver, Frame, LoadHistory, Model, Schedule, SolverOptions, Trajectory, trapezoid,
};
use indentify_identify::{
    Evaluator, ForceRecord, Identifiability, IdentifyConfig, Method, ParamSpec, Problem,
    SplitMix64, multiplicative_noise,
};
use indentify_laws::{LawMaterial, Material, Maxwell, NortonHoff};
use indentify_testkit::{cone_model, force};

/// Newton to a residual of 1e-11, the other solver options at their defaults.
pub fn tight_opts() -> SolverOptions {
    SolverOptions {
        residual_tol: 1e-11,
        ..SolverOptions::default()
    }
}

/// Force 0 -> 60 N (1 s) -> hold (1 s) -> 24 N (1 s), 6 steps per segment.
pub fn load_hold_unload() -> LoadHistory {
    LoadHistory::from_segments(&[
        force(1.0, 60.0, 6),
        force(1.0, 60.0, 6),
        force(1.0, 24.0, 6),
    ])
    .unwrap()
}

/// Machine depth to `h` (mm), hold, unload to `0.6 h`, `steps` per segment (1 s each).
pub fn depth_lhu(h: f64, steps: usize) -> Schedule {
    indentify_testkit::depth_lhu(h, 0.6 * h, steps)
}

/// A load-controlled run's depths at its schedule's times (index 0: the initial state, 0).
pub fn schedule_depths(traj: &Trajectory) -> Vec<f64> {
    std::iter::once(0.0)
        .chain(traj.schedule_steps().map(|s| s.depth))
        .collect()
}

/// The forces a compliant run of `mat` at `c` on `m` through `frame` gives at the
/// schedule's times ([`tight_opts`]), with uniform noise of half-width `noise` (N, seed
/// `seed`; none at the initial state).
pub fn frame_forces(
    m: &Model,
    mat: &dyn Material,
    c: &[f64],
    schedule: &Schedule,
    frame: &Frame,
    noise: f64,
    seed: u64,
) -> ForceRecord {
    let traj = DirectSolver::new(m)
        .unwrap()
        .run_compliant(mat, c, schedule, frame, &tight_opts())
        .unwrap();
    let mut rng = SplitMix64::new(seed);
    let f: Vec<f64> = traj
        .forces()
        .iter()
        .enumerate()
        .map(|(i, f)| {
            if i == 0 {
                0.0
            } else {
                f + noise * rng.next_symmetric()
            }
        })
        .collect();
    ForceRecord::new(schedule.t.clone(), f).unwrap()
}

/// The small R1-like problem: Maxwell at `truth` on the cone model over the trapezoid
/// 0 -> 0.1 mm -> hold -> 0 (1 s each, 6 steps per segment), default solver options, the
/// forces with multiplicative noise `noise` (seed 7; none when `noise` is 0).
pub fn maxwell_problem(truth: &[f64], noise: f64) -> Problem {
    let s = Schedule::from_segments(&trapezoid(0.1, 1.0, 1.0, 1.0, 6)).unwrap();
    let f = DirectSolver::new(&cone_model())
        .unwrap()
        .run(&LawMaterial(&Maxwell), truth, &s, &SolverOptions::default())
        .unwrap()
        .forces();
    let f = if noise > 0.0 {
        multiplicative_noise(&f, noise, 7)
    } else {
        f
    };
    let rec = ForceRecord::new(s.t.clone(), f).unwrap();
    Problem::new(
        cone_model(),
        &Maxwell,
        s,
        &rec,
        None,
        SolverOptions::default(),
    )
    .unwrap()
}

/// The truth of the small R2-like problem: Norton-Hoff E (MPa), nu, K (MPa s^(1/m)), m,
/// sY (MPa).
pub const NH_TRUTH: [f64; 5] = [1e5, 0.3, 1500.0, 5.0, 500.0];

/// The small R2-like data: Norton-Hoff at [`NH_TRUTH`] on the cone model over the
/// trapezoid 0 -> 0.1 mm (in `rise` s) -> hold (1 s) -> 0 (1 s), 8 steps per segment,
/// default solver options, the forces with 2% multiplicative noise (seed `seed`).
pub fn nh_data(rise: f64, seed: u64) -> (Schedule, ForceRecord) {
    let s = Schedule::from_segments(&trapezoid(0.1, rise, 1.0, 1.0, 8)).unwrap();
    let f = DirectSolver::new(&cone_model())
        .unwrap()
        .run(
            &LawMaterial(&NortonHoff),
            &NH_TRUTH,
            &s,
            &SolverOptions::default(),
        )
        .unwrap()
        .forces();
    let f = multiplicative_noise(&f, 0.02, seed);
    let rec = ForceRecord::new(s.t.clone(), f).unwrap();
    (s, rec)
}

/// Levenberg-Marquardt on E, K and sY of the small R2-like problem (nu and m fixed at the
/// truth), from (7e4, 2500, 350).
pub fn nh_lm() -> IdentifyConfig {
    let mut cfg = IdentifyConfig::new(vec![
        ParamSpec::free("E", 7e4, 1e3, 1e7),
        ParamSpec::fixed("nu", 0.3),
        ParamSpec::free("K", 2500.0, 10.0, 1e6),
        ParamSpec::fixed("m", 5.0),
        ParamSpec::free("sY", 350.0, 1.0, 1e5),
    ]);
    cfg.method = Method::LevenbergMarquardt;
    cfg
}

/// The central difference of the evaluator's cost in parameter `k` at `c`, step `step`.
pub fn cost_difference(ev: &mut Evaluator, c: &[f64], k: usize, step: f64) -> f64 {
    let mut cp = c.to_vec();
    cp[k] += step;
    let mut cm = c.to_vec();
    cm[k] -= step;
    (ev.cost(&cp).unwrap() - ev.cost(&cm).unwrap()) / (2.0 * step)
}

/// Entry `k` of `J^T r`: column `k` of the Jacobian rows `jac` times the weighted
/// residuals of the simulated observable `sim` against `p`'s target.
pub fn jt_r(p: &Problem, jac: &[Vec<f64>], sim: &[f64], k: usize) -> f64 {
    jac.iter()
        .zip(sim)
        .zip(p.target.iter().zip(&p.weights))
        .map(|((row, s), (tg, w))| w * (s - tg) * row[k])
        .sum()
}

/// One parameter's gradient check, printed: the adjoint `g` against the central
/// difference `fd` (`rel(g, fd) < 1e-6`) and `J^T r` against the adjoint
/// (`rel(jt_r, g) < 1e-8`), with the test's own relative difference `rel`.
pub fn assert_gradient_entry(
    label: &str,
    name: &str,
    g: f64,
    fd: f64,
    jt_r: f64,
    rel: fn(f64, f64) -> f64,
) {
    println!(
        "{label} dJ/d{name}: adjoint {g:.10e}, FD {fd:.10e} (rel {:.1e}), J^T r {jt_r:.10e} (rel {:.1e})",
        rel(g, fd),
        rel(jt_r, g)
    );
    assert!(rel(g, fd) < 1e-6, "{label} {name}: adjoint {g} vs FD {fd}");
    assert!(
        rel(jt_r, g) < 1e-8,
        "{label} {name}: J^T r {jt_r} vs adjoint {g}"
    );
}

/// Maxwell's parameters: E free from `e` in [1000, 1e6] MPa, nu fixed at 0.3, eta free
/// from `eta` in [1000, 1e7] MPa s.
pub fn maxwell_specs(e: f64, eta: f64) -> Vec<ParamSpec> {
    vec![
        ParamSpec::free("E", e, 1000.0, 1e6),
        ParamSpec::fixed("nu", 0.3),
        ParamSpec::free("eta", eta, 1000.0, 1e7),
    ]
}

/// Each identified `c[k]`, `k` in `ks` (the `i`-th free parameter of `id`), within two of
/// the identifiability's standard deviations of its truth `truth[i]`; printed.
pub fn assert_within_two_sigma(id: &Identifiability, c: &[f64], ks: &[usize], truth: &[f64]) {
    for (i, (&k, &t)) in ks.iter().zip(truth).enumerate() {
        let dev = (c[k] - t).abs();
        println!(
            "{}: {:.6e} vs {t:.6e}: {:.2} sigma (sigma {:.3e})",
            id.names[i],
            c[k],
            dev / id.std_dev[i],
            id.std_dev[i]
        );
        assert!(
            dev <= 2.0 * id.std_dev[i],
            "{}: |{} - {t}| = {dev:.3e} > 2 sigma = {:.3e}",
            id.names[i],
            c[k],
            2.0 * id.std_dev[i]
        );
    }
}
