//! The rim of a flat punch: quarter-point singular elements around the top corner node
//! at the punch radius.
//!
//! Under a flat rigid punch of radius `a` the half-space solution (Boussinesq) has a
//! pressure `~ 1/sqrt(a - r)` and, in the `(r, z)` plane, a displacement `~ sqrt(rho)`
//! around the rim point (`rho` the distance to it). Quadratic elements around that point
//! converge at first order and overestimate the force: +2.6% on R0's 20 x 20 graded
//! cylinder (half-space value). [`treat_rim`] moves the midside nodes of the edges from
//! the rim node to their quarter points ([`Mesh::with_quarter_points`], Barsoum's singular
//! elements), which puts the `sqrt(rho)` term into the element space: +1.1% on the same
//! mesh, still converging at first order with a constant about 2.4 times smaller
//! (`docs/validation.md`, "Flat punch at the default mesh").
//!
//! The treatment needs a corner node at `r = a` on the top surface: the FE contact zone is
//! a set of nodes, so only then does the punch have its nominal radius. A rim inside an
//! element (or on a midside node) is left untreated and reported as
//! [`Rim::OffCorner`], with the radius the FE contact zone actually ends at; the
//! automatic specimen (its core is the punch radius) always has the corner, and the CLI
//! moves the nearest grid line of a `Cylinder` specimen onto the rim.

use indentify_mesh::{Mesh, QuarterPoint};

use super::Punch;
use crate::ContactError;

/// Relative tolerance on `r / a - 1` for a top node to be the rim node.
pub const RIM_TOLERANCE: f64 = 1e-9;

/// What [`treat_rim`] did.
#[derive(Clone, Debug, PartialEq)]
pub enum Rim {
    /// Not a flat punch: the mesh is unchanged.
    Smooth,
    /// Quarter-point elements around the top corner node `node` at the punch radius.
    QuarterPoint {
        /// The rim node.
        node: usize,
        /// The midside nodes moved to the quarter points.
        moved: Vec<QuarterPoint>,
    },
    /// A flat punch whose radius is not at a top corner node: the mesh is unchanged and
    /// the rim singularity untreated. The FE contact zone ends at the last top node at or
    /// inside the radius, `inner`, so the force is that of a punch of radius about
    /// `inner`, not `radius`.
    OffCorner {
        /// The punch radius (mm).
        radius: f64,
        /// Radius of the last top node at or inside the punch radius (mm).
        inner: f64,
        /// Radius of the nearest top corner node (mm), where a rim would be treated.
        nearest_corner: f64,
    },
}

impl Rim {
    /// One line for logs and reports.
    pub fn describe(&self) -> String {
        match self {
            Rim::Smooth => "no rim".into(),
            Rim::QuarterPoint { node, moved } => format!(
                "quarter-point singular elements at the flat punch's rim (node {node}, {} \
                 midside nodes moved)",
                moved.len()
            ),
            Rim::OffCorner {
                radius,
                inner,
                nearest_corner,
            } => format!(
                "the flat punch's radius {radius} mm is not at a corner node of the top \
                 surface: its rim singularity is untreated and the contact zone ends at the \
                 node at r = {inner} mm (nearest corner node: r = {nearest_corner} mm)"
            ),
        }
    }
}

/// For a [`Punch::Flat`] whose radius is at a top corner node (to a relative
/// [`RIM_TOLERANCE`]), the mesh with quarter-point elements around that node; otherwise
/// the mesh unchanged. The top node set (`top`, sorted by r) locates the rim. Cones,
/// spheres and other smooth profiles are left alone ([`Rim::Smooth`]): their pressure
/// vanishes at the contact edge and has no singularity to treat.
///
/// # Errors
/// [`ContactError::Input`] for an invalid punch, a mesh without `top` nodes, or a rim
/// element that the move would invert (field `mesh`; not expected for the meshers of
/// `indentify-mesh`, whose elements are rectangles).
pub fn treat_rim(mesh: Mesh, punch: &Punch) -> Result<(Mesh, Rim), ContactError> {
    punch.validate()?;
    let Punch::Flat { radius } = *punch else {
        return Ok((mesh, Rim::Smooth));
    };
    let top = mesh.node_set("top");
    let corners: Vec<usize> = top
        .iter()
        .copied()
        .filter(|&n| mesh.corner_edges(n).is_ok())
        .collect();
    let r = |n: usize| mesh.nodes[n][0];
    let Some(&nearest) = corners
        .iter()
        .min_by(|&&a, &&b| (r(a) - radius).abs().total_cmp(&(r(b) - radius).abs()))
    else {
        return Err(ContactError::Input {
            field: "mesh.top",
            value: "no corner node".into(),
            allowed: "a top surface of element edges (the `top` node set)".into(),
        });
    };
    if (r(nearest) / radius - 1.0).abs() > RIM_TOLERANCE {
        let rim = Rim::OffCorner {
            radius,
            inner: top
                .iter()
                .map(|&n| r(n))
                .filter(|&x| x <= radius * (1.0 + RIM_TOLERANCE))
                .fold(0.0, f64::max),
            nearest_corner: r(nearest),
        };
        return Ok((mesh, rim));
    }
    let (treated, moved) = mesh
        .with_quarter_points(nearest)
        .map_err(|e| ContactError::Input {
            field: "mesh",
            value: format!("the flat punch's rim node {nearest} at r = {radius} mm"),
            allowed: format!("quarter-point elements around it: {e}"),
        })?;
    Ok((
        treated,
        Rim::QuarterPoint {
            node: nearest,
            moved,
        },
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use indentify_mesh::CylinderMesher;
    use indentify_mesh::cylinder::graded_positions;

    fn r0_mesh() -> Mesh {
        CylinderMesher::REFERENCE.build().unwrap()
    }

    #[test]
    fn flat_punch_on_a_corner_gets_quarter_points() {
        let mesh = r0_mesh();
        let a = graded_positions(10.0, 20, 1.3)[6];
        // within the relative tolerance, either side
        for radius in [a, a * (1.0 + 5e-10), a * (1.0 - 5e-10)] {
            let (treated, rim) = treat_rim(mesh.clone(), &Punch::Flat { radius }).unwrap();
            let Rim::QuarterPoint { node, moved } = &rim else {
                panic!("{rim:?}");
            };
            assert_eq!(*node, mesh.node_set("top")[12]);
            assert_eq!(moved.len(), 3);
            treated.check_quality().unwrap();
            // the top midside nodes on both sides of the rim sit at a quarter of their edge
            let top = treated.node_set("top");
            let x = |k: usize| treated.nodes[top[k]][0];
            assert!(((x(12) - x(11)) / (x(12) - x(10)) - 0.25).abs() < 1e-12);
            assert!(((x(13) - x(12)) / (x(14) - x(12)) - 0.25).abs() < 1e-12);
            assert!(rim.describe().contains("quarter-point"));
            // the rim node is on the punch face
            let punch = Punch::Flat { radius };
            assert_eq!(punch.profile(x(12)), 0.0);
            assert!(punch.profile(x(13)).is_infinite());
        }
    }

    /// The lumped top areas follow the isoparametric edges: they still add up to the top
    /// face, and a quarter-point edge gives its far corner 1/3 of the edge's length-weight
    /// and the rim node almost nothing (`int N_k 2 pi r dr` with `r(xi)` quadratic).
    #[test]
    fn lumped_areas_follow_quarter_point_edges() {
        let a = graded_positions(10.0, 20, 1.3)[6];
        let punch = Punch::Flat { radius: a };
        let (treated, _) = treat_rim(r0_mesh(), &punch).unwrap();
        let plain = crate::Model::new(r0_mesh(), punch.clone()).unwrap();
        let model = crate::Model::new(treated, punch).unwrap();
        let face = std::f64::consts::PI * 100.0;
        for m in [&plain, &model] {
            let total: f64 = m.candidate_area.iter().sum();
            assert!((total - face).abs() < 1e-12 * face, "{total} vs {face}");
        }
        // the rim node (candidate 12) loses area to its neighbours' far corners
        assert!(model.candidate_area[12] < 0.2 * plain.candidate_area[12]);
        // int N_k 2 pi r dr over the edge (r0, rm, r1) by a fine midpoint sum
        let edge_integral = |r0: f64, rm: f64, r1: f64, k: usize| -> f64 {
            let steps = 200_000;
            let h = 2.0 / steps as f64;
            (0..steps)
                .map(|i| {
                    let xi = -1.0 + (i as f64 + 0.5) * h;
                    let n = [0.5 * xi * (xi - 1.0), 1.0 - xi * xi, 0.5 * xi * (xi + 1.0)];
                    let r = n[0] * r0 + n[1] * rm + n[2] * r1;
                    let dr = (xi - 0.5) * r0 - 2.0 * xi * rm + (xi + 0.5) * r1;
                    n[k] * 2.0 * std::f64::consts::PI * r * dr * h
                })
                .sum()
        };
        let r = |k: usize| model.candidate_r(k);
        // node 14 is the far corner of the quarter-point edge and the near corner of the next
        let far = edge_integral(r(12), r(13), r(14), 2);
        let near = edge_integral(r(14), r(15), r(16), 0);
        let expected = far + near;
        assert!(
            (model.candidate_area[14] - expected).abs() < 1e-8 * expected,
            "{} vs {expected}",
            model.candidate_area[14]
        );
    }

    #[test]
    fn smooth_punches_leave_the_mesh_alone() {
        let mesh = r0_mesh();
        for punch in [
            Punch::Cone {
                half_angle_deg: 68.0,
            },
            Punch::Sphere { radius: 0.5 },
            Punch::Berkovich { tip_radius: None },
        ] {
            let (m, rim) = treat_rim(mesh.clone(), &punch).unwrap();
            assert_eq!(rim, Rim::Smooth);
            assert_eq!(m, mesh);
        }
    }

    #[test]
    fn off_corner_rim_is_reported_not_treated() {
        let mesh = r0_mesh();
        let r = graded_positions(10.0, 20, 1.3);
        // on a midside node, and inside an element
        for radius in [0.5 * (r[6] + r[7]), r[6] + 0.3 * (r[7] - r[6])] {
            let (m, rim) = treat_rim(mesh.clone(), &Punch::Flat { radius }).unwrap();
            assert_eq!(m, mesh);
            let Rim::OffCorner {
                inner,
                nearest_corner,
                ..
            } = rim
            else {
                panic!("{rim:?}");
            };
            assert!(inner <= radius && inner >= r[6], "{inner}");
            assert!(nearest_corner == r[6] || nearest_corner == r[7]);
            assert!(rim.describe().contains("not at a corner node"));
        }
        let e = treat_rim(mesh, &Punch::Flat { radius: -1.0 })
            .unwrap_err()
            .to_string();
        assert!(e.contains("punch.radius"), "{e}");
    }
}
