//! The time-stepped direct problem (P): global Newton on equilibrium coupled with a
//! primal-dual active set for frictionless contact, adaptive step cutting, and the
//! recorded trajectory that the adjoint replays.
//!
//! At step i (DESIGN.md §1): local backward-Euler updates at every Gauss point give
//! `sigma_i(u_i)` and the tangent `C_i`; equilibrium `sum_g w_g B^T sigma_i = G^T lambda_i`
//! holds on the free dofs; on the active set `A_i` the contact dofs are prescribed,
//! `u_z,k = phi(r_k) - U_i`, and `lambda_k = -f_int,z,k` is the nodal reaction. The set is
//! updated by releasing nodes with `lambda_k < 0` and activating nodes with `gap_k < 0`.
//!
//! With [`ContactKind::Normal`] the gap of an active node is its signed distance to the
//! punch surface along the normal `m` at its closest point, `lambda_k = -m . f_int,k`, and
//! its two dofs are rotated into the surface frame: `m . du = g` is prescribed, the
//! tangential equation `t . f_int = 0` is solved with the curvature stiffness
//! `-lambda kappa / (1 + g kappa)` (docs/validation-contact.md §2). The force is always the
//! vertical one, `F = -sum_k f_int,z,k`.
//!
//! Cost (see `ConstrainedSystem`): affine laws (elasticity, Maxwell) converge in one solve
//! per active set and start each step from the stored internal force; nonlinear laws start
//! Newton from the displacement extrapolated in time while the depth keeps its rate
//! (by the polynomial of degree 1 to 3 that predicted the last step best), and solve
//! the Newton systems by CG preconditioned with an earlier factorization, to a relative
//! residual equal to Newton's own (Dembo, Eisenstat & Steihaug 1982), so that Newton stays
//! quadratic with a fraction of the factorizations.

use indentify_fe::dofs::NO_EQ;
use indentify_fe::{Discretization, DofMap, FeError, Pattern, QP_PER_ELEMENT};
use indentify_laws::{Law, Mat4, Vec4};
use indentify_mesh::Mesh;

use crate::ContactError;
use crate::friction::{self, Status};
use crate::history::Schedule;
use crate::kinematics::{self, ELEMENT_CHUNK, FiniteFailure, FiniteOut, Kinematics};
use crate::normal::{ContactKind, Projection, Surface};
use crate::punch::Punch;
use crate::system::{ConstrainedSystem, NodeFrame};
use rayon::prelude::*;

/// Numerical options of the direct solver.
#[derive(Clone, Debug, PartialEq)]
pub struct SolverOptions {
    /// Relative tolerance on the equilibrium residual (inf-norm over free dofs, relative
    /// to the largest internal force component).
    pub residual_tol: f64,
    /// Maximum global Newton iterations per step (counting re-solves after active-set changes).
    pub max_iterations: usize,
    /// Maximum number of successive halvings of a step before giving up.
    pub max_cuts: u32,
    /// Relative residual below which the active set is checked (and corrected) before full
    /// convergence: semi-smooth Newton on equilibrium and complementarity together. The
    /// default 1e-2 corrects a wrong set early (R2 with the degree-2 predictor: 298 Newton
    /// iterations with 1e-6, 284 with 1e-2, same solution); a step converges only with its
    /// set verified at `residual_tol`.
    pub active_set_check_tol: f64,
    /// Relative tolerance on penetration before a node is activated: times the current
    /// depth, and never less than times the width of the first element under the punch
    /// ([`Model::gap_length`]), so that near depth 0 a node just released is not
    /// re-activated by a penetration of round-off size.
    pub gap_tol: f64,
    /// Relative tolerance on tensile reactions (times the current force) before a node is released.
    pub lambda_tol: f64,
    /// Keep stresses and displacements of every step (needed by the adjoint and VTU output).
    pub record_fields: bool,
    /// With `record_fields = false`, save the solver state every this many schedule steps
    /// (0: never) so that the adjoint can replay segments instead of storing every step.
    pub checkpoint_every: usize,
}

impl Default for SolverOptions {
    fn default() -> Self {
        SolverOptions {
            residual_tol: 1e-10,
            max_iterations: 60,
            max_cuts: 8,
            active_set_check_tol: 1e-2,
            gap_tol: 1e-10,
            lambda_tol: 1e-10,
            record_fields: true,
            checkpoint_every: 0,
        }
    }
}

/// The direct problem's fixed data: mesh, Gauss-point geometry, dofs, pattern, contact
/// candidates and punch. Built once, solved for many parameter sets.
#[derive(Debug)]
pub struct Model {
    /// The mesh.
    pub mesh: Mesh,
    /// Gauss-point geometry.
    pub disc: Discretization,
    /// Dof map with the supports eliminated (axis u_r = 0, bottom u_z = 0).
    pub dofs: DofMap,
    /// Sparsity pattern of the tangent over equations.
    pub pattern: Pattern,
    /// Contact candidate nodes (the `top` node set, sorted by r).
    pub candidates: Vec<usize>,
    /// `phi(r_k)` of each candidate (mm).
    pub candidate_profile: Vec<f64>,
    /// Lumped full-circle area `int N_k 2 pi r dr` of each candidate (mm^2), for pressures.
    pub candidate_area: Vec<f64>,
    /// The punch.
    pub punch: Punch,
    /// Direction of the contact constraint (set at construction).
    pub contact: ContactKind,
    /// The punch surface of normal contact (`None` for vertical contact).
    surface: Option<Surface>,
    /// Small or finite strain ([`Model::with_kinematics`]; small by default).
    pub kinematics: Kinematics,
}

impl Model {
    /// Assembles the model for a mesh with `axis`, `bottom` and `top` node sets.
    ///
    /// The mesh is used as given: for a flat punch, pass it through
    /// [`crate::punch::treat_rim`] first (quarter-point elements at the rim; the CLI does).
    ///
    /// # Errors
    /// [`ContactError::Input`] for an invalid punch or a mesh without a `top` set.
    pub fn new(mesh: Mesh, punch: Punch) -> Result<Model, ContactError> {
        Model::with_contact(mesh, punch, ContactKind::Vertical)
    }

    /// As [`Model::new`] with the contact direction `contact` ([`ContactKind::Vertical`]
    /// is [`Model::new`]).
    ///
    /// # Errors
    /// As [`Model::new`].
    pub fn with_contact(
        mesh: Mesh,
        punch: Punch,
        contact: ContactKind,
    ) -> Result<Model, ContactError> {
        punch.validate()?;
        contact.validate()?;
        let surface = match contact {
            ContactKind::Vertical => None,
            ContactKind::Normal | ContactKind::NormalFriction { .. } => Some(Surface::new(&punch)?),
        };
        let candidates = mesh.node_set("top").to_vec();
        if candidates.len() < 3 || candidates.len() % 2 == 0 {
            return Err(ContactError::Input {
                field: "mesh.top",
                value: format!("{} nodes", candidates.len()),
                allowed: "an odd number >= 3 of top nodes (quadratic edges, sorted by r)".into(),
            });
        }
        let disc = Discretization::new(&mesh);
        let dofs = DofMap::cylinder(&mesh);
        let pattern = Pattern::new(&disc, &dofs);
        let r: Vec<f64> = candidates.iter().map(|&n| mesh.nodes[n][0]).collect();
        let candidate_profile = r.iter().map(|&x| punch.profile(x)).collect();
        // lumped areas of quadratic edges (r0, rm, r1): int N_k 2 pi r dr over the
        // isoparametric edge r(xi) = sum N_k r_k (a midside node need not be at the middle:
        // quarter-point rims); 3-point Gauss is exact for the quintic integrand
        let mut candidate_area = vec![0.0; r.len()];
        let p = (0.6f64).sqrt();
        for e in (0..r.len() - 1).step_by(2) {
            let re = [r[e], r[e + 1], r[e + 2]];
            for (xi, w) in [(-p, 5.0 / 9.0), (0.0, 8.0 / 9.0), (p, 5.0 / 9.0)] {
                let n = [0.5 * xi * (xi - 1.0), 1.0 - xi * xi, 0.5 * xi * (xi + 1.0)];
                let dn = [xi - 0.5, -2.0 * xi, xi + 0.5];
                let rr: f64 = (0..3).map(|k| n[k] * re[k]).sum();
                let jac: f64 = (0..3).map(|k| dn[k] * re[k]).sum();
                for k in 0..3 {
                    candidate_area[e + k] += w * n[k] * 2.0 * std::f64::consts::PI * rr * jac;
                }
            }
        }
        Ok(Model {
            mesh,
            disc,
            dofs,
            pattern,
            candidates,
            candidate_profile,
            candidate_area,
            punch,
            contact,
            surface,
            kinematics: Kinematics::Small,
        })
    }

    /// This model with the kinematics `kinematics`.
    ///
    /// # Errors
    /// [`ContactError::Input`] for [`Kinematics::Finite`] with vertical contact: its gap is
    /// taken at the node's reference radius and its reaction stays vertical, which has no
    /// meaning once the surface moves and rotates; finite strain needs `contact: Normal`.
    pub fn with_kinematics(mut self, kinematics: Kinematics) -> Result<Model, ContactError> {
        kinematics.check_contact(self.contact)?;
        self.kinematics = kinematics;
        Ok(self)
    }

    /// The closest point of the punch surface to candidate `k` displaced by `u` (all
    /// dofs) at depth `depth` (normal contact; the axis node, whose `u_r` is fixed, gets
    /// the vertical projection). With vertical contact: the vertical gap and frame.
    pub fn project(&self, k: usize, u: &[f64], depth: f64) -> Projection {
        let node = self.candidates[k];
        self.project_at(k, [u[2 * node], u[2 * node + 1]], depth)
    }

    /// As [`Model::project`] with the displacement `(u_r, u_z)` of the candidate.
    pub fn project_at(&self, k: usize, [ur, uz]: [f64; 2], depth: f64) -> Projection {
        let node = self.candidates[k];
        match &self.surface {
            Some(s) if self.dofs.equation(2 * node).is_some() => {
                let x = self.mesh.nodes[node];
                s.project([x[0] + ur, x[1] + uz + depth])
            }
            _ => Projection::vertical(
                self.candidate_profile[k] - depth - uz - self.mesh.nodes[node][1],
            ),
        }
    }

    /// The frames of the active candidates of a converged normal-contact step (empty for
    /// vertical contact): the rotation of each node's dofs and the curvature stiffness
    /// `-lambda kappa / (1 + g kappa)` on its tangential dof, from the recorded reactions
    /// `lambda` and the displacement `u` (all dofs) at depth `depth`. The adjoint and the
    /// sensitivities transpose the system these frames define.
    pub fn frames(&self, active: &[u32], lambda: &[f64], u: &[f64], depth: f64) -> Vec<NodeFrame> {
        if self.surface.is_none() {
            return Vec::new();
        }
        active
            .iter()
            .zip(lambda)
            .filter_map(|(&k, &lam)| {
                let p = self.project(k as usize, u, depth).in_contact();
                self.frame(k as usize, &p, lam)
            })
            .collect()
    }

    /// The frames of the active candidates of a converged step with Coulomb friction
    /// (empty without normal contact): as [`Model::frames`], with each node's stick/slip
    /// status `slip` (same order as `active`, [`StepRecord::slip`]) and the internal
    /// force `f_int` (all dofs, N) of the converged state, from which the reactions and
    /// the slipping nodes' curvature stiffness `kappa (-lambda + mu sigma tau) / (1 + g
    /// kappa)` are formed as in the forward Newton iteration. The adjoint and the
    /// sensitivities with friction transpose the system these frames define.
    pub fn friction_frames(
        &self,
        active: &[u32],
        slip: &[Status],
        f_int: &[f64],
        u: &[f64],
        depth: f64,
    ) -> Vec<NodeFrame> {
        if self.surface.is_none() {
            return Vec::new();
        }
        let mu = self.contact.friction();
        active
            .iter()
            .zip(slip)
            .filter_map(|(&k, &st)| {
                let k = k as usize;
                let n = self.candidates[k];
                let p = self.project(k, u, depth).in_contact();
                crate::friction::frame(self, k, &p, [f_int[2 * n], f_int[2 * n + 1]], st, mu)
            })
            .collect()
    }

    /// The frame of candidate `k` with projection `p` and normal reaction `lambda`.
    fn frame(&self, k: usize, p: &Projection, lambda: f64) -> Option<NodeFrame> {
        let node = self.candidates[k];
        let ez = self.dofs.equation(2 * node + 1)?;
        let er = self.dofs.equation(2 * node);
        Some(NodeFrame {
            er,
            ez,
            t: p.t,
            m: p.m,
            d: if er.is_some() {
                curvature_stiffness(lambda, p)
            } else {
                0.0
            },
            stick: false,
            slip: 0.0,
        })
    }

    /// Radius of candidate `k` (mm).
    pub fn candidate_r(&self, k: usize) -> f64 {
        self.mesh.nodes[self.candidates[k]][0]
    }

    /// The length (mm) below which the penetration tolerance stops shrinking with the
    /// depth: the width of the first element under the punch (the radius of the third
    /// contact candidate, the first element's outer corner; of the last candidate on a
    /// top edge with fewer). The tolerance is `gap_tol * max(|depth|, gap_length)`:
    /// relative to the depth alone it vanished at depth 0, where a node leaving contact
    /// with a gap of round-off size was re-activated and the active set cycled.
    pub fn gap_length(&self) -> f64 {
        let k = self.candidates.len().saturating_sub(1).min(2);
        self.candidates
            .get(k)
            .map_or(0.0, |_| self.candidate_r(k))
            .max(1e-12)
    }
}

/// What the solver records at each converged step.
#[derive(Clone, Debug, PartialEq)]
pub struct StepRecord {
    /// End time of the step (s).
    pub t: f64,
    /// Step length (s).
    pub dt: f64,
    /// Punch depth `U_i` (mm).
    pub depth: f64,
    /// Punch force `F_i = sum_k lambda_k` (N, full circle).
    pub force: f64,
    /// Contact radius: radius of the outermost active node (mm), 0 without contact.
    pub contact_radius: f64,
    /// Active candidates (indices into [`Model::candidates`]), increasing.
    pub active: Vec<u32>,
    /// Nodal reactions `lambda_k` of the active candidates (N), same order as `active`.
    pub lambda: Vec<f64>,
    /// Coulomb friction: the stick/slip status of the active candidates, same order as
    /// `active` (0 sticks, +-1 slips along +-t; [`crate::friction`]); empty without
    /// friction.
    pub slip: Vec<Status>,
    /// Global Newton iterations (linear solves) of this step.
    pub iterations: u32,
    /// Active-set changes during this step.
    pub active_set_changes: u32,
    /// `true` for steps ending on a time of the schedule, `false` for sub-steps (of a cut,
    /// or the schedule's own, [`Schedule::with_substeps`]).
    pub on_schedule: bool,
    /// Index of the schedule time this step ends at (or heads to, for a sub-step).
    pub schedule_index: usize,
}

/// Fields of one converged step, kept when [`SolverOptions::record_fields`] is set.
#[derive(Clone, PartialEq)]
pub struct StepFields {
    /// Displacements, all dofs (mm).
    pub u: Vec<f64>,
    /// Converged stress at every Gauss point (MPa, Mandel).
    pub sigma: Vec<Vec4>,
}

impl std::fmt::Debug for StepFields {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "StepFields {{ {} dofs, {} Gauss points }}",
            self.u.len(),
            self.sigma.len()
        )
    }
}

/// The recorded forward run: one record per converged step (sub-steps included), the
/// fields of the initial state (index 0) and of every step (`fields[i + 1]` for `steps[i]`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Trajectory {
    /// Step records in time order.
    pub steps: Vec<StepRecord>,
    /// Fields: initial state then one per step (empty unless recorded).
    pub fields: Vec<StepFields>,
    /// Saved states every [`SolverOptions::checkpoint_every`] schedule steps (empty when 0).
    pub checkpoints: Vec<Checkpoint>,
    /// Parameters of the run.
    pub params: Vec<f64>,
    /// Wall-clock split of the run.
    pub timing: Timing,
}

impl Trajectory {
    /// The records ending on schedule times, in order (sub-steps of cut steps left out).
    pub fn schedule_steps(&self) -> impl Iterator<Item = &StepRecord> {
        self.steps.iter().filter(|s| s.on_schedule)
    }

    /// Force at each schedule time, starting with 0 for the initial state.
    pub fn forces(&self) -> Vec<f64> {
        std::iter::once(0.0)
            .chain(self.schedule_steps().map(|s| s.force))
            .collect()
    }

    /// Bytes held by the recorded fields and records (an estimate of the memory the
    /// adjoint's replay needs).
    pub fn recorded_bytes(&self) -> usize {
        let f: usize = self
            .fields
            .iter()
            .map(|f| 8 * f.u.len() + 32 * f.sigma.len())
            .sum();
        let s: usize = self
            .steps
            .iter()
            .map(|s| std::mem::size_of::<StepRecord>() + 12 * s.active.len())
            .sum();
        let c: usize = self.checkpoints.iter().map(Checkpoint::bytes).sum();
        f + s + c
    }

    /// Total global iterations over all steps.
    pub fn total_iterations(&self) -> u64 {
        self.steps.iter().map(|s| s.iterations as u64).sum()
    }
}

/// Wall-clock time split of a run (s).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Timing {
    /// Local updates and internal forces.
    pub local: f64,
    /// Tangent assembly.
    pub assembly: f64,
    /// Numeric factorizations.
    pub factorization: f64,
    /// Triangular solves.
    pub solve: f64,
    /// Whole run.
    pub total: f64,
    /// Number of numeric factorizations.
    pub factorizations: usize,
    /// Conjugate-gradient iterations of the inexact solves (nonlinear laws: Newton
    /// iterations reuse an earlier factorization as preconditioner).
    pub cg_iterations: usize,
}

impl std::fmt::Display for Timing {
    /// `F factorizations, C CG iterations; local .. ms, assembly .. ms, factorization .. ms,
    /// solve .. ms, total .. ms`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} factorizations, {} CG iterations; local {:.1} ms, assembly {:.1} ms, \
             factorization {:.1} ms, solve {:.1} ms, total {:.1} ms",
            self.factorizations,
            self.cg_iterations,
            1e3 * self.local,
            1e3 * self.assembly,
            1e3 * self.factorization,
            1e3 * self.solve,
            1e3 * self.total
        )
    }
}

/// A step failure the driver reacts to by cutting the step.
#[derive(Clone, Debug, PartialEq)]
enum StepFailure {
    Local {
        qp: usize,
        reason: String,
        factor: f64,
    },
    Newton {
        residual: f64,
    },
    Cycling {
        changes: u32,
    },
    Linear(String),
    /// A node in normal contact beyond the end of the punch surface: not cured by cutting.
    Geometry(String),
    /// Finite strain: an element inverted (`det F <= 0`) at Gauss point `qp`.
    Inverted {
        qp: usize,
        det: f64,
        depth: f64,
    },
}

impl std::fmt::Display for StepFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StepFailure::Local { qp, reason, .. } => {
                write!(
                    f,
                    "local update failed at Gauss point {qp} (element {}): {reason}",
                    qp / QP_PER_ELEMENT
                )
            }
            StepFailure::Newton { residual } => write!(
                f,
                "global Newton did not converge (relative residual {residual:.3e})"
            ),
            StepFailure::Cycling { changes } => {
                write!(f, "active set cycling after {changes} changes")
            }
            StepFailure::Linear(m) => write!(f, "linear solve failed: {m}"),
            StepFailure::Geometry(m) => write!(f, "{m}"),
            StepFailure::Inverted { qp, det, depth } => write!(
                f,
                "element {} is inverted (det F = {det:.3e} at its Gauss point {}) at the \
                 depth {depth} mm: the mesh cannot follow the deformation under the punch; \
                 refine it there (specimen nr and nz, or elements_in_contact) or reduce \
                 the maximum depth",
                qp / QP_PER_ELEMENT,
                qp % QP_PER_ELEMENT
            ),
        }
    }
}

/// The state carried from step to step.
#[derive(Clone, Debug, PartialEq)]
struct State {
    t: f64,
    /// Largest internal-force component seen in converged steps: the residual's scale
    /// when the current forces vanish (full unloading).
    f_scale: f64,
    u: Vec<f64>,
    sigma: Vec<Vec4>,
    /// Internal force `sum_g w_g B^T sigma_g` of the converged state, all dofs (N).
    f_int: Vec<f64>,
    active: Vec<bool>,
    /// The last three steps' displacement increments (all dofs), lengths and depth rates,
    /// the latest first (a zero length: no such step).
    past: [Increment; 3],
    /// The degree (1 to 3) of the time extrapolation that predicted the last step best.
    order: usize,
    /// Punch depth of the state (mm).
    depth: f64,
    /// Coulomb friction (empty without): the arc coordinate of every candidate's closest
    /// point at this state (the stick points of the next step) and the stick/slip status
    /// of every candidate (meaningful for the active ones).
    xi: Vec<f64>,
    slip: Vec<Status>,
}

/// One past step of a [`State`] (`du` empty where it is never read).
#[derive(Clone, Debug, PartialEq)]
struct Increment {
    du: Vec<f64>,
    dt: f64,
    rate: f64,
}

impl State {
    fn initial(model: &Model, t0: f64, depth0: f64) -> State {
        let nc = model.candidates.len();
        State {
            t: t0,
            f_scale: 0.0,
            u: vec![0.0; model.disc.n_dofs()],
            sigma: vec![Vec4::ZERO; model.disc.n_qp()],
            f_int: vec![0.0; model.disc.n_dofs()],
            active: vec![false; nc],
            // steps of zero length: only the latest increment is ever read (times 0)
            past: std::array::from_fn(|k| Increment {
                du: if k == 0 {
                    vec![0.0; model.disc.n_dofs()]
                } else {
                    Vec::new()
                },
                dt: 0.0,
                rate: 0.0,
            }),
            order: 1,
            depth: depth0,
            xi: if model.contact.friction() > 0.0 {
                let u0 = vec![0.0; model.disc.n_dofs()];
                (0..nc).map(|k| model.project(k, &u0, depth0).s).collect()
            } else {
                Vec::new()
            },
            slip: if model.contact.friction() > 0.0 {
                vec![0; nc]
            } else {
                Vec::new()
            },
        }
    }
}

/// A saved solver state at a schedule time, from which [`DirectSolver::replay`] recomputes
/// the following steps exactly (checkpointing bounds the memory of the adjoint's replay).
#[derive(Clone, PartialEq)]
pub struct Checkpoint {
    /// Schedule index of the saved state.
    pub schedule_index: usize,
    /// Number of trajectory steps (sub-steps included) before this state.
    pub steps_done: usize,
    state: State,
}

impl Checkpoint {
    /// Bytes held by the saved state.
    pub fn bytes(&self) -> usize {
        // u and f_int per dof, the past increments kept; stress per Gauss point; active flag
        // and more per candidate
        16 * self.state.u.len()
            + 8 * self.state.past.iter().map(|p| p.du.len()).sum::<usize>()
            + 32 * self.state.sigma.len()
            + 17 * self.state.active.len()
            + 9 * self.state.xi.len()
    }
}

impl std::fmt::Debug for Checkpoint {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "Checkpoint {{ schedule_index: {}, steps_done: {} }}",
            self.schedule_index, self.steps_done
        )
    }
}

/// One chunk of the small-strain Gauss-point pass: its index, and its elements' forces,
/// stresses and tangents.
type PassChunk<'a> = (
    usize,
    ((&'a mut [[f64; 16]], &'a mut [Vec4]), &'a mut [Mat4]),
);

/// Reusable solver workspace: the symbolic factorization and scratch vectors, so that
/// repeated runs (an optimizer's iterations) allocate and analyse nothing new.
#[derive(Debug)]
pub struct DirectSolver {
    system: ConstrainedSystem,
    /// The laws' consistent tangents of the last evaluation (every Gauss point; under
    /// finite strain `dT/dE`, from which the element tangents are formed).
    tangents: Vec<Mat4>,
    f_int: Vec<f64>,
    rhs: Vec<f64>,
    aux: Vec<f64>,
    /// Relative residual of every pass of the last step attempted, with the active-set
    /// changes made before it.
    residuals: Vec<(f64, u32)>,
    /// Finite strain: the element tangents of the last Newton solve, and the Hencky strains
    /// of the step's initial state (empty under small strain).
    finite_ke: Vec<[[f64; 16]; 16]>,
    finite_e0: Vec<Vec4>,
    /// Finite strain: each Gauss point's deformation and Hencky strain of the last
    /// evaluation, from which its element tangents are formed.
    finite_points: Vec<kinematics::Point>,
    /// Small strain: each element's internal force of the last evaluation (summed into
    /// `f_int` in element order).
    element_forces: Vec<[f64; 16]>,
}

impl DirectSolver {
    /// The constrained tangent system of the last step solved (see
    /// [`ConstrainedSystem::matrix`]).
    pub fn system(&self) -> &ConstrainedSystem {
        &self.system
    }

    /// Analyses the model's pattern once.
    ///
    /// # Errors
    /// [`ContactError::Fe`] if the symbolic factorization fails.
    pub fn new(model: &Model) -> Result<DirectSolver, ContactError> {
        let n = model.dofs.n_eq;
        let nq = model.disc.n_qp();
        Ok(DirectSolver {
            system: ConstrainedSystem::new(model)?,
            tangents: vec![Mat4::ZERO; nq],
            f_int: vec![0.0; model.disc.n_dofs()],
            rhs: vec![0.0; n],
            aux: vec![0.0; n],
            residuals: Vec::new(),
            finite_ke: Vec::new(),
            finite_e0: Vec::new(),
            finite_points: Vec::new(),
            element_forces: Vec::new(),
        })
    }

    /// The relative equilibrium residual of every Newton pass of the last step attempted
    /// (the last step of a run: its convergence history, for rate checks), each with the
    /// number of active-set changes made before that pass.
    pub fn last_residuals(&self) -> &[(f64, u32)] {
        &self.residuals
    }

    /// Runs the whole schedule for parameters `c` of `law`.
    ///
    /// # Errors
    /// [`ContactError::Parameters`] for inadmissible parameters;
    /// [`ContactError::StepFailed`] when a step fails even after `max_cuts` halvings, carrying
    /// the trajectory up to the last converged step.
    pub fn run(
        &mut self,
        model: &Model,
        law: &dyn Law,
        c: &[f64],
        schedule: &Schedule,
        opts: &SolverOptions,
    ) -> Result<Trajectory, ContactError> {
        law.check_params(c)?;
        let mut traj = Trajectory {
            params: c.to_vec(),
            ..Default::default()
        };
        let state = State::initial(model, schedule.t[0], schedule.depth[0]);
        let last = schedule.t.len() - 1;
        self.advance(
            model,
            law,
            c,
            schedule,
            opts,
            state,
            0,
            last,
            &mut traj,
            opts.record_fields,
            opts.checkpoint_every,
        )?;
        Ok(traj)
    }

    /// Replays the run from `checkpoint` up to schedule index `j_end`, recording fields:
    /// the returned trajectory's `fields[0]` is the checkpoint's state and its steps are
    /// those of the original run from `checkpoint.steps_done` on (the computation is
    /// deterministic, so they are the same steps).
    ///
    /// # Errors
    /// As [`DirectSolver::run`]; also [`ContactError::Input`] if `j_end` is before the
    /// checkpoint or beyond the schedule.
    #[allow(clippy::too_many_arguments)]
    pub fn replay(
        &mut self,
        model: &Model,
        law: &dyn Law,
        c: &[f64],
        schedule: &Schedule,
        opts: &SolverOptions,
        checkpoint: &Checkpoint,
        j_end: usize,
    ) -> Result<Trajectory, ContactError> {
        if j_end < checkpoint.schedule_index || j_end >= schedule.t.len() {
            return Err(ContactError::Input {
                field: "replay.j_end",
                value: j_end.to_string(),
                allowed: format!(
                    "a schedule index in [{}, {}]",
                    checkpoint.schedule_index,
                    schedule.t.len() - 1
                ),
            });
        }
        let mut traj = Trajectory {
            params: c.to_vec(),
            ..Default::default()
        };
        let state = checkpoint.state.clone();
        self.advance(
            model,
            law,
            c,
            schedule,
            opts,
            state,
            checkpoint.schedule_index,
            j_end,
            &mut traj,
            true,
            0,
        )?;
        Ok(traj)
    }

    /// Steps from `state` (at schedule index `j0`) to schedule index `j1`, appending to
    /// `traj`; stores fields when `record`, and a checkpoint every `every` schedule steps.
    #[allow(clippy::too_many_arguments)]
    fn advance(
        &mut self,
        model: &Model,
        law: &dyn Law,
        c: &[f64],
        schedule: &Schedule,
        opts: &SolverOptions,
        mut state: State,
        j0: usize,
        j1: usize,
        traj: &mut Trajectory,
        record: bool,
        every: usize,
    ) -> Result<(), ContactError> {
        let start = std::time::Instant::now();
        if record {
            traj.fields.push(StepFields {
                u: state.u.clone(),
                sigma: state.sigma.clone(),
            });
        }
        let factorizations0 = self.system.factorizations();
        let cg0 = self.system.pcg_iterations;
        let seconds0 = self.system.seconds;
        for j in j0 + 1..=j1 {
            if j == j0 + 1 || (every > 0 && (j - 1 - j0) % every == 0) {
                // a run, and every stretch a replay may start from, begins with a fresh
                // factorization: the replay then repeats its steps bit for bit
                self.system.forget_preconditioner();
            }
            if every > 0 && (j - 1 - j0) % every == 0 {
                traj.checkpoints.push(Checkpoint {
                    schedule_index: j - 1,
                    steps_done: traj.steps.len(),
                    state: state.clone(),
                });
            }
            // targets still to reach, last first (the step's sub-steps, then t[j]); a failed
            // step pushes an intermediate time
            let mut targets: Vec<(f64, u32)> = schedule
                .step_targets(j)
                .into_iter()
                .rev()
                .map(|t| (t, 0u32))
                .collect();
            while let Some(&(t1, level)) = targets.last() {
                let u1 = schedule.depth_at(t1);
                match self.step(model, law, c, &state, t1, u1, opts, &mut traj.timing) {
                    Ok((rec_state, mut rec)) => {
                        targets.pop();
                        rec.on_schedule = targets.is_empty();
                        rec.schedule_index = j;
                        tracing::debug!(
                            step = j,
                            t = rec.t,
                            depth_mm = rec.depth,
                            force_n = rec.force,
                            active = rec.active.len(),
                            iterations = rec.iterations,
                            "step converged"
                        );
                        state = rec_state;
                        if record {
                            traj.fields.push(StepFields {
                                u: state.u.clone(),
                                sigma: state.sigma.clone(),
                            });
                        }
                        traj.steps.push(rec);
                    }
                    Err(fail) => {
                        // a failed step may have assembled non-finite tangents
                        self.system.forget_assembly();
                        if level >= opts.max_cuts || matches!(fail, StepFailure::Geometry(_)) {
                            traj.timing.total += start.elapsed().as_secs_f64();
                            return Err(ContactError::StepFailed {
                                step: j,
                                t: t1,
                                cuts: level,
                                reason: fail.to_string(),
                                partial: Box::new(std::mem::take(traj)),
                            });
                        }
                        let factor = match fail {
                            StepFailure::Local { factor, .. } => factor.clamp(0.1, 0.5),
                            _ => 0.5,
                        };
                        let tm = state.t + factor * (t1 - state.t);
                        tracing::debug!(
                            step = j,
                            from = state.t,
                            to = t1,
                            retry_to = tm,
                            cut = level + 1,
                            "step cut: {fail}"
                        );
                        targets.push((tm, level + 1));
                        // the remaining part keeps its level so repeated failures keep cutting
                        let n = targets.len();
                        targets[n - 2].1 = level + 1;
                    }
                }
            }
        }
        traj.timing.factorizations += self.system.factorizations() - factorizations0;
        traj.timing.cg_iterations += self.system.pcg_iterations - cg0;
        traj.timing.assembly += self.system.seconds[0] - seconds0[0];
        traj.timing.factorization += self.system.seconds[1] - seconds0[1];
        traj.timing.solve += self.system.seconds[2] - seconds0[2];
        traj.timing.total += start.elapsed().as_secs_f64();
        Ok(())
    }

    /// Local updates at every Gauss point for displacement `u` from `state`; fills
    /// `sigma_out` and `self.f_int`, and `self.tangents` unless the law is `affine`
    /// (`sigma_1 = A sigma_0 + C deps` everywhere: its one tangent is `C`). With an affine
    /// law and `u` the state's own displacement (a step's first pass) the strain
    /// increments vanish and `sigma_1 = A sigma_0`; with `A = I` besides (elasticity) the
    /// internal force is the state's own and nothing is computed.
    #[allow(clippy::too_many_arguments)]
    fn evaluate(
        &mut self,
        model: &Model,
        law: &dyn Law,
        c: &[f64],
        state: &State,
        u: &[f64],
        dt: f64,
        affine: Option<&(Mat4, Mat4)>,
        sigma_out: &mut [Vec4],
    ) -> Result<(), StepFailure> {
        let disc = &model.disc;
        if model.kinematics == Kinematics::Finite {
            let domain = law.elastic_domain(c, dt);
            let out = FiniteOut {
                sigma: sigma_out,
                f_int: &mut self.f_int,
                tangents: &mut self.tangents,
                points: &mut self.finite_points,
            };
            return kinematics::evaluate(
                disc,
                law,
                c,
                dt,
                &state.sigma,
                &self.finite_e0,
                u,
                domain.as_ref(),
                out,
            )
            .map_err(|f| finite_failure(f, state.depth));
        }
        // (only affine laws use it: a nonlinear law's iterate is never compared)
        let at_start = affine.is_some() && u == state.u.as_slice();
        if at_start && affine.is_some_and(|(a, _)| *a == Mat4::IDENTITY) {
            self.f_int.copy_from_slice(&state.f_int);
            sigma_out.copy_from_slice(&state.sigma);
            return Ok(());
        }
        // one pass: strains, local updates and each element's internal force while the
        // stresses are hot, on rayon over fixed chunks of elements (each point's update is
        // independent); points whose elastic trial stays below yield skip the law's update.
        // The element forces are then summed serially in element order, as a serial pass
        // would: the result is the same bits for any number of threads.
        let domain = law.elastic_domain(c, dt);
        let ne = disc.elements.len();
        let nq = QP_PER_ELEMENT * ne;
        self.element_forces.resize(ne, [0.0; 16]);
        let chunk_qp = QP_PER_ELEMENT * ELEMENT_CHUNK;
        let tangents = &mut self.tangents[..nq];
        let work = |(chunk, ((fes, sig), tan)): PassChunk<'_>| {
            for (i, fe) in fes.iter_mut().enumerate() {
                let e = chunk * ELEMENT_CHUNK + i;
                let dofs = disc.element_dofs(e);
                let due: [f64; 16] = std::array::from_fn(|k| u[dofs[k]] - state.u[dofs[k]]);
                *fe = [0.0; 16];
                for g in 0..QP_PER_ELEMENT {
                    let q = QP_PER_ELEMENT * e + g;
                    let l = QP_PER_ELEMENT * i + g;
                    let qp = &disc.qp[q];
                    if let Some((a, cm)) = affine {
                        let mut s = a.mul_vec(&state.sigma[q]);
                        if !at_start {
                            s += cm.mul_vec(&Vec4(qp.strain(&due)));
                        }
                        qp.add_bt(&s.0, qp.w, fe);
                        sig[l] = s;
                        continue;
                    }
                    let deps = Vec4(qp.strain(&due));
                    if let Some(dom) = &domain {
                        if let Some(s1) = dom.update(&state.sigma[q], &deps) {
                            qp.add_bt(&s1.0, qp.w, fe);
                            sig[l] = s1;
                            tan[l] = dom.stiffness;
                            continue;
                        }
                    }
                    match law.update(c, &state.sigma[q], &deps, dt) {
                        Ok(up) => {
                            qp.add_bt(&up.sigma.0, qp.w, fe);
                            sig[l] = up.sigma;
                            tan[l] = up.tangent;
                        }
                        Err(f) => {
                            return Some(StepFailure::Local {
                                qp: q,
                                reason: f.reason,
                                factor: f.suggested_dt_factor,
                            });
                        }
                    }
                }
            }
            None
        };
        // on one thread, in place (handing a pass to a pool of one costs more than it does)
        let failure = if rayon::current_num_threads() > 1 {
            self.element_forces
                .par_chunks_mut(ELEMENT_CHUNK)
                .zip(sigma_out[..nq].par_chunks_mut(chunk_qp))
                .zip(tangents.par_chunks_mut(chunk_qp))
                .enumerate()
                .find_map_first(work)
        } else {
            self.element_forces
                .chunks_mut(ELEMENT_CHUNK)
                .zip(sigma_out[..nq].chunks_mut(chunk_qp))
                .zip(tangents.chunks_mut(chunk_qp))
                .enumerate()
                .find_map(work)
        };
        if let Some(f) = failure {
            return Err(f);
        }
        self.f_int.fill(0.0);
        for (e, fe) in self.element_forces.iter().enumerate() {
            for (d, v) in disc.element_dofs(e).iter().zip(fe) {
                self.f_int[*d] += v;
            }
        }
        Ok(())
    }

    #[allow(clippy::too_many_arguments)]
    fn step(
        &mut self,
        model: &Model,
        law: &dyn Law,
        c: &[f64],
        state: &State,
        t1: f64,
        depth: f64,
        opts: &SolverOptions,
        timing: &mut Timing,
    ) -> Result<(State, StepRecord), StepFailure> {
        let dt = t1 - state.t;
        let nc = model.candidates.len();
        let gap_length = model.gap_length();
        let n_eq = model.dofs.n_eq;
        let mut u = state.u.clone();
        let mut sigma = state.sigma.clone();
        let mut active = state.active.clone();
        // predictor: activate nodes that the new depth makes penetrate, with the surface
        // displacement extrapolated from the last increment
        let last = &state.past[0];
        let ratio = if last.dt > 0.0 { dt / last.dt } else { 0.0 };
        let zdof = |k: usize| 2 * model.candidates[k] + 1;
        let normal = model.contact.is_normal();
        let mu = model.contact.friction();
        let with_friction = mu > 0.0;
        let mut slip = state.slip.clone();
        if normal {
            for k in 0..nc {
                let n = model.candidates[k];
                let x = [
                    u[2 * n] + ratio * last.du[2 * n],
                    u[2 * n + 1] + ratio * last.du[2 * n + 1],
                ];
                if !active[k] && model.project_at(k, x, depth).gap < 0.0 {
                    active[k] = true;
                    if with_friction {
                        slip[k] = 0;
                    }
                }
            }
        } else {
            for k in 0..nc {
                if !active[k] && gap(model, k, depth, &u) - ratio * last.du[zdof(k)] < 0.0 {
                    active[k] = true;
                }
            }
        }
        let finite = model.kinematics == Kinematics::Finite;
        if finite {
            // the Hencky strains of the initial state, from which the laws' increments run
            let (nq, ne) = (model.disc.n_qp(), model.disc.elements.len());
            self.finite_e0.resize(nq, Vec4::ZERO);
            self.finite_ke.resize(ne, [[0.0; 16]; 16]);
            if self.finite_points.len() != nq {
                self.finite_points = vec![kinematics::undeformed_point(&model.disc); nq];
            }
            kinematics::log_strains(&model.disc, &state.u, &mut self.finite_e0)
                .map_err(|f| finite_failure(f, state.depth))?;
        }
        // finite strain: no affine update (the tangent depends on the displacement)
        let affine = if finite {
            None
        } else {
            law.affine_update(c, dt)
        };
        // a nonlinear law starts Newton from the displacement extrapolated in time, while
        // the depth keeps its rate (within a segment): by the polynomial of degree 1 to 3
        // through the last states that predicted the last step best (in R2's settled creep
        // and relaxation the higher degrees predict 5-15 times closer: a Newton iteration
        // fewer per step). Affine laws converge in one solve from anywhere and keep their
        // cheap first pass.
        let rate = if dt > 0.0 {
            (depth - state.depth) / dt
        } else {
            0.0
        };
        let same = |a: f64, b: f64| (a - b).abs() <= 1e-9 * a.abs().max(b.abs());
        // the highest degree the segment's past steps allow (0: no extrapolation; 1 for a
        // step more than twice the last one, after a cut, where the higher degrees' weights
        // grow like (dt / h_1)^degree)
        let degrees = if affine.is_some() {
            0
        } else {
            let kept = state
                .past
                .iter()
                .take_while(|p| p.dt > 0.0 && p.du.len() == u.len() && same(rate, p.rate))
                .count();
            if dt > 2.0 * last.dt {
                kept.min(1)
            } else {
                kept
            }
        };
        let h = state.past.each_ref().map(|p| p.dt);
        let weights: [[f64; 3]; 3] = std::array::from_fn(|k| extrapolation_weights(dt, h, k + 1));
        // the increment predicted by degree `d` at dof `i` (reads the `d` latest steps only)
        let predict = |d: usize, i: usize| -> f64 {
            let w = &weights[d - 1];
            (0..d).map(|k| w[k] * state.past[k].du[i]).sum()
        };
        if degrees > 0 {
            let d = state.order.min(degrees);
            for (i, x) in u.iter_mut().enumerate() {
                *x += predict(d, i);
            }
        }
        let mut seen: Vec<(Vec<bool>, Vec<Status>)> = vec![(active.clone(), slip.clone())];
        let mut changes = 0u32;
        let mut iterations = 0u32;
        let mut constrained = vec![false; n_eq];
        let mut single_change = false;
        let mut proj: Vec<Projection> = Vec::new();
        self.residuals.clear();
        let mut frames: Vec<NodeFrame> = Vec::new();
        loop {
            // every pass evaluates the current iterate once, then checks or solves
            let tl = std::time::Instant::now();
            self.evaluate(model, law, c, state, &u, dt, affine.as_ref(), &mut sigma)
                .map_err(|f| match f {
                    StepFailure::Inverted { qp, det, .. } => {
                        StepFailure::Inverted { qp, det, depth }
                    }
                    other => other,
                })?;
            timing.local += tl.elapsed().as_secs_f64();
            if normal {
                proj.clear();
                proj.extend((0..nc).map(|k| {
                    let p = model.project(k, &u, depth);
                    if active[k] { p.in_contact() } else { p }
                }));
            }
            // the force on a node along its contact normal (normal contact)
            let f_node = |k: usize| -> [f64; 2] {
                let n = model.candidates[k];
                [self.f_int[2 * n], self.f_int[2 * n + 1]]
            };
            let lambda_of = |k: usize| -> f64 {
                if normal {
                    let (f, m) = (f_node(k), proj[k].m);
                    -(f[0] * m[0] + f[1] * m[1])
                } else {
                    -self.f_int[zdof(k)]
                }
            };
            // residual on free, unconstrained equations (normal contact: the tangential
            // component at the active nodes)
            constrained.fill(false);
            for k in 0..nc {
                if active[k] {
                    if let Some(e) = model.dofs.equation(zdof(k)) {
                        constrained[e] = true;
                    }
                    if normal {
                        if let Some(e) = model.dofs.equation(zdof(k) - 1) {
                            constrained[e] = true;
                        }
                    }
                }
            }
            let mut res: f64 = 0.0;
            let mut fmax: f64 = 0.0;
            for (d, &e) in model.dofs.eq.iter().enumerate() {
                if e != NO_EQ {
                    fmax = fmax.max(self.f_int[d].abs());
                    if !constrained[e as usize] {
                        res = res.max(self.f_int[d].abs());
                    }
                }
            }
            if normal && !with_friction {
                for k in (0..nc).filter(|&k| active[k]) {
                    if model.dofs.equation(zdof(k) - 1).is_some() {
                        let (f, t) = (f_node(k), proj[k].t);
                        res = res.max((f[0] * t[0] + f[1] * t[1]).abs());
                    }
                }
            }
            if with_friction {
                for k in (0..nc).filter(|&k| active[k] && slip[k] != 0) {
                    if model.dofs.equation(zdof(k) - 1).is_some() {
                        let r = friction::tangential_residual(&proj[k], f_node(k), slip[k], mu);
                        res = res.max(r.abs());
                    }
                }
            }
            let targets_met = if normal {
                (0..nc).filter(|&k| active[k]).all(|k| {
                    proj[k].gap.abs() <= 1e-13 * (1.0 + depth.abs())
                        && (!with_friction
                            || slip[k] != 0
                            || model.dofs.equation(zdof(k) - 1).is_none()
                            || (proj[k].s - state.xi[k]).abs() <= 1e-13 * (1.0 + depth.abs()))
                })
            } else {
                (0..nc).filter(|&k| active[k]).all(|k| {
                    let target = model.candidate_profile[k] - depth;
                    (u[zdof(k)] - target).abs() <= 1e-13 * (1.0 + target.abs())
                })
            };
            let scale = fmax.max(state.f_scale);
            let rel = if scale > 0.0 { res / scale } else { res };
            self.residuals.push((rel, changes));
            let converged = rel <= opts.residual_tol || res == 0.0;
            // complementarity is checked once equilibrium for the current set is loosely met
            // (semi-smooth Newton): a wrong set is corrected without a full Newton solve
            if iterations > 0 && targets_met && (converged || rel <= opts.active_set_check_tol) {
                let force: f64 = (0..nc)
                    .filter(|&k| active[k])
                    .map(|k| -self.f_int[zdof(k)])
                    .sum();
                let ltol = opts.lambda_tol * force.abs().max(1e-300);
                let gtol = opts.gap_tol * depth.abs().max(gap_length);
                let mut worst: Option<(usize, f64)> = None;
                let mut violations = Vec::new();
                for k in 0..nc {
                    // (a sticking node under tension first turns to slip: its release is
                    // decided slipping, by the friction check below)
                    let sticking =
                        with_friction && slip[k] == 0 && model.dofs.equation(zdof(k) - 1).is_some();
                    let v = if active[k] {
                        let lam = lambda_of(k);
                        if lam < -ltol && !sticking {
                            -lam / force.abs().max(1e-300)
                        } else {
                            0.0
                        }
                    } else {
                        let g = if normal {
                            proj[k].gap
                        } else {
                            gap(model, k, depth, &u)
                        };
                        if g < -gtol {
                            -g / depth.abs().max(1e-12)
                        } else {
                            0.0
                        }
                    };
                    if v > 0.0 {
                        violations.push(k);
                        if worst.is_none_or(|(_, w)| v > w) {
                            worst = Some((k, v));
                        }
                    }
                }
                // the stick/slip partition, checked once the contact set holds
                let mut slip_flips: Vec<(usize, Status, f64)> = Vec::new();
                if with_friction && violations.is_empty() {
                    // a borderline node (slip increment ~ 0, tangential force ~ mu lambda)
                    // satisfies both statuses to the solver's precision: these wider
                    // tolerances keep it from cycling between them
                    let stol = 1e3 * gtol;
                    let ctol = 1e2 * ltol;
                    for k in (0..nc).filter(|&k| active[k]) {
                        if model.dofs.equation(zdof(k) - 1).is_none() {
                            continue;
                        }
                        if let Some((st, v)) = friction::check(
                            &proj[k],
                            f_node(k),
                            state.xi[k],
                            slip[k],
                            mu,
                            ctol,
                            stol,
                            force.abs().max(1e-300),
                        ) {
                            slip_flips.push((k, st, v));
                        }
                    }
                }
                if violations.is_empty() && slip_flips.is_empty() && converged {
                    if let Some(k) = (0..proj.len()).find(|&k| active[k] && proj[k].beyond_end) {
                        return Err(StepFailure::Geometry(beyond_end_message(model, k, &u)));
                    }
                    let mut rec =
                        self.record(model, &active, &u, t1, dt, depth, iterations, changes);
                    if normal {
                        for (l, &k) in rec.lambda.iter_mut().zip(&rec.active) {
                            *l = lambda_of(k as usize);
                        }
                        rec.contact_radius = rec.active.last().map_or(0.0, |&k| {
                            let n = model.candidates[k as usize];
                            model.mesh.nodes[n][0] + u[2 * n]
                        });
                    }
                    if with_friction {
                        rec.slip = rec.active.iter().map(|&k| slip[k as usize]).collect();
                    }
                    let f_scale = state.f_scale.max(fmax);
                    let du: Vec<f64> = u.iter().zip(&state.u).map(|(a, b)| a - b).collect();
                    // hindsight: the degree that would have predicted this step best
                    let mut err = [0.0f64; 3];
                    if degrees > 1 {
                        for (i, &d) in du.iter().enumerate() {
                            for (k, e) in err.iter_mut().enumerate().take(degrees) {
                                *e += (d - predict(k + 1, i)).powi(2);
                            }
                        }
                    }
                    let order = (1..=degrees.max(1))
                        .min_by(|&a, &b| err[a - 1].total_cmp(&err[b - 1]))
                        .unwrap_or(1);
                    // the older increments serve the extrapolation of nonlinear laws only
                    let older = |p: &Increment| Increment {
                        du: if affine.is_none() {
                            p.du.clone()
                        } else {
                            Vec::new()
                        },
                        ..*p
                    };
                    let (p0, p1) = (older(&state.past[0]), older(&state.past[1]));
                    let next = State {
                        t: t1,
                        f_scale,
                        u,
                        sigma,
                        f_int: self.f_int.clone(),
                        active,
                        past: [Increment { du, dt, rate }, p0, p1],
                        order,
                        depth,
                        xi: if with_friction {
                            proj.iter().map(|p| p.s).collect()
                        } else {
                            Vec::new()
                        },
                        slip,
                    };
                    return Ok((next, rec));
                }
                let any_change = !violations.is_empty() || !slip_flips.is_empty();
                if !violations.is_empty() {
                    let flip: Vec<usize> = if single_change {
                        vec![worst.map_or(0, |w| w.0)]
                    } else {
                        violations
                    };
                    for k in flip {
                        active[k] = !active[k];
                        if with_friction && active[k] {
                            // a node entering contact starts sticking
                            slip[k] = 0;
                        }
                    }
                } else if !slip_flips.is_empty() {
                    let flip: Vec<(usize, Status, f64)> = if single_change {
                        slip_flips
                            .iter()
                            .copied()
                            .max_by(|a, b| a.2.total_cmp(&b.2))
                            .into_iter()
                            .collect()
                    } else {
                        slip_flips
                    };
                    for (k, st, _) in flip {
                        slip[k] = st;
                    }
                }
                if any_change {
                    changes += 1;
                    let key = (active.clone(), slip.clone());
                    if seen.contains(&key) {
                        if single_change {
                            return Err(StepFailure::Cycling { changes });
                        }
                        single_change = true;
                    }
                    seen.push(key);
                }
            }
            if iterations as usize >= opts.max_iterations {
                return Err(StepFailure::Newton { residual: rel });
            }
            iterations += 1;
            match &affine {
                Some((_, cm)) => self.system.set_tangent_uniform(model, cm, (c, dt)),
                None if finite => {
                    // the element tangents of this iterate: formed only now that a solve
                    // needs them (a converged pass returned above without them)
                    let tl = std::time::Instant::now();
                    // (from the deformations and Hencky strains the evaluation of this
                    // iterate kept: the same `u`)
                    kinematics::element_tangents(
                        &model.disc,
                        &self.finite_points,
                        &sigma,
                        &self.tangents,
                        &mut self.finite_ke,
                    );
                    timing.local += tl.elapsed().as_secs_f64();
                    self.system.set_tangent_elements(model, &self.finite_ke)
                }
                None => {
                    let reuse = law.is_linear().then_some((c, dt));
                    self.system.set_tangent(model, &self.tangents, reuse)
                }
            };
            self.system.set_active(model, &active);
            if normal {
                frames.clear();
                if with_friction {
                    frames.extend((0..nc).filter(|&k| active[k]).filter_map(|k| {
                        friction::frame(model, k, &proj[k], f_node(k), slip[k], mu)
                    }));
                } else {
                    frames.extend(
                        (0..nc)
                            .filter(|&k| active[k])
                            .filter_map(|k| model.frame(k, &proj[k], lambda_of(k))),
                    );
                }
                self.system.set_frames(&frames);
            }
            // reusable tangents factorize (or reuse) exactly; others prepare inexact solves
            self.system
                .prepare_inexact(model)
                .map_err(|e: FeError| StepFailure::Linear(e.to_string()))
                .map_err(|f| distortion(model, f, &u, depth))?;
            // right-hand side: -R on free equations, prescribed increments on active ones
            self.aux.fill(0.0);
            for k in 0..nc {
                if active[k] {
                    if let Some(e) = model.dofs.equation(zdof(k)) {
                        self.aux[e] = if normal {
                            // Newton on the gap: m . du = g
                            proj[k].gap
                        } else {
                            model.candidate_profile[k] - depth - u[zdof(k)]
                        };
                    }
                    if with_friction && slip[k] == 0 {
                        // a sticking node: Newton on the arc coordinate, s(x) = xi
                        if let Some(e) = model.dofs.equation(zdof(k) - 1) {
                            self.aux[e] = friction::stick_increment(&proj[k], state.xi[k]);
                        }
                    }
                }
            }
            for (d, &e) in model.dofs.eq.iter().enumerate() {
                if e != NO_EQ {
                    self.rhs[e as usize] = -self.f_int[d];
                }
            }
            // forcing term eta = |R| (relative): inexact Newton stays quadratic
            // (Dembo, Eisenstat & Steihaug 1982); near convergence no tighter than
            // what brings the residual a decade below the tolerance (no oversolving)
            let eta = rel
                .max(0.1 * opts.residual_tol / rel.max(1e-300))
                .clamp(1e-12, 0.1);
            self.system
                .solve_inexact(model, &mut self.rhs, &self.aux, eta)
                .map_err(|e: FeError| StepFailure::Linear(e.to_string()))
                .map_err(|f| distortion(model, f, &u, depth))?;
            for (d, &e) in model.dofs.eq.iter().enumerate() {
                if e != NO_EQ {
                    u[d] += self.rhs[e as usize];
                }
            }
            if u.iter().any(|v| !v.is_finite()) {
                return Err(StepFailure::Linear("non-finite displacement".into()));
            }
        }
    }

    #[allow(clippy::too_many_arguments)]
    fn record(
        &self,
        model: &Model,
        active: &[bool],
        _u: &[f64],
        t: f64,
        dt: f64,
        depth: f64,
        iterations: u32,
        changes: u32,
    ) -> StepRecord {
        let idx: Vec<u32> = (0..active.len())
            .filter(|&k| active[k])
            .map(|k| k as u32)
            .collect();
        let lambda: Vec<f64> = idx
            .iter()
            .map(|&k| -self.f_int[2 * model.candidates[k as usize] + 1])
            .collect();
        StepRecord {
            t,
            dt,
            depth,
            force: lambda.iter().sum(),
            contact_radius: idx.last().map_or(0.0, |&k| model.candidate_r(k as usize)),
            active: idx,
            lambda,
            slip: Vec::new(),
            iterations,
            active_set_changes: changes,
            on_schedule: true,
            schedule_index: 0,
        }
    }
}

/// Weights `w` of the increment `w_1 du_1 + w_2 du_2 + w_3 du_3` predicted over the next
/// step `dt` from the last increments `du_1` (latest), `du_2`, `du_3` of lengths
/// `h = [h_1, h_2, h_3]`: the polynomial of degree `order` (1 to 3) in time through the
/// last `order + 1` states, in Lagrange form with nodes `0, -h_1, -h_1 - h_2, ...` (the
/// current time at 0). Exact for a displacement polynomial of that degree, whatever the
/// step lengths; unused steps get weight 0.
fn extrapolation_weights(dt: f64, h: [f64; 3], order: usize) -> [f64; 3] {
    let tau = [0.0, -h[0], -h[0] - h[1], -h[0] - h[1] - h[2]];
    let lagrange: [f64; 4] = std::array::from_fn(|k| {
        if k > order {
            return 0.0;
        }
        (0..=order)
            .filter(|&j| j != k)
            .map(|j| (dt - tau[j]) / (tau[k] - tau[j]))
            .product()
    });
    // u_(n-k) = u_n - du_1 - ... - du_k, and the weights sum to 1
    [
        -(lagrange[1] + lagrange[2] + lagrange[3]),
        -(lagrange[2] + lagrange[3]),
        -lagrange[3],
    ]
}

/// Under finite strain a tangent that is no longer positive definite means extreme
/// distortion (or a loss of stability): the failure then names the most distorted element
/// of the iterate `u` at the depth `depth` and what to do.
fn distortion(model: &Model, f: StepFailure, u: &[f64], depth: f64) -> StepFailure {
    match f {
        StepFailure::Linear(m) if model.kinematics == Kinematics::Finite => {
            let (qp, det) = kinematics::smallest_det(&model.disc, u);
            StepFailure::Linear(format!(
                "{m}; under finite strain: extreme distortion at the depth {depth} mm, \
                 smallest det F = {det:.3e} in element {} (Gauss point {}): refine the mesh \
                 under the punch (specimen nr and nz, or elements_in_contact) or reduce the \
                 maximum depth",
                qp / QP_PER_ELEMENT,
                qp % QP_PER_ELEMENT
            ))
        }
        other => other,
    }
}

/// The step failure of a finite-strain evaluation at the depth `depth`.
fn finite_failure(f: FiniteFailure, depth: f64) -> StepFailure {
    match f {
        FiniteFailure::Inverted { qp, det } => StepFailure::Inverted { qp, det, depth },
        FiniteFailure::Local { qp, reason, factor } => StepFailure::Local { qp, reason, factor },
    }
}

/// Why a node in normal contact beyond the surface's end stops the run.
fn beyond_end_message(model: &Model, k: usize, u: &[f64]) -> String {
    let n = model.candidates[k];
    let r = model.mesh.nodes[n][0];
    let where_ = match &model.punch {
        Punch::Tabulated { r: rs, .. } => format!(
            "the last point of the tabulated profile (r = {} mm)",
            rs.last().copied().unwrap_or(0.0)
        ),
        other => format!("the end of the {} surface", other.describe()),
    };
    format!(
        "candidate {k} (node {n}, r = {r} mm, displaced to r = {} mm) is in normal contact \
         beyond {where_}: the punch has no surface (or no normal) there; extend the \
         tabulated profile or use `contact: Vertical`",
        r + u[2 * n]
    )
}

/// The stiffness `-lambda kappa / (1 + g kappa)` (N/mm) that the rotation of the normal
/// adds on the tangential dof of a node in normal contact: the derivative of the
/// tangential residual `t(x) . f_int` through `t` is `f_int . dt = -lambda m . dt`, and
/// `m . dt = kappa ds = kappa (t . du) / (1 + g kappa)` (the closest point moves by the
/// arc length `ds` when the node moves by `du` at a distance `g` from the surface).
/// Zero on straight pieces; 0 also past the center of curvature (`1 + g kappa <= 0`,
/// which no converged state reaches).
fn curvature_stiffness(lambda: f64, p: &Projection) -> f64 {
    let den = 1.0 + p.gap * p.kappa;
    #[cfg(test)]
    if tests::NO_CURVATURE.with(std::cell::Cell::get) {
        return 0.0;
    }
    if p.kappa == 0.0 || !(den > 0.0) {
        0.0
    } else {
        -lambda * p.kappa / den
    }
}

/// Gap `phi(r_k) - U - u_z,k` of candidate k (mm).
fn gap(model: &Model, k: usize, depth: f64, u: &[f64]) -> f64 {
    model.candidate_profile[k] - depth - u[2 * model.candidates[k] + 1]
}

/// Nodal pressures of a step: `lambda_k / int N_k 2 pi r dr` at the active candidates (MPa),
/// as `(r, p)` pairs sorted by r.
pub fn nodal_pressures(model: &Model, rec: &StepRecord) -> Vec<(f64, f64)> {
    rec.active
        .iter()
        .zip(&rec.lambda)
        .map(|(&k, &l)| {
            (
                model.candidate_r(k as usize),
                l / model.candidate_area[k as usize],
            )
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::extrapolation_weights;
    use crate::{ContactKind, DirectSolver, Model, Punch, Schedule, Segment, SolverOptions};
    use indentify_laws::Elastic;
    use indentify_mesh::CylinderMesher;

    thread_local! {
        /// Drops the curvature stiffness (this thread's tests only): the tangent is then
        /// not the derivative of the residual on a curved punch.
        pub(super) static NO_CURVATURE: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
    }

    /// Newton iterations and residuals of the last step of an elastic ramp to 0.05 mm
    /// under a sphere (R = 0.5 mm) with normal contact, on a 2 x 2 mm cylinder.
    fn sphere_last_step(no_curvature: bool) -> Vec<f64> {
        let mesh = CylinderMesher {
            radius: 2.0,
            height: 2.0,
            nr: 12,
            nz: 12,
            grading_r: 1.3,
            grading_z: 1.3,
        }
        .build()
        .unwrap();
        let model =
            Model::with_contact(mesh, Punch::Sphere { radius: 0.5 }, ContactKind::Normal).unwrap();
        let sched = Schedule::from_segments(&[Segment {
            duration: 1.0,
            depth: 0.05,
            steps: 10,
        }])
        .unwrap();
        let opts = SolverOptions {
            residual_tol: 1e-13,
            ..Default::default()
        };
        NO_CURVATURE.with(|c| c.set(no_curvature));
        let mut solver = DirectSolver::new(&model).unwrap();
        let run = solver.run(&model, &Elastic, &[20000.0, 0.3], &sched, &opts);
        NO_CURVATURE.with(|c| c.set(false));
        run.unwrap();
        solver.last_residuals().iter().map(|r| r.0).collect()
    }

    /// The curvature stiffness makes Newton quadratic on a sphere; without it the same
    /// step converges linearly (each residual a roughly constant fraction of the last),
    /// in more iterations.
    #[test]
    fn curvature_stiffness_makes_newton_quadratic() {
        let with = sphere_last_step(false);
        let without = sphere_last_step(true);
        println!("with curvature stiffness: {with:?}\nwithout: {without:?}");
        assert!(without.len() > with.len() + 1, "{with:?} {without:?}");
        // without: linear contraction between 1e-3 and 1e-11 (no pair squares)
        let pairs: Vec<f64> = without
            .windows(2)
            .filter(|w| w[0] < 1e-3 && w[1] > 1e-11)
            .map(|w| w[1] / w[0])
            .collect();
        assert!(pairs.len() >= 3, "{without:?}");
        for w in without.windows(2).filter(|w| w[0] < 1e-3 && w[1] > 1e-11) {
            assert!(w[1] > 10.0 * w[0] * w[0], "{:e} -> {:e}", w[0], w[1]);
        }
    }

    /// The extrapolation of degree p is exact for polynomials of degree p and misses
    /// degree p + 1, with unequal steps (a cut step among full ones).
    #[test]
    fn extrapolation_is_exact_for_polynomials_of_its_degree() {
        let times = [0.1, 0.3, 0.55, 0.675, 0.925];
        let (t_next, t) = (times[4], &times[..4]);
        let h = [t[3] - t[2], t[2] - t[1], t[1] - t[0]];
        let dt = t_next - t[3];
        for order in 1..=3 {
            let w = extrapolation_weights(dt, h, order);
            for degree in 0..=order + 1 {
                let u = |x: f64| {
                    (0..=degree)
                        .map(|k| (1.0 + k as f64) * x.powi(k as i32))
                        .sum::<f64>()
                };
                let du = [u(t[3]) - u(t[2]), u(t[2]) - u(t[1]), u(t[1]) - u(t[0])];
                let got = w[0] * du[0] + w[1] * du[1] + w[2] * du[2];
                let err = (got - (u(t_next) - u(t[3]))).abs();
                if degree <= order {
                    assert!(err < 1e-13, "order {order}, degree {degree}: {err:e}");
                } else {
                    assert!(err > 1e-3, "order {order} fits degree {degree}: {err:e}");
                }
            }
            // only the steps the degree uses carry weight
            assert!(w[order..].iter().all(|&x| x == 0.0), "{w:?}");
        }
    }
}
