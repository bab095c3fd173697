//! Structured mesher for the cylindrical specimen, graded geometrically towards the axis
//! and the top surface.

use std::collections::BTreeMap;

use crate::{Mesh, MeshError};

/// A cylinder of radius `radius` and height `height` (mm), occupying
/// `0 <= r <= radius`, `-height <= z <= 0`, cut into `nr x nz` Q8 elements.
///
/// Element sizes grow geometrically by `grading_r` from the axis outwards and by
/// `grading_z` from the top surface downwards (1 = uniform): the first size is
/// `h0 = L (q - 1) / (q^n - 1)`. docs/theory.md §11's default (10 x 10 mm, 20 x 20, q = 1.3)
/// gives a smallest element of 0.016 mm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CylinderMesher {
    /// Radius (mm), > 0.
    pub radius: f64,
    /// Height (mm), > 0.
    pub height: f64,
    /// Elements along r, >= 1.
    pub nr: usize,
    /// Elements along z, >= 1.
    pub nz: usize,
    /// Size ratio between neighbouring elements along r (>= 1, growing away from the axis).
    pub grading_r: f64,
    /// Size ratio between neighbouring elements along z (>= 1, growing away from the top).
    pub grading_z: f64,
}

impl CylinderMesher {
    /// The mesh of the reference problems R0-R2: a 10 x 10 mm cylinder, 20 x 20
    /// elements graded 1.3 towards the axis and the top.
    pub const REFERENCE: CylinderMesher = CylinderMesher {
        radius: 10.0,
        height: 10.0,
        nr: 20,
        nz: 20,
        grading_r: 1.3,
        grading_z: 1.3,
    };
}

/// Largest ratio of the largest to the smallest element along r or z that
/// [`CylinderMesher::validate`] accepts.
pub const MAX_SIZE_SPREAD: f64 = 1e8;

/// Cumulative positions `0 = x_0 < ... < x_n = length` of a geometric grading with ratio `q`.
pub fn graded_positions(length: f64, n: usize, q: f64) -> Vec<f64> {
    let h0 = if (q - 1.0).abs() < 1e-12 {
        length / n as f64
    } else {
        length * (q - 1.0) / (q.powi(n as i32) - 1.0)
    };
    let mut x = Vec::with_capacity(n + 1);
    let mut acc = 0.0;
    x.push(0.0);
    for k in 0..n {
        acc += h0 * q.powi(k as i32);
        x.push(acc);
    }
    x[n] = length;
    x
}

/// `Ok` for a finite length > 0, else the input error naming `field`.
pub(crate) fn positive_length(field: &'static str, v: f64) -> Result<(), MeshError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(MeshError::Input {
            field,
            value: v.to_string(),
            allowed: "a finite value > 0 (mm)",
        })
    }
}

impl CylinderMesher {
    /// Validates the inputs.
    ///
    /// # Errors
    /// [`MeshError::Input`] naming the field (as `specimen.<field>`), value and range.
    pub fn validate(&self) -> Result<(), MeshError> {
        positive_length("specimen.radius", self.radius)?;
        positive_length("specimen.height", self.height)?;
        for (field, n) in [("specimen.nr", self.nr), ("specimen.nz", self.nz)] {
            if !(1..=2000).contains(&n) {
                return Err(MeshError::Input {
                    field,
                    value: n.to_string(),
                    allowed: "an integer in [1, 2000]",
                });
            }
        }
        for (field, q) in [
            ("specimen.grading_r", self.grading_r),
            ("specimen.grading_z", self.grading_z),
        ] {
            if !(q.is_finite() && (1.0..=3.0).contains(&q)) {
                return Err(MeshError::Input {
                    field,
                    value: q.to_string(),
                    allowed: "a ratio in [1, 3]",
                });
            }
        }
        for (field, q, n) in [
            ("specimen.grading_r", self.grading_r, self.nr),
            ("specimen.grading_z", self.grading_z, self.nz),
        ] {
            // The largest element is q^(n-1) times the smallest: past about 1e16 the
            // smallest has no size left in double precision, and well before that the
            // stiffness matrix loses its digits.
            let spread = q.powi(i32::try_from(n.saturating_sub(1)).unwrap_or(i32::MAX));
            if spread > MAX_SIZE_SPREAD {
                return Err(MeshError::Input {
                    field,
                    value: format!(
                        "{q} over {n} elements (the largest element {spread:.1e} times the smallest)"
                    ),
                    allowed: "a largest-to-smallest element size ratio grading^(n - 1) of at \
                              most 1e8: lower the grading or the number of elements",
                });
            }
        }
        Ok(())
    }

    /// Size of the smallest element edge along r and along z (mm).
    pub fn smallest_sizes(&self) -> (f64, f64) {
        let r = graded_positions(self.radius, self.nr, self.grading_r);
        let z = graded_positions(self.height, self.nz, self.grading_z);
        (r[1] - r[0], z[1] - z[0])
    }

    /// Builds the mesh with node sets `axis`, `bottom`, `outer`, `top` (sorted by r, then z).
    ///
    /// # Errors
    /// [`MeshError::Input`] for invalid inputs.
    pub fn build(&self) -> Result<Mesh, MeshError> {
        self.validate()?;
        let rc = graded_positions(self.radius, self.nr, self.grading_r);
        let dc = graded_positions(self.height, self.nz, self.grading_z);
        tensor_mesh(&rc, &dc)
    }

    /// The element boundaries along r (`0 = r_0 < ... < r_nr = radius`) with a boundary at
    /// `r`: the graded positions unchanged if one of them is `r` to a relative 1e-9,
    /// otherwise with the movable boundary (`r_1 .. r_nr-1`) nearest to `r` among the two
    /// that bracket it moved onto `r`, which keeps the positions increasing.
    ///
    /// # Errors
    /// [`MeshError::Input`] for invalid mesher inputs, an `r` outside `(0, radius)`
    /// (field `line radius`), or `nr = 1` (no inner boundary to move).
    pub fn radial_positions_through(&self, r: f64) -> Result<Vec<f64>, MeshError> {
        self.validate()?;
        let mut rc = graded_positions(self.radius, self.nr, self.grading_r);
        if rc.iter().any(|&x| (x / r - 1.0).abs() <= 1e-9) {
            return Ok(rc);
        }
        if !(r.is_finite() && r > 0.0 && r < self.radius) {
            return Err(MeshError::Input {
                field: "line radius",
                value: r.to_string(),
                allowed: "a radius inside the cylinder, in (0, specimen.radius) (mm)",
            });
        }
        if self.nr < 2 {
            return Err(MeshError::Input {
                field: "specimen.nr",
                value: self.nr.to_string(),
                allowed: "at least 2 elements along r to move an inner element boundary",
            });
        }
        // rc[j] < r < rc[j + 1]
        let j = rc.partition_point(|&x| x < r) - 1;
        let k = if j == 0 {
            1
        } else if j + 1 == self.nr || r - rc[j] <= rc[j + 1] - r {
            j
        } else {
            j + 1
        };
        rc[k] = r;
        Ok(rc)
    }

    /// The mesh of [`build`](Self::build) with a vertical line of element corners at
    /// radius `r` (see [`radial_positions_through`](Self::radial_positions_through)): the
    /// same mesh if a boundary is already there, else one boundary moved by at most half
    /// an element. Returns the mesh and the radius of the moved boundary before the move
    /// (`None` if none moved).
    ///
    /// # Errors
    /// As [`radial_positions_through`](Self::radial_positions_through).
    pub fn build_through(&self, r: f64) -> Result<(Mesh, Option<f64>), MeshError> {
        let graded = graded_positions(self.radius, self.nr, self.grading_r);
        let rc = self.radial_positions_through(r)?;
        let dc = graded_positions(self.height, self.nz, self.grading_z);
        let moved = graded
            .iter()
            .zip(&rc)
            .find(|(a, b)| a != b)
            .map(|(a, _)| *a);
        Ok((tensor_mesh(&rc, &dc)?, moved))
    }
}

/// Structured Q8 mesh of the rectangle `0 <= r <= rc[last]`, `-dc[last] <= z <= 0` on the
/// element boundaries `rc` (radii from the axis) and `dc` (depths from the top surface),
/// both increasing from 0; midside nodes at the middle of each edge. Node sets `axis`,
/// `bottom`, `outer`, `top`, sorted by r, then z.
///
/// # Errors
/// [`MeshError::Distorted`] if the positions are not increasing (zero or negative sizes).
pub(crate) fn tensor_mesh(rc: &[f64], dc: &[f64]) -> Result<Mesh, MeshError> {
    let (nr, nz) = (rc.len() - 1, dc.len() - 1);
    // Fine grid (2nr+1) x (2nz+1) without element centres; J counts from the bottom.
    let r_at = |i: usize| {
        if i % 2 == 0 {
            rc[i / 2]
        } else {
            0.5 * (rc[i / 2] + rc[i / 2 + 1])
        }
    };
    // z measured downwards from the top, then mapped to z = -depth.
    let z_at = |j: usize| {
        let k = 2 * nz - j; // fine index measured from the top
        -(if k % 2 == 0 {
            dc[k / 2]
        } else {
            0.5 * (dc[k / 2] + dc[k / 2 + 1])
        })
    };
    let (ni, nj) = (2 * nr + 1, 2 * nz + 1);
    let mut id = vec![usize::MAX; ni * nj];
    let mut nodes = Vec::new();
    for j in 0..nj {
        for i in 0..ni {
            if i % 2 == 1 && j % 2 == 1 {
                continue;
            }
            id[j * ni + i] = nodes.len();
            nodes.push([r_at(i), z_at(j)]);
        }
    }
    let at = |i: usize, j: usize| id[j * ni + i];
    let mut elements = Vec::with_capacity(nr * nz);
    for ej in 0..nz {
        for ei in 0..nr {
            let (i, j) = (2 * ei, 2 * ej);
            elements.push([
                at(i, j),
                at(i + 2, j),
                at(i + 2, j + 2),
                at(i, j + 2),
                at(i + 1, j),
                at(i + 2, j + 1),
                at(i + 1, j + 2),
                at(i, j + 1),
            ]);
        }
    }
    let mut sets = BTreeMap::new();
    sets.insert("axis".to_string(), (0..nj).map(|j| at(0, j)).collect());
    sets.insert(
        "outer".to_string(),
        (0..nj).map(|j| at(ni - 1, j)).collect(),
    );
    sets.insert("bottom".to_string(), (0..ni).map(|i| at(i, 0)).collect());
    sets.insert("top".to_string(), (0..ni).map(|i| at(i, nj - 1)).collect());
    Mesh::new(nodes, elements, sets)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn default_mesher() -> CylinderMesher {
        CylinderMesher::REFERENCE
    }

    #[test]
    fn a_grading_that_leaves_no_size_to_the_smallest_element_is_refused() {
        let m = CylinderMesher {
            nr: 2000,
            grading_r: 3.0,
            ..default_mesher()
        };
        let e = m.validate().unwrap_err().to_string();
        assert!(
            e.contains("specimen.grading_r")
                && e.contains("over 2000 elements")
                && e.contains("1e8"),
            "{e}"
        );
        // 1.3 over 20 elements (R0-R2) spreads sizes by 146: accepted
        default_mesher().validate().unwrap();
    }

    #[test]
    fn default_cylinder_counts_and_sizes() {
        let m = default_mesher().build().unwrap();
        assert_eq!(m.elements.len(), 400);
        assert_eq!(m.nodes.len(), 41 * 41 - 400);
        let (hr, hz) = default_mesher().smallest_sizes();
        assert!(
            (hr - 0.0159).abs() < 2e-4 && (hz - hr).abs() < 1e-15,
            "{hr} {hz}"
        );
        let top = m.node_set("top");
        assert_eq!(top.len(), 41);
        assert!(top.windows(2).all(|w| m.nodes[w[0]][0] < m.nodes[w[1]][0]));
        assert!(top.iter().all(|&n| m.nodes[n][1] == 0.0));
        assert!(m.node_set("axis").iter().all(|&n| m.nodes[n][0] == 0.0));
        assert!(m.node_set("bottom").iter().all(|&n| m.nodes[n][1] == -10.0));
        assert!(m.node_set("outer").iter().all(|&n| m.nodes[n][0] == 10.0));
    }

    #[test]
    fn total_area_is_the_rectangle() {
        let m = CylinderMesher {
            grading_r: 1.1,
            grading_z: 1.7,
            ..default_mesher()
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
        assert!((area - 100.0).abs() < 1e-10);
    }

    #[test]
    fn invalid_inputs_name_the_field() {
        let e = CylinderMesher {
            nr: 0,
            ..default_mesher()
        }
        .build()
        .unwrap_err()
        .to_string();
        assert!(e.contains("specimen.nr") && e.contains("[1, 2000]"), "{e}");
        let e = CylinderMesher {
            radius: -1.0,
            ..default_mesher()
        }
        .build()
        .unwrap_err()
        .to_string();
        assert!(e.contains("specimen.radius") && e.contains("-1"), "{e}");
    }

    #[test]
    fn a_line_of_corners_is_put_through_a_given_radius() {
        let m = default_mesher();
        let rc = graded_positions(10.0, 20, 1.3);
        // already a boundary: the same mesh
        let (same, moved) = m.build_through(rc[6] * (1.0 + 1e-12)).unwrap();
        assert_eq!((same, moved), (m.build().unwrap(), None));
        // the nearest movable boundary of the bracket moves, the others stay
        for (r, k) in [
            (rc[6] + 0.3 * (rc[7] - rc[6]), 6),
            (rc[6] + 0.7 * (rc[7] - rc[6]), 7),
            (0.1 * rc[1], 1),
            (rc[19] + 0.9 * (rc[20] - rc[19]), 19),
        ] {
            let p = m.radial_positions_through(r).unwrap();
            assert_eq!(p[k], r);
            assert!(p.windows(2).all(|w| w[0] < w[1]));
            assert_eq!((0..=20).filter(|&i| p[i] != rc[i]).count(), 1);
            let (mesh, moved) = m.build_through(r).unwrap();
            assert_eq!(moved, Some(rc[k]));
            let top = mesh.node_set("top");
            assert_eq!(mesh.nodes[top[2 * k]][0], r);
            mesh.check_quality().unwrap();
        }
        assert_eq!(m.build_through(10.0).unwrap().1, None);
        for r in [0.0, -1.0, 12.0, f64::NAN] {
            let e = m.build_through(r).unwrap_err().to_string();
            assert!(e.contains("line radius"), "{e}");
        }
        let e = CylinderMesher {
            nr: 1,
            ..default_mesher()
        }
        .build_through(3.0)
        .unwrap_err()
        .to_string();
        assert!(e.contains("specimen.nr"), "{e}");
    }

    #[test]
    fn distorted_element_is_rejected() {
        let mut m = default_mesher().build().unwrap();
        let e0 = m.elements[0];
        m.nodes[e0[2]] = [-1.0, -20.0];
        assert!(matches!(
            m.check_quality(),
            Err(MeshError::Distorted { element: 0, .. })
        ));
    }
}
