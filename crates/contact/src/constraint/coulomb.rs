//! Normal contact with Coulomb friction ([`crate::ContactKind::NormalFriction`]): the
//! frictionless piece ([`super::frictionless`]) for the gaps and the contact set, plus the
//! stick/slip partition of the active nodes (`crate::friction`: a sticking node's
//! tangential dof prescribed so that its closest point keeps its arc coordinate, a
//! slipping node's tangential row `(t - mu sigma m) . f_int = 0`).

use super::frictionless::Frictionless;
use super::{Constraint, ContactSet, Iterate, StatusFlip, Tolerances};
use crate::StepRecord;
use crate::friction;
use crate::model::Model;
use crate::newton::StepFailure;
use crate::system::{ConstrainedSystem, NodeFrame};

/// Normal contact with friction coefficient `mu` (> 0).
#[derive(Debug)]
pub(crate) struct Coulomb<'m> {
    normal: Frictionless<'m>,
    mu: f64,
}

impl<'m> Coulomb<'m> {
    pub(crate) fn new(model: &'m Model, mu: f64) -> Coulomb<'m> {
        Coulomb {
            normal: Frictionless::new(model),
            mu,
        }
    }
}

impl Constraint for Coulomb<'_> {
    fn predict(&self, set: &mut ContactSet, u: &[f64], du: &[f64], ratio: f64, depth: f64) {
        self.normal.predict(set, u, du, ratio, depth);
    }

    fn update(&mut self, set: &ContactSet, it: &Iterate<'_>) {
        self.normal.update(set, it);
    }

    fn constrained_equations(&self, set: &ContactSet, constrained: &mut [bool]) {
        self.normal.constrained_equations(set, constrained);
    }

    /// The slipping nodes' tangential residual (sticking nodes have none: their
    /// tangential dof is prescribed).
    fn residual(&self, set: &ContactSet, it: &Iterate<'_>) -> f64 {
        let model = self.normal.model;
        let mut res: f64 = 0.0;
        for k in set.active().filter(|&k| set.slip[k] != 0) {
            if self.normal.tangential(k).is_some() {
                let r = friction::tangential_residual(
                    &self.normal.proj[k],
                    it.node_force(model, k),
                    set.slip[k],
                    self.mu,
                );
                res = res.max(r.abs());
            }
        }
        res
    }

    /// The gaps closed, and the sticking nodes' closest points at their stick points.
    fn targets_met(&self, set: &ContactSet, it: &Iterate<'_>) -> bool {
        set.active().all(|k| {
            self.normal.gaps_closed(k, it.depth)
                && (set.slip[k] != 0
                    || self.normal.tangential(k).is_none()
                    || (self.normal.proj[k].s - it.xi[k]).abs() <= 1e-13 * (1.0 + it.depth.abs()))
        })
    }

    fn lambda(&self, k: usize, it: &Iterate<'_>) -> f64 {
        self.normal.lambda(k, it)
    }

    fn gap(&self, k: usize, it: &Iterate<'_>) -> f64 {
        self.normal.gap(k, it)
    }

    /// A sticking node under tension first turns to slip: its release is decided
    /// slipping, by [`Constraint::check_status`].
    fn holds_under_tension(&self, set: &ContactSet, k: usize) -> bool {
        set.slip[k] == 0 && self.normal.tangential(k).is_some()
    }

    fn check_status(
        &self,
        set: &ContactSet,
        it: &Iterate<'_>,
        tol: &Tolerances,
        flips: &mut Vec<StatusFlip>,
    ) {
        // a borderline node (slip increment ~ 0, tangential force ~ mu lambda) satisfies
        // both statuses to the solver's precision: these wider tolerances keep it from
        // cycling between them
        let stol = 1e3 * tol.gap;
        let ctol = 1e2 * tol.lambda;
        let model = self.normal.model;
        for k in set.active() {
            if self.normal.tangential(k).is_none() {
                continue;
            }
            if let Some((st, v)) = friction::check(
                &self.normal.proj[k],
                it.node_force(model, k),
                it.xi[k],
                set.slip[k],
                self.mu,
                friction::CheckTolerances {
                    cone: ctol,
                    slip: stol,
                    scale: tol.force,
                },
            ) {
                flips.push((k, st, v));
            }
        }
    }

    fn accept(&self, set: &ContactSet, it: &Iterate<'_>) -> Result<(), StepFailure> {
        self.normal.accept(set, it)
    }

    fn record(&self, set: &ContactSet, it: &Iterate<'_>, rec: &mut StepRecord) {
        self.normal.record(set, it, rec);
        rec.slip = rec.active.iter().map(|&k| set.slip[k as usize]).collect();
    }

    fn stick_points(&self) -> Vec<f64> {
        self.normal.proj.iter().map(|p| p.s).collect()
    }

    fn impose(&mut self, set: &ContactSet, it: &Iterate<'_>, system: &mut ConstrainedSystem) {
        let model = self.normal.model;
        self.normal.frames.clear();
        for k in set.active() {
            let f = it.node_force(model, k);
            if let Some(frame) =
                friction::frame(model, k, &self.normal.proj[k], f, set.slip[k], self.mu)
            {
                self.normal.frames.push(frame);
            }
        }
        system.set_frames(&self.normal.frames);
    }

    fn prescribe(&self, set: &ContactSet, it: &Iterate<'_>, xbar: &mut [f64]) {
        self.normal.prescribe(set, it, xbar);
        for k in set.active().filter(|&k| set.slip[k] == 0) {
            // a sticking node: Newton on the arc coordinate, s(x) = xi
            if let Some(e) = self.normal.tangential(k) {
                xbar[e] = friction::stick_increment(&self.normal.proj[k], it.xi[k]);
            }
        }
    }

    fn frames_need_force(&self) -> bool {
        true
    }

    fn recorded_frames(
        &self,
        rec: &StepRecord,
        u: &[f64],
        f_int: Option<&[f64]>,
    ) -> Vec<NodeFrame> {
        let f_int = f_int.expect("the frames with friction need the internal force");
        let model = self.normal.model;
        model.friction_frames(&rec.active, &rec.slip, f_int, u, rec.depth)
    }
}
