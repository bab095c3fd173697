//! Depth-driven loading histories: piecewise-linear segments (load / hold / unload and
//! any sequence), or a measured depth record, turned into the time grid of the driver.

use serde::{Deserialize, Serialize};

use crate::ContactError;

/// One piecewise-linear segment: move linearly to `depth` (mm) over `duration` (s) in
/// `steps` equal time steps.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Segment {
    /// Duration (s), > 0.
    pub duration: f64,
    /// Punch depth at the end of the segment (mm, positive into the body).
    pub depth: f64,
    /// Number of time steps, >= 1.
    pub steps: usize,
}

impl Segment {
    /// Checks segment `i` of a history (the errors name `history.segments[]` and `i`).
    ///
    /// # Errors
    /// As [`Schedule::from_segments`].
    pub(crate) fn check(&self, i: usize) -> Result<(), ContactError> {
        let s = self;
        if !(s.duration.is_finite() && s.duration > 0.0) {
            return Err(ContactError::Input {
                field: "history.segments[].duration",
                value: format!("{} (segment {i})", s.duration),
                allowed: "a duration > 0 s (time must increase)".into(),
            });
        }
        if !s.depth.is_finite() {
            return Err(ContactError::Input {
                field: "history.segments[].depth",
                value: format!("{} (segment {i})", s.depth),
                allowed: "a finite depth (mm)".into(),
            });
        }
        if !(1..=1_000_000).contains(&s.steps) {
            return Err(ContactError::Input {
                field: "history.segments[].steps",
                value: format!("{} (segment {i})", s.steps),
                allowed: "an integer in [1, 1000000]".into(),
            });
        }
        Ok(())
    }
}

/// The largest number of sub-steps of one schedule step ([`Schedule::with_substeps`]).
pub const MAX_SUBSTEPS: usize = 1000;

/// The discrete schedule: times `t[0] < t[1] < ...` (s) and punch depths `depth[i]` (mm).
/// Index 0 is the initial, stress-free state; steps are `1..len`.
///
/// Each step may be solved in several equal sub-steps ([`Schedule::with_substeps`]; the
/// depth linearly interpolated between its ends): the solver's steps are then finer than
/// the schedule, whose times stay the only ones where the force is reported and compared
/// with data (the sub-steps are recorded as the sub-steps of a cut step are, with
/// `on_schedule = false`, and the adjoint transposes them).
#[derive(Clone, Debug, PartialEq)]
pub struct Schedule {
    /// Times (s), strictly increasing.
    pub t: Vec<f64>,
    /// Depth of the punch tip below the undeformed surface (mm).
    pub depth: Vec<f64>,
    /// Sub-steps of each step: step `j` (from 1) is solved in `substeps[j - 1]` equal
    /// sub-steps. Empty: one each (the schedule's steps are the solver's).
    pub substeps: Vec<usize>,
}

impl Schedule {
    /// Builds the schedule of consecutive segments starting at `t = 0`, depth 0.
    ///
    /// # Errors
    /// [`ContactError::Input`] for an empty list, a non-positive duration (which would make
    /// time non-monotonic), zero steps or a non-finite depth, naming `history.segments[i]`.
    pub fn from_segments(segments: &[Segment]) -> Result<Schedule, ContactError> {
        if segments.is_empty() {
            return Err(ContactError::Input {
                field: "history.segments",
                value: "[]".into(),
                allowed: "at least one segment (duration, depth, steps)".into(),
            });
        }
        let mut t = vec![0.0];
        let mut depth = vec![0.0];
        for (i, s) in segments.iter().enumerate() {
            s.check(i)?;
            let (t0, d0) = (*t.last().unwrap_or(&0.0), *depth.last().unwrap_or(&0.0));
            for k in 1..=s.steps {
                let f = k as f64 / s.steps as f64;
                t.push(t0 + f * s.duration);
                depth.push(d0 + f * (s.depth - d0));
            }
        }
        Ok(Schedule {
            t,
            depth,
            substeps: Vec::new(),
        })
    }

    /// A schedule from a measured record `(t_i, h_i)`; the first point is the initial state.
    ///
    /// # Errors
    /// [`ContactError::Input`] if fewer than 2 points, lengths differ, a value is not finite,
    /// or time does not strictly increase (naming the index).
    pub fn from_record(t: &[f64], depth: &[f64]) -> Result<Schedule, ContactError> {
        if t.len() != depth.len() || t.len() < 2 {
            return Err(ContactError::Input {
                field: "history.record",
                value: format!("{} times and {} depths", t.len(), depth.len()),
                allowed: "at least 2 points with as many times as depths".into(),
            });
        }
        for i in 0..t.len() {
            if !t[i].is_finite() || !depth[i].is_finite() {
                return Err(ContactError::Input {
                    field: "history.record",
                    value: format!("point {i}: t = {}, h = {}", t[i], depth[i]),
                    allowed: "finite values".into(),
                });
            }
            if i > 0 && !(t[i] > t[i - 1]) {
                return Err(ContactError::Input {
                    field: "history.record.t",
                    value: format!("t[{i}] = {} after t[{}] = {}", t[i], i - 1, t[i - 1]),
                    allowed: "strictly increasing times".into(),
                });
            }
        }
        Ok(Schedule {
            t: t.to_vec(),
            depth: depth.to_vec(),
            substeps: Vec::new(),
        })
    }

    /// The schedule with step `j` (from 1) solved in `counts[j - 1]` equal sub-steps
    /// (an empty `counts`, or all ones, is the schedule as it is).
    ///
    /// # Errors
    /// [`ContactError::Input`] for a count outside `[1, MAX_SUBSTEPS]` or a length other
    /// than the number of steps.
    pub fn with_substeps(mut self, counts: Vec<usize>) -> Result<Schedule, ContactError> {
        if !counts.is_empty() && counts.len() != self.n_steps() {
            return Err(ContactError::Input {
                field: "schedule.substeps",
                value: format!("{} counts", counts.len()),
                allowed: format!("one count per step ({})", self.n_steps()),
            });
        }
        if let Some(j) = counts.iter().position(|k| !(1..=MAX_SUBSTEPS).contains(k)) {
            return Err(ContactError::Input {
                field: "schedule.substeps",
                value: format!("{} (step {})", counts[j], j + 1),
                allowed: format!("an integer in [1, {MAX_SUBSTEPS}]"),
            });
        }
        self.substeps = if counts.iter().all(|&k| k == 1) {
            Vec::new()
        } else {
            counts
        };
        Ok(self)
    }

    /// The schedule with every step solved in `k` equal sub-steps.
    ///
    /// # Errors
    /// As [`Schedule::with_substeps`].
    pub fn with_uniform_substeps(self, k: usize) -> Result<Schedule, ContactError> {
        let n = self.n_steps();
        self.with_substeps(vec![k; n])
    }

    /// The number of sub-steps of step `j` (from 1): 1 without sub-steps.
    pub fn substeps_of(&self, j: usize) -> usize {
        j.checked_sub(1)
            .and_then(|i| self.substeps.get(i))
            .copied()
            .unwrap_or(1)
    }

    /// The times the solver steps to in step `j` (from 1): its sub-steps' ends, `t[j]`
    /// last (only `t[j]` without sub-steps).
    pub fn step_targets(&self, j: usize) -> Vec<f64> {
        let k = self.substeps_of(j);
        let (ta, tb) = (self.t[j - 1], self.t[j]);
        (1..=k)
            .map(|i| {
                if i == k {
                    tb
                } else {
                    ta + (tb - ta) * i as f64 / k as f64
                }
            })
            .collect()
    }

    /// The number of solver steps without cuts: the sum of the sub-steps.
    pub fn n_solver_steps(&self) -> usize {
        (1..=self.n_steps()).map(|j| self.substeps_of(j)).sum()
    }

    /// The sub-steps in words, `None` without: `2 sub-steps per step` (all equal) or
    /// `1 to 3 sub-steps per step`.
    pub fn substeps_summary(&self) -> Option<String> {
        let lo = self.substeps.iter().copied().min()?;
        let hi = self.substeps.iter().copied().max()?;
        Some(if lo == hi {
            format!("{lo} sub-steps per step")
        } else {
            format!("{lo} to {hi} sub-steps per step")
        })
    }

    /// The first `j + 1` points (steps 1 to `j`) with their sub-steps.
    pub fn prefix(&self, j: usize) -> Schedule {
        Schedule {
            t: self.t[..=j].to_vec(),
            depth: self.depth[..=j].to_vec(),
            substeps: self.substeps.iter().take(j).copied().collect(),
        }
    }

    /// Number of time steps (`t.len() - 1`).
    pub fn n_steps(&self) -> usize {
        self.t.len() - 1
    }

    /// Depth at time `t`, linearly interpolated (clamped at the ends).
    pub fn depth_at(&self, t: f64) -> f64 {
        let n = self.t.len();
        if t <= self.t[0] {
            return self.depth[0];
        }
        if t >= self.t[n - 1] {
            return self.depth[n - 1];
        }
        let i = self.t.partition_point(|&x| x <= t) - 1;
        let f = (t - self.t[i]) / (self.t[i + 1] - self.t[i]);
        self.depth[i] + f * (self.depth[i + 1] - self.depth[i])
    }
}

/// One segment of a history that may prescribe the force instead of the depth: move
/// linearly over `duration` (s) in `steps` equal steps to the punch `depth` (mm) or to the
/// punch `force` (N), exactly one of the two. A depth-controlled segment after a
/// load-controlled one starts from the depth the load reached; a load-controlled segment
/// starts from the force the last step carried (docs/theory.md §13).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HistorySegment {
    /// Duration (s), > 0.
    pub duration: f64,
    /// Punch depth at the end of the segment (mm): a depth-controlled segment.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub depth: Option<f64>,
    /// Punch force at the end of the segment (N, > 0): a load-controlled segment.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub force: Option<f64>,
    /// Number of time steps, >= 1.
    pub steps: usize,
}

impl From<Segment> for HistorySegment {
    fn from(s: Segment) -> HistorySegment {
        HistorySegment {
            duration: s.duration,
            depth: Some(s.depth),
            force: None,
            steps: s.steps,
        }
    }
}

impl HistorySegment {
    /// What segment `i` prescribes at its end.
    ///
    /// # Errors
    /// [`ContactError::Input`] naming `history.segments[].depth` / `.force` for both or
    /// neither, or a force that is not finite and > 0.
    pub(crate) fn target(&self, i: usize) -> Result<Target, ContactError> {
        let s = self;
        match (s.depth, s.force) {
            (Some(d), None) => Ok(Target::Depth(d)),
            (None, Some(f)) => {
                if !(f.is_finite() && f > 0.0) {
                    return Err(ContactError::Input {
                        field: "history.segments[].force",
                        value: format!("{f} (segment {i})"),
                        allowed: "a finite force > 0 N (a force of 0 leaves the depth \
                                  undetermined: end an unloading in depth control, \
                                  `depth: 0.0`)"
                            .into(),
                    });
                }
                Ok(Target::Force(f))
            }
            (d, f) => Err(ContactError::Input {
                field: "history.segments[].depth",
                value: format!(
                    "{} (segment {i})",
                    if d.is_some() && f.is_some() {
                        "both depth and force"
                    } else {
                        "neither depth nor force"
                    }
                ),
                allowed: "exactly one of `depth` (mm, depth control) and `force` \
                              (N, load control) per segment"
                    .into(),
            }),
        }
    }

    /// The checks of [`Schedule::from_segments`] of segment `i` (duration, depth, steps).
    ///
    /// # Errors
    /// As [`Schedule::from_segments`].
    pub(crate) fn check_plain(&self, i: usize) -> Result<(), ContactError> {
        Segment {
            duration: self.duration,
            depth: self.depth.unwrap_or(0.0),
            steps: self.steps,
        }
        .check(i)
    }
}

/// What a segment of a [`LoadHistory`] prescribes at its end.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Target {
    /// The punch depth (mm).
    Depth(f64),
    /// The punch force (N, > 0).
    Force(f64),
}

/// A history whose segments prescribe the depth or the force: the schedule's times, and
/// the end time and target of every segment. `schedule.depth` holds the prescribed depths
/// of depth-controlled points and, at load-controlled points, the last prescribed depth
/// before them (a placeholder: the depth there is an unknown of the run, recorded in the
/// trajectory).
#[derive(Clone, Debug, PartialEq)]
pub struct LoadHistory {
    /// The time grid (and the depths where prescribed).
    pub schedule: Schedule,
    /// `(t_end, target)` of every segment, in time order.
    pub ends: Vec<(f64, Target)>,
    /// For every segment of `ends`, the index of the configured segment it comes from: a
    /// constant-`Pdot/P` segment's steps share one (`pdotp.rs`), and a force record is one
    /// configured segment. Where it changes the drive restarts Newton's first guess
    /// (`drive.rs`, [`LoadHistory::starts_configured_segment`]).
    pub configured: Vec<usize>,
}

impl LoadHistory {
    /// The history of consecutive segments from `t = 0`, depth 0, force 0.
    ///
    /// # Errors
    /// [`ContactError::Input`] naming `history.segments[].depth` / `.force` for a segment
    /// with both or neither, a negative, zero or non-finite force; and the errors of
    /// [`Schedule::from_segments`].
    pub fn from_segments(segments: &[HistorySegment]) -> Result<LoadHistory, ContactError> {
        let mut plain = Vec::with_capacity(segments.len());
        let mut ends = Vec::with_capacity(segments.len());
        let (mut t, mut last_depth) = (0.0, 0.0);
        for (i, s) in segments.iter().enumerate() {
            let target = s.target(i)?;
            if let Target::Depth(d) = target {
                last_depth = d;
            }
            plain.push(Segment {
                duration: s.duration,
                depth: last_depth,
                steps: s.steps,
            });
            t += s.duration;
            ends.push((t, target));
        }
        let schedule = Schedule::from_segments(&plain)?;
        // the segments' end times as the schedule accumulates them (bit for bit)
        let mut j = 0;
        for (end, s) in ends.iter_mut().zip(segments) {
            j += s.steps;
            end.0 = schedule.t[j];
        }
        let configured = (0..ends.len()).collect();
        Ok(LoadHistory {
            schedule,
            ends,
            configured,
        })
    }

    /// A history prescribing a measured force record `(t_i, F_i)` (s, N), one
    /// load-controlled segment per interval; the first point is the initial state (its
    /// force is not read: the run starts stress-free).
    ///
    /// # Errors
    /// [`ContactError::Input`] as [`Schedule::from_record`], and for a force that is not
    /// finite and > 0 after the first point (naming `data.force` and the index).
    pub fn from_force_record(t: &[f64], force: &[f64]) -> Result<LoadHistory, ContactError> {
        let zeros = vec![0.0; force.len()];
        let schedule = Schedule::from_record(t, &zeros)?;
        if t.len() != force.len() {
            return Err(ContactError::Input {
                field: "data.force",
                value: format!("{} times and {} forces", t.len(), force.len()),
                allowed: "as many forces as times".into(),
            });
        }
        let mut ends = Vec::with_capacity(t.len() - 1);
        for i in 1..t.len() {
            if !(force[i].is_finite() && force[i] > 0.0) {
                return Err(ContactError::Input {
                    field: "data.force",
                    value: format!("F[{i}] = {}", force[i]),
                    allowed: "a finite force > 0 N at every point after the first (load \
                              control cannot prescribe a zero force)"
                        .into(),
                });
            }
            ends.push((t[i], Target::Force(force[i])));
        }
        // one configured segment: a record's force rate jumps from sample to sample on a
        // coarse contact while its depth moves smoothly, so no sample restarts the guess
        let configured = vec![0; ends.len()];
        Ok(LoadHistory {
            schedule,
            ends,
            configured,
        })
    }

    /// Whether some segment prescribes the force.
    pub fn is_load_controlled(&self) -> bool {
        self.ends.iter().any(|e| matches!(e.1, Target::Force(_)))
    }

    /// The segment a step ending at time `t` (s) belongs to: its end time and target.
    pub fn segment_at(&self, t: f64) -> (f64, Target) {
        self.ends[self.index_at(t)]
    }

    /// The index in `ends` of the segment a step ending at time `t` (s) belongs to.
    fn index_at(&self, t: f64) -> usize {
        let i = self.ends.partition_point(|e| e.0 < t);
        i.min(self.ends.len() - 1)
    }

    /// Whether a step from the state at `t0` (s; the end of the last step) to `t1` (s)
    /// is the first of another configured segment than the last step's (`false` from the
    /// initial state, and for a history without [`LoadHistory::configured`] entries).
    pub fn starts_configured_segment(&self, t0: f64, t1: f64) -> bool {
        if t0 <= self.schedule.t[0] {
            return false;
        }
        let (a, b) = (self.index_at(t0), self.index_at(t1));
        match (self.configured.get(a), self.configured.get(b)) {
            (Some(x), Some(y)) => x != y,
            _ => false,
        }
    }
}

/// The trapezoid of docs/theory.md §11: ramp to `h_max` in `t_load`, hold `t_hold`, unload to 0
/// in `t_unload`, `steps` per segment.
pub fn trapezoid(
    h_max: f64,
    t_load: f64,
    t_hold: f64,
    t_unload: f64,
    steps: usize,
) -> Vec<Segment> {
    vec![
        Segment {
            duration: t_load,
            depth: h_max,
            steps,
        },
        Segment {
            duration: t_hold,
            depth: h_max,
            steps,
        },
        Segment {
            duration: t_unload,
            depth: 0.0,
            steps,
        },
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trapezoid_schedule() {
        let s = Schedule::from_segments(&trapezoid(0.1, 1.0, 1.0, 1.0, 30)).unwrap();
        assert_eq!(s.n_steps(), 90);
        assert!((s.t[30] - 1.0).abs() < 1e-15 && (s.depth[30] - 0.1).abs() < 1e-15);
        assert!((s.depth[60] - 0.1).abs() < 1e-15 && s.depth[90].abs() < 1e-15);
        assert!((s.depth_at(0.5) - 0.05).abs() < 1e-15);
    }

    #[test]
    fn bad_histories_are_rejected() {
        let e = Schedule::from_segments(&[Segment {
            duration: -1.0,
            depth: 0.1,
            steps: 3,
        }])
        .unwrap_err();
        assert!(e.to_string().contains("duration"), "{e}");
        let e = Schedule::from_record(&[0.0, 1.0, 0.5], &[0.0, 0.1, 0.2]).unwrap_err();
        assert!(e.to_string().contains("t[2] = 0.5"), "{e}");
    }

    #[test]
    fn substeps_split_steps_equally_and_are_checked() {
        let s = Schedule::from_record(&[0.0, 1.0, 4.0], &[0.0, 0.1, 0.2]).unwrap();
        assert_eq!(s.step_targets(2), vec![4.0]);
        let s3 = s.clone().with_substeps(vec![1, 3]).unwrap();
        assert_eq!(s3.step_targets(1), vec![1.0]);
        assert_eq!(s3.step_targets(2), vec![2.0, 3.0, 4.0]);
        assert_eq!((s3.n_steps(), s3.n_solver_steps()), (2, 4));
        assert_eq!(s3.prefix(1).substeps, vec![1]);
        assert_eq!(
            s3.substeps_summary().as_deref(),
            Some("1 to 3 sub-steps per step")
        );
        assert_eq!(s.substeps_summary(), None);
        // all ones is the schedule itself
        assert_eq!(s.clone().with_uniform_substeps(1).unwrap(), s);
        for bad in [vec![0, 1], vec![1, MAX_SUBSTEPS + 1], vec![2]] {
            let e = s.clone().with_substeps(bad).unwrap_err().to_string();
            assert!(e.contains("schedule.substeps"), "{e}");
        }
    }
}
