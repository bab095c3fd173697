//! The discretization error of a fit: the forward problem re-run at the optimum on a mesh
//! refined 2x in each direction and with every time step halved, the change of the fitted
//! force at the schedule times, and the parameter shift it implies through the
//! sensitivities (docs/discretization.md).
//!
//! With `S = dF/dc` of the fit (original discretization, free parameters), `W` the cost's
//! weights and `delta_F_i = F_refined(t_i) - F_fit(t_i)`, the parameters that the refined
//! discretization would identify from the same data are, to first order (the residual of
//! the fit is orthogonal to the columns of `S` at the optimum),
//! `c_refined ~ c_fit + delta_c`, `delta_c = -(S^T W S)^-1 S^T W delta_F`: the refined model
//! predicts `delta_F` more force, so the parameters move to take it back. The small system
//! is solved on the relative scale (`D = diag(|c|)`, columns normalized) by an
//! eigendecomposition with a rank cut; a parameter that does not act on the data, or that
//! lies in a dropped direction, gets no shift ("undetermined").
//!
//! A joint fit refines every test (each on its own mesh and schedule, the tests in
//! parallel) and stacks them as the fit does: `delta_F` and `S` are the tests' rows laid
//! end to end, `W` their weights (the test weights `w_k` included), so `delta_c` is the
//! shift of the joint identification.
//!
//! Refinement rules: a `Cylinder` specimen gets `2 nr x 2 nz` elements with the gradings
//! square-rooted (every element split in four: the refined mesh nests the original); an
//! `Auto` specimen gets `2 elements_in_contact` in its uniform core and its far-field
//! grading square-rooted (about twice the elements per direction there too). A history
//! gets every segment's `steps` doubled; a schedule from a measured record gets a midpoint
//! (time and depth linearly interpolated) inserted in every step. Either way the original
//! schedule times are every second refined time, where the refined force is read.

use std::time::Instant;

use anyhow::{Context as _, Result, anyhow, bail};
use indentify_contact::{DirectSolver, LoadHistory, Model, Schedule, SegmentSpec, SolverOptions};
use indentify_identify::{Evaluator, Problem, identifiability::INSENSITIVE};

use crate::config::{Config, History, Mesher};
use crate::solve::forward;

/// Relative eigenvalue of the normalized Fisher matrix under which a direction is dropped
/// (a singular value 1e-6 of the largest).
pub const RANK_CUT: f64 = 1e-12;

/// The discretization error of a fit at its optimum.
#[derive(Clone, Debug, PartialEq)]
pub struct Discretization {
    /// The refined mesh, e.g. `graded cylinder 12 x 12 Q8 (...)`; for a joint fit each
    /// test's, `name: mesh` joined by `; ` (the same mesh named once).
    pub mesh: String,
    /// The refined time steps, e.g. `every segment's steps doubled: 24 steps (was 12)`;
    /// for a joint fit each test's, as `mesh`.
    pub steps: String,
    /// Elements of the original and of the refined mesh (a joint fit: summed over the
    /// tests).
    pub elements: (usize, usize),
    /// Solver steps (the schedule's steps times their sub-steps, without cuts) of the
    /// original and of the refined run (a joint fit: summed).
    pub n_steps: (usize, usize),
    /// `F_refined(t_i) - F_fit(t_i)` at the schedule times (N); a joint fit's tests laid
    /// end to end as the problem's data.
    pub delta_f: Vec<f64>,
    /// RMS of `delta_F` (N), all rows.
    pub rms: f64,
    /// RMS of `delta_F` over the largest |F_fit|; for a joint fit the largest of the
    /// tests' (each over its own F_max).
    pub rms_rel: f64,
    /// Largest |delta_F| (N).
    pub max_abs: f64,
    /// Per law parameter: `c_refined - c_fit` predicted through the sensitivities; `None`
    /// for a fixed or an undetermined parameter. A joint fit's shift is the joint one:
    /// every test refined at once, the tests' weighted sensitivities stacked.
    pub shift: Vec<Option<f64>>,
    /// `shift / |c|`.
    pub relative_shift: Vec<Option<f64>>,
    /// Free parameters that the data do not determine (no shift).
    pub undetermined: Vec<&'static str>,
    /// Wall time of the refined runs and the sensitivities (s).
    pub seconds: f64,
    /// Per test (one entry for a one-test fit): its refined discretization and force
    /// change.
    pub tests: Vec<TestDiscretization>,
}

/// One test's part of a [`Discretization`].
#[derive(Clone, Debug, PartialEq)]
pub struct TestDiscretization {
    /// The test's name (`tests[K].name` or `test K`; the configuration's for one test).
    pub name: String,
    /// Its refined mesh, described.
    pub mesh: String,
    /// Its refined time steps, described.
    pub steps: String,
    /// Elements of the original and of the refined mesh.
    pub elements: (usize, usize),
    /// Solver steps (the schedule's steps times their sub-steps) of the original and of
    /// the refined run.
    pub n_steps: (usize, usize),
    /// Its rows in [`Discretization::delta_f`].
    pub rows: std::ops::Range<usize>,
    /// RMS of its `delta_F` (N).
    pub rms: f64,
    /// RMS of its `delta_F` over its largest |F_fit|.
    pub rms_rel: f64,
    /// Its largest |delta_F| (N).
    pub max_abs: f64,
}

impl Discretization {
    /// One line: `refined mesh ..., steps ...: force change RMS 0.12% of F_max`.
    pub fn summary(&self) -> String {
        if self.tests.len() > 1 {
            return format!(
                "discretization: each of the {} tests on its mesh refined 2x with its steps                  halved: the force changes by RMS {:.3}% of F_max at most ({}), max {:.3e} N,                  {:.1} s",
                self.tests.len(),
                100.0 * self.rms_rel,
                self.tests
                    .iter()
                    .map(|t| format!("{} {:.3}%", t.name, 100.0 * t.rms_rel))
                    .collect::<Vec<_>>()
                    .join(", "),
                self.max_abs,
                self.seconds
            );
        }
        format!(
            "discretization: {} and {}: the force changes by RMS {:.3}% of F_max (max {:.3e} \
             N), {:.1} s",
            self.mesh,
            self.steps,
            100.0 * self.rms_rel,
            self.max_abs,
            self.seconds
        )
    }
}

/// One test of the fit, as [`compute`] needs it.
pub struct TestInputs<'a> {
    /// The test's name (for messages and the per-test results).
    pub name: String,
    /// The test's configuration (a joint fit's `Config::test_config`: its specimen,
    /// punch, contact, kinematics, history or data).
    pub config: &'a Config,
    /// The test's mesher as prepared.
    pub mesher: &'a Mesher,
    /// Solver options of the test's run.
    pub solver: &'a SolverOptions,
}

/// The pieces of the fit the computation needs.
pub struct Inputs<'a> {
    /// The tests, in the problem's order (one for a one-test fit).
    pub tests: &'a [TestInputs<'a>],
    /// The identification problem (original models, schedules, weights).
    pub problem: &'a Problem,
    /// The optimum (full law vector).
    pub c: &'a [f64],
    /// Which law parameters are free.
    pub free: &'a [bool],
    /// The configuration's name, for messages.
    pub name: &'a str,
}

/// The mesher refined 2x in each direction (see the module's rules).
///
/// # Errors
/// A refined count past the mesher's limit (2000).
pub fn refine_mesher(mesher: &Mesher) -> Result<Mesher> {
    let refined = match *mesher {
        Mesher::Cylinder(mut m) => {
            m.nr *= 2;
            m.nz *= 2;
            m.grading_r = m.grading_r.sqrt();
            m.grading_z = m.grading_z.sqrt();
            m.validate()
                .context("the mesh cannot be refined 2x for the discretization error")?;
            Mesher::Cylinder(m)
        }
        Mesher::Zoned(mut m) => {
            m.core_elements *= 2;
            m.grading = m.grading.sqrt();
            m.validate()
                .context("the mesh cannot be refined 2x for the discretization error")?;
            Mesher::Zoned(m)
        }
    };
    Ok(refined)
}

/// The schedule with every step halved: a history's segments with twice the steps, a
/// record's schedule with its midpoints inserted; with a description.
///
/// # Errors
/// A history whose doubled steps exceed the schedule's limit.
pub fn refine_schedule(
    history: Option<&History>,
    schedule: &Schedule,
) -> Result<(Schedule, String)> {
    let n = schedule.n_steps();
    if let Some(h) = history {
        let segments: Vec<SegmentSpec> = h
            .segments
            .iter()
            .map(|s| SegmentSpec {
                steps: 2 * s.steps,
                ..*s
            })
            .collect();
        let s = LoadHistory::from_specs(&segments)?.schedule;
        let text = format!(
            "every segment's steps doubled ({} steps, was {n})",
            s.n_steps()
        );
        return Ok((s, text));
    }
    let mut t = Vec::with_capacity(2 * n + 1);
    let mut d = Vec::with_capacity(2 * n + 1);
    let mut k = Vec::with_capacity(2 * n);
    for i in 0..n {
        t.push(schedule.t[i]);
        d.push(schedule.depth[i]);
        t.push(0.5 * (schedule.t[i] + schedule.t[i + 1]));
        d.push(0.5 * (schedule.depth[i] + schedule.depth[i + 1]));
        // each half keeps the step's sub-steps: the solver's steps are halved too
        k.extend([schedule.substeps_of(i + 1); 2]);
    }
    t.push(schedule.t[n]);
    d.push(schedule.depth[n]);
    let s = Schedule::from_record(&t, &d)?.with_substeps(k)?;
    let text = if s.substeps.is_empty() {
        format!(
            "the record's midpoints inserted ({} steps, was {n})",
            s.n_steps()
        )
    } else {
        format!(
            "the record's midpoints inserted ({} steps, was {n}; {} solver steps, was {})",
            s.n_steps(),
            s.n_solver_steps(),
            schedule.n_solver_steps()
        )
    };
    Ok((s, text))
}

/// One test's refined run at `c`: its force change at the schedule times against
/// `f_fit` (the test's rows of the fit) and its description.
fn refine_test(
    t: &TestInputs<'_>,
    test: &indentify_identify::Test,
    law: &dyn indentify_laws::Material,
    c: &[f64],
    f_fit: &[f64],
    rows: std::ops::Range<usize>,
    name: &str,
) -> Result<(Vec<f64>, TestDiscretization)> {
    let fine_mesher = refine_mesher(t.mesher)?;
    let (mesh, _, _) = fine_mesher
        .build_for(&test.model.punch)
        .context("cannot build the refined mesh")?;
    let elements = (test.model.mesh.elements.len(), mesh.elements.len());
    let model = Model::with_contact(mesh, test.model.punch.clone(), t.config.contact)
        .and_then(|m| m.with_kinematics(t.config.kinematics))
        .context("cannot build the refined model")?;
    let (schedule, steps) = refine_schedule(t.config.history.as_ref(), &test.schedule)?;
    let n = test.schedule.t.len();
    if schedule.t.len() != 2 * n - 1 {
        bail!(
            "the refined schedule has {} times, expected {}",
            schedule.t.len(),
            2 * n - 1
        );
    }
    let opts = SolverOptions {
        record_fields: false,
        checkpoint_every: 0,
        ..t.solver.clone()
    };
    let mut direct = DirectSolver::new(&model)?;
    let traj = forward(&mut direct, law, c, &schedule, &opts, name)
        .context("the refined run for the discretization error failed")?;
    let f_fine = traj.forces();
    if f_fine.len() != schedule.t.len() || f_fit.len() != n {
        return Err(anyhow!(
            "the refined run did not reach the end of the schedule"
        ));
    }
    let delta_f: Vec<f64> = (0..n).map(|i| f_fine[2 * i] - f_fit[i]).collect();
    let f_max = f_fit.iter().fold(0.0_f64, |m, f| m.max(f.abs()));
    let rms = (delta_f.iter().map(|d| d * d).sum::<f64>() / n as f64).sqrt();
    let max_abs = delta_f.iter().fold(0.0_f64, |m, d| m.max(d.abs()));
    let rms_rel = if f_max > 0.0 { rms / f_max } else { f64::NAN };
    Ok((
        delta_f,
        TestDiscretization {
            name: t.name.clone(),
            mesh: fine_mesher.describe(),
            steps,
            elements,
            // the solver's steps: the schedule's with their own sub-steps (data.substeps)
            n_steps: (test.schedule.n_solver_steps(), schedule.n_solver_steps()),
            rows,
            rms,
            rms_rel,
            max_abs,
        },
    ))
}

/// `name: text` of every test, a text shared by all tests given once.
fn per_test_text(
    tests: &[TestDiscretization],
    text: impl Fn(&TestDiscretization) -> &str,
) -> String {
    let first = tests.first().map_or("", &text);
    if tests.len() == 1 || tests.iter().all(|t| text(t) == first) {
        return first.to_string();
    }
    tests
        .iter()
        .map(|t| format!("{}: {}", t.name, text(t)))
        .collect::<Vec<_>>()
        .join("; ")
}

/// Runs every test's refined forward problem at the optimum (the tests in parallel on the
/// problem's pool) and the sensitivities of the fit, and returns the force changes and the
/// parameter shift.
///
/// # Errors
/// A refined mesh or schedule that cannot be built, a refined run or a sensitivity pass
/// that fails (naming the test of a joint fit).
pub fn compute(inputs: &Inputs<'_>) -> Result<Discretization> {
    use rayon::prelude::*;
    let clock = Instant::now();
    let Inputs {
        tests,
        problem,
        c,
        free,
        name,
    } = *inputs;
    if tests.len() != problem.tests.len() {
        bail!(
            "{} tests given for a problem of {}",
            tests.len(),
            problem.tests.len()
        );
    }
    // the fit: forces and sensitivities in the original discretization
    let mut ev = Evaluator::new(problem)?;
    let f_fit = ev.forces(c)?;
    let jac = ev.jacobian(c)?;
    drop(ev);

    // the refined runs, in test order whatever the threads
    let joint = tests.len() > 1;
    let law = &problem.law;
    let runs: Vec<Result<(Vec<f64>, TestDiscretization)>> = problem.install(|| {
        tests
            .par_iter()
            .zip(problem.tests.par_iter())
            .enumerate()
            .map(|(k, (t, test))| {
                let rows = problem.rows_of(k);
                let label = if joint {
                    format!("{name} [{}]", t.name)
                } else {
                    name.to_string()
                };
                let f = f_fit.get(rows.clone()).unwrap_or_default();
                refine_test(t, test, &**law, c, f, rows, &label).with_context(|| {
                    if joint {
                        format!("in test {} ({})", k + 1, t.name)
                    } else {
                        String::new()
                    }
                })
            })
            .collect()
    });
    let mut delta_f = Vec::with_capacity(f_fit.len());
    let mut per_test = Vec::with_capacity(tests.len());
    for r in runs {
        let (d, t) = r?;
        delta_f.extend(d);
        per_test.push(t);
    }
    let n = delta_f.len();
    let rms = (delta_f.iter().map(|d| d * d).sum::<f64>() / n as f64).sqrt();
    let max_abs = delta_f.iter().fold(0.0_f64, |m, d| m.max(d.abs()));
    let rms_rel = per_test.iter().map(|t| t.rms_rel).fold(f64::NAN, f64::max);

    let free_idx: Vec<usize> = (0..c.len()).filter(|&k| free[k]).collect();
    let (shifts, undetermined_idx) = shift(&jac, &problem.weights, &delta_f, c, &free_idx);
    let mut shift_full = vec![None; c.len()];
    for (&k, s) in free_idx.iter().zip(shifts) {
        shift_full[k] = s;
    }
    let relative_shift = shift_full
        .iter()
        .zip(c)
        .map(|(s, v)| s.map(|s| s / v.abs()))
        .collect();
    let names = problem.law.params();
    Ok(Discretization {
        mesh: per_test_text(&per_test, |t| &t.mesh),
        steps: per_test_text(&per_test, |t| &t.steps),
        elements: per_test
            .iter()
            .fold((0, 0), |(a, b), t| (a + t.elements.0, b + t.elements.1)),
        n_steps: per_test
            .iter()
            .fold((0, 0), |(a, b), t| (a + t.n_steps.0, b + t.n_steps.1)),
        delta_f,
        rms,
        rms_rel,
        max_abs,
        shift: shift_full,
        relative_shift,
        undetermined: undetermined_idx.iter().map(|&k| names[k].name).collect(),
        seconds: clock.elapsed().as_secs_f64(),
        tests: per_test,
    })
}

/// `delta_c = -(S^T W S)^-1 S^T W delta_F` over the free parameters `free` (indices into
/// the law vector), solved on the relative scale with a rank cut; returns one shift per
/// free parameter (`None`: undetermined) and the law indices of the undetermined ones.
pub fn shift(
    jac: &[Vec<f64>],
    weights: &[f64],
    delta_f: &[f64],
    c: &[f64],
    free: &[usize],
) -> (Vec<Option<f64>>, Vec<usize>) {
    let p = free.len();
    // weighted rows, relative columns: a_ik = sqrt(w_i) dF_i/dc_k |c_k|
    let rows: Vec<(Vec<f64>, f64)> = jac
        .iter()
        .zip(weights)
        .zip(delta_f)
        .filter(|((_, w), _)| **w > 0.0)
        .map(|((r, w), d)| {
            let sw = w.sqrt();
            (
                free.iter().map(|&k| sw * r[k] * c[k].abs()).collect(),
                sw * d,
            )
        })
        .collect();
    let scale: Vec<f64> = (0..p)
        .map(|a| rows.iter().map(|(r, _)| r[a] * r[a]).sum::<f64>().sqrt())
        .collect();
    let largest = scale
        .iter()
        .copied()
        .filter(|s| s.is_finite())
        .fold(0.0, f64::max);
    let kept: Vec<usize> = (0..p)
        .filter(|&a| scale[a].is_finite() && largest > 0.0 && scale[a] > INSENSITIVE * largest)
        .collect();
    let q = kept.len();
    // normalized normal matrix (unit diagonal) and right-hand side
    let mut m = vec![vec![0.0; q]; q];
    let mut rhs = vec![0.0; q];
    for (r, b) in &rows {
        for (i, &a) in kept.iter().enumerate() {
            let ra = r[a] / scale[a];
            rhs[i] += ra * b;
            for (j, &bb) in kept.iter().enumerate() {
                m[i][j] += ra * r[bb] / scale[bb];
            }
        }
    }
    let (values, vectors) = jacobi_eigen(&m);
    let top = values.iter().copied().fold(0.0, f64::max);
    let mut y = vec![0.0; q];
    let mut dropped = vec![0.0; q];
    for (l, &lambda) in values.iter().enumerate() {
        let v: Vec<f64> = (0..q).map(|i| vectors[i][l]).collect();
        if top > 0.0 && lambda > RANK_CUT * top {
            let coef = v.iter().zip(&rhs).map(|(a, b)| a * b).sum::<f64>() / lambda;
            for i in 0..q {
                y[i] += coef * v[i];
            }
        } else {
            for i in 0..q {
                dropped[i] += v[i] * v[i];
            }
        }
    }
    let mut out = vec![None; p];
    for (i, &a) in kept.iter().enumerate() {
        // a parameter mostly in a dropped direction is not determined by the data
        if dropped[i] < 1e-2 {
            let rel = -y[i] / scale[a];
            out[a] = Some(rel * c[free[a]].abs()).filter(|s| s.is_finite());
        }
    }
    let undetermined = (0..p)
        .filter(|&a| out[a].is_none())
        .map(|a| free[a])
        .collect();
    (out, undetermined)
}

/// Eigenvalues and eigenvectors (columns) of a small symmetric matrix by cyclic Jacobi
/// rotations.
fn jacobi_eigen(a: &[Vec<f64>]) -> (Vec<f64>, Vec<Vec<f64>>) {
    let n = a.len();
    let mut a: Vec<Vec<f64>> = a.to_vec();
    let mut v: Vec<Vec<f64>> = (0..n)
        .map(|i| (0..n).map(|j| if i == j { 1.0 } else { 0.0 }).collect())
        .collect();
    for _sweep in 0..100 {
        let off: f64 = (0..n)
            .flat_map(|i| (0..n).filter(move |&j| j != i).map(move |j| (i, j)))
            .map(|(i, j)| a[i][j] * a[i][j])
            .sum();
        let diag: f64 = (0..n).map(|i| a[i][i] * a[i][i]).sum();
        if off <= 1e-30 * diag || off == 0.0 {
            break;
        }
        for p in 0..n {
            for q in p + 1..n {
                if a[p][q] == 0.0 {
                    continue;
                }
                let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let cs = 1.0 / (t * t + 1.0).sqrt();
                let sn = t * cs;
                for k in 0..n {
                    let (akp, akq) = (a[k][p], a[k][q]);
                    a[k][p] = cs * akp - sn * akq;
                    a[k][q] = sn * akp + cs * akq;
                }
                for k in 0..n {
                    let (apk, aqk) = (a[p][k], a[q][k]);
                    a[p][k] = cs * apk - sn * aqk;
                    a[q][k] = sn * apk + cs * aqk;
                }
                for row in v.iter_mut() {
                    let (vp, vq) = (row[p], row[q]);
                    row[p] = cs * vp - sn * vq;
                    row[q] = sn * vp + cs * vq;
                }
            }
        }
    }
    ((0..n).map(|i| a[i][i]).collect(), v)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A linear model F = S c: the shift recovers the least-squares change exactly.
    #[test]
    fn shift_of_a_linear_model_is_the_least_squares_solution() {
        let x: Vec<f64> = (0..10).map(|i| i as f64).collect();
        let jac: Vec<Vec<f64>> = x.iter().map(|&xi| vec![xi, 1.0, 0.0]).collect();
        let w = vec![1.0; 10];
        // delta_F = S (0.5, -2): the refined model gives more force, the parameters drop
        let df: Vec<f64> = x.iter().map(|&xi| 0.5 * xi - 2.0).collect();
        let (s, und) = shift(&jac, &w, &df, &[3.0, 7.0, 1.0], &[0, 1, 2]);
        assert!((s[0].unwrap() + 0.5).abs() < 1e-12, "{s:?}");
        assert!((s[1].unwrap() - 2.0).abs() < 1e-12, "{s:?}");
        assert_eq!(s[2], None);
        assert_eq!(und, vec![2]);
        // two columns with the same effect: neither is determined
        let jac: Vec<Vec<f64>> = x.iter().map(|&xi| vec![xi, xi]).collect();
        let (s, und) = shift(&jac, &w, &x, &[1.0, 1.0], &[0, 1]);
        assert_eq!(s, vec![None, None]);
        assert_eq!(und, vec![0, 1]);
    }
}
