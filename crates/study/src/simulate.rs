//! The simulation pipeline: the direct problem of a configuration, its force-depth curve
//! (with optional multiplicative noise), the optional VTU field series, and the assembled
//! tangent of a step for users who inspect the matrices.

use std::path::PathBuf;
use std::time::Instant;

use indentify_contact::{ContactError, DirectSolver, Trajectory};
use indentify_identify::{Cancel, multiplicative_noise};
use indentify_laws::Material;

use crate::config::Config;
use crate::config::{Measured, Mesher};
use crate::error::{Classify, Error, ErrorKind, Result};
use crate::output::{self, CurveRow};
use crate::source::ConfigSource;
use crate::stoppable::{STOPPED, Stoppable};

/// What to simulate and what to write.
#[derive(Clone, Debug)]
pub struct SimulateOptions {
    /// The configuration.
    pub config: ConfigSource,
    /// `dotted.path=value` overrides.
    pub sets: Vec<String>,
    /// Multiplicative noise `F (1 + a xi)` with amplitude and seed (on the depth,
    /// `h (1 + a xi)`, under load control: the observable).
    pub noise: Option<(f64, u64)>,
    /// Write the curve here (atomically); `None` keeps it in the outcome only.
    pub out: Option<PathBuf>,
    /// Write the field series (VTU and steps.pvd) into this folder.
    pub vtu: Option<PathBuf>,
    /// Write the constrained tangent of schedule step N (from 1) into this folder as
    /// Matrix Market (`K_step_N.mtx`, through sprs), with `equations.csv` (equation, node,
    /// component, r, z, constrained).
    pub matrix_market: Option<(PathBuf, usize)>,
    /// The test (from 1) of a joint configuration (`tests: [...]`) to work on; required
    /// for one, refused for a one-test configuration.
    pub test: Option<usize>,
}

impl SimulateOptions {
    /// The simulation of `config`, nothing written.
    pub fn new(config: ConfigSource) -> SimulateOptions {
        SimulateOptions {
            config,
            sets: Vec::new(),
            noise: None,
            out: None,
            vtu: None,
            matrix_market: None,
            test: None,
        }
    }
}

/// A simulation's outcome.
#[derive(Debug)]
pub struct SimulateOutcome {
    /// The configuration's name.
    pub config: String,
    /// The law's name and its parameters as `name = value`.
    pub law: &'static str,
    /// `name = value` of every parameter.
    pub params: Vec<String>,
    /// The punch, described.
    pub punch: String,
    /// The mesher.
    pub mesher: Mesher,
    /// Nodes and elements.
    pub size: (usize, usize),
    /// Schedule steps.
    pub schedule_steps: usize,
    /// The schedule's own sub-steps in words (`data.substeps`), `None` without.
    pub substeps: Option<String>,
    /// The steps the solver took beyond the schedule's steps and their own sub-steps: the
    /// sub-steps of cut steps (also those of a step the run stopped in).
    pub cut_substeps: usize,
    /// The curve at the schedule times reached (noise applied).
    pub rows: Vec<CurveRow>,
    /// The trajectory (timings, iterations, steps).
    pub trajectory: Trajectory,
    /// The measured record driving the schedule, if any.
    pub measured: Option<Measured>,
    /// Field states written to `vtu`.
    pub vtu_states: Option<usize>,
    /// The Matrix Market file written, with its size and non-zeros.
    pub matrix: Option<(PathBuf, usize, usize)>,
    /// Why the run stopped early (a step that failed even after cutting); the curve is
    /// then the converged part.
    pub failure: Option<String>,
    /// Wall time (s).
    pub seconds: f64,
}

/// Runs the simulation and writes what `opts` asks.
///
/// # Errors
/// An invalid configuration or noise amplitude, an output that cannot be written (checked
/// before solving). A step that fails even after cutting is not an error: the outcome's
/// `failure` says so and the curve up to there is written.
pub fn run(opts: &SimulateOptions) -> Result<SimulateOutcome> {
    run_here(opts, None)
}

/// [`run`] that stops between steps once `cancel` is raised: the forward run ends at the
/// step in progress ([`crate::stoppable`]), the outcome's `failure` says it was stopped
/// (containing [`crate::stoppable::STOPPED`]) and the curve up to the last converged
/// step is written as for a failed step. Until then, the same bits as [`run`].
///
/// # Errors
/// As [`run`].
pub fn run_cancellable(opts: &SimulateOptions, cancel: &Cancel) -> Result<SimulateOutcome> {
    run_here(opts, Some(cancel))
}

fn run_here(opts: &SimulateOptions, cancel: Option<&Cancel>) -> Result<SimulateOutcome> {
    let start = Instant::now();
    let name = opts.config.name();
    crate::identify::check_noise(opts.noise)?;
    let cfg = opts
        .config
        .load(&opts.sets)?
        .one_test(opts.test, "simulate", &name)
        .kind(ErrorKind::Config)?;
    let (law, params) = cfg.law.build().kind(ErrorKind::Config)?;
    let law = &law;
    let (prepared, load) = prepare_driven(&cfg, &name)?;
    let (mesher, model, schedule) = (prepared.mesher, prepared.model, prepared.schedule);
    let solver_opts = cfg.solver.options(opts.vtu.is_some());
    // fail on unwritable outputs before solving
    if let Some(p) = &opts.out {
        let dir = p
            .parent()
            .filter(|d| !d.as_os_str().is_empty())
            .map_or_else(|| PathBuf::from("."), PathBuf::from);
        if p.is_dir() {
            return Err(Error::msg(
                ErrorKind::Io,
                format!(
                    "cannot write the curve file `{}`: it is a folder; give a file name, e.g. \
                     `{}`",
                    p.display(),
                    p.join("curve.csv").display()
                ),
            ));
        }
        if !dir.is_dir() {
            return Err(Error::msg(
                ErrorKind::Io,
                format!(
                    "cannot write the curve file `{}`: the folder `{}` does not exist",
                    p.display(),
                    dir.display()
                ),
            ));
        }
    }
    if let Some(dir) = &opts.vtu {
        crate::atomic::ensure_writable_dir(dir).kind(ErrorKind::Io)?;
    }
    if let Some((dir, step)) = &opts.matrix_market {
        if load.is_some() {
            return Err(Error::msg(
                ErrorKind::Config,
                format!("--matrix-market replays a depth-driven run: `{name}` is load-controlled"),
            ));
        }
        if *step == 0 || *step > schedule.n_steps() {
            return Err(Error::msg(
                ErrorKind::Config,
                format!(
                    "--at-step {step} is not a step of `{name}`: expected 1 to {}",
                    schedule.n_steps()
                ),
            ));
        }
        crate::atomic::ensure_writable_dir(dir).kind(ErrorKind::Io)?;
    }
    let mut solver = DirectSolver::new(&model).kind(ErrorKind::Solver)?;
    let stoppable = cancel.map(|c| Stoppable::new(&**law, c.clone()));
    let mat: &dyn Material = match &stoppable {
        Some(s) => s,
        None => &**law,
    };
    let run = match &load {
        Some(h) => solver.run_history(mat, &params, h, &solver_opts),
        None => solver.run(mat, &params, &schedule, &solver_opts),
    };
    let (trajectory, failure) = outcome(run, &name)?;
    let mut rows = output::curve(&schedule, &trajectory);
    if let Some((a, seed)) = opts.noise {
        // test K of a joint configuration draws its own noise, as `identify` does
        let seed = opts.test.map_or(seed, |k| {
            crate::identify::test_seed(seed, k.saturating_sub(1))
        });
        // the noise goes on the observable: the force under depth control, the depth
        // under load control (the prescribed force stays as prescribed)
        if load.is_some() {
            let depths: Vec<f64> = rows.iter().map(|r| r.h).collect();
            for (r, h) in rows.iter_mut().zip(multiplicative_noise(&depths, a, seed)) {
                r.h = h;
            }
        } else {
            let forces: Vec<f64> = rows.iter().map(|r| r.f).collect();
            for (r, f) in rows.iter_mut().zip(multiplicative_noise(&forces, a, seed)) {
                r.f = f;
            }
        }
    }
    if let Some(p) = &opts.out {
        output::write_curve(Some(p), &rows).kind(ErrorKind::Io)?;
    }
    let vtu_states = match &opts.vtu {
        Some(dir) => Some(
            output::write_vtu_series(dir, &model, &**law, &params, &trajectory)
                .kind(ErrorKind::Io)?,
        ),
        None => None,
    };
    let matrix = match &opts.matrix_market {
        Some((dir, step)) => Some(write_matrix(
            dir, *step, &model, &**law, &params, &schedule,
        )?),
        None => None,
    };
    Ok(SimulateOutcome {
        config: name,
        law: law.name(),
        params: law
            .params()
            .iter()
            .zip(&params)
            .map(|(i, v)| format!("{} = {v}", i.name))
            .collect(),
        punch: cfg.punch.describe(),
        mesher,
        size: (model.mesh.nodes.len(), model.mesh.elements.len()),
        schedule_steps: schedule.n_steps(),
        substeps: schedule.substeps_summary(),
        cut_substeps: cut_substeps(&schedule, &trajectory),
        rows,
        trajectory,
        measured: prepared.measured,
        vtu_states,
        matrix,
        failure,
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// The trajectory of a forward run and why it ended early, if it did: a step that failed
/// even after cutting, or a stop asked through [`run_cancellable`] (not errors: the curve
/// up to there is the outcome).
fn outcome(
    run: std::result::Result<Trajectory, ContactError>,
    name: &str,
) -> Result<(Trajectory, Option<String>)> {
    Ok(match run {
        Ok(t) => (t, None),
        Err(ContactError::StepFailed {
            step,
            t,
            reason,
            partial,
            ..
        }) if reason.contains(STOPPED) => (
            *partial,
            Some(format!("{STOPPED} during step {step} (t = {t} s)")),
        ),
        Err(ContactError::StepFailed {
            step,
            t,
            cuts,
            reason,
            partial,
        }) => (
            *partial,
            Some(format!(
                "step {step} (t = {t} s) failed after {cuts} step cuts: {reason}"
            )),
        ),
        Err(e) => {
            return Err(Error::new(
                ErrorKind::Solver,
                anyhow::anyhow!(e).context(format!("cannot simulate `{name}`")),
            ));
        }
    })
}

/// [`Config::prepare_driven`] with its errors classified as `identify::prepare` does: a
/// record that cannot be read or drive a simulation is a data error, anything else a
/// configuration error.
fn prepare_driven(
    cfg: &Config,
    name: &str,
) -> Result<(
    crate::config::Prepared,
    Option<indentify_contact::LoadHistory>,
)> {
    cfg.prepare_driven(name).map_err(|e| {
        let kind = if e.downcast_ref::<crate::config::DataFailure>().is_some() {
            ErrorKind::Data
        } else {
            ErrorKind::Config
        };
        Error::new(kind, e)
    })
}

/// The steps of `traj` that a cut inserted: those ending at none of the times its
/// schedule step plans (the step's own sub-steps and its end, [`indentify_contact::Schedule::step_targets`];
/// a cut's times lie strictly between the last converged time and the next planned one,
/// so they never coincide). Exact also when the run stopped inside a step.
fn cut_substeps(
    schedule: &indentify_contact::Schedule,
    traj: &indentify_contact::Trajectory,
) -> usize {
    traj.steps
        .iter()
        .filter(|s| {
            !schedule
                .step_targets(s.schedule_index)
                .iter()
                .any(|t| t.to_bits() == s.t.to_bits())
        })
        .count()
}

/// Runs the first `step` schedule steps again and writes the constrained tangent of the
/// last one (Matrix Market, full symmetric storage) and the equation map.
fn write_matrix(
    dir: &std::path::Path,
    step: usize,
    model: &indentify_contact::Model,
    law: &dyn indentify_laws::Material,
    params: &[f64],
    schedule: &indentify_contact::Schedule,
) -> Result<(PathBuf, usize, usize)> {
    let prefix = schedule.prefix(step);
    let mut solver = DirectSolver::new(model).kind(ErrorKind::Solver)?;
    let opts = indentify_contact::SolverOptions {
        record_fields: false,
        ..Default::default()
    };
    solver
        .run(law, params, &prefix, &opts)
        .map_err(|e| Error::new(ErrorKind::Solver, anyhow::anyhow!(e)))?;
    let (k, constrained) = solver.system().matrix(model);
    let path = dir.join(format!("K_step_{step}.mtx"));
    let tmp = dir.join(format!(".K_step_{step}.mtx.tmp-{}", std::process::id()));
    sprs::io::write_matrix_market(&tmp, &k)
        .and_then(|()| std::fs::rename(&tmp, &path))
        .map_err(|e| {
            let _ = std::fs::remove_file(&tmp);
            Error::msg(
                ErrorKind::Io,
                format!("cannot write `{}`: {e}", path.display()),
            )
        })?;
    let mut eqs = String::from("equation,node,component,r,z,constrained\n");
    for (d, &e) in model.dofs.eq.iter().enumerate() {
        if e == indentify_fe::dofs::NO_EQ {
            continue;
        }
        let node = d / 2;
        let [r, z] = model.mesh.nodes[node];
        eqs.push_str(&format!(
            "{e},{node},{},{r},{z},{}\n",
            if d % 2 == 0 { "r" } else { "z" },
            u8::from(constrained[e as usize])
        ));
    }
    crate::atomic::write(&dir.join("equations.csv"), eqs).kind(ErrorKind::Io)?;
    Ok((path, k.rows(), k.nnz()))
}

#[cfg(test)]
mod tests {
    use super::cut_substeps;
    use indentify_contact::{Schedule, StepRecord, Trajectory};

    fn step(t: f64, j: usize, on_schedule: bool) -> StepRecord {
        StepRecord {
            t,
            dt: 0.0,
            depth: 0.0,
            force: 0.0,
            contact_radius: 0.0,
            active: Vec::new(),
            lambda: Vec::new(),
            slip: Vec::new(),
            iterations: 1,
            active_set_changes: 0,
            on_schedule,
            schedule_index: j,
        }
    }

    /// Two sub-steps per step, one cut in step 2, and a run that stopped after the first
    /// sub-step of step 3: one cut step, not two (the planned sub-step of the step the run
    /// stopped in is not a cut).
    #[test]
    fn cuts_are_the_steps_at_unplanned_times() {
        let s = Schedule::from_record(&[0.0, 1.0, 2.0, 3.0], &[0.0, 0.1, 0.2, 0.1])
            .unwrap()
            .with_uniform_substeps(2)
            .unwrap();
        let traj = Trajectory {
            steps: vec![
                step(0.5, 1, false),
                step(1.0, 1, true),
                step(1.25, 2, false),
                step(1.5, 2, false),
                step(2.0, 2, true),
                step(2.5, 3, false),
            ],
            ..Default::default()
        };
        assert_eq!(cut_substeps(&s, &traj), 1);
        let whole = Trajectory {
            steps: traj.steps[..5].to_vec(),
            ..Default::default()
        };
        assert_eq!(cut_substeps(&s, &whole), 1);
    }
}
