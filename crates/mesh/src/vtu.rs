//! VTU (VTK XML unstructured grid, ASCII) export of a mesh with nodal and cell fields,
//! and of Gauss-point clouds, for ParaView.

use std::fmt::Write as _;

use crate::Mesh;

/// A named field with `ncomp` components per entity, stored entity-major.
#[derive(Clone, Copy, Debug)]
pub struct Field<'a> {
    /// Name shown in ParaView.
    pub name: &'a str,
    /// Components per entity (1 scalar, 2 or 3 vector, 4 Mandel tensor...).
    pub ncomp: usize,
    /// Values, `ncomp` per entity.
    pub values: &'a [f64],
}

fn data_array(out: &mut String, f: &Field<'_>) {
    let _ = writeln!(
        out,
        "<DataArray type=\"Float64\" Name=\"{}\" NumberOfComponents=\"{}\" format=\"ascii\">",
        f.name, f.ncomp
    );
    for chunk in f.values.chunks(f.ncomp.max(1)) {
        for v in chunk {
            let _ = write!(out, "{v:e} ");
        }
        out.push('\n');
    }
    out.push_str("</DataArray>\n");
}

fn check_len(f: &Field<'_>, n: usize, what: &str) {
    assert_eq!(
        f.values.len(),
        f.ncomp * n,
        "field `{}` must have {} x {} {what} values",
        f.name,
        f.ncomp,
        n
    );
}

/// The mesh as a VTU document: `QUADRATIC_QUAD` cells in the (x = r, y = z) plane, with
/// point fields (one entry per node) and cell fields (one per element).
///
/// # Panics
/// If a field's length is not `ncomp` times the number of nodes (points) or elements (cells).
pub fn mesh_to_vtu(mesh: &Mesh, point_fields: &[Field<'_>], cell_fields: &[Field<'_>]) -> String {
    let mut out = String::new();
    out.push_str("<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n<UnstructuredGrid>\n");
    let _ = writeln!(
        out,
        "<Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">",
        mesh.nodes.len(),
        mesh.elements.len()
    );
    out.push_str(
        "<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n",
    );
    for [r, z] in &mesh.nodes {
        let _ = writeln!(out, "{r:e} {z:e} 0");
    }
    out.push_str("</DataArray>\n</Points>\n<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n");
    for conn in &mesh.elements {
        for n in conn {
            let _ = write!(out, "{n} ");
        }
        out.push('\n');
    }
    out.push_str("</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n");
    for e in 0..mesh.elements.len() {
        let _ = write!(out, "{} ", 8 * (e + 1));
    }
    out.push_str("\n</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n");
    out.push_str(&"23 ".repeat(mesh.elements.len()));
    out.push_str("\n</DataArray>\n</Cells>\n<PointData>\n");
    for f in point_fields {
        check_len(f, mesh.nodes.len(), "point");
        data_array(&mut out, f);
    }
    out.push_str("</PointData>\n<CellData>\n");
    for f in cell_fields {
        check_len(f, mesh.elements.len(), "cell");
        data_array(&mut out, f);
    }
    out.push_str("</CellData>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n");
    out
}

/// Gauss-point values as a VTU point cloud (`VERTEX` cells at `positions`, e.g. from
/// [`Mesh::gauss_point_positions`]), so quadrature-point fields appear unsmoothed.
///
/// # Panics
/// If a field's length is not `ncomp` times the number of positions.
pub fn points_to_vtu(positions: &[[f64; 2]], fields: &[Field<'_>]) -> String {
    let n = positions.len();
    let mut out = String::new();
    out.push_str("<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n<UnstructuredGrid>\n");
    let _ = writeln!(out, "<Piece NumberOfPoints=\"{n}\" NumberOfCells=\"{n}\">");
    out.push_str(
        "<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n",
    );
    for [r, z] in positions {
        let _ = writeln!(out, "{r:e} {z:e} 0");
    }
    out.push_str("</DataArray>\n</Points>\n<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n");
    for i in 0..n {
        let _ = write!(out, "{i} ");
    }
    out.push_str("\n</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n");
    for i in 0..n {
        let _ = write!(out, "{} ", i + 1);
    }
    out.push_str("\n</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n");
    out.push_str(&"1 ".repeat(n));
    out.push_str("\n</DataArray>\n</Cells>\n<PointData>\n");
    for f in fields {
        check_len(f, n, "point");
        data_array(&mut out, f);
    }
    out.push_str("</PointData>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n");
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::CylinderMesher;

    #[test]
    fn vtu_has_the_declared_counts_and_fields() {
        let m = CylinderMesher {
            radius: 1.0,
            height: 1.0,
            nr: 2,
            nz: 3,
            grading_r: 1.0,
            grading_z: 1.0,
        }
        .build()
        .unwrap();
        let disp = vec![0.5; 2 * m.nodes.len()];
        let s = mesh_to_vtu(
            &m,
            &[Field {
                name: "u",
                ncomp: 2,
                values: &disp,
            }],
            &[],
        );
        assert!(s.contains(&format!(
            "NumberOfPoints=\"{}\" NumberOfCells=\"6\"",
            m.nodes.len()
        )));
        assert!(s.contains("Name=\"u\" NumberOfComponents=\"2\""));
        assert!(s.contains("Name=\"types\" format=\"ascii\">\n23 23 23 23 23 23 \n"));
        let g = m.gauss_point_positions();
        let p = points_to_vtu(
            &g,
            &[Field {
                name: "seq",
                ncomp: 1,
                values: &vec![1.0; g.len()],
            }],
        );
        assert!(p.contains("NumberOfPoints=\"54\""));
    }
}
