//! The direct problem's fixed data ([`Model`]): mesh, Gauss-point geometry, dofs, the
//! sparsity pattern, the contact candidates with their profile and lumped areas, the
//! punch with its surface, the contact kind and the kinematics. Built once, shared by the
//! direct solver, the constrained system, the contact constraints and the adjoint.

use indentify_fe::{Discretization, DofMap, Pattern};
use indentify_mesh::Mesh;

use crate::ContactError;
use crate::friction::{self, Status};
use crate::kinematics::Kinematics;
use crate::normal::{ContactKind, Projection, Surface};
use crate::punch::Punch;
use crate::system::NodeFrame;

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
        punch.require_profile()?;
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
        let mut out = Vec::new();
        self.frames_into(active, lambda, u, depth, &mut out);
        out
    }

    /// [`Model::frames`] into `out` (cleared first; its capacity kept, so a caller that
    /// keeps `out` from step to step allocates nothing once it holds a step's frames).
    pub fn frames_into(
        &self,
        active: &[u32],
        lambda: &[f64],
        u: &[f64],
        depth: f64,
        out: &mut Vec<NodeFrame>,
    ) {
        out.clear();
        if self.surface.is_none() {
            return;
        }
        out.extend(active.iter().zip(lambda).filter_map(|(&k, &lam)| {
            let p = self.project(k as usize, u, depth).in_contact();
            self.frame(k as usize, &p, lam)
        }));
    }

    /// The frames of the active candidates of a converged step with Coulomb friction
    /// (empty without normal contact): as [`Model::frames`], with each node's stick/slip
    /// status `slip` (same order as `active`, [`crate::StepRecord::slip`]) and the internal
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
        let mut out = Vec::new();
        self.friction_frames_into(active, slip, f_int, u, depth, &mut out);
        out
    }

    /// [`Model::friction_frames`] into `out` (cleared first; its capacity kept, as
    /// [`Model::frames_into`]).
    pub fn friction_frames_into(
        &self,
        active: &[u32],
        slip: &[Status],
        f_int: &[f64],
        u: &[f64],
        depth: f64,
        out: &mut Vec<NodeFrame>,
    ) {
        out.clear();
        if self.surface.is_none() {
            return;
        }
        let mu = self.contact.friction();
        out.extend(active.iter().zip(slip).filter_map(|(&k, &st)| {
            let k = k as usize;
            let n = self.candidates[k];
            let p = self.project(k, u, depth).in_contact();
            friction::frame(self, k, &p, [f_int[2 * n], f_int[2 * n + 1]], st, mu)
        }));
    }

    /// The frame of candidate `k` with projection `p` and normal reaction `lambda`
    /// (frictionless normal contact).
    pub(crate) fn frame(&self, k: usize, p: &Projection, lambda: f64) -> Option<NodeFrame> {
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

    /// The vertical gap `phi(r_k) - U - u_z,k` of candidate `k` (mm) at depth `depth`
    /// and displacement `u` (all dofs): vertical contact's gap.
    pub(crate) fn vertical_gap(&self, k: usize, depth: f64, u: &[f64]) -> f64 {
        self.candidate_profile[k] - depth - u[2 * self.candidates[k] + 1]
    }
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
    if test_hooks::NO_CURVATURE.with(std::cell::Cell::get) {
        return 0.0;
    }
    if p.kappa == 0.0 || !(den > 0.0) {
        0.0
    } else {
        -lambda * p.kappa / den
    }
}

#[cfg(test)]
pub(crate) mod test_hooks {
    thread_local! {
        /// Drops the curvature stiffness (this thread's tests only): the tangent is then
        /// not the derivative of the residual on a curved punch.
        pub(crate) static NO_CURVATURE: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
    }
}
