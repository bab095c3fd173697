//! Coarse to fine: the first iterations of a fit on a model 2x coarser in space (and in
//! time where the schedule allows it), then the fit at full fidelity from the coarse
//! optimum (docs/performance.md, "Coarse to fine").
//!
//! Coarsening rules, the inverse of [`crate::discretization`]'s refinement: a `Cylinder`
//! specimen gets `ceil(nr / 2) x ceil(nz / 2)` elements with the gradings squared (at most
//! 3, the mesher's limit); an `Auto` specimen gets `elements_in_contact / 2` in its
//! uniform core and its far-field grading squared (at most 3). A mesh with fewer than
//! [`MIN_CONTACT_ELEMENTS`] elements under the contact-radius bound at the schedule's
//! largest depth is refused, naming the field. In time, a schedule whose every step has
//! at least two solver sub-steps (a record's `data.substeps`) keeps its times and halves
//! the sub-steps; otherwise a schedule of an even number of steps whose every second time
//! is the depth history's own (a history whose segments all have even `steps`) keeps every
//! second time, its targets there and twice their weights; otherwise the time grid is kept.
//! The coarse problem compares with the fine problem's own targets (never data synthesized
//! again on the coarse model), so its optimum is the coarse model's fit of the same data.
//!
//! [`Coarsening`] varies the factor in space (`1.5`: `ceil(nr / 1.5)` elements, gradings to
//! the power 1.5; `1`: the fine mesh) and keeps the time grid if asked; the default (2 in
//! space, time coarsened) is the rules above.
//!
//! Output correction (`corrections`, after the coarse fit; space mapping's zeroth-order
//! correction): one fine forward run at the coarse optimum `x_c` gives the coarse model's
//! discrepancy there, `d = F_fine(x_c) - F_coarse(x_c)` on the coarse model's rows; the
//! coarse model fits the targets `y - d` from `x_c`, so that its optimum is the fine
//! model's as far as `d` does not change between `x_c` and it. Each correction costs one
//! fine forward run and one more coarse fit.
//!
//! The fine phase is the ordinary fit from the coarse optimum: what it reports (stop
//! reason, deviations, the discretization check) is that of the full-fidelity model. A
//! coarse phase that cannot be built or fails falls back to the full-fidelity fit from the
//! configuration's start, and says so.

use anyhow::{Context as _, Result, anyhow, bail};
use indentify_contact::{Model, Schedule};
use indentify_identify::{
    Evaluator, IdentifyConfig, IdentifyResult, IterationRecord, Problem, Test,
};

use crate::config::Mesher;
use crate::identify::Setup;

/// The fewest elements a coarse mesh may have under the contact-radius bound at the
/// largest depth (the contact resolution: below it the contact radius moves by a large
/// fraction of itself from one node to the next).
pub const MIN_CONTACT_ELEMENTS: usize = 4;

/// The largest grading the meshers accept.
const MAX_GRADING: f64 = 3.0;

/// How much coarser the coarse model is: `space`, the factor on the element sizes
/// (`2`: half the elements along each direction, the gradings squared; `1`: the fine
/// mesh), and whether the time grid is coarsened 2x where the schedule allows it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coarsening {
    /// The factor on the element sizes, in `[1, 4]`.
    pub space: f64,
    /// Whether the time grid is coarsened (the module's rules) or kept.
    pub time: bool,
}

impl Default for Coarsening {
    /// 2x in space and in time: the module's rules.
    fn default() -> Self {
        Coarsening {
            space: 2.0,
            time: true,
        }
    }
}

/// The mesher 2x coarser in each direction (see the module's rules), before the contact
/// resolution check.
///
/// # Errors
/// A coarse mesher the mesh crate refuses (naming the field).
pub fn coarsen_mesher(mesher: &Mesher) -> Result<Mesher> {
    coarsen_mesher_by(mesher, 2.0)
}

/// The mesher `factor` times coarser in each direction (`ceil(n / factor)` elements, the
/// gradings to the power `factor`, at most 3; an `Auto` core `floor(n / factor)`
/// elements), before the contact resolution check.
///
/// # Errors
/// A factor outside `[1, 4]`, a coarse mesher the mesh crate refuses (naming the field).
pub fn coarsen_mesher_by(mesher: &Mesher, factor: f64) -> Result<Mesher> {
    if !(1.0..=4.0).contains(&factor) {
        bail!("the coarse mesh's factor {factor} is outside [1, 4]");
    }
    // 2: the integer halving and the squares of the first version, bit for bit
    let count = |n: usize| {
        if factor == 2.0 {
            n.div_ceil(2)
        } else {
            ((n as f64 / factor).ceil() as usize).max(1)
        }
    };
    let grade = |g: f64| {
        let c = if factor == 2.0 { g * g } else { g.powf(factor) };
        c.min(MAX_GRADING)
    };
    let coarse = match *mesher {
        Mesher::Cylinder(mut m) => {
            m.nr = count(m.nr);
            m.nz = count(m.nz);
            m.grading_r = grade(m.grading_r);
            m.grading_z = grade(m.grading_z);
            m.validate()
                .context("the mesh cannot be coarsened for the coarse phase")?;
            Mesher::Cylinder(m)
        }
        Mesher::Zoned(mut m) => {
            let core = (m.core_elements as f64 / factor).floor() as usize;
            if core < MIN_CONTACT_ELEMENTS {
                bail!(
                    "specimen.elements_in_contact = {}: a {factor}x coarser mesh would have \
                     {core} elements under the contact radius, below the contact resolution \
                     of {} (coarse to fine needs specimen.elements_in_contact >= {})",
                    m.core_elements,
                    MIN_CONTACT_ELEMENTS,
                    (factor * MIN_CONTACT_ELEMENTS as f64).ceil()
                );
            }
            m.core_elements = core;
            m.grading = grade(m.grading);
            m.validate()
                .context("the mesh cannot be coarsened for the coarse phase")?;
            Mesher::Zoned(m)
        }
    };
    Ok(coarse)
}

/// Elements of `mesh` whose top edge (nodes at `z = 0`) starts inside radius `a`.
pub fn elements_under(mesh: &indentify_mesh::Mesh, a: f64) -> usize {
    let top = mesh
        .nodes
        .iter()
        .fold(f64::NEG_INFINITY, |m, p| m.max(p[1]));
    let tol = 1e-9 * mesh.nodes.iter().fold(0.0_f64, |m, p| m.max(p[1].abs()));
    mesh.elements
        .iter()
        .filter(|e| {
            let r_min = e
                .iter()
                .map(|&n| mesh.nodes[n])
                .filter(|p| (p[1] - top).abs() <= tol)
                .map(|p| p[0])
                .fold(f64::INFINITY, f64::min);
            r_min < a
        })
        .count()
}

/// A schedule 2x coarser in time with its rows of the fine one (see the module's rules),
/// and a description; `None` when the time grid is kept.
fn coarsen_schedule(
    schedule: &Schedule,
    history: Option<&crate::config::History>,
) -> Result<Option<(Schedule, Vec<usize>, String)>> {
    let n = schedule.n_steps();
    let all: Vec<usize> = (0..=n).collect();
    if !schedule.substeps.is_empty() && (1..=n).all(|j| schedule.substeps_of(j) >= 2) {
        let k: Vec<usize> = (1..=n).map(|j| schedule.substeps_of(j) / 2).collect();
        let s = schedule.clone().with_substeps(k)?;
        let text = format!(
            "every step's sub-steps halved ({} solver steps, was {})",
            s.n_solver_steps(),
            schedule.n_solver_steps()
        );
        return Ok(Some((s, all, text)));
    }
    let Some(h) = history else {
        return Ok(None);
    };
    if n % 2 != 0 || h.segments.iter().any(|s| s.steps % 2 != 0) || !schedule.substeps.is_empty() {
        return Ok(None);
    }
    let rows: Vec<usize> = (0..=n).step_by(2).collect();
    let t: Vec<f64> = rows.iter().map(|&i| schedule.t[i]).collect();
    let d: Vec<f64> = rows.iter().map(|&i| schedule.depth[i]).collect();
    let s = Schedule::from_record(&t, &d)?;
    let text = format!("every second time ({} steps, was {n})", s.n_steps());
    Ok(Some((s, rows, text)))
}

/// The coarse problem of a set-up fit and its description.
///
/// # Errors
/// A load-controlled test, a coarse mesh below the contact resolution (naming the field),
/// a coarse model or schedule that cannot be built.
pub fn coarse_problem(s: &Setup) -> Result<(Problem, String)> {
    coarse_problem_with(s, Coarsening::default())
}

/// The coarse problem of a set-up fit, `how` coarser, and its description.
///
/// # Errors
/// As [`coarse_problem`]; a space factor outside `[1, 4]`.
pub fn coarse_problem_with(s: &Setup, how: Coarsening) -> Result<(Problem, String)> {
    let mut tests = Vec::with_capacity(s.problem.tests.len());
    let mut texts = Vec::new();
    for (test, info) in s.problem.tests.iter().zip(&s.tests) {
        if test.load.is_some() {
            bail!(
                "{}: coarse to fine is for depth-controlled tests (this one is load-controlled)",
                info.label
            );
        }
        let mesher =
            coarsen_mesher_by(&info.mesher, how.space).with_context(|| info.label.clone())?;
        let (mesh, _, _) = mesher
            .build_for(&test.model.punch)
            .context("cannot build the coarse mesh")?;
        let h_max = test.schedule.depth.iter().fold(0.0_f64, |m, d| m.max(*d));
        let a = test.model.punch.contact_radius_bound(h_max);
        let under = elements_under(&mesh, a);
        if under < MIN_CONTACT_ELEMENTS {
            bail!(
                "{}: specimen (nr, elements_in_contact): the {}x coarser mesh has {under} \
                 elements under the contact radius bound {a:.3e} mm, below the contact \
                 resolution of {MIN_CONTACT_ELEMENTS}",
                info.label,
                how.space
            );
        }
        let model = Model::with_contact(mesh, test.model.punch.clone(), info.config.contact)
            .and_then(|m| m.with_kinematics(info.config.kinematics))
            .context("cannot build the coarse model")?;
        let coarser = match how.time {
            true => coarsen_schedule(&test.schedule, info.config.history.as_ref())?,
            false => None,
        };
        let (schedule, rows, time) = match coarser {
            Some((sc, rows, text)) => (sc, rows, text),
            None => (
                test.schedule.clone(),
                (0..test.schedule.t.len()).collect(),
                "time steps kept".to_string(),
            ),
        };
        let factor = test.schedule.t.len() as f64 / rows.len() as f64;
        texts.push(format!(
            "{} ({under} under the contact), {time}",
            mesher.describe()
        ));
        tests.push(Test {
            model,
            schedule,
            solver_options: test.solver_options.clone(),
            target: rows.iter().map(|&i| test.target[i]).collect(),
            weights: rows.iter().map(|&i| factor * test.weights[i]).collect(),
            weight: test.weight,
            load: None,
        });
    }
    let problem = crate::instrument::problem(
        &s.cfg,
        &s.name,
        &s.law,
        tests,
        &crate::config::Overrides::default(),
    )
    .map_err(|e| anyhow!("{e}"))?;
    Ok((problem, texts.join("; ")))
}

/// What the coarse phase did.
#[derive(Clone, Debug)]
pub struct CoarsePhase {
    /// The coarse model, described (`None`: none was built).
    pub model: Option<String>,
    /// The coarse fit (`None`: it could not be built or failed); with corrections, the
    /// first one, from the configuration's start.
    pub result: Option<IdentifyResult>,
    /// The output corrections that followed it, in order (the last one's end point is
    /// the fine phase's start).
    pub corrections: Vec<Correction>,
    /// Why the fit fell back to full fidelity from the configuration's start, if it did.
    pub fallback: Option<String>,
    /// Wall time of the coarse phase (s), set-up included.
    pub seconds: f64,
}

/// One output correction of the coarse phase: a fine forward run at the last coarse end
/// point, then the coarse fit of the corrected targets from there.
#[derive(Clone, Debug)]
pub struct Correction {
    /// The discrepancy `F_fine - F_coarse` at the last coarse end point, RMS over the
    /// coarse rows with weight, over the RMS of the targets.
    pub discrepancy: f64,
    /// The corrected coarse fit.
    pub result: IdentifyResult,
}

impl CoarsePhase {
    /// The coarse phase's end point: the last correction's, else the coarse fit's.
    pub fn end(&self) -> Option<&IdentifyResult> {
        match self.corrections.last() {
            Some(c) => Some(&c.result),
            None => self.result.as_ref(),
        }
    }

    /// The coarse phase's totals over its fits: iterations, coarse forward solves, coarse
    /// sensitivity solves, rejected trials; and the fine forward runs of its corrections.
    pub fn totals(&self) -> (usize, usize, usize, usize, usize) {
        let fits = self
            .result
            .iter()
            .chain(self.corrections.iter().map(|c| &c.result));
        let mut t = (0, 0, 0, 0, self.corrections.len());
        for r in fits {
            t.0 += r.iterations;
            t.1 += r.forward_solves;
            t.2 += r.sensitivity_solves;
            t.3 += r.rejected_trials;
        }
        t
    }

    /// What the report says: the coarse phase's counts, stop and end point, or why the fit
    /// ran at full fidelity from the configuration's start.
    pub fn summary(&self) -> String {
        let model = self.model.as_deref().unwrap_or("none built");
        match (&self.result, &self.fallback) {
            (_, Some(why)) => format!(
                "The fit was to run coarse to fine, but {why}: it ran at full fidelity from \
                 the configuration's start (coarse model: {model})."
            ),
            (Some(r), None) => {
                let end = self.end().unwrap_or(r);
                let at: Vec<String> = end
                    .params
                    .iter()
                    .filter(|p| p.free)
                    .map(|p| format!("{} = {:.6e}", p.name, p.value))
                    .collect();
                let corrected = if self.corrections.is_empty() {
                    String::new()
                } else {
                    let d: Vec<String> = self
                        .corrections
                        .iter()
                        .map(|c| format!("{:.2e}", c.discrepancy))
                        .collect();
                    let (it, fw, se, _, _) = self.totals();
                    format!(
                        ", then {} output correction(s) (a full-fidelity forward run each, \
                         relative discrepancy {}, and the coarse fit of the corrected \
                         targets; {it} coarse iterations, {fw} forward and {se} sensitivity \
                         solves in all)",
                        self.corrections.len(),
                        d.join(", ")
                    )
                };
                format!(
                    "The fit ran coarse to fine: {} iterations ({} forward and {} sensitivity \
                     solves, {:.1} s; stop: {}) on the coarser model ({model}) from the \
                     configuration's start{corrected}, ending at {}; then the full-fidelity \
                     fit from there, whose iterations, stop, deviations and discretization \
                     check are the ones reported.",
                    r.iterations,
                    r.forward_solves,
                    r.sensitivity_solves,
                    self.seconds,
                    r.stop_reason,
                    at.join(", ")
                )
            }
            (None, None) => "The coarse phase did not run.".to_string(),
        }
    }
}

/// The coarse phase: at most `coarse_iterations` iterations (the configuration's other
/// stopping rules, no identifiability summary) of `coarse` (from [`coarse_problem`]; an
/// error is reported as the fallback), from `config`'s start. Returns `config` with the
/// free parameters' starts moved to the coarse optimum (unchanged on a fallback) and what
/// the phase did. Runs on the current rayon pool.
pub fn coarse_phase(
    s: &Setup,
    coarse: Result<(Problem, String)>,
    config: &IdentifyConfig,
    coarse_iterations: usize,
    observer: &mut dyn FnMut(&IterationRecord),
) -> (IdentifyConfig, CoarsePhase) {
    coarse_phase_corrected(s, coarse, config, (coarse_iterations, 0), observer)
}

/// [`coarse_phase`] followed by `corrections` output corrections (the module's text):
/// each a fine forward run at the last coarse end point and a coarse fit (at most
/// `coarse_iterations` iterations) of the corrected targets from there. A correction that
/// fails ends the corrections; the phase keeps the last end point reached.
pub fn coarse_phase_corrected(
    s: &Setup,
    coarse: Result<(Problem, String)>,
    config: &IdentifyConfig,
    (coarse_iterations, corrections): (usize, usize),
    observer: &mut dyn FnMut(&IterationRecord),
) -> (IdentifyConfig, CoarsePhase) {
    let clock = std::time::Instant::now();
    let mut phase = CoarsePhase {
        model: None,
        result: None,
        corrections: Vec::new(),
        fallback: None,
        seconds: 0.0,
    };
    let mut fine_cfg = config.clone();
    match coarse {
        Err(e) => phase.fallback = Some(format!("no coarse model: {e:#}")),
        Ok((mut coarse, text)) => {
            phase.model = Some(text);
            let mut cc = config.clone();
            cc.stop.max_iterations = coarse_iterations;
            cc.identifiability = false;
            let r = indentify_identify::identify(&coarse, &cc, observer);
            match r {
                Err(e) => phase.fallback = Some(format!("the coarse phase failed: {e}")),
                Ok(r) if !r.c.iter().all(|v| v.is_finite()) => {
                    phase.fallback = Some("the coarse phase ended at a non-finite point".into());
                }
                Ok(r) => {
                    let targets = coarse.target.clone();
                    let mut end = r.clone();
                    phase.result = Some(r);
                    for _ in 0..corrections {
                        match correct(s, &mut coarse, &targets, &cc, &end, observer) {
                            Ok(c) => {
                                end = c.result.clone();
                                phase.corrections.push(c);
                            }
                            Err(e) => {
                                tracing::info!("  coarse to fine: a correction failed: {e:#}");
                                break;
                            }
                        }
                    }
                    set_start(s, &mut fine_cfg, &end.c);
                }
            }
        }
    }
    phase.seconds = clock.elapsed().as_secs_f64();
    (fine_cfg, phase)
}

/// Moves the free parameters' starts of `cfg` to `c` (the law's parameters in order).
fn set_start(s: &Setup, cfg: &mut IdentifyConfig, c: &[f64]) {
    let names = s.problem.law.params();
    for p in cfg.params.iter_mut().filter(|p| p.free) {
        if let Some(k) = names.iter().position(|n| n.name == p.name) {
            p.value = Some(c[k]);
        }
    }
}

/// The coarse rows' fine rows, test by test: the fine row of the same time (the coarse
/// schedules keep a subset of the fine times, bit for bit).
fn fine_rows(fine: &Problem, coarse: &Problem) -> Result<Vec<usize>> {
    let mut rows = Vec::with_capacity(coarse.target.len());
    for (k, (f, c)) in fine.tests.iter().zip(&coarse.tests).enumerate() {
        let base = fine.rows_of(k).start;
        let mut j = 0;
        for t in &c.schedule.t {
            while j < f.schedule.t.len() && f.schedule.t[j] != *t {
                j += 1;
            }
            if j == f.schedule.t.len() {
                bail!("the coarse time {t} s of test {k} is not a fine time");
            }
            rows.push(base + j);
        }
    }
    Ok(rows)
}

/// One output correction from the coarse fit `last`: the fine forces at its end point,
/// the coarse targets `targets - (F_fine - F_coarse)`, the coarse fit from there.
fn correct(
    s: &Setup,
    coarse: &mut Problem,
    targets: &[f64],
    cc: &IdentifyConfig,
    last: &IdentifyResult,
    observer: &mut dyn FnMut(&IterationRecord),
) -> Result<Correction> {
    let rows = fine_rows(&s.problem, coarse)?;
    let fine = Evaluator::new(&s.problem)?.forces(&last.c)?;
    if fine.len() != s.problem.target.len() || last.forces.len() != targets.len() {
        bail!("the forces at the coarse end point do not match the targets");
    }
    let (mut dd, mut yy) = (0.0, 0.0);
    let corrected: Vec<f64> = (0..targets.len())
        .map(|i| {
            let d = fine[rows[i]] - last.forces[i];
            let w = coarse.weights[i];
            dd += w * d * d;
            yy += w * targets[i] * targets[i];
            targets[i] - d
        })
        .collect();
    if !corrected.iter().all(|v| v.is_finite()) {
        bail!("the fine forward run at the coarse end point failed");
    }
    for k in 0..coarse.tests.len() {
        let r = coarse.rows_of(k);
        coarse.tests[k].target = corrected[r].to_vec();
    }
    coarse.target = corrected;
    let mut cfg = cc.clone();
    set_start(s, &mut cfg, &last.c);
    let result = indentify_identify::identify(coarse, &cfg, observer)?;
    if !result.c.iter().all(|v| v.is_finite()) {
        bail!("the corrected coarse fit ended at a non-finite point");
    }
    Ok(Correction {
        discrepancy: (dd / yy.max(f64::MIN_POSITIVE)).sqrt(),
        result,
    })
}

/// Runs the coarse phase ([`coarse_phase`]), then the full-fidelity fit from its optimum
/// on `s.problem`; a coarse phase that cannot be built or fails is reported in
/// [`CoarsePhase::fallback`] and the fine fit starts from the configuration's start.
/// Both phases run on the current rayon pool: call it inside `s.problem.install` for the
/// problem's own.
///
/// # Errors
/// The full-fidelity fit's errors.
pub fn identify(
    s: &Setup,
    config: &IdentifyConfig,
    coarse_iterations: usize,
    observer: &mut dyn FnMut(&IterationRecord),
) -> Result<(IdentifyResult, CoarsePhase)> {
    identify_with(
        s,
        config,
        (Coarsening::default(), coarse_iterations, 0),
        observer,
    )
}

/// [`identify`] with the coarse model `how` coarser and `corrections` output corrections
/// after the coarse fit ([`coarse_phase_corrected`]).
///
/// # Errors
/// The full-fidelity fit's errors.
pub fn identify_with(
    s: &Setup,
    config: &IdentifyConfig,
    (how, coarse_iterations, corrections): (Coarsening, usize, usize),
    observer: &mut dyn FnMut(&IterationRecord),
) -> Result<(IdentifyResult, CoarsePhase)> {
    let (fine_cfg, phase) = coarse_phase_corrected(
        s,
        coarse_problem_with(s, how),
        config,
        (coarse_iterations, corrections),
        observer,
    );
    let fine = indentify_identify::identify(&s.problem, &fine_cfg, observer)?;
    Ok((fine, phase))
}

#[cfg(test)]
mod tests {
    use super::*;
    use indentify_mesh::{CylinderMesher, ZonedCylinderMesher};

    #[test]
    fn coarse_cylinder_halves_the_counts_and_squares_the_gradings() {
        let m = Mesher::Cylinder(CylinderMesher {
            radius: 10.0,
            height: 10.0,
            nr: 20,
            nz: 21,
            grading_r: 1.3,
            grading_z: 1.9,
        });
        let Mesher::Cylinder(c) = coarsen_mesher(&m).expect("coarse") else {
            panic!("a cylinder")
        };
        assert_eq!((c.nr, c.nz), (10, 11));
        assert!((c.grading_r - 1.69).abs() < 1e-12);
        assert_eq!(c.grading_z, 3.0);
        // the refinement of the discretization check nests it back: 2x in each direction
        let Mesher::Cylinder(f) =
            crate::discretization::refine_mesher(&Mesher::Cylinder(c)).expect("refined")
        else {
            panic!("a cylinder")
        };
        assert_eq!(f.nr, 20);
        assert!((f.grading_r - 1.3).abs() < 1e-12);
    }

    #[test]
    fn a_coarsening_factor_scales_the_counts_and_powers_the_gradings() {
        let m = Mesher::Cylinder(CylinderMesher {
            radius: 10.0,
            height: 10.0,
            nr: 20,
            nz: 21,
            grading_r: 1.3,
            grading_z: 1.9,
        });
        let Mesher::Cylinder(c) = coarsen_mesher_by(&m, 1.5).expect("coarse") else {
            panic!("a cylinder")
        };
        // ceil(20 / 1.5) = 14, ceil(21 / 1.5) = 14; 1.3^1.5 = 1.48223..., 1.9^1.5 > 2.6
        assert_eq!((c.nr, c.nz), (14, 14));
        assert!((c.grading_r - 1.482_228_05).abs() < 1e-8, "{}", c.grading_r);
        assert!((c.grading_z - 2.618_969_26).abs() < 1e-8, "{}", c.grading_z);
        // 1: the fine mesh itself
        assert_eq!(coarsen_mesher_by(&m, 1.0).expect("same"), m);
        // 2: the rules of coarsen_mesher
        assert_eq!(
            coarsen_mesher_by(&m, 2.0).expect("2x"),
            coarsen_mesher(&m).expect("2x")
        );
        for bad in [0.5, 4.5, f64::NAN] {
            let e = coarsen_mesher_by(&m, bad).expect_err("refused");
            assert!(format!("{e:#}").contains("outside [1, 4]"), "{e:#}");
        }
        let zoned = Mesher::Zoned(ZonedCylinderMesher {
            radius: 1.0,
            height: 1.0,
            core: 0.1,
            core_elements: 12,
            grading: 1.5,
        });
        let Mesher::Zoned(z) = coarsen_mesher_by(&zoned, 1.5).expect("12 -> 8") else {
            panic!("zoned")
        };
        assert_eq!(z.core_elements, 8);
        let e = coarsen_mesher_by(&zoned, 3.5).expect_err("12 -> 3 is below 4");
        assert!(format!("{e:#}").contains("contact resolution"), "{e:#}");
    }

    #[test]
    fn a_coarse_mesh_below_the_contact_resolution_is_refused_naming_the_field() {
        let zoned = |core_elements| {
            Mesher::Zoned(ZonedCylinderMesher {
                radius: 1.0,
                height: 1.0,
                core: 0.1,
                core_elements,
                grading: 1.5,
            })
        };
        let Mesher::Zoned(c) = coarsen_mesher(&zoned(12)).expect("12 -> 6") else {
            panic!("zoned")
        };
        assert_eq!(c.core_elements, 6);
        assert!((c.grading - 2.25).abs() < 1e-12);
        let e = coarsen_mesher(&zoned(7)).expect_err("7 -> 3 is below 4");
        let text = format!("{e:#}");
        assert!(text.contains("specimen.elements_in_contact = 7"), "{text}");
        assert!(text.contains("contact resolution"), "{text}");
    }

    #[test]
    fn elements_under_counts_the_top_edges_inside_the_radius() {
        let mesh = indentify_mesh::CylinderMesher {
            radius: 1.0,
            height: 1.0,
            nr: 10,
            nz: 3,
            grading_r: 1.0,
            grading_z: 1.0,
        }
        .build()
        .expect("mesh");
        // uniform edges 0.1 wide: those starting at 0, 0.1, 0.2 lie under a = 0.25
        assert_eq!(elements_under(&mesh, 0.25), 3);
        assert_eq!(elements_under(&mesh, 1.5), 10);
    }
}
