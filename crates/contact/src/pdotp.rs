//! Loading at a constant `Pdot/P` (the KLA/Agilent "constant strain rate" protocol): a
//! load-controlled segment whose force grows exponentially, `P(t) = P_s exp(r (t - t_s))`,
//! from the force `P_s` the previous load-controlled segment prescribed to a target force,
//! so that the loading strain rate `hdot/h = r/2` is constant wherever `h ~ sqrt(P)`
//! (a self-similar indentation; docs/theory.md §13, "Loading at constant Pdot/P").
//!
//! The segment is written with the instrument's own parameters, the target force and the
//! rate `r` (1/s): `(force: 100.0, pdot_over_p: 0.05, steps: 40)`; its duration follows,
//! `T = ln(P_end / P_s) / r`. The start force is the previous segment's prescribed force,
//! known before the run, so the time grid is fixed before any solve (a fit compares the
//! model with data at fixed times). A segment that would start at `P = 0` (the first
//! segment, or one after a depth-controlled segment, whose force is computed) is refused
//! naming the field: approach in depth control and then prescribe a trigger force with a
//! linear force segment, `(duration: 0.1, force: 1.0, steps: 2)`.
//!
//! Its steps are uniform in `ln P` (each loads the same fraction `(P_end / P_s)^(1/n)`),
//! which at a constant `r` is uniform in time. The segment becomes one linear force segment
//! per step ([`LoadHistory::from_specs`]), each ending exactly on the exponential: the
//! drive, the bordered Newton step, the adjoint and the forward sensitivities see plain
//! load-controlled steps whose start force is the previous step's prescribed one (no
//! parameter dependence), and only a cut step or a sub-step interpolates the force
//! linearly in time between two points of the exponential.

use serde::{Deserialize, Serialize};

use crate::ContactError;
use crate::history::{HistorySegment, LoadHistory, Segment};

/// A load-controlled segment at constant `Pdot/P`: from the force the previous segment
/// prescribed (`P_s > 0`) to `force` (N, `> P_s`) at the rate `pdot_over_p` (1/s), in
/// `steps` steps uniform in `ln P`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PdotP {
    /// The force at the segment's end (N).
    pub force: f64,
    /// `r = Pdot/P` (1/s), > 0.
    pub pdot_over_p: f64,
    /// Number of time steps, >= 1.
    pub steps: usize,
}

impl PdotP {
    /// The segment's duration (s) from the start force `start` (N):
    /// `ln(force / start) / pdot_over_p`.
    pub fn duration(&self, start: f64) -> f64 {
        (self.force / start).ln() / self.pdot_over_p
    }

    /// The prescribed force at the end of step `k` (1 to `steps`) from `start` (N):
    /// `start (force / start)^(k / steps)`, the target itself at `k = steps`.
    pub fn force_at_step(&self, start: f64, k: usize) -> f64 {
        if k >= self.steps {
            self.force
        } else {
            start * (self.force / start).powf(k as f64 / self.steps as f64)
        }
    }

    /// Checks segment `i` starting from the prescribed force `start` (`None`: no force
    /// prescribed before it) and returns its duration (s).
    ///
    /// # Errors
    /// [`ContactError::Input`] naming `history.segments[].pdot_over_p` for a rate that is
    /// not finite and > 0, a segment without a start force, or a duration that is not
    /// finite; `.force` for a target that is not finite or not above the start force;
    /// `.steps` for a count outside `[1, 1000000]`.
    pub fn check(&self, i: usize, start: Option<f64>) -> Result<f64, ContactError> {
        let r = self.pdot_over_p;
        if !(r.is_finite() && r > 0.0) {
            return Err(ContactError::Input {
                field: "history.segments[].pdot_over_p",
                value: format!("{r} (segment {i})"),
                allowed: "a finite rate Pdot/P > 0 (1/s; e.g. 0.05: the loading strain rate \
                          hdot/h = 0.025/s)"
                    .into(),
            });
        }
        if !(self.force.is_finite() && self.force > 0.0) {
            return Err(ContactError::Input {
                field: "history.segments[].force",
                value: format!("{} (segment {i}, at constant pdot_over_p)", self.force),
                allowed: "a finite target force > 0 N".into(),
            });
        }
        if !(1..=1_000_000).contains(&self.steps) {
            return Err(ContactError::Input {
                field: "history.segments[].steps",
                value: format!("{} (segment {i})", self.steps),
                allowed: "an integer in [1, 1000000]".into(),
            });
        }
        let Some(start) = start.filter(|&p| p > 0.0) else {
            return Err(ContactError::Input {
                field: "history.segments[].pdot_over_p",
                value: format!(
                    "{r} (segment {i}) starting at P = 0 ({})",
                    if i == 0 {
                        "the first segment"
                    } else {
                        "after a depth-controlled segment, whose force the run computes"
                    }
                ),
                allowed: "a constant-Pdot/P segment after a load-controlled segment, whose \
                          prescribed force (> 0 N) it starts from: approach in depth control, \
                          then a force segment to the trigger force, e.g. `(duration: 0.1, \
                          force: 1.0, steps: 2)`"
                    .into(),
            });
        };
        if !(self.force > start) {
            return Err(ContactError::Input {
                field: "history.segments[].force",
                value: format!(
                    "{} N (segment {i}, at constant pdot_over_p) from the start force {start} N",
                    self.force
                ),
                allowed: format!(
                    "a target force > the start force {start} N (a constant-Pdot/P segment \
                     loads; hold or unload with a `duration` segment)"
                ),
            });
        }
        let duration = self.duration(start);
        if !(duration.is_finite() && duration > 0.0) {
            return Err(ContactError::Input {
                field: "history.segments[].pdot_over_p",
                value: format!("{r} (segment {i}): a duration of {duration} s"),
                allowed: "a rate that loads from the start force to the target in a finite \
                          time, ln(force / start) / pdot_over_p"
                    .into(),
            });
        }
        Ok(duration)
    }

    /// The segment as one linear load-controlled segment per step from `start` (N) with
    /// duration `duration` (s, from [`PdotP::check`]): equal times, forces on the
    /// exponential.
    pub fn linear_steps(&self, start: f64, duration: f64) -> Vec<HistorySegment> {
        let dt = duration / self.steps as f64;
        (1..=self.steps)
            .map(|k| HistorySegment {
                duration: dt,
                depth: None,
                force: Some(self.force_at_step(start, k)),
                steps: 1,
            })
            .collect()
    }
}

/// A segment of a configured history: depth control `(duration, depth, steps)`, linear
/// load control `(duration, force, steps)`, or load control at constant `Pdot/P`
/// `(force, pdot_over_p, steps)` (no `duration`: it follows from the rate).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SegmentSpec {
    /// Duration (s, > 0) of a linear segment; left out at constant `Pdot/P`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub duration: Option<f64>,
    /// Punch depth at the segment's end (mm): depth control.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub depth: Option<f64>,
    /// Punch force at the segment's end (N, > 0): load control.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub force: Option<f64>,
    /// `Pdot/P` (1/s, > 0): the force grows exponentially to `force`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pdot_over_p: Option<f64>,
    /// Number of time steps, >= 1.
    pub steps: usize,
}

impl From<HistorySegment> for SegmentSpec {
    fn from(s: HistorySegment) -> SegmentSpec {
        SegmentSpec {
            duration: Some(s.duration),
            depth: s.depth,
            force: s.force,
            pdot_over_p: None,
            steps: s.steps,
        }
    }
}

impl From<Segment> for SegmentSpec {
    fn from(s: Segment) -> SegmentSpec {
        HistorySegment::from(s).into()
    }
}

/// What a [`SegmentSpec`] is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Leg {
    /// A linear segment (depth or force).
    Linear(HistorySegment),
    /// A constant-`Pdot/P` segment.
    PdotP(PdotP),
}

impl SegmentSpec {
    /// Whether the segment prescribes the force (linear or at constant `Pdot/P`).
    pub fn is_load_controlled(&self) -> bool {
        self.force.is_some()
    }

    /// The segment's kind (segment `i` of the history, for the errors).
    ///
    /// # Errors
    /// [`ContactError::Input`] naming `history.segments[].duration` for a linear segment
    /// without one, or a constant-`Pdot/P` segment with one; `.pdot_over_p` for a rate
    /// beside a `depth` or without a `force`.
    pub fn leg(&self, i: usize) -> Result<Leg, ContactError> {
        match (self.pdot_over_p, self.duration) {
            (None, Some(duration)) => Ok(Leg::Linear(HistorySegment {
                duration,
                depth: self.depth,
                force: self.force,
                steps: self.steps,
            })),
            (None, None) => Err(ContactError::Input {
                field: "history.segments[].duration",
                value: format!("missing (segment {i})"),
                allowed: "a duration > 0 s for a depth or force segment, or `pdot_over_p` \
                          (1/s) for a force segment at constant Pdot/P"
                    .into(),
            }),
            (Some(r), Some(d)) => Err(ContactError::Input {
                field: "history.segments[].duration",
                value: format!("{d} (segment {i}, with pdot_over_p: {r})"),
                allowed: "no `duration` at constant Pdot/P: it follows from the rate, \
                          ln(force / start force) / pdot_over_p"
                    .into(),
            }),
            (Some(r), None) => match (self.force, self.depth) {
                (Some(force), None) => Ok(Leg::PdotP(PdotP {
                    force,
                    pdot_over_p: r,
                    steps: self.steps,
                })),
                _ => Err(ContactError::Input {
                    field: "history.segments[].pdot_over_p",
                    value: format!("{r} (segment {i}) with a `depth` or without a `force`"),
                    allowed: "a target `force` (N) and no `depth`: constant Pdot/P is a \
                              load-controlled segment, (force: 100.0, pdot_over_p: 0.05, \
                              steps: 40)"
                        .into(),
                }),
            },
        }
    }
}

impl LoadHistory {
    /// The history of configured segments from `t = 0`, depth 0, force 0: a
    /// constant-`Pdot/P` segment becomes one linear force segment per step (module
    /// docs); a history without one is [`LoadHistory::from_segments`] of its segments,
    /// bit for bit.
    ///
    /// # Errors
    /// [`ContactError::Input`] naming the field: those of [`SegmentSpec::leg`],
    /// [`PdotP::check`] and [`LoadHistory::from_segments`] (with the configured
    /// segment's index).
    pub fn from_specs(specs: &[SegmentSpec]) -> Result<LoadHistory, ContactError> {
        let legs = specs
            .iter()
            .enumerate()
            .map(|(i, s)| s.leg(i))
            .collect::<Result<Vec<Leg>, _>>()?;
        let mut plain = Vec::with_capacity(specs.len());
        // the configured segment of every plain one
        let mut configured = Vec::with_capacity(specs.len());
        // the force the last segment prescribed (`None` after depth control)
        let mut prescribed: Option<f64> = None;
        for (i, leg) in legs.iter().enumerate() {
            match leg {
                Leg::Linear(s) => {
                    // its own checks, with the configured index
                    s.target(i)?;
                    s.check_plain(i)?;
                    prescribed = s.force;
                    plain.push(*s);
                }
                Leg::PdotP(p) => {
                    let duration = p.check(i, prescribed)?;
                    let start = prescribed.unwrap_or(p.force);
                    plain.extend(p.linear_steps(start, duration));
                    prescribed = Some(p.force);
                }
            }
            configured.resize(plain.len(), i);
        }
        let mut history = LoadHistory::from_segments(&plain)?;
        history.configured = configured;
        Ok(history)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::history::Target;

    fn spec(duration: Option<f64>, force: Option<f64>, r: Option<f64>) -> SegmentSpec {
        SegmentSpec {
            duration,
            depth: None,
            force,
            pdot_over_p: r,
            steps: 8,
        }
    }

    /// A ramp to 2 N, then constant Pdot/P = 0.5/s to 32 N in 8 steps: the duration is
    /// ln(16) / 0.5, the steps equal in time, each force 2^(1/2) times the last, so
    /// `ln P` is linear in time with slope r.
    #[test]
    fn steps_are_uniform_in_ln_p_at_the_rate() {
        let h = LoadHistory::from_specs(&[
            spec(Some(0.2), Some(2.0), None),
            spec(None, Some(32.0), Some(0.5)),
        ])
        .unwrap();
        let n = h.schedule.n_steps();
        assert_eq!(n, 16);
        let t_end = 0.2 + 16f64.ln() / 0.5;
        assert!((h.schedule.t[n] - t_end).abs() < 1e-13 * t_end);
        let forces: Vec<f64> = h
            .ends
            .iter()
            .map(|e| match e.1 {
                Target::Force(p) => p,
                Target::Depth(_) => panic!("depth"),
            })
            .collect();
        assert_eq!(forces.len(), 9);
        assert_eq!(*forces.last().unwrap(), 32.0);
        for k in 1..=8 {
            let (t, p) = (h.ends[k].0, forces[k]);
            // ln P - ln 2 = r (t - 0.2)
            assert!(
                ((p / 2.0).ln() - 0.5 * (t - 0.2)).abs() < 1e-12,
                "{k}: {t} {p}"
            );
            assert!((p / forces[k - 1] - 2f64.sqrt()).abs() < 1e-12);
            let dt = h.schedule.t[8 + k] - h.schedule.t[8 + k - 1];
            assert!((dt - t_end.mul_add(1.0, -0.2) / 8.0).abs() < 1e-12);
        }
        // a history without the new kind is from_segments' bit for bit
        let linear = [
            spec(Some(0.2), Some(2.0), None),
            spec(Some(1.0), Some(3.0), None),
        ];
        let plain: Vec<HistorySegment> = linear
            .iter()
            .map(|s| match s.leg(0).unwrap() {
                Leg::Linear(l) => l,
                Leg::PdotP(_) => panic!(),
            })
            .collect();
        assert_eq!(
            LoadHistory::from_specs(&linear).unwrap(),
            LoadHistory::from_segments(&plain).unwrap()
        );
    }

    #[test]
    fn bad_segments_are_refused_naming_the_field() {
        let msg = |s: &[SegmentSpec]| LoadHistory::from_specs(s).unwrap_err().to_string();
        let ramp = spec(Some(0.2), Some(2.0), None);
        let depth = SegmentSpec {
            depth: Some(0.01),
            force: None,
            ..ramp
        };
        for (specs, field, words) in [
            (
                vec![spec(None, Some(10.0), Some(0.1))],
                ".pdot_over_p",
                "P = 0",
            ),
            (
                vec![depth, spec(None, Some(10.0), Some(0.1))],
                ".pdot_over_p",
                "depth-controlled",
            ),
            (
                vec![ramp, spec(None, Some(10.0), Some(0.0))],
                ".pdot_over_p",
                "> 0",
            ),
            (
                vec![ramp, spec(None, Some(10.0), Some(-1.0))],
                ".pdot_over_p",
                "-1",
            ),
            (
                vec![ramp, spec(None, Some(10.0), Some(f64::NAN))],
                ".pdot_over_p",
                "NaN",
            ),
            (
                vec![ramp, spec(None, Some(10.0), Some(1e-320))],
                ".pdot_over_p",
                "inf",
            ),
            (
                vec![ramp, spec(None, Some(1.0), Some(0.1))],
                ".force",
                "start force 2",
            ),
            (
                vec![ramp, spec(None, Some(2.0), Some(0.1))],
                ".force",
                "start force 2",
            ),
            (
                vec![ramp, spec(None, Some(f64::INFINITY), Some(0.1))],
                ".force",
                "inf",
            ),
            (
                vec![ramp, spec(None, None, Some(0.1))],
                ".pdot_over_p",
                "force",
            ),
            (
                vec![ramp, spec(Some(1.0), Some(5.0), Some(0.1))],
                ".duration",
                "follows",
            ),
            (vec![spec(None, Some(2.0), None)], ".duration", "missing"),
        ] {
            let e = msg(&specs);
            assert!(
                e.contains(&format!("history.segments[]{field}")) && e.contains(words),
                "{e}"
            );
            let i = specs.len() - 1;
            assert!(e.contains(&format!("segment {i}")), "{e}");
        }
        let mut zero = spec(None, Some(10.0), Some(0.1));
        zero.steps = 0;
        let e = msg(&[ramp, zero]);
        assert!(
            e.contains("history.segments[].steps") && e.contains("segment 1"),
            "{e}"
        );
        // a linear segment's own error names its configured index, not the expanded one
        let e = msg(&[
            ramp,
            spec(None, Some(10.0), Some(0.1)),
            spec(Some(-1.0), Some(5.0), None),
        ]);
        assert!(e.contains("duration") && e.contains("segment 2"), "{e}");
    }
}
