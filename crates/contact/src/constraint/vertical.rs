//! The paper's vertical contact ([`crate::ContactKind::Vertical`]): the gap of candidate
//! `k` at its reference radius, `g_k = phi(r_k) - U - u_z,k`, the vertical dof of an
//! active node prescribed, `u_z,k = phi(r_k) - U`, and its reaction
//! `lambda_k = -f_int,z,k`. In the adjoint, `V_z,k = dJ/dF_i` on the active nodes
//! (docs/theory.md §3).

use super::{Constraint, ContactSet, Iterate, Step};
use crate::StepRecord;
use crate::model::Model;
use crate::system::{ConstrainedSystem, NodeFrame};

/// Vertical contact on `model`'s candidates.
#[derive(Debug)]
pub(crate) struct Vertical<'m> {
    model: &'m Model,
}

impl<'m> Vertical<'m> {
    pub(crate) fn new(model: &'m Model) -> Vertical<'m> {
        Vertical { model }
    }

    /// The vertical dof of candidate `k`.
    fn zdof(&self, k: usize) -> usize {
        2 * self.model.candidates[k] + 1
    }
}

impl Constraint for Vertical<'_> {
    fn predict(&self, set: &mut ContactSet, u: &[f64], du: &[f64], ratio: f64, depth: f64) {
        for k in 0..set.active.len() {
            if !set.active[k]
                && self.model.vertical_gap(k, depth, u) - ratio * du[self.zdof(k)] < 0.0
            {
                set.activate(k);
            }
        }
    }

    fn update(&mut self, _set: &ContactSet, _it: &Iterate<'_>) {}

    fn constrained_equations(&self, set: &ContactSet, constrained: &mut [bool]) {
        for k in set.active() {
            if let Some(e) = self.model.dofs.equation(self.zdof(k)) {
                constrained[e] = true;
            }
        }
    }

    fn residual(&self, _set: &ContactSet, _it: &Iterate<'_>) -> f64 {
        0.0
    }

    fn targets_met(&self, set: &ContactSet, it: &Iterate<'_>) -> bool {
        set.active().all(|k| {
            let target = self.model.candidate_profile[k] - it.depth;
            (it.u[self.zdof(k)] - target).abs() <= 1e-13 * (1.0 + target.abs())
        })
    }

    fn lambda(&self, k: usize, it: &Iterate<'_>) -> f64 {
        -it.f_int[self.zdof(k)]
    }

    fn gap(&self, k: usize, it: &Iterate<'_>) -> f64 {
        self.model.vertical_gap(k, it.depth, it.u)
    }

    fn impose(&mut self, _set: &ContactSet, _it: &Iterate<'_>, _system: &mut ConstrainedSystem) {}

    fn prescribe(&self, set: &ContactSet, it: &Iterate<'_>, xbar: &mut [f64]) {
        for k in set.active() {
            if let Some(e) = self.model.dofs.equation(self.zdof(k)) {
                xbar[e] = self.model.candidate_profile[k] - it.depth - it.u[self.zdof(k)];
            }
        }
    }

    fn recorded_frames(
        &self,
        _rec: &StepRecord,
        _u: &[f64],
        _f_int: Option<&[f64]>,
        frames: &mut Vec<NodeFrame>,
    ) -> Result<(), String> {
        frames.clear();
        Ok(())
    }

    /// The adjoint's vertical displacement of an active node is the cost's `dJ/dF_i`.
    fn adjoint_rhs(&mut self, step: &Step<'_>, rho: f64, _g: &mut [f64], v_p: &mut [f64]) {
        for &k in &step.rec.active {
            if let Some(e) = self.model.dofs.equation(self.zdof(k as usize)) {
                v_p[e] = rho;
            }
        }
    }
}
