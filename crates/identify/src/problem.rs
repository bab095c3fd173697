//! The identification problem (model, law, schedule, target forces, weights) and the
//! [`Evaluator`]: the cost `J`, its adjoint gradient and the sensitivity Jacobian at a
//! parameter point, with a one-point cache keyed on the exact parameter bits so that one
//! forward solve and at most one adjoint sweep serve every request at that point.

use std::collections::HashSet;
use std::time::Instant;

use indentify_adjoint::Adjoint;
use indentify_contact::{ContactError, DirectSolver, Model, Schedule, SolverOptions, Trajectory};
use indentify_laws::Law;

use crate::IdentifyError;
use crate::data::ForceRecord;

/// Everything fixed during an identification: the direct problem (model, law, depth
/// schedule, solver options) and the data it is compared with.
///
/// The cost (DESIGN.md §2, paper eq. 16) is
/// `J(c) = 1/2 sum_{i=0..I} w_i (F_i(c) - F_i^exp)^2` over the schedule times `t_i`
/// (index 0 is the stress-free initial state, `F_0 = 0`); `F^exp` is the record
/// interpolated at `t_i`.
#[derive(Debug)]
pub struct Problem {
    /// The direct problem's model (mesh, punch, ...).
    pub model: Model,
    /// The constitutive law whose parameters are identified.
    pub law: &'static dyn Law,
    /// Depth history driving the simulation (the measured `U^exp(t)`).
    pub schedule: Schedule,
    /// Options of the direct solver (fields are always recorded: the adjoint needs them).
    pub solver_options: SolverOptions,
    /// `F_i^exp` at the schedule times (N), `schedule.t.len()` entries.
    pub target: Vec<f64>,
    /// Weights `w_i >= 0`, `schedule.t.len()` entries.
    pub weights: Vec<f64>,
}

impl Problem {
    /// Builds the problem; `record` is interpolated onto the schedule's times; `weights`
    /// default to 1 (one per schedule time, index 0 included).
    ///
    /// # Errors
    /// [`IdentifyError::RecordDoesNotCover`] when the record does not span the schedule;
    /// [`IdentifyError::InvalidWeights`] for a wrong length, a negative or non-finite
    /// weight, or all weights zero.
    pub fn new(
        model: Model,
        law: &'static dyn Law,
        schedule: Schedule,
        record: &ForceRecord,
        weights: Option<Vec<f64>>,
        solver_options: SolverOptions,
    ) -> Result<Problem, IdentifyError> {
        let target = record.at_times(&schedule.t)?;
        let n = schedule.t.len();
        let weights = weights.unwrap_or_else(|| vec![1.0; n]);
        if weights.len() != n {
            return Err(IdentifyError::InvalidWeights {
                why: format!(
                    "{} weights for {n} schedule times (one per time, the initial state included)",
                    weights.len()
                ),
            });
        }
        if let Some(i) = weights.iter().position(|w| !(w.is_finite() && *w >= 0.0)) {
            return Err(IdentifyError::InvalidWeights {
                why: format!("weight {i} = {} is not a finite value >= 0", weights[i]),
            });
        }
        if weights.iter().all(|&w| w == 0.0) {
            return Err(IdentifyError::InvalidWeights {
                why: "all weights are zero".into(),
            });
        }
        // with checkpoints, the states are saved every `checkpoint_every` steps and the
        // gradient replays the segments (bounded memory); otherwise every step's fields
        let solver_options = SolverOptions {
            record_fields: solver_options.checkpoint_every == 0,
            ..solver_options
        };
        Ok(Problem {
            model,
            law,
            schedule,
            solver_options,
            target,
            weights,
        })
    }

    /// Number of data points that count (non-zero weight).
    pub fn n_data(&self) -> usize {
        self.weights.iter().filter(|&&w| w > 0.0).count()
    }

    /// `J_ref = 1/2 sum w_i (F_i^exp)^2`: the cost of predicting zero force, the scale that
    /// the optimizers divide `J` by (so `sqrt(2 J / J_ref)` is a relative RMS misfit).
    pub fn reference_cost(&self) -> f64 {
        let j: f64 = 0.5
            * self
                .weights
                .iter()
                .zip(&self.target)
                .map(|(w, f)| w * f * f)
                .sum::<f64>();
        if j > 0.0 { j } else { 1.0 }
    }

    /// `J` of forces at the schedule times.
    pub fn cost_of(&self, forces: &[f64]) -> f64 {
        0.5 * forces
            .iter()
            .zip(&self.target)
            .zip(&self.weights)
            .map(|((f, d), w)| w * (f - d).powi(2))
            .sum::<f64>()
    }

    /// `dJ/dF` per trajectory step: `w_j (F_i - F_j^exp)` for a step ending on schedule
    /// time j, 0 for the sub-steps of a cut step (the cost does not see them).
    pub fn dj_df(&self, traj: &Trajectory) -> Vec<f64> {
        traj.steps
            .iter()
            .map(|s| {
                if s.on_schedule {
                    let j = s.schedule_index;
                    self.weights[j] * (s.force - self.target[j])
                } else {
                    0.0
                }
            })
            .collect()
    }
}

/// Counters of the expensive operations an [`Evaluator`] performed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counts {
    /// Forward (direct problem) solves, failed ones included.
    pub forward: usize,
    /// Forward solves that failed (the cost is then `+inf`).
    pub forward_failed: usize,
    /// Adjoint sweeps.
    pub adjoint: usize,
    /// Forward-sensitivity (Jacobian) computations.
    pub sensitivities: usize,
    /// Requests answered from the cache.
    pub cache_hits: usize,
    /// Distinct parameter points requested (forward solves can only exceed this when the
    /// optimizer comes back to a point it left: the cache holds one point).
    pub distinct_points: usize,
}

/// What the cache holds for the last parameter point.
#[derive(Debug)]
struct Entry {
    key: Vec<u64>,
    cost: f64,
    forces: Option<Vec<f64>>,
    traj: Option<Trajectory>,
    gradient: Option<Vec<f64>>,
    jacobian: Option<Vec<Vec<f64>>>,
}

/// The cost/gradient oracle of one [`Problem`]: owns the forward and adjoint
/// workspaces and caches the last point (its trajectory, `J`, `dJ/dc`, `dF/dc`).
///
/// A request at the same point (the same bits of every parameter) is served from the
/// cache, so a line search's cost call, the optimizer's gradient call after it and a
/// report's force call cost one forward solve and one adjoint sweep in total.
/// Each request at a new point replaces the entry.
#[derive(Debug)]
pub struct Evaluator<'p> {
    problem: &'p Problem,
    solver: DirectSolver,
    adjoint: Adjoint,
    entry: Option<Entry>,
    counts: Counts,
    best: Option<(f64, Vec<f64>)>,
    start: Instant,
    seen: HashSet<Vec<u64>>,
}

fn key_of(c: &[f64]) -> Vec<u64> {
    c.iter().map(|v| v.to_bits()).collect()
}

impl<'p> Evaluator<'p> {
    /// Workspaces for `problem` (one symbolic analysis each for the forward and the adjoint).
    ///
    /// # Errors
    /// [`IdentifyError::Forward`] / [`IdentifyError::Adjoint`] if the analysis fails.
    pub fn new(problem: &'p Problem) -> Result<Evaluator<'p>, IdentifyError> {
        let solver =
            DirectSolver::new(&problem.model).map_err(|source| IdentifyError::Forward {
                params: vec![],
                source,
            })?;
        let adjoint = Adjoint::new(&problem.model).map_err(|source| IdentifyError::Adjoint {
            params: vec![],
            source,
        })?;
        Ok(Evaluator {
            problem,
            solver,
            adjoint,
            entry: None,
            counts: Counts::default(),
            best: None,
            start: Instant::now(),
            seen: HashSet::new(),
        })
    }

    /// The problem.
    pub fn problem(&self) -> &'p Problem {
        self.problem
    }

    /// Counters so far.
    pub fn counts(&self) -> Counts {
        self.counts
    }

    /// Seconds since this evaluator was created.
    pub fn elapsed(&self) -> f64 {
        self.start.elapsed().as_secs_f64()
    }

    /// The lowest finite cost seen so far and its parameters.
    pub fn best(&self) -> Option<(f64, &[f64])> {
        self.best.as_ref().map(|(j, c)| (*j, c.as_slice()))
    }

    /// Makes sure the cache holds point `c` with its trajectory (one forward solve unless
    /// already there). A failed forward solve caches `J = +inf`.
    fn ensure(&mut self, c: &[f64], need_traj: bool) -> Result<&mut Entry, IdentifyError> {
        let key = key_of(c);
        if self.seen.insert(key.clone()) {
            self.counts.distinct_points += 1;
        }
        let hit = self
            .entry
            .as_ref()
            .is_some_and(|e| e.key == key && (!need_traj || e.traj.is_some()));
        if hit {
            self.counts.cache_hits += 1;
        } else {
            self.counts.forward += 1;
            let p = self.problem;
            let run = self
                .solver
                .run(&p.model, p.law, c, &p.schedule, &p.solver_options);
            let entry = match run {
                Ok(traj) => {
                    let forces = traj.forces();
                    let cost = p.cost_of(&forces);
                    if cost.is_finite() && self.best.as_ref().is_none_or(|(b, _)| cost < *b) {
                        self.best = Some((cost, c.to_vec()));
                    }
                    Entry {
                        key,
                        cost,
                        forces: Some(forces),
                        traj: Some(traj),
                        gradient: None,
                        jacobian: None,
                    }
                }
                Err(ContactError::StepFailed { .. }) if !need_traj => {
                    self.counts.forward_failed += 1;
                    Entry {
                        key,
                        cost: f64::INFINITY,
                        forces: None,
                        traj: None,
                        gradient: None,
                        jacobian: None,
                    }
                }
                Err(source) => {
                    if matches!(source, ContactError::StepFailed { .. }) {
                        self.counts.forward_failed += 1;
                    }
                    self.entry = None;
                    return Err(IdentifyError::Forward {
                        params: c.to_vec(),
                        source,
                    });
                }
            };
            self.entry = Some(entry);
        }
        match self.entry.as_mut() {
            Some(e) => Ok(e),
            None => Err(IdentifyError::Optimizer("cache entry vanished".into())),
        }
    }

    /// `J(c)`; `+inf` when the direct problem fails even after step cutting (so that a
    /// line search backs off).
    ///
    /// # Errors
    /// [`IdentifyError::Forward`] for inadmissible parameters.
    pub fn cost(&mut self, c: &[f64]) -> Result<f64, IdentifyError> {
        Ok(self.ensure(c, false)?.cost)
    }

    /// Forces `F_i(c)` at the schedule times (index 0 = initial state).
    ///
    /// # Errors
    /// [`IdentifyError::Forward`] when the direct problem fails.
    pub fn forces(&mut self, c: &[f64]) -> Result<Vec<f64>, IdentifyError> {
        let e = self.ensure(c, true)?;
        Ok(e.forces.clone().unwrap_or_default())
    }

    /// The recorded trajectory at `c`.
    ///
    /// # Errors
    /// [`IdentifyError::Forward`] when the direct problem fails.
    pub fn trajectory(&mut self, c: &[f64]) -> Result<&Trajectory, IdentifyError> {
        let e = self.ensure(c, true)?;
        e.traj
            .as_ref()
            .ok_or_else(|| IdentifyError::Optimizer("trajectory missing".into()))
    }

    /// `J(c)` and the full physical gradient `dJ/dc` (law order) by the adjoint.
    ///
    /// # Errors
    /// [`IdentifyError::Forward`] when the direct problem fails, [`IdentifyError::Adjoint`]
    /// when the adjoint does (e.g. Norton-Hoff with `m <= 1`).
    pub fn cost_and_gradient(&mut self, c: &[f64]) -> Result<(f64, Vec<f64>), IdentifyError> {
        let p = self.problem;
        // hit or miss, `ensure` counts it; a gradient already there is a second hit
        let has_grad = {
            let e = self.ensure(c, true)?;
            e.gradient.clone().map(|g| (e.cost, g))
        };
        if let Some(r) = has_grad {
            return Ok(r);
        }
        self.counts.adjoint += 1;
        let Some(e) = self.entry.as_mut() else {
            return Err(IdentifyError::Optimizer("cache entry vanished".into()));
        };
        let Some(traj) = e.traj.as_ref() else {
            return Err(IdentifyError::Optimizer("trajectory missing".into()));
        };
        let rho = p.dj_df(traj);
        let g = if p.solver_options.checkpoint_every > 0 {
            self.adjoint.gradient_replayed(
                &p.model,
                p.law,
                c,
                traj,
                &rho,
                &mut self.solver,
                &p.schedule,
                &p.solver_options,
            )
        } else {
            self.adjoint.gradient(&p.model, p.law, c, traj, &rho)
        }
        .map_err(|source| IdentifyError::Adjoint {
            params: c.to_vec(),
            source,
        })?;
        e.gradient = Some(g.dj_dc.clone());
        Ok((e.cost, g.dj_dc))
    }

    /// The Jacobian `dF_i/dc_k` at the schedule times (row 0, the initial state, is 0), all
    /// law parameters, by forward sensitivities.
    ///
    /// # Errors
    /// As [`Evaluator::cost_and_gradient`].
    pub fn jacobian(&mut self, c: &[f64]) -> Result<Vec<Vec<f64>>, IdentifyError> {
        let p = self.problem;
        let np = c.len();
        let cached = self.ensure(c, true)?.jacobian.clone();
        if let Some(j) = cached {
            return Ok(j);
        }
        self.counts.sensitivities += 1;
        let Some(e) = self.entry.as_mut() else {
            return Err(IdentifyError::Optimizer("cache entry vanished".into()));
        };
        let Some(traj) = e.traj.as_ref() else {
            return Err(IdentifyError::Optimizer("trajectory missing".into()));
        };
        // the forward sensitivities need every step's fields: a checkpointed trajectory
        // is recorded again in full for them (the memory of one unbounded run)
        let full;
        let traj = if traj.fields.len() == traj.steps.len() + 1 {
            traj
        } else {
            let opts = SolverOptions {
                record_fields: true,
                checkpoint_every: 0,
                ..p.solver_options.clone()
            };
            full = self
                .solver
                .run(&p.model, p.law, c, &p.schedule, &opts)
                .map_err(|source| IdentifyError::Forward {
                    params: c.to_vec(),
                    source,
                })?;
            &full
        };
        let sens = self
            .adjoint
            .sensitivities(&p.model, p.law, c, traj)
            .map_err(|source| IdentifyError::Adjoint {
                params: c.to_vec(),
                source,
            })?;
        let mut jac = vec![vec![0.0; np]; p.schedule.t.len()];
        for (s, row) in traj.steps.iter().zip(&sens.df_dc) {
            if s.on_schedule {
                jac[s.schedule_index].clone_from(row);
            }
        }
        e.jacobian = Some(jac.clone());
        Ok(jac)
    }
}
