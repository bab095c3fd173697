//! Quarter-point (Barsoum) singular elements around one corner node of a Q8 mesh.
//!
//! Where the exact displacement behaves like `sqrt(rho)` at a point (rho the distance
//! to it), as at a crack tip or at the rim of a flat rigid punch (the Boussinesq edge
//! singularity, pressure `~ 1/sqrt(a - r)`), a quadratic element converges only at first
//! order in its size. Moving the midside node of every edge that starts at the singular
//! corner node `P` to the quarter point, `P + (Q - P)/4` for the edge `P -> Q`, makes the
//! isoparametric map along that edge `s = |Q - P| (1 + xi)^2 / 4` (`xi = -1` at `P`):
//! the quadratic field in `xi` is then `a + b sqrt(s) + c s`, which contains the
//! `sqrt(rho)` term exactly along the edge (R. S. Barsoum, "On the use of isoparametric
//! finite elements in linear fracture mechanics", Int. J. Numer. Meth. Engng 10 (1976)
//! 25-37; R. D. Henshell and K. G. Shaw, same journal 9 (1975) 495-507).
//!
//! The Jacobian vanishes at `P` only; it stays positive at every Gauss point, which
//! [`Mesh::new`] checks again on the result. The edges are taken straight (their ends
//! define them; the meshers of this crate make straight edges).

use std::collections::BTreeMap;

use crate::{Mesh, MeshError};

/// Local midside node of the Q8 edge from corner `c` to corner `(c + 1) % 4`.
fn next_edge_midside(c: usize) -> usize {
    4 + c
}

/// Local midside node of the Q8 edge from corner `(c + 3) % 4` to corner `c`.
fn previous_edge_midside(c: usize) -> usize {
    4 + (c + 3) % 4
}

/// A midside node moved by [`Mesh::with_quarter_points`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QuarterPoint {
    /// The midside node.
    pub node: usize,
    /// The corner node at the other end of its edge.
    pub far_corner: usize,
    /// Its position before the move, `[r, z]` (mm).
    pub from: [f64; 2],
    /// Its position after the move, `[r, z]` (mm): a quarter of the edge from the
    /// singular node.
    pub to: [f64; 2],
}

impl Mesh {
    /// The corner nodes at the far end of the edges incident to corner node `node`, each
    /// with the midside node of its edge, as `(midside, far corner)` pairs sorted by
    /// midside node (every edge once, whether one or two elements share it), and whether
    /// `node` lies on the boundary (some incident edge belongs to a single element).
    ///
    /// # Errors
    /// [`MeshError::UnknownNode`] if `node` is not a node of the mesh;
    /// [`MeshError::NotACornerNode`] if it is the midside node of an element or belongs
    /// to no element.
    pub fn corner_edges(&self, node: usize) -> Result<(Vec<(usize, usize)>, bool), MeshError> {
        if node >= self.nodes.len() {
            return Err(MeshError::UnknownNode {
                node,
                nodes: self.nodes.len(),
            });
        }
        // (midside, far corner) -> number of elements holding the edge
        let mut edges: BTreeMap<(usize, usize), usize> = BTreeMap::new();
        for (e, conn) in self.elements.iter().enumerate() {
            match conn.iter().position(|&n| n == node) {
                None => {}
                Some(k) if k >= 4 => {
                    return Err(MeshError::NotACornerNode {
                        node,
                        reason: format!("it is the midside node {k} of element {e}"),
                    });
                }
                Some(c) => {
                    for (mid, far) in [
                        (next_edge_midside(c), (c + 1) % 4),
                        (previous_edge_midside(c), (c + 3) % 4),
                    ] {
                        *edges.entry((conn[mid], conn[far])).or_insert(0) += 1;
                    }
                }
            }
        }
        if edges.is_empty() {
            return Err(MeshError::NotACornerNode {
                node,
                reason: "it belongs to no element".into(),
            });
        }
        let on_boundary = edges.values().any(|&count| count == 1);
        Ok((edges.into_keys().collect(), on_boundary))
    }

    /// A copy of the mesh whose midside nodes on the edges incident to the corner node
    /// `node` are moved to the quarter points nearer to it (see the [module
    /// documentation](crate::singular)): the quarter-point singular elements that
    /// reproduce a `sqrt(rho)` displacement around `node`, e.g. the rim of a flat punch.
    /// Connectivity and node sets are unchanged; the moved nodes are returned.
    ///
    /// Every edge from `node` is treated, in every element sharing it (the elements
    /// stay conforming). The node must lie on the boundary: a singular point inside the
    /// body is not what this treatment models.
    ///
    /// # Errors
    /// [`MeshError::UnknownNode`], [`MeshError::NotACornerNode`],
    /// [`MeshError::InteriorNode`], or [`MeshError::Distorted`] if an element becomes
    /// invalid (a Gauss point with a non-positive Jacobian determinant).
    pub fn with_quarter_points(&self, node: usize) -> Result<(Mesh, Vec<QuarterPoint>), MeshError> {
        let (edges, on_boundary) = self.corner_edges(node)?;
        if !on_boundary {
            return Err(MeshError::InteriorNode { node });
        }
        let p = self.nodes[node];
        let mut nodes = self.nodes.clone();
        let moved: Vec<QuarterPoint> = edges
            .into_iter()
            .map(|(mid, far)| {
                let q = self.nodes[far];
                let to = [p[0] + 0.25 * (q[0] - p[0]), p[1] + 0.25 * (q[1] - p[1])];
                nodes[mid] = to;
                QuarterPoint {
                    node: mid,
                    far_corner: far,
                    from: self.nodes[mid],
                    to,
                }
            })
            .collect();
        let mesh = Mesh::new(nodes, self.elements.clone(), self.node_sets.clone())?;
        Ok((mesh, moved))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{CylinderMesher, q8};

    fn graded() -> Mesh {
        CylinderMesher::REFERENCE.build().unwrap()
    }

    /// The top node at radius index `k` (even: a corner).
    fn top(m: &Mesh, k: usize) -> usize {
        m.node_set("top")[k]
    }

    fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
        (a[0] - b[0]).hypot(a[1] - b[1])
    }

    #[test]
    fn top_corner_gets_three_quarter_point_edges() {
        let m = graded();
        let rim = top(&m, 12);
        let (q, moved) = m.with_quarter_points(rim).unwrap();
        // left and right top edges, and the vertical edge below
        assert_eq!(moved.len(), 3);
        let p = m.nodes[rim];
        for mv in &moved {
            let far = m.nodes[mv.far_corner];
            assert!((dist(p, mv.to) - 0.25 * dist(p, far)).abs() < 1e-15);
            assert!((dist(mv.to, far) - 0.75 * dist(p, far)).abs() < 1e-15);
            assert!((dist(p, mv.from) - 0.5 * dist(p, far)).abs() < 1e-15);
            assert_eq!(q.nodes[mv.node], mv.to);
        }
        let top_moved = moved.iter().filter(|mv| mv.to[1] == 0.0).count();
        assert_eq!(top_moved, 2);
        // everything else unchanged, top nodes still sorted by r and on z = 0
        let changed = (0..m.nodes.len())
            .filter(|&n| m.nodes[n] != q.nodes[n])
            .count();
        assert_eq!(changed, 3);
        let t = q.node_set("top");
        assert!(t.windows(2).all(|w| q.nodes[w[0]][0] < q.nodes[w[1]][0]));
        assert!(t.iter().all(|&n| q.nodes[n][1] == 0.0));
        assert_eq!(q.elements, m.elements);
        assert_eq!(q.node_sets, m.node_sets);
    }

    #[test]
    fn edge_map_is_the_square_root_map() {
        // along a quarter-point edge, s(xi) = L (1 + xi)^2 / 4: xi = sqrt(4 s / L) - 1
        let m = graded();
        let rim = top(&m, 12);
        let (q, _) = m.with_quarter_points(rim).unwrap();
        // the element to the right of the rim on the top row: rim is its corner 3
        let e = (0..q.elements.len())
            .find(|&e| q.elements[e][3] == rim)
            .unwrap();
        let x = q.element_coords(e);
        let len = x[2][0] - x[3][0];
        for xi in [-1.0, -0.9, -0.5, 0.0, 0.3, 1.0] {
            // top edge eta = 1, from corner 3 (xi = -1) to corner 2 (xi = 1)
            let n = q8::shape(xi, 1.0);
            let r: f64 = (0..8).map(|a| n[a] * x[a][0]).sum();
            let s = r - x[3][0];
            assert!(
                (s - len * (1.0 + xi) * (1.0 + xi) / 4.0).abs() < 1e-14,
                "{xi}"
            );
            // a field a + b sqrt(s) is then exactly quadratic in xi: interpolated exactly
            let f = |s: f64| 0.3 + 2.0 * s.max(0.0).sqrt();
            let nodal = [f(len), f(0.25 * len), f(0.0)]; // corner 2, midside 6, corner 3
            let fh = n[2] * nodal[0] + n[6] * nodal[1] + n[3] * nodal[2];
            assert!((fh - f(s)).abs() < 1e-12, "{xi}: {fh} vs {}", f(s));
        }
    }

    #[test]
    fn jacobian_stays_positive_at_every_gauss_point() {
        let m = graded();
        for k in [2, 12, 20, 38] {
            let (q, _) = m.with_quarter_points(top(&m, k)).unwrap();
            q.check_quality().unwrap();
            let (lo, _) = q.jacobian_ratio_range();
            assert!(lo > 0.0 && lo < 0.5, "{k}: {lo}");
        }
        // outer top corner (one element), axis corner, bottom corner
        let last = *m.node_set("top").last().unwrap();
        let (_, moved) = m.with_quarter_points(last).unwrap();
        assert_eq!(moved.len(), 2);
        for n in [m.node_set("axis")[10], m.node_set("bottom")[0]] {
            m.with_quarter_points(n).unwrap().0.check_quality().unwrap();
        }
        // the treated element's area is unchanged (straight edges, same corners)
        let area = |mesh: &Mesh| -> f64 {
            (0..mesh.elements.len())
                .map(|e| {
                    let x = mesh.element_coords(e);
                    q8::gauss3x3()
                        .iter()
                        .map(|([a, b], w)| w * q8::jacobian(&x, *a, *b).1)
                        .sum::<f64>()
                })
                .sum()
        };
        let (q, _) = m.with_quarter_points(top(&m, 12)).unwrap();
        assert!((area(&q) - 100.0).abs() < 1e-10);
    }

    #[test]
    fn bad_nodes_are_errors_naming_the_node() {
        let m = graded();
        let e = m.with_quarter_points(top(&m, 13)).unwrap_err();
        assert!(matches!(e, MeshError::NotACornerNode { .. }), "{e}");
        assert!(e.to_string().contains("midside"), "{e}");
        let e = m.with_quarter_points(m.nodes.len()).unwrap_err();
        assert!(matches!(e, MeshError::UnknownNode { .. }), "{e}");
        // an interior corner: element 50's corner 2 is inside the 20 x 20 grid
        let inner = m.elements[50][2];
        let e = m.with_quarter_points(inner).unwrap_err();
        assert_eq!(e, MeshError::InteriorNode { node: inner });
        assert!(e.to_string().contains(&inner.to_string()), "{e}");
        // a node in no element
        let mut lone = m.clone();
        lone.nodes.push([20.0, 0.0]);
        let e = lone.with_quarter_points(m.nodes.len()).unwrap_err();
        assert!(e.to_string().contains("no element"), "{e}");
    }
}
