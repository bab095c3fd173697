//! Normal contact with Coulomb friction ([`crate::ContactKind::NormalFriction`]): the
//! frictionless piece ([`super::frictionless`]) for the gaps and the contact set, plus the
//! stick/slip partition of the active nodes (`crate::friction`: a sticking node's
//! tangential dof prescribed so that its closest point keeps its arc coordinate, a
//! slipping node's tangential row `(t - mu sigma m) . f_int = 0`).
//!
//! The exact adjoint and forward sensitivities, the contact set and the stick/slip
//! partition held at their converged values (docs/validation-contact.md §7), small or
//! finite strain. Step `i` linearized, in the frames `(t, m)` of its active nodes
//! (`z = Q^T du`): `m . du = 0` on every active node; a sticking node ties its closest
//! point to the previous step's, `t_i . du_i = (1 + g_i kappa_i) t_{i-1} . du_{i-1} /
//! (1 + g_{i-1} kappa_{i-1})` (the prescribed value `p_i` of its tangential slot: the
//! previous step's displacement enters the step, [`Constraint::sensitivity_ties`]); a
//! slipping node's row is `(t + c m) . (K du + B* C q) + d t . du = 0` with
//! `c = -mu sigma` (unsymmetric: `A = S + E W^T` on the free slots);
//! `dsigma = C (B du + q)`, `dF = -e_A . B* dsigma` as without friction. The adjoint
//! transposes it: with the step's outgoing functional `rho dF + <mu_{i+1}, y> + l_i . du`
//! (`l_i` the load of step `i + 1`'s sticking nodes on this step's tangential motion),
//!
//! ```text
//! g   = B* [(C S - I) mu_{i+1} - rho C B e_A] + l_i
//! V   = Q w^,  w = A^-T (Q^T g)_F,  w^ = w on F, c_k w_t,k on slipping normal slots
//! pi  = (Q^T g - K^ w^)_P   at the sticking tangential slots (cotangent of p_i)
//! mu_i = C (S mu_{i+1} - B (V + rho e_A)),  dJ/dc -= <mu_i, R_i>
//! l_{i-1} = sum_k pi_k (1 + g_i kappa_i) / (1 + g_{i-1} kappa_{i-1}) t_{i-1,k}
//! ```
//!
//! The `rho e_A` shift is [`ForceCotangent::Shifted`] (the body's part, `B*` and the
//! back-substitution, is the adjoint crate's); `l_i` is [`Constraint::adjoint_rhs`], `pi`
//! the transposed solve's (`ConstrainedSystem::solve_transposed`) and
//! [`Constraint::adjoint_carry`] turns it into `l_{i-1}`. Under finite strain
//! (docs/validation-finite-strain.md §7) the friction rows and the stick ties are the
//! same (the closest point, its arc coordinate and `1 + g kappa` are functions of the
//! displaced node); `B` becomes the step's `G_i`, `B* C B e_A` the consistent tangent
//! `K e_A`, and the frames' reactions the finite internal force.

use super::frictionless::Frictionless;
use super::{Constraint, ContactSet, ForceCotangent, Iterate, StatusFlip, Step, Tie, Tolerances};
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
    /// The adjoint sweep: the cotangents of the sticking nodes' prescribed tangential
    /// values of the step after the current one, times its `1 + g kappa` (candidate,
    /// value).
    carry: Vec<(usize, f64)>,
}

impl<'m> Coulomb<'m> {
    pub(crate) fn new(model: &'m Model, mu: f64) -> Coulomb<'m> {
        Coulomb {
            normal: Frictionless::new(model),
            mu,
            carry: Vec::new(),
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
        frames: &mut Vec<NodeFrame>,
    ) -> Result<(), String> {
        let f_int = f_int.expect("the frames with friction need the internal force");
        let model = self.normal.model;
        model.friction_frames_into(&rec.active, &rec.slip, f_int, u, rec.depth, frames);
        // one frame per active node, in order (the adjoint pairs them by index)
        for (j, &k) in rec.active.iter().enumerate() {
            let ez = model.dofs.equation(2 * model.candidates[k as usize] + 1);
            if frames.get(j).is_none_or(|f| Some(f.ez) != ez) {
                return Err(format!("active candidate {k} has no contact frame"));
            }
        }
        if rec.slip.len() != rec.active.len() {
            return Err(format!(
                "the step records {} stick/slip statuses for {} active nodes",
                rec.slip.len(),
                rec.active.len()
            ));
        }
        Ok(())
    }

    fn force_cotangent(&self) -> ForceCotangent {
        ForceCotangent::Shifted
    }

    /// `+ l_i`: the sticking loads of step `i + 1` on this step's tangential motion.
    fn adjoint_rhs(&mut self, step: &Step<'_>, _rho: f64, g: &mut [f64], _v_p: &mut [f64]) {
        let model = self.normal.model;
        let rec = step.rec;
        let active_now = |k: usize| rec.active.binary_search(&(k as u32)).is_ok();
        for (k, pi) in self.carry.drain(..) {
            let (rate, t) = arc_rate(model, k, step.u, rec.depth, active_now(k));
            let n = model.candidates[k];
            for (d, tc) in [(2 * n, t[0]), (2 * n + 1, t[1])] {
                if let Some(e) = model.dofs.equation(d) {
                    g[e] += pi / rate * tc;
                }
            }
        }
    }

    /// `l_i . (du_U + e_z)` over the tied nodes: the later sticking ties read each node's
    /// position relative to the punch, `x + U e_z`, so a unit depth increment moves a tied
    /// node by its depth column plus `e_z` (an active node's column is `w - e_z`: it moves
    /// by `w`; a node out of contact stays, and the punch moves past it).
    fn adjoint_depth(&self, step: &Step<'_>, col: &[f64]) -> f64 {
        let model = self.normal.model;
        let rec = step.rec;
        let active_now = |k: usize| rec.active.binary_search(&(k as u32)).is_ok();
        let at = |d: usize| model.dofs.equation(d).map_or(0.0, |e| col[e]);
        let mut a = 0.0;
        for &(k, pi) in &self.carry {
            let (rate, t) = arc_rate(model, k, step.u, rec.depth, active_now(k));
            let n = model.candidates[k];
            a += pi / rate * (t[0] * at(2 * n) + t[1] * (at(2 * n + 1) + 1.0));
        }
        a
    }

    /// This step's sticking nodes load the previous step.
    fn adjoint_carry(&mut self, step: &Step<'_>, stick: &[f64]) {
        let model = self.normal.model;
        let rec = step.rec;
        for (j, &k) in rec.active.iter().enumerate() {
            if step.frames[j].stick && stick[j] != 0.0 {
                let (rate, _) = arc_rate(model, k as usize, step.u, rec.depth, true);
                self.carry.push((k as usize, stick[j] * rate));
            }
        }
    }

    fn adjoint_pending(&self) -> bool {
        !self.carry.is_empty()
    }

    fn adjoint_reset(&mut self) {
        self.carry.clear();
    }

    fn ties_steps(&self) -> bool {
        true
    }

    /// Sticking nodes: `t_i . du_i = coef t_{i-1} . du_{i-1}`.
    fn sensitivity_ties(
        &self,
        step: &Step<'_>,
        prev: Option<(&StepRecord, &[f64])>,
        ties: &mut Vec<Tie>,
    ) {
        let Some((prev, u0)) = prev else {
            return;
        };
        let model = self.normal.model;
        let rec = step.rec;
        for (j, &k) in rec.active.iter().enumerate() {
            let f = step.frames[j];
            if let (true, Some(er)) = (f.stick, f.er) {
                let k = k as usize;
                let was_active = prev.active.binary_search(&(k as u32)).is_ok();
                let (rate0, t0) = arc_rate(model, k, u0, prev.depth, was_active);
                let (rate1, _) = arc_rate(model, k, step.u, rec.depth, true);
                ties.push(Tie {
                    eq: er,
                    node: model.candidates[k],
                    coef: rate1 / rate0,
                    t: t0,
                });
            }
        }
    }
}

/// `1 + g kappa` of candidate `k`'s closest point at displacement `u` and depth `depth`
/// (`active`: measured as a node in contact), with its tangent: the closest point moves by
/// `t . du / (1 + g kappa)`.
fn arc_rate(model: &Model, k: usize, u: &[f64], depth: f64, active: bool) -> (f64, [f64; 2]) {
    let p = model.project(k, u, depth);
    let p = if active { p.in_contact() } else { p };
    (1.0 + p.gap * p.kappa, p.t)
}
