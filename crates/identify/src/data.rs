//! The experimental force record `(t_j, F_j)` and its linear interpolation onto the
//! simulation's schedule times (docs/theory.md §6: the cost lives on the simulation times).

use crate::IdentifyError;

/// A measured (or synthetic) force history: times (s, strictly increasing) and punch
/// forces (N, full circle).
#[derive(Clone, Debug, PartialEq)]
pub struct ForceRecord {
    /// Times (s), strictly increasing.
    pub t: Vec<f64>,
    /// Forces (N).
    pub force: Vec<f64>,
}

impl ForceRecord {
    /// Validates and builds a record.
    ///
    /// # Errors
    /// [`IdentifyError::TooFewPoints`] below 2 points or when the lengths differ
    /// ([`IdentifyError::InvalidRecord`]); [`IdentifyError::InvalidRecord`] for a
    /// non-finite value or times that do not strictly increase, naming the point.
    pub fn new(t: Vec<f64>, force: Vec<f64>) -> Result<ForceRecord, IdentifyError> {
        if t.len() != force.len() {
            return Err(IdentifyError::InvalidRecord {
                index: t.len().min(force.len()),
                why: format!("{} times but {} forces", t.len(), force.len()),
            });
        }
        if t.len() < 2 {
            return Err(IdentifyError::TooFewPoints {
                got: t.len(),
                needed: 2,
                why: "a record is interpolated between points".into(),
            });
        }
        for i in 0..t.len() {
            if !t[i].is_finite() || !force[i].is_finite() {
                return Err(IdentifyError::InvalidRecord {
                    index: i,
                    why: format!("t = {}, F = {} is not finite", t[i], force[i]),
                });
            }
            if i > 0 && !(t[i] > t[i - 1]) {
                return Err(IdentifyError::InvalidRecord {
                    index: i,
                    why: format!(
                        "t = {} does not follow t = {} (times must strictly increase)",
                        t[i],
                        t[i - 1]
                    ),
                });
            }
        }
        Ok(ForceRecord { t, force })
    }

    /// The record's forces at `times`, linearly interpolated; a time within
    /// `1e-9 * span` of an end is taken at that end (round-off of a CSV).
    ///
    /// # Errors
    /// [`IdentifyError::RecordDoesNotCover`] when a time lies outside the record.
    pub fn at_times(&self, times: &[f64]) -> Result<Vec<f64>, IdentifyError> {
        let (t0, t1) = (self.t[0], self.t[self.t.len() - 1]);
        let tol = 1e-9 * (t1 - t0).abs().max(1e-300);
        if let (Some(&s0), Some(&s1)) = (times.first(), times.last()) {
            let lo = times.iter().cloned().fold(s0, f64::min);
            let hi = times.iter().cloned().fold(s1, f64::max);
            if lo < t0 - tol || hi > t1 + tol {
                return Err(IdentifyError::RecordDoesNotCover {
                    record_start: t0,
                    record_end: t1,
                    sim_start: lo,
                    sim_end: hi,
                });
            }
        }
        Ok(times.iter().map(|&s| self.interpolate(s)).collect())
    }

    /// Linear interpolation at `s`, clamped to the end values outside the record.
    pub fn interpolate(&self, s: f64) -> f64 {
        let n = self.t.len();
        if s <= self.t[0] {
            return self.force[0];
        }
        if s >= self.t[n - 1] {
            return self.force[n - 1];
        }
        // first index with t > s
        let j = self.t.partition_point(|&x| x <= s);
        let (ta, tb) = (self.t[j - 1], self.t[j]);
        let (fa, fb) = (self.force[j - 1], self.force[j]);
        if s == ta {
            return fa;
        }
        fa + (fb - fa) * (s - ta) / (tb - ta)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolation_is_exact_on_nodes_and_linear_between() {
        let r = ForceRecord::new(vec![0.0, 1.0, 3.0], vec![0.0, 10.0, 30.0]).unwrap();
        let f = r.at_times(&[0.0, 0.5, 1.0, 2.0, 3.0]).unwrap();
        assert_eq!(f, vec![0.0, 5.0, 10.0, 20.0, 30.0]);
    }

    #[test]
    fn a_record_that_ends_early_is_rejected() {
        let r = ForceRecord::new(vec![0.0, 1.0], vec![0.0, 1.0]).unwrap();
        let e = r.at_times(&[0.0, 2.0]).unwrap_err();
        assert!(matches!(e, IdentifyError::RecordDoesNotCover { .. }), "{e}");
        assert!(e.to_string().contains("[0, 2] s"), "{e}");
    }

    #[test]
    fn bad_records_are_rejected_with_the_point() {
        let e = ForceRecord::new(vec![0.0], vec![0.0]).unwrap_err();
        assert!(
            matches!(e, IdentifyError::TooFewPoints { got: 1, .. }),
            "{e}"
        );
        let e = ForceRecord::new(vec![0.0, 1.0, 1.0], vec![0.0; 3]).unwrap_err();
        assert!(
            matches!(e, IdentifyError::InvalidRecord { index: 2, .. }),
            "{e}"
        );
        let e = ForceRecord::new(vec![0.0, 1.0], vec![0.0, f64::NAN]).unwrap_err();
        assert!(
            matches!(e, IdentifyError::InvalidRecord { index: 1, .. }),
            "{e}"
        );
    }
}
