//! Dao et al. (2001)'s dimensionless functions of sharp indentation (Acta Materialia 49,
//! 3899-3918: a 70.3-degree cone, finite strain, Coulomb friction 0.15, J2 plasticity with
//! the power-law hardening `sigma = sY (1 + E eps_p / sY)^n`, `nu = 0.3`) and our forward
//! runs of the same problem measured against them (`cargo xtask dao`; the table of
//! docs/validation-laws.md §9).
//!
//! The functions and the measurement live in the analysis crate
//! (`indentify_analysis::dao`, with Dao's reverse algorithm: the closed-form start of a law
//! with a yield stress); this module re-exports them and runs the comparison.
//!
//! The functions (their Appendix A; the coefficients as publicly transcribed, not yet
//! compared with the printed appendix: docs/validation-laws.md §9 says how far they are
//! checked; `x = ln(E*/sigma_r)`,
//! `sigma_r = sigma(eps_p = 0.033)` the representative stress, `E* = E/(1 - nu^2)` for the
//! rigid tip used here):
//! - `Pi1 = C/sigma_r`, `C = P/h^2` on loading ([`pi1`]);
//! - `Pi2 = S/(E* h_m)`, `S` the initial unloading slope ([`pi2`]);
//! - `Pi4 = p_ave/E*` against `h_r/h_m`, `p_ave = P_m/A_m` the mean contact pressure at
//!   the maximum load ([`pi4`]);
//! - `Pi5 = W_p/W_t` against `h_r/h_m` ([`pi5`]).
//!
//! Dao's forward algorithm chains them: `C` and `S` from `Pi1`, `Pi2`; the contact area from
//! `S = c* E* sqrt(A_m)` (`c* = 1.1957` for the cone); `h_r/h_m` by inverting `Pi4`;
//! `W_p/W_t` from `Pi5` ([`dao_forward`]).
//!
//! What is measured on our curve ([`measure`]): `C` by least squares of `P = C h^2` over
//! the loading's upper half (`h >= h_m/2`), `S` as the slope at `h_m` of a quadratic fitted
//! to the unloading points above `0.75 P_m`, `h_r` where the unloading force reaches zero
//! (linear between the two steps around it: the first step out of contact, since the force
//! is exactly zero there, so `h_r` is resolved to the unloading step), the works by the
//! trapezoid rule, `p_ave` with
//! our contact radius at `h_m` (node-resolved: one element of the core is about 8% of it on
//! the coarse mesh).

use std::fmt::Write as _;

use anyhow::{Context, Result, bail};
use indentify_study::ConfigSource;
use indentify_study::simulate::{self, SimulateOptions};

pub use indentify_analysis::dao::{
    C_STAR, DaoPrediction, EPS_R, HALF_ANGLE_DEG, dao_forward, e_star, flow_stress, pi1, pi2, pi4,
    pi5, pi5_inverse, sigma_r,
};

/// Dao's Coulomb friction coefficient.
pub const FRICTION: f64 = 0.15;
/// Poisson's ratio of every Dao material.
pub const NU: f64 = 0.3;
/// Young's modulus of our runs (MPa); `sY = E / ratio`.
pub const E: f64 = 200_000.0;

/// A point of a force-depth curve: depth (mm), force (N), contact radius (mm).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Point {
    /// Depth (mm).
    pub h: f64,
    /// Force (N).
    pub f: f64,
    /// Contact radius (mm).
    pub a: f64,
}

/// What [`measure`] reads off one loading-unloading curve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Measured {
    /// Maximum depth (mm).
    pub h_m: f64,
    /// Force at the maximum depth (N).
    pub p_m: f64,
    /// `C` of `P = C h^2` fitted over `h >= h_m/2` on loading (MPa).
    pub c: f64,
    /// Initial unloading slope (N/mm).
    pub s: f64,
    /// Residual depth: where the unloading force reaches zero (mm).
    pub h_r: f64,
    /// Plastic work over total work.
    pub wp_wt: f64,
    /// Contact radius at the maximum depth (mm).
    pub a_m: f64,
}

/// Reads `C`, `S`, `h_r`, `W_p/W_t` and the contact radius at `h_m` off a curve that loads
/// monotonically to its deepest point and then unloads
/// (`indentify_analysis::dao::measure`, the contact radius beside).
///
/// # Errors
/// A curve without a loading and an unloading part, one whose unloading never reaches
/// zero force, too few points for the fits.
pub fn measure(curve: &[Point]) -> Result<Measured> {
    let h: Vec<f64> = curve.iter().map(|p| p.h).collect();
    let f: Vec<f64> = curve.iter().map(|p| p.f).collect();
    let m = indentify_analysis::dao::measure(&h, &f)?;
    let (Some(h_r), Some(wp_wt)) = (m.h_r, m.wp_wt) else {
        bail!("the unloading never reaches zero force: unload further");
    };
    Ok(Measured {
        h_m: m.h_m,
        p_m: m.p_m,
        c: m.c,
        s: m.s,
        h_r,
        wp_wt,
        a_m: curve[m.unloading_start].a,
    })
}

/// One material of the grid and the discretization it runs on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Run {
    /// `E/sY`.
    pub ratio: f64,
    /// Hardening exponent.
    pub n: f64,
    /// Element edges across the contact-radius bound (`specimen: Auto(elements_in_contact)`).
    pub elements: usize,
    /// Loading steps.
    pub load_steps: usize,
    /// Unloading steps to 0.95, 0.5 and 0 of the maximum depth (10, 30, 5 in the table).
    pub unload_steps: [usize; 3],
    /// Coulomb friction coefficient (0: frictionless normal contact).
    pub friction: f64,
}

/// The maximum depth of every run (mm): the problem has no length scale (a sharp cone, a
/// rate-independent law), so any depth gives the same `C`, `S/h_m`, `h_r/h_m`.
pub const H_MAX: f64 = 0.01;

impl Run {
    /// The yield stress `E / ratio` (MPa).
    pub fn sy(&self) -> f64 {
        E / self.ratio
    }

    /// The configuration (text): the cone, finite strain, normal contact with friction,
    /// `Plastic(E, nu, sY, Power(n))` rate-independent; loading to [`H_MAX`], unloading to
    /// 0.95, 0.5 and 0 of it in `unload_steps` (fine where the slope is taken).
    pub fn config(&self) -> String {
        let contact = if self.friction > 0.0 {
            format!("Normal(friction: {})", self.friction)
        } else {
            "Normal".to_string()
        };
        format!(
            "(specimen: Auto(elements_in_contact: {k}), punch: Cone(half_angle_deg: {HALF_ANGLE_DEG}), \
             contact: {contact}, kinematics: Finite, \
             law: Plastic(E: {E:?}, nu: {NU:?}, sY: {sy:?}, hardening: Power(n: {n:?})), \
             history: (segments: [(duration: 1.0, depth: {h:?}, steps: {nl}), \
             (duration: 0.2, depth: {h95:?}, steps: {u0}), (duration: 0.6, depth: {h50:?}, steps: {u1}), \
             (duration: 0.2, depth: 0.0, steps: {u2})]))",
            k = self.elements,
            sy = self.sy(),
            n = self.n,
            h = H_MAX,
            nl = self.load_steps,
            h95 = 0.95 * H_MAX,
            h50 = 0.5 * H_MAX,
            u0 = self.unload_steps[0],
            u1 = self.unload_steps[1],
            u2 = self.unload_steps[2],
        )
    }

    /// Runs it: the curve (depth, force, contact radius at every schedule step) and its
    /// wall time (s).
    ///
    /// # Errors
    /// The configuration's or the simulation's errors; a run that stops early.
    pub fn simulate(&self) -> Result<(Vec<Point>, f64)> {
        let source = ConfigSource::Text {
            text: self.config(),
            name: format!("dao-{}-{}", self.ratio, self.n),
        };
        let out = simulate::run(&SimulateOptions::new(source))
            .map_err(|e| anyhow::anyhow!("{:#}", anyhow::Error::from(e)))?;
        if let Some(f) = out.failure {
            bail!(
                "E/sY = {}, n = {}: the run stopped early: {f}",
                self.ratio,
                self.n
            );
        }
        Ok((
            out.rows
                .iter()
                .map(|r| Point {
                    h: r.h,
                    f: r.f,
                    a: r.a,
                })
                .collect(),
            out.seconds,
        ))
    }
}

/// One row of the comparison: our measurement and Dao's prediction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Compared {
    /// The run.
    pub run: Run,
    /// Ours.
    pub ours: Measured,
    /// Dao's forward algorithm.
    pub dao: DaoPrediction,
    /// Wall time of our run (s).
    pub seconds: f64,
}

impl Compared {
    /// Runs `run` and compares.
    ///
    /// # Errors
    /// As [`Run::simulate`] and [`measure`].
    pub fn of(run: Run) -> Result<Compared> {
        let (curve, seconds) = run.simulate()?;
        let ours = measure(&curve)?;
        Ok(Compared {
            run,
            ours,
            dao: dao_forward(E, NU, run.sy(), run.n),
            seconds,
        })
    }

    /// `E*/sigma_r`.
    pub fn estar_over_sr(&self) -> f64 {
        e_star(E, NU) / sigma_r(E, self.run.sy(), self.run.n)
    }

    /// Our `C` over `Pi1`'s.
    pub fn c_ratio(&self) -> f64 {
        self.ours.c / self.dao.c
    }

    /// Our `S/(E* h_m)`.
    pub fn s_norm(&self) -> f64 {
        self.ours.s / (e_star(E, NU) * self.ours.h_m)
    }

    /// Our `h_r/h_m`.
    pub fn hr_hm(&self) -> f64 {
        self.ours.h_r / self.ours.h_m
    }

    /// Our `p_ave/E*` with our contact radius.
    pub fn p_ave_norm(&self) -> f64 {
        self.ours.p_m / (std::f64::consts::PI * self.ours.a_m.powi(2)) / e_star(E, NU)
    }
}

/// The Markdown table of `rows`.
pub fn table(rows: &[Compared]) -> String {
    let mut s = String::from(
        "| E/sY | n | E*/σr | C/σr ours | Π1 | ratio | S/(E* h_m) ours | Π2 | ratio | h_r/h_m ours | Dao (Π4⁻¹) | W_p/W_t ours | Π5(ours h_r/h_m) | Dao (chain) | p_ave/E* ours | Π4(ours h_r/h_m) | s |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let sr = sigma_r(E, r.run.sy(), r.run.n);
        let _ = writeln!(
            s,
            "| {} | {} | {:.1} | {:.3} | {:.3} | **{:.3}** | {:.4} | {:.4} | **{:.3}** | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.4} | {:.4} | {:.0} |",
            r.run.ratio,
            r.run.n,
            r.estar_over_sr(),
            r.ours.c / sr,
            r.dao.c / sr,
            r.c_ratio(),
            r.s_norm(),
            r.dao.s_norm,
            r.s_norm() / r.dao.s_norm,
            r.hr_hm(),
            r.dao.hr_hm,
            r.ours.wp_wt,
            pi5(r.hr_hm()),
            r.dao.wp_wt,
            r.p_ave_norm(),
            pi4(r.hr_hm()),
            r.seconds,
        );
    }
    s
}

/// The mesh convergence of `coarse` against `fine` (same materials, row by row).
pub fn convergence(coarse: &[Compared], fine: &[Compared]) -> String {
    let mut s = String::from(
        "| E/sY | n | C fine/coarse - 1 | S fine/coarse - 1 | h_r/h_m fine - coarse | W_p/W_t fine - coarse |\n|---|---|---|---|---|---|\n",
    );
    for (c, f) in coarse.iter().zip(fine) {
        let _ = writeln!(
            s,
            "| {} | {} | {:+.2}% | {:+.2}% | {:+.4} | {:+.4} |",
            c.run.ratio,
            c.run.n,
            100.0 * (f.ours.c / c.ours.c - 1.0),
            100.0 * (f.ours.s / c.ours.s - 1.0),
            f.hr_hm() - c.hr_hm(),
            f.ours.wp_wt - c.ours.wp_wt,
        );
    }
    s
}

/// `cargo xtask dao [--ratios 50,200,1000] [--n 0,0.2,0.4] [--meshes 12,24]
/// [--load-steps 30] [--friction 0.15] [--jobs N]`: the grid on each mesh, Dao's functions
/// beside, and the mesh convergence between the first two meshes.
///
/// # Errors
/// A bad option; a run that fails.
pub fn run(args: &[String]) -> Result<()> {
    let list = |v: String, what: &str| -> Result<Vec<f64>> {
        v.split(',')
            .map(|x| {
                x.trim()
                    .parse::<f64>()
                    .ok()
                    .filter(|y| y.is_finite() && *y >= 0.0)
                    .with_context(|| format!("{what}: `{x}` is not a number >= 0"))
            })
            .collect()
    };
    let mut ratios = vec![50.0, 200.0, 1000.0];
    let mut ns = vec![0.0, 0.2, 0.4];
    let mut meshes = vec![12usize, 24];
    let mut load_steps = 30usize;
    let mut friction = FRICTION;
    let mut jobs = 1usize;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut val = || it.next().cloned().unwrap_or_default();
        match a.as_str() {
            "--ratios" => ratios = list(val(), "--ratios")?,
            "--n" => ns = list(val(), "--n")?,
            "--meshes" => {
                meshes = list(val(), "--meshes")?
                    .into_iter()
                    .map(|m| m as usize)
                    .collect()
            }
            "--load-steps" => load_steps = val().parse().context("--load-steps: a count")?,
            "--friction" => friction = list(val(), "--friction")?[0],
            "--jobs" => jobs = val().parse().context("--jobs: a count >= 1")?,
            other => bail!("unknown option {other}"),
        }
    }
    let mut all = Vec::new();
    for &elements in &meshes {
        let runs: Vec<Run> = ratios
            .iter()
            .flat_map(|&ratio| {
                ns.iter().map(move |&n| Run {
                    ratio,
                    n,
                    elements,
                    load_steps,
                    unload_steps: [10, 30, 5],
                    friction,
                })
            })
            .collect();
        let rows = run_all(&runs, jobs.max(1))?;
        println!(
            "\n### Auto(elements_in_contact: {elements}), {load_steps} loading steps, friction {friction}\n\n{}",
            table(&rows)
        );
        all.push(rows);
    }
    if all.len() >= 2 {
        println!(
            "\n### Mesh convergence ({} against {} elements in contact)\n\n{}",
            meshes[1],
            meshes[0],
            convergence(&all[0], &all[1])
        );
    }
    Ok(())
}

/// Runs `runs` on `jobs` threads (each run's result does not depend on it), in order.
fn run_all(runs: &[Run], jobs: usize) -> Result<Vec<Compared>> {
    let next = std::sync::atomic::AtomicUsize::new(0);
    let results: Vec<std::sync::Mutex<Option<Result<Compared>>>> =
        runs.iter().map(|_| std::sync::Mutex::new(None)).collect();
    std::thread::scope(|s| {
        for _ in 0..jobs.min(runs.len()) {
            s.spawn(|| {
                loop {
                    let i = next.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
                    let Some(run) = runs.get(i) else { break };
                    let r = Compared::of(*run);
                    match &r {
                        Ok(c) => eprintln!(
                            "E/sY = {}, n = {}, {} elements: C ratio {:.4}, S ratio {:.4}, W_p/W_t {:.3} ({:.0} s)",
                            run.ratio,
                            run.n,
                            run.elements,
                            c.c_ratio(),
                            c.s_norm() / c.dao.s_norm,
                            c.ours.wp_wt,
                            c.seconds
                        ),
                        Err(e) => eprintln!("E/sY = {}, n = {}: {e:#}", run.ratio, run.n),
                    }
                    if let Ok(mut slot) = results[i].lock() {
                        *slot = Some(r);
                    }
                }
            });
        }
    });
    results
        .into_iter()
        .map(|m| {
            m.into_inner()
                .ok()
                .flatten()
                .unwrap_or_else(|| Err(anyhow::anyhow!("a run did not report")))
        })
        .collect()
}
