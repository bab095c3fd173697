//! A synthetic map of indents for the batch runner and its tests: an `n x n` grid over a
//! two-phase Maxwell material (a round inclusion of phase B in a matrix of phase A), each
//! indent's curve simulated on R1's set-up and perturbed by multiplicative noise, written
//! as `t,h,F` records with a manifest (`id,data,x,y`) and a base configuration that
//! identifies (E, eta) by Levenberg-Marquardt from a start between the phases.

use std::path::{Path, PathBuf};

use indentify_contact::{DirectSolver, trapezoid};
use indentify_identify::multiplicative_noise;

use crate::config::{History, MethodName, ParamSetting, Reference, ScalingName, Specimen};
use crate::error::{Classify, Error, ErrorKind, Result};
use crate::identify::prepare;
use crate::output;

/// Phase A (matrix): `(E, eta)` in (MPa, MPa s).
pub const PHASE_A: (f64, f64) = (20000.0, 30000.0);
/// Phase B (inclusion): `(E, eta)`.
pub const PHASE_B: (f64, f64) = (60000.0, 8000.0);

/// How to make the map.
#[derive(Clone, Debug)]
pub struct MapOptions {
    /// Indents per side.
    pub n: usize,
    /// Indent spacing (mm): the map's positions.
    pub spacing: f64,
    /// Multiplicative noise amplitude (0.02 = +-2%).
    pub noise: f64,
    /// Seed of the first indent's noise (indent k uses `seed + k`).
    pub seed: u64,
    /// A coarse model (8 x 8 elements, 10 steps per segment) for fast tests; otherwise R1's
    /// (20 x 20, 30 steps per segment).
    pub coarse: bool,
}

impl Default for MapOptions {
    /// The 10 x 10 map of `cargo xtask make-map`: 2% noise, R1's model.
    fn default() -> Self {
        MapOptions {
            n: 10,
            spacing: 0.05,
            noise: 0.02,
            seed: 1,
            coarse: false,
        }
    }
}

/// What [`make_map`] wrote.
#[derive(Clone, Debug)]
pub struct MapFiles {
    /// manifest.csv.
    pub manifest: PathBuf,
    /// base.ron.
    pub base: PathBuf,
    /// Per indent: id, position, phase (`'A'` or `'B'`).
    pub indents: Vec<(String, f64, f64, char)>,
}

/// The phase at grid cell `(i, j)` of an `n x n` map: B inside the disk of radius
/// `0.3 n` cells around the centre.
pub fn phase(i: usize, j: usize, n: usize) -> char {
    let c = (n as f64 - 1.0) / 2.0;
    let (di, dj) = (i as f64 - c, j as f64 - c);
    if (di * di + dj * dj).sqrt() <= 0.3 * n as f64 {
        'B'
    } else {
        'A'
    }
}

/// The base configuration of the map: R1's set-up (coarse or not) identifying E and eta
/// from (35000, 15000) by Levenberg-Marquardt.
pub fn base_config(coarse: bool) -> crate::config::Config {
    let mut cfg = Reference::R1Maxwell.config();
    if coarse {
        if let Specimen::Cylinder { nr, nz, .. } = &mut cfg.specimen {
            *nr = 8;
            *nz = 8;
        }
        cfg.history = Some(History {
            segments: trapezoid(0.1, 1.0, 1.0, 1.0, 10)
                .into_iter()
                .map(Into::into)
                .collect(),
        });
    }
    let mut id = Reference::R1Maxwell.identify_section();
    let free = |start: f64, lower: f64, upper: f64| ParamSetting::Free {
        start: Some(start),
        lower: Some(lower),
        upper: Some(upper),
        scaling: Some(ScalingName::Log),
    };
    id.params.insert("E".into(), free(35000.0, 1e3, 1e6));
    id.params.insert("eta".into(), free(15000.0, 1e2, 1e7));
    id.method = MethodName::Lm;
    id.stop.relative_decrease_tol = 1e-8;
    id.stop.max_iterations = 40;
    cfg.identify = Some(id);
    cfg
}

/// Writes the map into `dir`: `records/<id>.csv`, `manifest.csv`, `base.ron`.
///
/// # Errors
/// An unwritable folder, a size of 0, a noise amplitude outside [0, 1), a failing
/// simulation.
pub fn make_map(dir: &Path, o: &MapOptions) -> Result<MapFiles> {
    if o.n == 0 || !(0.0..1.0).contains(&o.noise) || !(o.spacing > 0.0) {
        return Err(Error::msg(
            ErrorKind::Config,
            format!(
                "a map needs n >= 1 (got {}), a noise amplitude in [0, 1) (got {}) and a \
                 spacing > 0 (got {})",
                o.n, o.noise, o.spacing
            ),
        ));
    }
    let records = dir.join("records");
    crate::atomic::ensure_writable_dir(&records).kind(ErrorKind::Io)?;
    let cfg = base_config(o.coarse);
    let prepared = prepare(&cfg, "synthetic map")?;
    let (law, _) = cfg.law.build().kind(ErrorKind::Config)?;
    let law = &law;
    let mut solver = DirectSolver::new(&prepared.model).kind(ErrorKind::Solver)?;
    let opts = cfg.solver.options(false);
    let mut curves = std::collections::HashMap::new();
    for (p, (e, eta)) in [('A', PHASE_A), ('B', PHASE_B)] {
        let params = [e, 0.3, eta];
        let traj = solver
            .run(&**law, &params, &prepared.schedule, &opts)
            .map_err(|e| Error::new(ErrorKind::Solver, anyhow::anyhow!(e)))?;
        curves.insert(p, output::curve(&prepared.schedule, &traj));
    }
    let mut manifest = String::from("id,data,x,y,phase\n");
    let mut indents = Vec::new();
    for i in 0..o.n {
        for j in 0..o.n {
            let k = i * o.n + j;
            let id = format!("p{i:02}_{j:02}");
            let ph = phase(i, j, o.n);
            let mut rows = curves[&ph].clone();
            let f: Vec<f64> = rows.iter().map(|r| r.f).collect();
            for (r, f) in rows
                .iter_mut()
                .zip(multiplicative_noise(&f, o.noise, o.seed + k as u64))
            {
                r.f = f;
            }
            output::write_curve(Some(&records.join(format!("{id}.csv"))), &rows)
                .kind(ErrorKind::Io)?;
            let (x, y) = (j as f64 * o.spacing, i as f64 * o.spacing);
            manifest.push_str(&format!("{id},records/{id}.csv,{x},{y},{ph}\n"));
            indents.push((id, x, y, ph));
        }
    }
    // `phase` is a column the batch does not know: keep it as a comment-free extra file
    let manifest_path = dir.join("manifest.csv");
    let plain: String = manifest
        .lines()
        .map(|l| l.rsplit_once(',').map_or(l, |(a, _)| a).to_string() + "\n")
        .collect();
    crate::atomic::write(&manifest_path, plain).kind(ErrorKind::Io)?;
    crate::atomic::write(&dir.join("phases.csv"), manifest).kind(ErrorKind::Io)?;
    let base = dir.join("base.ron");
    let text = crate::templates::annotated(
        &cfg,
        &[
            "Base configuration of a synthetic two-phase Maxwell map (indentify_study::synthetic)."
                .into(),
            format!(
                "Phase A: E = {} MPa, eta = {} MPa s; phase B: E = {} MPa, eta = {} MPa s; \
                 noise +-{}%.",
                PHASE_A.0,
                PHASE_A.1,
                PHASE_B.0,
                PHASE_B.1,
                100.0 * o.noise
            ),
        ],
    );
    crate::atomic::write(&base, text).kind(ErrorKind::Io)?;
    debug_assert_eq!(cfg.law.variant(), "Maxwell");
    Ok(MapFiles {
        manifest: manifest_path,
        base,
        indents,
    })
}
