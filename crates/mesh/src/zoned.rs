//! Cylinder specimen with a uniform core under the punch and a geometrically graded far
//! field: the mesher of the automatic (instrument-scale) specimen.

use crate::cylinder::{positive_length, tensor_mesh};
use crate::{Mesh, MeshError};

/// A cylinder of radius `radius` and height `height` (mm), occupying `0 <= r <= radius`,
/// `-height <= z <= 0`, whose top-left square `0 <= r <= core`, `-core <= z <= 0` (the
/// contact zone) is cut into `core_elements x core_elements` equal squares of side
/// `h = core / core_elements`, and whose far field grows geometrically away from it.
///
/// Along r (and likewise along the depth), the element sizes beyond the core are
/// `h q^k`, `k = 1..n`, with `n` the fewest elements for which the ratio `q` stays at or
/// below `grading` and `sum_k h q^k = radius - core` holds exactly. The positions are
/// computed in units of `core` and multiplied by it, so meshers that differ only by a
/// length scale give meshes that differ by that factor to round-off.
///
/// Every element is a rectangle with midside nodes at mid-edge: the Jacobian is constant
/// and positive at every scale.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ZonedCylinderMesher {
    /// Radius (mm), > `core`.
    pub radius: f64,
    /// Height (mm), > `core`.
    pub height: f64,
    /// Side of the uniform core (mm), > 0.
    pub core: f64,
    /// Elements across the core along r and along z, in [1, 2000].
    pub core_elements: usize,
    /// Largest size ratio between neighbouring elements outside the core, in [1, 3].
    pub grading: f64,
}

/// Element boundaries `0 = x_0 < ... < x_n = length` in units of the core side: `n_core`
/// equal elements on `[0, 1]`, then `h q^k` (k = 1..m) up to `length` (> 1), `h = 1/n_core`,
/// `q <= q_max` fitted by bisection so that the last boundary is `length` exactly.
fn zoned_positions(length: f64, n_core: usize, q_max: f64) -> Vec<f64> {
    let h = 1.0 / n_core as f64;
    let mut x: Vec<f64> = (0..=n_core).map(|i| i as f64 * h).collect();
    x[n_core] = 1.0;
    let rest = length - 1.0;
    // sum_{k=1..m} q^k, increasing in q > 0
    let sum = |q: f64, m: usize| (1..=m).map(|k| q.powi(k as i32)).sum::<f64>();
    let mut m = 1;
    while h * sum(q_max, m) < rest {
        m += 1;
    }
    let (mut lo, mut hi) = (0.0, q_max);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if h * sum(mid, m) < rest {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let q = 0.5 * (lo + hi);
    let mut acc = 1.0;
    for k in 1..=m {
        acc += h * q.powi(k as i32);
        x.push(acc);
    }
    let n = x.len() - 1;
    x[n] = length;
    x
}

impl ZonedCylinderMesher {
    /// Validates the inputs.
    ///
    /// # Errors
    /// [`MeshError::Input`] naming the field (as `specimen.<field>`), value and range,
    /// including a mesh of more than 2000 elements along r or z.
    pub fn validate(&self) -> Result<(), MeshError> {
        positive_length("specimen.core", self.core)?;
        positive_length("specimen.radius", self.radius)?;
        positive_length("specimen.height", self.height)?;
        for (field, v) in [
            ("specimen.radius", self.radius),
            ("specimen.height", self.height),
        ] {
            if !(v > self.core * (1.0 + 1e-9)) {
                return Err(MeshError::Input {
                    field,
                    value: format!("{v} (core {})", self.core),
                    allowed: "a length larger than the core side",
                });
            }
        }
        if !(1..=2000).contains(&self.core_elements) {
            return Err(MeshError::Input {
                field: "specimen.core_elements",
                value: self.core_elements.to_string(),
                allowed: "an integer in [1, 2000]",
            });
        }
        if !(self.grading.is_finite() && (1.0..=3.0).contains(&self.grading)) {
            return Err(MeshError::Input {
                field: "specimen.grading",
                value: self.grading.to_string(),
                allowed: "a ratio in [1, 3]",
            });
        }
        // element counts: the bound m <= rest / h at q = 1
        for (field, v) in [
            ("specimen.radius", self.radius),
            ("specimen.height", self.height),
        ] {
            let n = self.count(v);
            if n > 2000 {
                return Err(MeshError::Input {
                    field,
                    value: format!("{v} ({n} elements with the core and grading given)"),
                    allowed: "at most 2000 elements along r and along z",
                });
            }
        }
        Ok(())
    }

    /// Number of elements along a side of `length` (mm), without building positions.
    fn count(&self, length: f64) -> usize {
        let (h, rest, q) = (
            1.0 / self.core_elements as f64,
            length / self.core - 1.0,
            self.grading,
        );
        let m = if q - 1.0 < 1e-12 {
            (rest / h).ceil()
        } else {
            // smallest m with h q (q^m - 1) / (q - 1) >= rest
            ((1.0 + rest * (q - 1.0) / (h * q)).ln() / q.ln()).ceil()
        };
        self.core_elements + m.max(1.0) as usize
    }

    /// Element boundaries along r (radii from the axis) and along z (depths from the top
    /// surface), in mm. Call after [`validate`](Self::validate).
    pub fn positions(&self) -> (Vec<f64>, Vec<f64>) {
        let scale = |v: Vec<f64>| v.into_iter().map(|x| x * self.core).collect::<Vec<_>>();
        let n = self.core_elements;
        let mut r = scale(zoned_positions(self.radius / self.core, n, self.grading));
        let mut d = scale(zoned_positions(self.height / self.core, n, self.grading));
        let (nr, nd) = (r.len() - 1, d.len() - 1);
        r[nr] = self.radius;
        d[nd] = self.height;
        (r, d)
    }

    /// Numbers of elements `(nr, nz)` along r and z.
    ///
    /// # Errors
    /// [`MeshError::Input`] for invalid inputs.
    pub fn counts(&self) -> Result<(usize, usize), MeshError> {
        self.validate()?;
        let (r, d) = self.positions();
        Ok((r.len() - 1, d.len() - 1))
    }

    /// Builds the mesh with node sets `axis`, `bottom`, `outer`, `top` (sorted by r, then
    /// z), as [`CylinderMesher::build`](crate::CylinderMesher::build).
    ///
    /// # Errors
    /// [`MeshError::Input`] for invalid inputs.
    pub fn build(&self) -> Result<Mesh, MeshError> {
        self.validate()?;
        let (r, d) = self.positions();
        tensor_mesh(&r, &d)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mesher() -> ZonedCylinderMesher {
        ZonedCylinderMesher {
            radius: 40.0,
            height: 40.0,
            core: 1.0,
            core_elements: 8,
            grading: 1.5,
        }
    }

    #[test]
    fn core_is_uniform_and_far_field_graded_within_the_ratio() {
        let m = mesher();
        let (r, d) = m.positions();
        assert_eq!(r, d);
        for i in 0..8 {
            assert!((r[i + 1] - r[i] - 0.125).abs() < 1e-15, "{r:?}");
        }
        assert_eq!(r[8], 1.0);
        assert_eq!(*r.last().unwrap(), 40.0);
        for w in r.windows(3) {
            let ratio = (w[2] - w[1]) / (w[1] - w[0]);
            assert!((1.0 - 1e-12..=1.5 + 1e-12).contains(&ratio), "{ratio}");
        }
        let (nr, nz) = m.counts().unwrap();
        assert_eq!((nr, nz), (r.len() - 1, d.len() - 1));
        assert_eq!(m.count(40.0), nr);
        let mesh = m.build().unwrap();
        assert_eq!(mesh.elements.len(), nr * nz);
        assert_eq!(mesh.node_set("top").len(), 2 * nr + 1);
    }

    #[test]
    fn scaled_meshers_give_scaled_meshes() {
        let a = mesher().build().unwrap();
        for s in [1e-4, 3.7e-3, 25.0] {
            let b = ZonedCylinderMesher {
                radius: 40.0 * s,
                height: 40.0 * s,
                core: s,
                ..mesher()
            }
            .build()
            .unwrap();
            assert_eq!(a.elements, b.elements);
            for (p, q) in a.nodes.iter().zip(&b.nodes) {
                for k in 0..2 {
                    assert!((q[k] - s * p[k]).abs() <= 1e-14 * 40.0 * s, "{p:?} {q:?}");
                }
            }
        }
    }

    #[test]
    fn total_area_is_the_rectangle() {
        let m = ZonedCylinderMesher {
            height: 13.0,
            ..mesher()
        }
        .build()
        .unwrap();
        let area: f64 = (0..m.elements.len())
            .map(|e| {
                let x = m.element_coords(e);
                crate::q8::gauss3x3()
                    .iter()
                    .map(|([a, b], w)| w * crate::q8::jacobian(&x, *a, *b).1)
                    .sum::<f64>()
            })
            .sum();
        assert!((area - 40.0 * 13.0).abs() < 1e-9, "{area}");
    }

    #[test]
    fn invalid_inputs_name_the_field() {
        let err = |m: ZonedCylinderMesher| m.build().unwrap_err().to_string();
        let e = err(ZonedCylinderMesher {
            radius: 0.5,
            ..mesher()
        });
        assert!(e.contains("specimen.radius") && e.contains("core"), "{e}");
        let e = err(ZonedCylinderMesher {
            core_elements: 0,
            ..mesher()
        });
        assert!(e.contains("specimen.core_elements"), "{e}");
        let e = err(ZonedCylinderMesher {
            grading: 0.9,
            ..mesher()
        });
        assert!(e.contains("specimen.grading"), "{e}");
        let e = err(ZonedCylinderMesher {
            grading: 1.0,
            radius: 1e4,
            ..mesher()
        });
        assert!(e.contains("2000 elements"), "{e}");
        let e = err(ZonedCylinderMesher {
            core: f64::NAN,
            ..mesher()
        });
        assert!(e.contains("specimen.core"), "{e}");
    }
}
