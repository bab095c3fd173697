//! Axisymmetric meshes of 8-node serendipity quadrilaterals in `(r, z)` for indentify.
//!
//! [`Mesh`] holds nodes, elements and named node sets; [`CylinderMesher`] builds the
//! graded cylinder specimen; [`ZonedCylinderMesher`] the one with a uniform core under the
//! punch (the automatic specimen); [`Mesh::check_quality`] verifies a positive Jacobian at
//! every Gauss point; [`Mesh::with_quarter_points`] makes quarter-point singular elements
//! around a corner node ([`singular`]); [`vtu`] writes ParaView files. Lengths are in mm.
//! The body lies below `z = 0` (the top surface, where the punch presses) and right of the
//! axis `r = 0`. This crate knows nothing of materials, assembly or contact.

pub mod cylinder;
pub mod q8;
pub mod singular;
pub mod vtu;
pub mod zoned;

use std::collections::BTreeMap;

pub use cylinder::CylinderMesher;
pub use singular::QuarterPoint;
pub use zoned::ZonedCylinderMesher;

/// Errors of mesh construction and checks.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum MeshError {
    /// A mesher input outside its admissible range.
    #[error("mesh: `{field}` = {value} is not allowed: {allowed}")]
    Input {
        /// Field name as in configs (e.g. `specimen.nr`).
        field: &'static str,
        /// Offending value, as text.
        value: String,
        /// What is allowed.
        allowed: &'static str,
    },
    /// An element with a non-positive Jacobian determinant at a Gauss point.
    #[error(
        "mesh: element {element} has Jacobian determinant {det:.3e} <= 0 at Gauss point {gauss_point}"
    )]
    Distorted {
        /// Element index.
        element: usize,
        /// Gauss point index (0..9).
        gauss_point: usize,
        /// Determinant value.
        det: f64,
    },
    /// An element refers to a node that does not exist.
    #[error("mesh: element {element} refers to node {node}, but the mesh has {nodes} nodes")]
    BadConnectivity {
        /// Element index.
        element: usize,
        /// Node index.
        node: usize,
        /// Number of nodes.
        nodes: usize,
    },
    /// A node index beyond the mesh's nodes.
    #[error("mesh: there is no node {node}: the mesh has {nodes} nodes")]
    UnknownNode {
        /// Node index.
        node: usize,
        /// Number of nodes.
        nodes: usize,
    },
    /// A node that should be an element corner and is not.
    #[error("mesh: node {node} is not an element corner node: {reason}")]
    NotACornerNode {
        /// Node index.
        node: usize,
        /// What the node is instead.
        reason: String,
    },
    /// A node that should lie on the boundary of the mesh and is inside it.
    #[error(
        "mesh: node {node} is inside the mesh (every edge from it is shared by two elements), not on its boundary"
    )]
    InteriorNode {
        /// Node index.
        node: usize,
    },
}

/// An axisymmetric Q8 mesh: node coordinates `[r, z]` (mm), connectivity in
/// [`q8::NODES`] order, and named node sets.
#[derive(Clone, Debug, PartialEq)]
pub struct Mesh {
    /// Node coordinates `[r, z]` in mm.
    pub nodes: Vec<[f64; 2]>,
    /// Element connectivity, 8 nodes each, counter-clockwise in `(r, z)`.
    pub elements: Vec<[usize; 8]>,
    /// Named node sets. The cylinder mesher provides `axis`, `bottom`, `outer` and `top`
    /// (the contact candidates), each sorted by increasing `r` (then `z`).
    pub node_sets: BTreeMap<String, Vec<usize>>,
}

impl Mesh {
    /// Builds a mesh after checking its connectivity and quality.
    ///
    /// # Errors
    /// [`MeshError::BadConnectivity`] or [`MeshError::Distorted`].
    pub fn new(
        nodes: Vec<[f64; 2]>,
        elements: Vec<[usize; 8]>,
        node_sets: BTreeMap<String, Vec<usize>>,
    ) -> Result<Mesh, MeshError> {
        for (e, conn) in elements.iter().enumerate() {
            if let Some(&node) = conn.iter().find(|&&n| n >= nodes.len()) {
                return Err(MeshError::BadConnectivity {
                    element: e,
                    node,
                    nodes: nodes.len(),
                });
            }
        }
        let mesh = Mesh {
            nodes,
            elements,
            node_sets,
        };
        mesh.check_quality()?;
        Ok(mesh)
    }

    /// Coordinates of the eight nodes of element `e`.
    pub fn element_coords(&self, e: usize) -> [[f64; 2]; 8] {
        self.elements[e].map(|n| self.nodes[n])
    }

    /// The node set `name`, or an empty slice.
    pub fn node_set(&self, name: &str) -> &[usize] {
        self.node_sets.get(name).map_or(&[], |v| v.as_slice())
    }

    /// Checks that the Jacobian determinant is positive at every 3x3 Gauss point.
    ///
    /// # Errors
    /// [`MeshError::Distorted`] for the first failing element and point.
    pub fn check_quality(&self) -> Result<(), MeshError> {
        for e in 0..self.elements.len() {
            let x = self.element_coords(e);
            for (g, ([xi, eta], _)) in q8::gauss3x3().iter().enumerate() {
                let (_, det) = q8::jacobian(&x, *xi, *eta);
                if !(det > 0.0) {
                    return Err(MeshError::Distorted {
                        element: e,
                        gauss_point: g,
                        det,
                    });
                }
            }
        }
        Ok(())
    }

    /// Smallest and largest Jacobian-determinant ratio per element (min/max over its
    /// Gauss points); 1 for an affine element. A quality summary for reports.
    pub fn jacobian_ratio_range(&self) -> (f64, f64) {
        let mut lo = f64::INFINITY;
        let mut hi = 0.0_f64;
        for e in 0..self.elements.len() {
            let x = self.element_coords(e);
            let dets: Vec<f64> = q8::gauss3x3()
                .iter()
                .map(|([a, b], _)| q8::jacobian(&x, *a, *b).1)
                .collect();
            let ratio = dets.iter().cloned().fold(f64::INFINITY, f64::min)
                / dets.iter().cloned().fold(0.0, f64::max);
            lo = lo.min(ratio);
            hi = hi.max(ratio);
        }
        (lo, hi)
    }

    /// Position `[r, z]` of every Gauss point, element by element (9 per element).
    pub fn gauss_point_positions(&self) -> Vec<[f64; 2]> {
        let rule = q8::gauss3x3();
        let mut out = Vec::with_capacity(9 * self.elements.len());
        for e in 0..self.elements.len() {
            let x = self.element_coords(e);
            for ([xi, eta], _) in &rule {
                let n = q8::shape(*xi, *eta);
                let mut p = [0.0; 2];
                for a in 0..8 {
                    p[0] += n[a] * x[a][0];
                    p[1] += n[a] * x[a][1];
                }
                out.push(p);
            }
        }
        out
    }
}
