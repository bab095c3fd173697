//! The refresh policy of the inexact Newton solves (docs/solver.md, "The preconditioner
//! refresh policy"): a nonlinear law's Newton iterations solve their tangent systems by
//! conjugate gradients preconditioned with an earlier tangent's Cholesky factor
//! (`system.rs`), and this policy decides, from measured counts only (never from clocks,
//! so that the same inputs give the same bits), when that factor is refreshed: before a
//! solve (a proactive factorization) or after CG gave up on it (a fallback).

/// Which refresh rule the inexact solves follow.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum RefreshRule {
    /// The legacy rule for the stress-only laws (Elastic, Maxwell, Norton-Hoff: their bits
    /// are pinned) and [`RefreshRule::Adaptive`] for materials with internal variables.
    #[default]
    Auto,
    /// Factorize after a solve that needed [`LEGACY_REFRESH`] CG iterations or more; fall
    /// back to a factorization when CG has not converged in [`LEGACY_CAP`] iterations.
    Legacy,
    /// The legacy rule, and after [`STREAK`] solves of a step in a row that fell back
    /// (CG failed with the factor of the iterate just before), the step's further solves
    /// factorize without trying CG first: its tangent changes too much from one iterate
    /// to the next for an earlier factor to precondition it (rate-independent plasticity
    /// where many points switch between the elastic and plastic branches, docs/solver.md).
    /// Depth-controlled steps only: in load-controlled steps of the rate-independent laws,
    /// whose Newton iterations often cycle until the step is cut, it was measured to cost
    /// more (R2, power hardening: twice the factorizations) and the legacy rule applies.
    Adaptive,
}

/// An inexact solve that needed this many CG iterations makes the next one factorize:
/// the old factor has drifted too far from the tangent (R2 with the degree-2 predictor,
/// 283 Newton iterations: 41 factorizations and 579 CG iterations; 3 gives 55 and 429, 5
/// with at most 8 CG iterations 36 and 690, 6 30 and 844, all within the machine's noise
/// in time).
pub const LEGACY_REFRESH: usize = 4;

/// Largest number of CG iterations of an inexact solve before it factorizes instead (one
/// costs a matrix product and a triangular solve pair: about a seventh of a factorization
/// at R2's size).
pub const LEGACY_CAP: usize = 6;

/// Fallbacks in a row within a step after which [`RefreshRule::Adaptive`] factorizes the
/// step's further solves directly.
pub const STREAK: u32 = 2;

/// One preconditioned CG solve, as the policy saw it (the optional log of
/// [`crate::ConstrainedSystem::pcg_log`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PcgEvent {
    /// The Newton solve of the step it belongs to (1: the step's first).
    pub newton: u32,
    /// CG iterations done.
    pub iterations: u32,
    /// Whether CG reached its tolerance (otherwise the system was factorized).
    pub converged: bool,
}

/// The policy's state on one system: the rule and what it measured.
#[derive(Clone, Debug, Default)]
pub(crate) struct Refresh {
    pub(crate) rule: RefreshRule,
    /// The rule in force for the current run (`Auto` resolved).
    active: RefreshRule,
    /// Whether the current step prescribes the depth (the streak rule's domain).
    depth_step: bool,
    /// The most CG iterations a solve with the factor at hand needed on the last iterate's
    /// systems (0 after a factorization: its factor is fresh): the Newton solve's, or
    /// under load control the larger of it and the depth column's (which starts from the
    /// last column and may need none).
    last: usize,
    /// Whether a solve has run since the last preparation (the depth column's comes second).
    solved_once: bool,
    /// The Newton solve of the current step about to be prepared (1: the first).
    newton: u32,
    /// Solves of the current step in a row that factorized because CG failed (or, once
    /// [`STREAK`] is reached, because of it).
    streak: u32,
    /// A run has begun and has not prepared a solve yet: its first solve factorizes (the
    /// factor at hand may be the reusable tangent of an earlier run of a linear law on the
    /// same system, which the run must not depend on).
    first: bool,
    /// The log of every PCG solve, when kept.
    pub(crate) log: Option<Vec<PcgEvent>>,
}

impl Refresh {
    /// Resolves the rule for a run of a stress-only law (`law`) or another material. Every
    /// run starts with a factorization whatever ran before on the system.
    pub(crate) fn begin_run(&mut self, law: bool) {
        self.first = true;
        self.active = match self.rule {
            RefreshRule::Auto if law => RefreshRule::Legacy,
            RefreshRule::Auto => RefreshRule::Adaptive,
            r => r,
        };
        self.streak = 0;
    }

    /// A new time step begins (its first Newton solve comes next); `load`: it prescribes
    /// the force (or the depth through the frame's spring).
    pub(crate) fn begin_step(&mut self, load: bool) {
        self.depth_step = !load;
        self.newton = 0;
        self.streak = 0;
    }

    /// Whether the next solve factorizes its tangent instead of preconditioning CG with
    /// the factor at hand.
    pub(crate) fn factorize_next(&mut self) -> bool {
        self.newton += 1;
        self.solved_once = false;
        if std::mem::take(&mut self.first) {
            return true;
        }
        match self.active {
            RefreshRule::Adaptive if self.depth_step && self.streak >= STREAK => true,
            _ => self.last >= LEGACY_REFRESH,
        }
    }

    /// The largest number of CG iterations the next solve may take.
    pub(crate) fn cap(&self) -> usize {
        LEGACY_CAP
    }

    /// A CG solve took `iterations` and converged or not (then the system was factorized).
    pub(crate) fn solved(&mut self, iterations: usize, converged: bool) {
        self.last = match (converged, self.solved_once) {
            (false, _) => 0,
            (true, false) => iterations,
            (true, true) => self.last.max(iterations),
        };
        self.solved_once = true;
        self.streak = if converged { 0 } else { self.streak + 1 };
        if let Some(log) = &mut self.log {
            log.push(PcgEvent {
                newton: self.newton,
                iterations: iterations as u32,
                converged,
            });
        }
    }

    /// The tangent was factorized (the factor is this iterate's own).
    pub(crate) fn factorized(&mut self) {
        self.last = 0;
    }

    /// Forgets what was measured (the factor is dropped): what follows depends on the
    /// inputs from here on alone, so that a replay from a checkpoint repeats it bit for bit.
    pub(crate) fn forget(&mut self) {
        self.last = 0;
        self.streak = 0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn policy(rule: RefreshRule, law: bool) -> Refresh {
        let mut p = Refresh {
            rule,
            ..Refresh::default()
        };
        p.begin_run(law);
        p.begin_step(false);
        // every run factorizes first, whatever factor is at hand
        assert!(p.factorize_next());
        p.factorized();
        p.begin_step(false);
        p
    }

    /// `Auto` keeps the legacy rule for the stress-only laws and adapts for the others.
    #[test]
    fn auto_resolves_by_the_kind_of_material() {
        assert_eq!(policy(RefreshRule::Auto, true).active, RefreshRule::Legacy);
        assert_eq!(
            policy(RefreshRule::Auto, false).active,
            RefreshRule::Adaptive
        );
        assert_eq!(
            policy(RefreshRule::Legacy, false).active,
            RefreshRule::Legacy
        );
        assert_eq!(
            policy(RefreshRule::Adaptive, true).active,
            RefreshRule::Adaptive
        );
    }

    /// The legacy rule: CG is tried at every solve, a solve of `LEGACY_REFRESH` iterations
    /// or more makes the next one factorize, a fallback leaves a fresh factor.
    #[test]
    fn legacy_refreshes_after_a_long_solve_and_tries_cg_after_every_fallback() {
        let mut p = policy(RefreshRule::Legacy, false);
        assert!(!p.factorize_next());
        p.solved(LEGACY_REFRESH - 1, true);
        assert!(!p.factorize_next());
        p.solved(LEGACY_REFRESH, true);
        assert!(p.factorize_next());
        p.factorized();
        // fallbacks in a row never stop CG from being tried
        for _ in 0..10 {
            assert!(!p.factorize_next());
            p.solved(LEGACY_CAP, false);
        }
        assert_eq!(p.cap(), LEGACY_CAP);
    }

    /// The adaptive rule factorizes directly after `STREAK` fallbacks in a row, until the
    /// step ends; a converged solve or a forgotten history restarts the count.
    #[test]
    fn adaptive_stops_trying_cg_after_a_streak_of_fallbacks() {
        let mut p = policy(RefreshRule::Adaptive, false);
        for _ in 0..STREAK {
            assert!(!p.factorize_next());
            p.solved(LEGACY_CAP, false);
        }
        for _ in 0..5 {
            assert!(p.factorize_next());
            p.factorized();
        }
        // the next step tries CG again
        p.begin_step(false);
        assert!(!p.factorize_next());
        // a converged solve between two fallbacks breaks the streak
        p.solved(LEGACY_CAP, false);
        assert!(!p.factorize_next());
        p.solved(2, true);
        assert!(!p.factorize_next());
        p.solved(LEGACY_CAP, false);
        assert!(!p.factorize_next());
        p.solved(LEGACY_CAP, false);
        assert!(p.factorize_next());
        // a checkpoint forgets the streak (a replay from it repeats the run)
        p.forget();
        assert!(!p.factorize_next());
        // a load-controlled step keeps trying CG
        p.begin_step(true);
        for _ in 0..5 {
            assert!(!p.factorize_next());
            p.solved(LEGACY_CAP, false);
        }
    }

    /// The log records each solve with the Newton solve of its step.
    #[test]
    fn the_log_records_every_solve() {
        let mut p = policy(RefreshRule::Legacy, true);
        p.log = Some(Vec::new());
        assert!(!p.factorize_next());
        p.solved(3, true);
        assert!(!p.factorize_next());
        p.solved(6, false);
        assert_eq!(
            p.log.as_deref(),
            Some(
                &[
                    PcgEvent {
                        newton: 1,
                        iterations: 3,
                        converged: true
                    },
                    PcgEvent {
                        newton: 2,
                        iterations: 6,
                        converged: false
                    }
                ][..]
            )
        );
    }
}
