//! Frictionless normal contact ([`crate::ContactKind::Normal`]): the gap of an active node
//! is its signed distance to the punch surface along the normal `m` at its closest point,
//! `lambda = -m . f_int`, and its two dofs are rotated into the surface frame: `m . du = g`
//! is prescribed, the tangential equation `t . f_int = 0` is solved with the curvature
//! stiffness `-lambda kappa / (1 + g kappa)` (docs/validation-contact.md §2).
//! [`super::coulomb`] builds friction on this piece.
//!
//! Adjoint: each step's system is the forward's rotated one (`Q^T K Q + D` with `D` on
//! the tangential dofs, frames from the recorded displacement and reactions); the
//! adjoint's data become `m . V = rho m_z` on the normal dofs plus the source
//! `rho d t_z` on the tangential ones, so that the transposed recursion of the vertical
//! case holds (docs/validation-contact.md).

use super::{Constraint, ContactSet, Iterate, Step};
use crate::StepRecord;
use crate::model::Model;
use crate::newton::StepFailure;
use crate::normal::Projection;
use crate::punch::Punch;
use crate::system::{ConstrainedSystem, NodeFrame};

/// Normal contact on `model`'s candidates, with the closest points of the last iterate.
#[derive(Debug)]
pub(crate) struct Frictionless<'m> {
    pub(super) model: &'m Model,
    /// The closest point of every candidate at the last iterate ([`Constraint::update`]).
    pub(super) proj: Vec<Projection>,
    /// The frames of the last [`Constraint::impose`].
    pub(super) frames: Vec<NodeFrame>,
}

impl<'m> Frictionless<'m> {
    pub(crate) fn new(model: &'m Model) -> Frictionless<'m> {
        Frictionless {
            model,
            proj: Vec::new(),
            frames: Vec::new(),
        }
    }

    /// The equation of candidate `k`'s tangential (`u_r`) slot, `None` on the axis.
    pub(super) fn tangential(&self, k: usize) -> Option<usize> {
        self.model.dofs.equation(2 * self.model.candidates[k])
    }

    /// The equation of candidate `k`'s normal (`u_z`) slot.
    fn normal(&self, k: usize) -> Option<usize> {
        self.model.dofs.equation(2 * self.model.candidates[k] + 1)
    }

    /// The gaps of the active nodes are closed to round-off.
    pub(super) fn gaps_closed(&self, k: usize, depth: f64) -> bool {
        self.proj[k].gap.abs() <= 1e-13 * (1.0 + depth.abs())
    }
}

impl Constraint for Frictionless<'_> {
    fn predict(&self, set: &mut ContactSet, u: &[f64], du: &[f64], ratio: f64, depth: f64) {
        for k in 0..set.active.len() {
            let n = self.model.candidates[k];
            let x = [
                u[2 * n] + ratio * du[2 * n],
                u[2 * n + 1] + ratio * du[2 * n + 1],
            ];
            if !set.active[k] && self.model.project_at(k, x, depth).gap < 0.0 {
                set.activate(k);
            }
        }
    }

    fn update(&mut self, set: &ContactSet, it: &Iterate<'_>) {
        let model = self.model;
        self.proj.clear();
        self.proj.extend((0..set.active.len()).map(|k| {
            let p = model.project(k, it.u, it.depth);
            if set.active[k] { p.in_contact() } else { p }
        }));
    }

    fn constrained_equations(&self, set: &ContactSet, constrained: &mut [bool]) {
        for k in set.active() {
            for e in [self.normal(k), self.tangential(k)].into_iter().flatten() {
                constrained[e] = true;
            }
        }
    }

    fn residual(&self, set: &ContactSet, it: &Iterate<'_>) -> f64 {
        let mut res: f64 = 0.0;
        for k in set.active() {
            if self.tangential(k).is_some() {
                let (f, t) = (it.node_force(self.model, k), self.proj[k].t);
                res = res.max((f[0] * t[0] + f[1] * t[1]).abs());
            }
        }
        res
    }

    fn targets_met(&self, set: &ContactSet, it: &Iterate<'_>) -> bool {
        set.active().all(|k| self.gaps_closed(k, it.depth))
    }

    fn lambda(&self, k: usize, it: &Iterate<'_>) -> f64 {
        let (f, m) = (it.node_force(self.model, k), self.proj[k].m);
        -(f[0] * m[0] + f[1] * m[1])
    }

    fn gap(&self, k: usize, _it: &Iterate<'_>) -> f64 {
        self.proj[k].gap
    }

    fn accept(&self, set: &ContactSet, it: &Iterate<'_>) -> Result<(), StepFailure> {
        match (0..self.proj.len()).find(|&k| set.active[k] && self.proj[k].beyond_end) {
            Some(k) => Err(StepFailure::Geometry(beyond_end_message(
                self.model, k, it.u,
            ))),
            None => Ok(()),
        }
    }

    fn record(&self, _set: &ContactSet, it: &Iterate<'_>, rec: &mut StepRecord) {
        for (l, &k) in rec.lambda.iter_mut().zip(&rec.active) {
            *l = self.lambda(k as usize, it);
        }
        rec.contact_radius = rec.active.last().map_or(0.0, |&k| {
            let n = self.model.candidates[k as usize];
            self.model.mesh.nodes[n][0] + it.u[2 * n]
        });
    }

    fn impose(&mut self, set: &ContactSet, it: &Iterate<'_>, system: &mut ConstrainedSystem) {
        self.frames.clear();
        for k in set.active() {
            if let Some(f) = self.model.frame(k, &self.proj[k], self.lambda(k, it)) {
                self.frames.push(f);
            }
        }
        system.set_frames(&self.frames);
    }

    fn prescribe(&self, set: &ContactSet, _it: &Iterate<'_>, xbar: &mut [f64]) {
        for k in set.active() {
            if let Some(e) = self.normal(k) {
                // Newton on the gap: m . du = g
                xbar[e] = self.proj[k].gap;
            }
        }
    }

    fn recorded_frames(
        &self,
        rec: &StepRecord,
        u: &[f64],
        _f_int: Option<&[f64]>,
        frames: &mut Vec<NodeFrame>,
    ) -> Result<(), String> {
        (self.model).frames_into(&rec.active, &rec.lambda, u, rec.depth, frames);
        Ok(())
    }

    /// `m . V = rho m_z` on the active nodes, and the source `rho d t_z` along `t` on
    /// their tangential dofs (the curvature stiffness `d` couples the tangential motion
    /// to the vertical force).
    fn adjoint_rhs(&mut self, step: &Step<'_>, rho: f64, g: &mut [f64], v_p: &mut [f64]) {
        for f in step.frames {
            v_p[f.ez] = rho * f.m[1];
            if let Some(er) = f.er {
                let src = rho * f.d * f.t[1];
                g[er] += src * f.t[0];
                g[f.ez] += src * f.t[1];
            }
        }
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
