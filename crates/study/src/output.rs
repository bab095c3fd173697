//! Files the CLI writes: the force-depth curve as CSV, and the per-step fields of a run as
//! VTU files (mesh with cell averages, and Gauss-point clouds) indexed by a PVD collection.

use std::io::Write;
use std::path::Path;

use anyhow::{Context, Result};
use indentify_contact::{Model, Schedule, Trajectory, nodal_pressures};
use indentify_fe::QP_PER_ELEMENT;
use indentify_laws::mandel::SQRT2;
use indentify_laws::{Mat4, Material, Regime, Step, Vec4};
use indentify_mesh::vtu::{Field, mesh_to_vtu, points_to_vtu};

/// One row of the curve: time (s), depth (mm), force (N, full circle), contact radius (mm).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CurveRow {
    /// Time (s).
    pub t: f64,
    /// Punch depth (mm).
    pub h: f64,
    /// Punch force (N).
    pub f: f64,
    /// Contact radius (mm).
    pub a: f64,
}

/// The curve at the schedule times: the initial state, then every step that ends on a
/// schedule time (sub-steps, of cut steps or the schedule's own, left out).
pub fn curve(schedule: &Schedule, traj: &Trajectory) -> Vec<CurveRow> {
    std::iter::once(CurveRow {
        t: schedule.t[0],
        h: schedule.depth[0],
        f: 0.0,
        a: 0.0,
    })
    .chain(traj.schedule_steps().map(|s| CurveRow {
        t: s.t,
        h: s.depth,
        f: s.force,
        a: s.contact_radius,
    }))
    .collect()
}

/// Writes the curve as CSV with header `t,h,F,a` (s, mm, N, mm) to `out`.
///
/// # Errors
/// An I/O error of the writer.
pub fn write_curve_csv<W: Write>(out: W, rows: &[CurveRow]) -> Result<()> {
    let mut w = csv::Writer::from_writer(out);
    w.write_record(["t", "h", "F", "a"])?;
    for r in rows {
        w.write_record([r.t, r.h, r.f, r.a].map(csv_number))?;
    }
    w.flush()?;
    Ok(())
}

/// A number as CSV text: its shortest exact form, with `-0` written `0`.
pub fn csv_number(v: f64) -> String {
    if v == 0.0 { "0".into() } else { v.to_string() }
}

/// Writes the curve to the file `path` atomically (an interrupted write leaves the
/// previous file whole), or to standard output when `None`.
///
/// # Errors
/// The file cannot be created or written.
pub fn write_curve(path: Option<&Path>, rows: &[CurveRow]) -> Result<()> {
    match path {
        Some(p) => {
            let mut bytes = Vec::new();
            write_curve_csv(&mut bytes, rows)?;
            crate::atomic::write(p, bytes)
                .with_context(|| format!("cannot write the curve file `{}`", p.display()))
        }
        None => write_curve_csv(std::io::stdout().lock(), rows)
            .context("cannot write the curve to standard output"),
    }
}

/// Gauss-point fields of one recorded state, physical tensor components `[rr, zz, tt, rz]`.
struct QpFields {
    /// Stress (MPa), 4 per point.
    stress: Vec<f64>,
    /// von Mises equivalent stress (MPa).
    von_mises: Vec<f64>,
    /// Viscoplastic strain `eps - S sigma`, 4 per point.
    eps_p: Vec<f64>,
    /// Equivalent viscoplastic strain `sqrt(2/3 e:e)` of its deviator `e`.
    eps_p_eq: Vec<f64>,
}

/// Mandel `[rr, zz, tt, sqrt2 rz]` to tensor components `[rr, zz, tt, rz]`.
fn physical(m: &Vec4) -> [f64; 4] {
    [m.0[0], m.0[1], m.0[2], m.0[3] / SQRT2]
}

/// The elastic compliance `S` of `law` at `params`: a stress-only law's own; for a law with
/// internal variables, minus the stress block of `D = dR/dy_0`, which is `-S` for every law
/// whose stress rows read `S (sigma_1 - sigma_0) + ... - deps` (the `Material` convention).
fn elastic_compliance(law: &dyn Material, params: &[f64]) -> Mat4 {
    if let Some(l) = law.as_law() {
        return l.compliance(params);
    }
    let m = law.state_len();
    let y = vec![0.0; m];
    let step = Step {
        y0: &y,
        y1: &y,
        deps: &Vec4([0.0; 4]),
        dt: 0.0,
        regime: Regime::Elastic,
    };
    let mut d = vec![0.0; m * m];
    law.jac_previous(params, &step, &mut d);
    let mut s = Mat4([[0.0; 4]; 4]);
    for (a, row) in s.0.iter_mut().enumerate() {
        for (b, v) in row.iter_mut().enumerate() {
            *v = -d[a * m + b];
        }
    }
    s
}

fn qp_fields(
    model: &Model,
    law: &dyn Material,
    params: &[f64],
    u: &[f64],
    sigma: &[Vec4],
) -> QpFields {
    let nq = model.disc.n_qp();
    let mut eps = vec![[0.0; 4]; nq];
    model.disc.strains(u, &mut eps);
    let s = elastic_compliance(law, params);
    let mut f = QpFields {
        stress: Vec::with_capacity(4 * nq),
        von_mises: Vec::with_capacity(nq),
        eps_p: Vec::with_capacity(4 * nq),
        eps_p_eq: Vec::with_capacity(nq),
    };
    for (sig, e) in sigma.iter().zip(&eps) {
        let ep = Vec4(*e) - s.mul_vec(sig);
        let dev = ep.deviator();
        f.stress.extend(physical(sig));
        f.von_mises.push(sig.von_mises());
        f.eps_p.extend(physical(&ep));
        f.eps_p_eq.push((2.0 / 3.0 * dev.dot(&dev)).sqrt());
    }
    f
}

/// The law's own internal variables (`Material::internal`, e.g. J2's accumulated plastic
/// strain `p`, a Prony branch's viscous strain `ev1_zz`), one scalar field per variable named
/// `internal_<name>`, from a state's point-major `alpha`; none for a stress-only law.
fn internal_fields(law: &dyn Material, alpha: &[f64], nq: usize) -> Vec<(String, Vec<f64>)> {
    let n = law.n_internal();
    if n == 0 || alpha.len() != n * nq {
        return Vec::new();
    }
    law.internal()
        .iter()
        .enumerate()
        .map(|(i, info)| {
            let v = (0..nq).map(|q| alpha[q * n + i]).collect();
            (format!("internal_{}", info.name), v)
        })
        .collect()
}

/// Volume average over each element's Gauss points (weights `w_g`) of a field with
/// `ncomp` components per point.
fn cell_average(model: &Model, values: &[f64], ncomp: usize) -> Vec<f64> {
    let ne = model.disc.elements.len();
    let mut out = vec![0.0; ncomp * ne];
    for e in 0..ne {
        let mut wsum = 0.0;
        for g in 0..QP_PER_ELEMENT {
            let q = QP_PER_ELEMENT * e + g;
            let w = model.disc.qp[q].w;
            wsum += w;
            for c in 0..ncomp {
                out[ncomp * e + c] += w * values[ncomp * q + c];
            }
        }
        for v in &mut out[ncomp * e..ncomp * (e + 1)] {
            *v /= wsum;
        }
    }
    out
}

/// Writes `step_NNNN.vtu` (mesh: point displacement `(u_r, u_z, 0)` and contact pressure;
/// cell volume averages of stress, von Mises stress, viscoplastic strain and its equivalent,
/// and of the law's internal variables, `internal_<name>`)
/// and `gauss_NNNN.vtu` (the same fields at the Gauss points, unsmoothed) for every
/// recorded state (0 = initial, then every converged step, sub-steps included), and
/// `steps.pvd` indexing both by time. Returns the number of states written.
///
/// # Errors
/// The directory or a file cannot be created or written, or the trajectory holds no fields.
pub fn write_vtu_series(
    dir: &Path,
    model: &Model,
    law: &dyn Material,
    params: &[f64],
    traj: &Trajectory,
) -> Result<usize> {
    anyhow::ensure!(
        traj.fields.len() == traj.steps.len() + 1,
        "the run recorded {} field states for {} steps: nothing consistent to write",
        traj.fields.len(),
        traj.steps.len()
    );
    std::fs::create_dir_all(dir)
        .with_context(|| format!("cannot create the VTU directory `{}`", dir.display()))?;
    let n_nodes = model.mesh.nodes.len();
    let positions: Vec<[f64; 2]> = model.disc.qp.iter().map(|q| [q.r, q.z]).collect();
    let mut pvd = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n<Collection>\n",
    );
    for (k, state) in traj.fields.iter().enumerate() {
        let t = if k == 0 { 0.0 } else { traj.steps[k - 1].t };
        let mut disp = vec![0.0; 3 * n_nodes];
        for n in 0..n_nodes {
            disp[3 * n] = state.u[2 * n];
            disp[3 * n + 1] = state.u[2 * n + 1];
        }
        let mut pressure = vec![0.0; n_nodes];
        if k > 0 {
            let rec = &traj.steps[k - 1];
            for (&cand, (_, p)) in rec.active.iter().zip(nodal_pressures(model, rec)) {
                pressure[model.candidates[cand as usize]] = p;
            }
        }
        let q = qp_fields(model, law, params, &state.u, &state.sigma);
        let cell = (
            cell_average(model, &q.stress, 4),
            cell_average(model, &q.von_mises, 1),
            cell_average(model, &q.eps_p, 4),
            cell_average(model, &q.eps_p_eq, 1),
        );
        let internal = internal_fields(law, &state.alpha, model.disc.n_qp());
        let internal_cells: Vec<Vec<f64>> = internal
            .iter()
            .map(|(_, v)| cell_average(model, v, 1))
            .collect();
        let field = |name, ncomp, values| Field {
            name,
            ncomp,
            values,
        };
        let mut cell_fields = vec![
            field("stress", 4, &cell.0),
            field("von_mises", 1, &cell.1),
            field("eps_p", 4, &cell.2),
            field("eps_p_eq", 1, &cell.3),
        ];
        let mut gauss_fields = vec![
            field("stress", 4, &q.stress),
            field("von_mises", 1, &q.von_mises),
            field("eps_p", 4, &q.eps_p),
            field("eps_p_eq", 1, &q.eps_p_eq),
        ];
        for ((name, v), c) in internal.iter().zip(&internal_cells) {
            let scalar = |values| Field {
                name: name.as_str(),
                ncomp: 1,
                values,
            };
            gauss_fields.push(scalar(v));
            cell_fields.push(scalar(c));
        }
        let mesh_doc = mesh_to_vtu(
            &model.mesh,
            &[
                field("displacement", 3, &disp),
                field("contact_pressure", 1, &pressure),
            ],
            &cell_fields,
        );
        let gauss_doc = points_to_vtu(&positions, &gauss_fields);
        let mesh_name = format!("step_{k:04}.vtu");
        let gauss_name = format!("gauss_{k:04}.vtu");
        for (name, doc) in [(&mesh_name, mesh_doc), (&gauss_name, gauss_doc)] {
            let path = dir.join(name);
            crate::atomic::write(&path, doc)?;
        }
        pvd.push_str(&format!(
            "<DataSet timestep=\"{t}\" group=\"\" part=\"0\" file=\"{mesh_name}\"/>\n\
             <DataSet timestep=\"{t}\" group=\"\" part=\"1\" file=\"{gauss_name}\"/>\n"
        ));
    }
    pvd.push_str("</Collection>\n</VTKFile>\n");
    let path = dir.join("steps.pvd");
    crate::atomic::write(&path, pvd)?;
    Ok(traj.fields.len())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The elastic compliance read from a material's blocks (Plastic, Prony) is the
    /// stress-only `Elastic` law's own at the same E and nu, to round-off.
    #[test]
    fn elastic_compliance_of_internal_variable_laws_is_the_elastic_one() {
        use crate::config::LawSpec;
        let elastic = indentify_laws::Elastic;
        let c = [20000.0, 0.3];
        let want = indentify_laws::Law::compliance(&elastic, &c);
        for text in [
            "Plastic(E: 20000.0, nu: 0.3, sY: 150.0, hardening: Linear(H: 3000.0))",
            "Plastic(E: 20000.0, nu: 0.3, sY: 150.0, hardening: Voce(Q: 50.0, b: 20.0), \
             rate: Norton(K: 100.0, m: 3.0))",
            "Prony(E: 20000.0, nu: 0.3, terms: [(g: 0.3, tau: 1.0), (g: 0.2, tau: 10.0)])",
        ] {
            let spec: LawSpec = ron::from_str(text).unwrap();
            let (m, p) = spec.build().unwrap();
            assert!(m.as_law().is_none() && m.n_internal() > 0, "{text}");
            let got = elastic_compliance(&*m, &p);
            for a in 0..4 {
                for b in 0..4 {
                    let (g, w) = (got.0[a][b], want.0[a][b]);
                    assert!(
                        (g - w).abs() <= 1e-15 * want.0[0][0].abs(),
                        "{text}: {a},{b}: {g} vs {w}"
                    );
                }
            }
        }
    }

    #[test]
    fn negative_zero_is_written_as_zero() {
        assert_eq!(csv_number(-0.0), "0");
        assert_eq!(csv_number(-1.5), "-1.5");
    }

    #[test]
    fn csv_has_the_header_and_one_line_per_row() {
        let rows = [
            CurveRow {
                t: 0.0,
                h: 0.0,
                f: 0.0,
                a: 0.0,
            },
            CurveRow {
                t: 0.5,
                h: 0.05,
                f: 12.5,
                a: 0.01,
            },
        ];
        let mut buf = Vec::new();
        write_curve_csv(&mut buf, &rows).unwrap();
        assert_eq!(
            String::from_utf8(buf).unwrap(),
            "t,h,F,a\n0,0,0,0\n0.5,0.05,12.5,0.01\n"
        );
    }

    #[test]
    fn physical_components_undo_the_mandel_weight() {
        let p = physical(&Vec4([1.0, 2.0, 3.0, 4.0 * SQRT2]));
        assert!((p[3] - 4.0).abs() < 1e-14);
    }
}
