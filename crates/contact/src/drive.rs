//! What moves the punch: the drive of a run, its third piece beside the body's kinematics
//! (`body.rs`) and the contact constraint (`constraint/`), chosen once per run by the
//! direct solver. [`DepthDrive`] prescribes the depth history `U(t)` of a [`Schedule`]
//! (the force is measured); [`ForceDrive`] follows a [`LoadHistory`] whose segments
//! prescribe the depth or the force `P(t)`: in a load-controlled step the depth is one
//! more unknown with the scalar equation `sum_k lambda_k = P`, solved by the Newton
//! driver's bordered update on the same factorization (`newton.rs`, `Newton::border`;
//! docs/theory.md §13). The constraints never read the drive: they take the iterate's
//! depth (`constraint::Iterate::depth`), so a depth that changes between Newton
//! iterations needs no change in them (docs/solver.md). [`CompliantDrive`] prescribes
//! the depth through the instrument's frame: the recorded depth is the machine's, `h_meas
//! = h + Cf F + vd (t - t0) + h0`, so the punch is driven through a spring of compliance
//! `Cf` towards `H(t) = h_meas(t) - vd (t - t0) - h0`, each step solving `h + Cf F(h) = H`
//! by the same bordered update with the spring's stiffness `1 / Cf` on its diagonal
//! (docs/theory.md §13.7); `Cf = 0` is plain depth control.

use crate::history::{LoadHistory, Schedule, Target};
use crate::newton::State;

/// What a load-controlled step prescribes: the punch force at its end (N), or through
/// the instrument's spring a force that falls with the punch depth. (The time
/// extrapolation of nonlinear laws keys on the step's force rate, `newton.rs`.)
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Load {
    /// The prescribed force (N); under a [`Spring`], the force the last step carried
    /// (informative only).
    pub force: f64,
    /// The instrument's spring: the force is `(H - h) / Cf` at the punch depth `h`.
    pub spring: Option<Spring>,
    /// At the first step of a configured segment after a load-controlled step whose rate
    /// it does not share, and at the step after the one that loaded from zero force (the
    /// trigger's): the factor on the last step's increments (depth and displacement) that
    /// starts Newton, in place of the time extrapolation ([`ForceDrive`], `newton.rs`).
    pub restart: Option<f64>,
}

/// The frame's spring of a compliant depth-controlled step: `h + Cf F = H`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Spring {
    /// The prescribed machine depth `H` at the step's end, drift and offset removed (mm).
    pub prescribed: f64,
    /// The spring's stiffness `1 / Cf` (N/mm).
    pub stiffness: f64,
    /// The step's rate of `H` (mm/s): keys the time extrapolation as a depth rate does.
    pub rate: f64,
}

impl Load {
    /// The force (N) the step prescribes at the punch depth `depth` (mm).
    pub fn target(&self, depth: f64) -> f64 {
        match self.spring {
            None => self.force,
            Some(s) => (s.prescribed - depth) * s.stiffness,
        }
    }

    /// The rounding floor of [`Load::target`] at `depth` (N): `(H - h) / Cf` is known to
    /// `4 eps (|H| + |h|) / Cf` only, which a stiff frame (small `Cf`) makes larger than a
    /// tight residual tolerance; the step's residual does not count below it (0 under a
    /// plain load).
    pub fn floor(&self, depth: f64) -> f64 {
        self.spring.map_or(0.0, |s| {
            4.0 * f64::EPSILON * (s.prescribed.abs() + depth.abs()) * s.stiffness
        })
    }

    /// `-d target / d depth` (N/mm): the spring's stiffness, 0 under a plain load.
    pub fn stiffness(&self) -> f64 {
        self.spring.map_or(0.0, |s| s.stiffness)
    }

    /// Whether the force itself is prescribed (load control proper).
    pub fn is_force(&self) -> bool {
        self.spring.is_none()
    }
}

/// The drive of a run: what sets the punch of each step.
pub(crate) trait Drive: Sync {
    /// For the step from `state` to the time `t1` (s): the punch depth (mm) Newton starts
    /// from (prescribed under depth control), and the prescribed force under load control.
    fn step(&self, t1: f64, state: &State) -> (f64, Option<Load>);
}

/// The punch driven by the depth history of a schedule (the paper's problem (P)).
#[derive(Clone, Copy, Debug)]
pub(crate) struct DepthDrive<'a>(pub &'a Schedule);

impl Drive for DepthDrive<'_> {
    fn step(&self, t1: f64, _state: &State) -> (f64, Option<Load>) {
        (self.0.depth_at(t1), None)
    }
}

/// The punch driven by a history whose segments prescribe the depth or the force. Each
/// step moves linearly from its state towards its segment's end target (the force of
/// the state for a load-controlled segment, the depth for a depth-controlled one), so a
/// segment starts from wherever the previous one ended, and cut steps and sub-steps
/// follow the same straight line in time.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ForceDrive<'a>(pub &'a LoadHistory);

impl Drive for ForceDrive<'_> {
    fn step(&self, t1: f64, state: &State) -> (f64, Option<Load>) {
        let (t_end, target) = self.0.segment_at(t1);
        let f = (t1 - state.t) / (t_end - state.t);
        match target {
            Target::Depth(d) if f >= 1.0 => (d, None),
            Target::Depth(d) => (state.depth + f * (d - state.depth), None),
            Target::Force(p) => {
                let force = if f >= 1.0 {
                    p
                } else {
                    state.force + f * (p - state.force)
                };
                // Newton starts from the depth extrapolated linearly from the last step
                // (a nonlinear law's Newton driver replaces it by the displacement's own
                // time extrapolation, `newton.rs`); after the trigger's step and at the
                // start of a configured segment the last step's increments scaled to this
                // step's force increment
                let last = &state.past[0];
                let restart = match touchdown_factor(state, force) {
                    Some(q) => Some(q),
                    None if self.0.starts_configured_segment(state.t, t1) => {
                        restart_factor(state, force)
                    }
                    None => None,
                };
                let depth = match restart {
                    Some(q) => state.depth + q * last.depth,
                    None if last.dt > 0.0 => state.depth + (t1 - state.t) / last.dt * last.depth,
                    None => state.depth,
                };
                (
                    depth,
                    Some(Load {
                        force,
                        spring: None,
                        restart,
                    }),
                )
            }
        }
    }
}

/// The factor on the last step's increments that starts a load-controlled step to the
/// force `force` (N) from `state` where a configured segment begins: `None` unless the
/// last step prescribed the force and both steps load (or both unload) the punch.
///
/// The time extrapolation assumes the force rate carries on; a fast trigger ramp then a
/// slow segment (steps 9.2 times longer) put its first iterate about 18 increments too
/// deep, and Newton cycled between contact sets until the step was cut
/// (docs/validation-load-control.md §12). The depth follows the force instead: the power
/// law `h ~ F^m` through the last two states (`m = 1/2` for a sharp tip, `2/3` for a
/// sphere), where both are in contact and `m` lies in `[1/4, 1]`; otherwise the last
/// step's depth increment per newton, `dF / dF_last`.
pub(crate) fn restart_factor(state: &State, force: f64) -> Option<f64> {
    let last = &state.past[0];
    if !(last.load && last.dt > 0.0) {
        return None;
    }
    let df_last = last.rate * last.dt;
    follow_force(
        (state.force - df_last, state.depth - last.depth),
        (state.force, state.depth),
        force,
    )
}

/// The factor on the last step's increments that starts the load-controlled step to the
/// force `force` (N) after the step that loaded the punch from zero force (the trigger's
/// step): `None` elsewhere, or where the exponent is out of range.
///
/// From zero force the depth is not linear in the force (`h ~ F^m`, `m = 1/2` for a sharp
/// tip): the time extrapolation of the trigger's step put the next step's first iterate
/// 35% too deep on R2's reference mesh, where the predictor then activated two nodes too
/// many and Newton released them one set check at a time (14 iterations against the
/// depth-controlled run's 6; docs/validation-load-control.md §12). The exponent comes from
/// the contact stiffness `s = dF/dU` of the trigger step's last bordered solve, `m = F /
/// (s h)` at its depth increment `h` (the power law's own slope), taken where it lies in
/// `[1/4, 1]`; then `h(F) = h (F / F_1)^m`.
pub(crate) fn touchdown_factor(state: &State, force: f64) -> Option<f64> {
    let last = &state.past[0];
    if !(last.load && last.dt > 0.0 && state.stiffness > 0.0 && state.force > 0.0) {
        return None;
    }
    // the last step started from zero force
    let start = state.force - last.rate * last.dt;
    if start.abs() > 1e-6 * state.force || !(last.depth > 0.0) {
        return None;
    }
    let m = state.force / (state.stiffness * last.depth);
    let ratio = force / state.force;
    if !((0.25..=1.0).contains(&m) && ratio > 1.0 + 1e-6) {
        return None;
    }
    Some(ratio.powf(m) - 1.0)
}

/// [`restart_factor`] from the states before and after the last step, `(force N, depth
/// mm)`, to the force `force` (N): the new depth increment over the last one.
fn follow_force(before: (f64, f64), now: (f64, f64), force: f64) -> Option<f64> {
    let ((f0, h0), (f1, h1)) = (before, now);
    let (df_last, dh_last) = (f1 - f0, h1 - h0);
    let q = (force - f1) / df_last;
    // a hold (no force increment, as `newton.rs` counts it) keeps the time extrapolation
    let hold = (force - f1).abs() <= 1e-6 * force.abs();
    if hold || !(q.is_finite() && q > 0.0 && dh_last != 0.0) {
        return None;
    }
    if f0 > 0.0 && h0 > 0.0 {
        let m = (h1 / h0).ln() / (f1 / f0).ln();
        if (0.25..=1.0).contains(&m) {
            let h = h1 * (force / f1).powf(m);
            return Some((h - h1) / dh_last);
        }
    }
    Some(q)
}

/// The instrument's frame between the recorded depth and the punch (docs/theory.md
/// §13.6, §13.7): the recorded (machine) depth is `h + Cf F + vd (t - t0) + h0`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Frame {
    /// Frame compliance `Cf` (mm/N, >= 0).
    pub compliance: f64,
    /// Thermal drift rate `vd` (mm/s), from the schedule's first time `t0`.
    pub drift: f64,
    /// Depth offset `h0` (mm).
    pub offset: f64,
}

impl Frame {
    /// The prescribed punch-side depth `H(t) = h_meas(t) - vd (t - t0) - h0` (mm) of the
    /// machine depth `schedule` at time `t` (s).
    pub fn prescribed(&self, schedule: &Schedule, t: f64) -> f64 {
        schedule.depth_at(t) - self.drift * (t - schedule.t[0]) - self.offset
    }
}

/// The punch driven through the frame's spring by a schedule of machine depths
/// ([`Frame`]): each step solves `h + Cf F(h) = H(t1)` (bordered, `newton.rs`); with
/// `Cf = 0` the step prescribes `H(t1)` as [`DepthDrive`] does.
#[derive(Clone, Copy, Debug)]
pub(crate) struct CompliantDrive<'a> {
    pub schedule: &'a Schedule,
    pub frame: Frame,
}

impl Drive for CompliantDrive<'_> {
    fn step(&self, t1: f64, state: &State) -> (f64, Option<Load>) {
        let h = self.frame.prescribed(self.schedule, t1);
        let cf = self.frame.compliance;
        if cf == 0.0 {
            return (h, None);
        }
        let rate = if t1 > state.t {
            (h - self.frame.prescribed(self.schedule, state.t)) / (t1 - state.t)
        } else {
            0.0
        };
        // Newton starts where the spring keeps the last step's force
        let depth = h - cf * state.force;
        let spring = Spring {
            prescribed: h,
            stiffness: 1.0 / cf,
            rate,
        };
        (
            depth,
            Some(Load {
                force: state.force,
                spring: Some(spring),
                restart: None,
            }),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On `h = c F^m` (a sharp tip's `m = 1/2`, a sphere's `2/3`, a flat punch's 1) the
    /// restart lands on the power law's depth at the new force exactly, where the time
    /// extrapolation of a trigger at 40 N/s followed by 2 N/s in 9.2-times-longer steps
    /// would be about 18 increments deep.
    #[test]
    fn restart_follows_the_power_law_through_the_last_two_states() {
        for m in [0.5, 2.0 / 3.0, 1.0] {
            let h = |f: f64| 0.01 * f.powf(m);
            let (before, now) = ((2.0, h(2.0)), (4.0, h(4.0)));
            for force in [4.2, 5.04, 9.0, 3.9 + 1.0] {
                let q = follow_force(before, now, force).unwrap();
                let predicted = now.1 + q * (now.1 - before.1);
                assert!(
                    (predicted - h(force)).abs() <= 1e-13 * h(force),
                    "m {m}, F {force}: {predicted} vs {}",
                    h(force)
                );
            }
        }
    }

    /// After the step that loaded from zero force, the exponent read from the contact
    /// stiffness `s = dF/dh = F / (m h)` of `h = c F^m` puts the next depth on the power
    /// law exactly; a step that did not start from zero force, a hold and an exponent
    /// outside `[1/4, 1]` keep the time extrapolation.
    #[test]
    fn touchdown_restart_reads_the_exponent_from_the_contact_stiffness() {
        let state = |m: f64, f0: f64| {
            let h = move |f: f64| 0.01 * f.powf(m);
            let (f1, dt) = (4.0, 0.05);
            let mut s = State {
                t: 0.05,
                f_scale: 0.0,
                u: Vec::new(),
                sigma: Vec::new(),
                internal: Default::default(),
                f_int: Vec::new(),
                set: crate::constraint::ContactSet {
                    active: Vec::new(),
                    slip: Vec::new(),
                },
                past: std::array::from_fn(|_| crate::newton::Increment {
                    du: Vec::new(),
                    dt: 0.0,
                    rate: 0.0,
                    depth: 0.0,
                    load: false,
                }),
                order: 1,
                depth: h(f1),
                force: f1,
                stiffness: f1 / (m * h(f1)),
                xi: Vec::new(),
            };
            s.past[0].dt = dt;
            s.past[0].rate = (f1 - f0) / dt;
            s.past[0].depth = h(f1) - h(f0.max(0.0));
            s.past[0].load = true;
            (s, h)
        };
        for m in [0.5, 2.0 / 3.0, 1.0] {
            let (s, h) = state(m, 0.0);
            for force in [5.0, 8.0, 12.5] {
                let q = touchdown_factor(&s, force).unwrap();
                let predicted = s.depth + q * s.past[0].depth;
                assert!(
                    (predicted - h(force)).abs() <= 1e-13 * h(force),
                    "m {m}, F {force}: {predicted} vs {}",
                    h(force)
                );
            }
            // a hold, an unloading
            assert_eq!(touchdown_factor(&s, 4.0), None);
            assert_eq!(touchdown_factor(&s, 3.0), None);
            // the last step started from 2 N: not the trigger's
            let (s, _) = state(m, 2.0);
            assert_eq!(touchdown_factor(&s, 8.0), None);
        }
        // h ~ F^2: out of range
        let (s, _) = state(2.0, 0.0);
        assert_eq!(touchdown_factor(&s, 8.0), None);
    }

    /// Without two states in contact the depth follows the last step's depth per newton;
    /// an unloading after a loading (or a hold, no force increment) does not restart.
    #[test]
    fn restart_falls_back_to_the_force_ratio_and_skips_reversals() {
        // the last step loaded from zero force: dF / dF_last
        let q = follow_force((0.0, 0.001), (2.0, 0.003), 3.0).unwrap();
        assert!((q - 0.5).abs() < 1e-15, "{q}");
        // an exponent outside [1/4, 1] (h ~ F^2 here): the force ratio
        let q = follow_force((2.0, 0.04), (4.0, 0.16), 5.0).unwrap();
        assert!((q - 0.5).abs() < 1e-15, "{q}");
        // unloading after loading, a hold before, no depth increment
        assert_eq!(follow_force((2.0, 0.1), (4.0, 0.14), 3.0), None);
        assert_eq!(follow_force((4.0, 0.1), (4.0, 0.11), 5.0), None);
        assert_eq!(follow_force((2.0, 0.1), (4.0, 0.1), 5.0), None);
    }
}
