//! CalculiX under a concentrated force: the load-controlled referee of `cargo xtask calculix
//! --drive force` (docs/validation-load-control.md §11).
//!
//! The deck is the depth-controlled one ([`super::deck`]: our mesh node for node, the rigid
//! cone's strip of CAX4, node-to-surface penalty contact, the same materials) with the
//! punch made a rigid body driven by a force: every node of the strip keeps `u_r = 0`, and
//! `*EQUATION`s tie their `u_z` to the reference node (the strip's top node on the axis
//! side), which carries the `*CLOAD` `-P(t)` through an `*AMPLITUDE` of the history's
//! corners (ramp, hold, unload). CalculiX's `*CLOAD` on an axisymmetric model is the force
//! on the full circle (measured: a load of 2 N gave reactions of 2/180 N on the 2-degree
//! wedge the CAX elements model).
//!
//! **Soft start.** At `P = 0` the cone touches the specimen at the tip only, where no slave
//! node is held (the axis face is not a slave face, [`super::slave_faces`]): the punch's
//! vertical motion has no stiffness and ccx stops in the first increment ("increment size
//! smaller than minimum" after cutting it to 1e-6 s). A soft spring holds the punch: one
//! CAX4 element of modulus [`spring_modulus`] between the strip's first top face and two
//! fixed nodes 1 mm above it (about [`SPRING_STIFFNESS`] N/mm, 1 N at 0.1 mm), and the
//! first increment is 1e-3 of a schedule step so that the spring alone does not push the
//! punch through the specimen before the contact holds it (with the full step, a 1 N/mm
//! spring let the punch fall 333 mm: no contact was ever found). CalculiX's reaction at
//! the spring's fixed nodes is printed, so the force the contact carried is known exactly,
//! `F_c = P - F_spring`, and **our run is driven by that `F_c`** at CalculiX's output
//! times ([`LoadHistory::from_force_record`]): both codes carry the same contact force, and
//! the depths compare the two discretizations and contact formulations only.

use std::fmt::Write as _;

use anyhow::{Result, bail};
use indentify_contact::{DirectSolver, HistorySegment, LoadHistory, Punch, Target};
use indentify_mesh::Mesh;

use super::{
    CASES, Case, DeckOptions, FiniteElastic, Material, PUNCH_THICKNESS, RunOptions, head_cards,
    our_sets, stem, uniform_step,
};

/// Nominal stiffness of the soft spring holding the punch (N/mm, full circle).
pub const SPRING_STIFFNESS: f64 = 10.0;

/// Length of the soft spring element (mm).
pub const SPRING_LENGTH: f64 = 1.0;

/// The first increment of the first step, as a fraction of the schedule's step.
pub const FIRST_INCREMENT: f64 = 1e-3;

/// The peak force (N) of a load-controlled case: about the force of the depth-controlled
/// case at 0.1 mm (R0 360 N, R1 313 N, R2 513 N, R2 sY = 0 386 N,
/// docs/validation-contact.md §9), rounded.
pub fn peak_force(case: &str) -> Option<f64> {
    match case {
        "r0" | "r0-nu049" => Some(360.0),
        "r1" => Some(300.0),
        "r2" => Some(500.0),
        "r2-sy0" => Some(380.0),
        _ => None,
    }
}

/// The history of every load-controlled case: the force ramped to `p_max` in 1 s, held
/// 1 s, unloaded to `0.4 p_max` in 1 s, 30 steps each (the depth-controlled trapezoid's
/// grid; the unloading stops short of zero, where the depth is undetermined).
///
/// # Errors
/// A force that is not finite and > 0.
pub fn force_history(p_max: f64) -> Result<LoadHistory> {
    let seg = |force| HistorySegment {
        duration: 1.0,
        depth: None,
        force: Some(force),
        steps: 30,
    };
    Ok(LoadHistory::from_segments(&[
        seg(p_max),
        seg(p_max),
        seg(0.4 * p_max),
    ])?)
}

/// The prescribed force's corners `(t, P)`: the start (0, 0) and every segment's end.
pub fn force_corners(history: &LoadHistory) -> Vec<(f64, f64)> {
    let mut out = vec![(history.schedule.t[0], 0.0)];
    let mut last = 0.0;
    for &(t, target) in &history.ends {
        if let Target::Force(f) = target {
            last = f;
        }
        out.push((t, last));
    }
    out
}

/// The modulus (MPa, `nu = 0`) of the spring element between radii `r0` and `r1` whose
/// axial stiffness `E pi (r1^2 - r0^2) / L` is `stiffness` (N/mm); the element's bottom
/// face is sloped with the cone, so its shear adds to that: the deck's spring force is
/// read from CalculiX's reactions, never computed from this.
pub fn spring_modulus(stiffness: f64, r0: f64, r1: f64) -> f64 {
    stiffness * SPRING_LENGTH / (std::f64::consts::PI * (r1 * r1 - r0 * r0))
}

/// The CalculiX deck of `mesh` under the rigid cone of `punch` pressed by the force of
/// `history` (load-controlled segments only) on its reference node (module documentation).
///
/// Nodes: the specimen's `1..=n0`, the strip's flank `n0 + 1 + j` and top
/// `n0 + np + 2 + j` (`j = 0..=np`, `np` = [`DeckOptions::punch_segments`]); the reference
/// node is the top node `j = 0`, the spring's fixed nodes are `n0 + 2 np + 3` and
/// `n0 + 2 np + 4`.
///
/// # Errors
/// A punch other than a cone, a history with a depth-controlled segment or non-uniform
/// steps, a J2 material under the user material.
pub fn deck(
    title: &str,
    mesh: &Mesh,
    punch: &Punch,
    material: &Material,
    history: &LoadHistory,
    o: &DeckOptions,
) -> Result<String> {
    let Punch::Cone { half_angle_deg } = punch else {
        bail!(
            "the CalculiX decks model a cone; {} is not one",
            punch.describe()
        )
    };
    if history.ends.iter().any(|e| matches!(e.1, Target::Depth(_))) {
        bail!("the load-controlled deck prescribes the force in every segment");
    }
    if o.load_substeps == 0 {
        bail!("load_substeps = 0: expected at least 1 increment per schedule step");
    }
    let schedule = &history.schedule;
    let cot = 1.0 / half_angle_deg.to_radians().tan();
    let dt = uniform_step(schedule)?;
    let t_end = schedule.t[schedule.t.len() - 1];
    let corners = force_corners(history);
    let p_ref = corners.iter().map(|c| c.1).fold(0.0, f64::max);
    let mut s = String::new();
    let w = &mut s;
    head_cards(w, title, mesh, cot, material, o)?;
    let (n0, np) = (mesh.nodes.len(), o.punch_segments);
    let reference = n0 + np + 2;
    // the soft spring: one CAX4 above the strip's first top face, its top nodes fixed
    let r1 = o.punch_radius / np as f64;
    let (s0, s1) = (n0 + 2 * np + 3, n0 + 2 * np + 4);
    let top = |r: f64| r * cot + PUNCH_THICKNESS + SPRING_LENGTH;
    writeln!(
        w,
        "** the soft spring holding the punch at the start (xtask/src/calculix/force.rs)"
    )?;
    writeln!(w, "*NODE, NSET=SPRTOP")?;
    writeln!(
        w,
        "{s0}, {:.12e}, {:.12e}, 0.0",
        o.punch_r_min,
        top(o.punch_r_min)
    )?;
    writeln!(w, "{s1}, {r1:.12e}, {:.12e}, 0.0", top(r1))?;
    let e_spring = mesh.elements.len() + np + 1;
    writeln!(w, "*ELEMENT, TYPE=CAX4, ELSET=ESPRING")?;
    writeln!(w, "{e_spring}, {reference}, {}, {s1}, {s0}", reference + 1)?;
    writeln!(w, "*MATERIAL, NAME=SOFT")?;
    writeln!(w, "*ELASTIC")?;
    writeln!(
        w,
        "{:.12e}, 0.0",
        spring_modulus(SPRING_STIFFNESS, o.punch_r_min, r1)
    )?;
    writeln!(w, "*SOLID SECTION, ELSET=ESPRING, MATERIAL=SOFT")?;
    writeln!(w, "*NSET, NSET=REF")?;
    writeln!(w, "{reference},")?;
    // the rigid punch: every strip node's u_z is the reference node's
    writeln!(w, "*EQUATION")?;
    for n in n0 + 1..=n0 + 2 * np + 2 {
        if n != reference {
            writeln!(w, "2")?;
            writeln!(w, "{n}, 2, 1.0, {reference}, 2, -1.0")?;
        }
    }
    let total = if o.split_load {
        ", TIME=TOTAL TIME"
    } else {
        ""
    };
    writeln!(w, "*AMPLITUDE, NAME=FORCE{total}")?;
    for (t, p) in &corners {
        writeln!(w, "{t:.12e}, {:.12e}", p / p_ref)?;
    }
    writeln!(w, "*BOUNDARY")?;
    writeln!(w, "AXIS, 1, 1")?;
    writeln!(w, "BOTTOM, 2, 2")?;
    writeln!(w, "PUNCH, 1, 1")?;
    writeln!(w, "SPRTOP, 1, 2")?;
    writeln!(w, "*TIME POINTS, NAME=TP{total}")?;
    for t in &schedule.t[1..] {
        writeln!(w, "{t:.12e}")?;
    }
    let n_inc = 200 * schedule.t.len();
    let procedure = match material {
        Material::Elastic { .. } | Material::Plastic { .. } => "*STATIC",
        Material::Viscoplastic { .. } => "*VISCO, CETOL=1.0",
    };
    // as the depth-controlled deck: one step, or the loading and the rest (split_load)
    let steps: Vec<f64> = match corners.get(1) {
        Some(&(t1, _)) if o.split_load && t1 < t_end => vec![t1, t_end - t1],
        _ => vec![t_end],
    };
    for (k, duration) in steps.into_iter().enumerate() {
        let (first, max) = if k == 0 {
            let max = dt / o.load_substeps as f64;
            (max * FIRST_INCREMENT, max)
        } else {
            (dt, dt)
        };
        if o.nlgeom {
            writeln!(w, "*STEP, NLGEOM, INC={n_inc}")?;
        } else {
            writeln!(w, "*STEP, INC={n_inc}")?;
        }
        writeln!(w, "*CONTROLS, PARAMETERS=TIME INCREMENTATION")?;
        writeln!(w, "20, 30, 9, 200, 10, 4, , 20")?;
        writeln!(w, "{procedure}")?;
        writeln!(
            w,
            "{first:.12e}, {duration:.12e}, {:.12e}, {max:.12e}",
            dt * 1e-7
        )?;
        writeln!(w, "*CLOAD, AMPLITUDE=FORCE")?;
        writeln!(w, "{reference}, 2, {:.12e}", -p_ref)?;
        writeln!(w, "*NODE PRINT, NSET=REF, TIME POINTS=TP")?;
        writeln!(w, "U")?;
        writeln!(w, "*NODE PRINT, NSET=SPRTOP, TOTALS=ONLY, TIME POINTS=TP")?;
        writeln!(w, "RF")?;
        writeln!(w, "*END STEP")?;
    }
    Ok(s)
}

/// A raw output time of CalculiX: `(t, h, F_spring)` (s, mm, N).
pub type Raw = (f64, f64, f64);

/// One output time of a load-controlled CalculiX run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Point {
    /// Time (s).
    pub t: f64,
    /// Punch depth: the reference node's downward displacement (mm).
    pub h: f64,
    /// The prescribed force `P(t)` (N).
    pub p: f64,
    /// The force the contact carried, `P - F_spring` (N).
    pub f_contact: f64,
}

/// Reads the reference node's displacement and the spring's reaction from a `.dat`:
/// `(t, h, F_spring)` (mm, N on the full circle, `F_spring = 180 RF_y` of `SPRTOP`:
/// upward on the punch when it has moved down).
///
/// # Errors
/// A block without its values, a time with only one of the two.
pub fn parse_dat(text: &str) -> Result<Vec<(f64, f64, f64)>> {
    let mut h: Vec<(f64, f64)> = Vec::new();
    let mut f: Vec<(f64, f64)> = Vec::new();
    let displacement = |l: &str| l.starts_with("displacements") && l.contains("set REF");
    let spring = |l: &str| l.starts_with("total force") && l.contains("set SPRTOP");
    for b in super::dat_blocks(text, |l| displacement(l) || spring(l))? {
        let (l, values, v) = (b.header, b.raw, &b.values);
        if displacement(l) {
            // node, ux, uy, uz
            if v.len() < 3 {
                bail!("cannot read the displacement `{values}` after `{l}`");
            }
            h.push((b.t, -v[2]));
        } else {
            if v.len() < 2 {
                bail!("cannot read the total force `{values}` after `{l}`");
            }
            f.push((b.t, 180.0 * v[1]));
        }
    }
    if h.len() != f.len() {
        bail!(
            "{} displacements of REF but {} spring forces",
            h.len(),
            f.len()
        );
    }
    h.iter()
        .zip(&f)
        .map(|(&(t, h), &(tf, fs))| {
            if (t - tf).abs() > 1e-9 * t.abs().max(1.0) {
                bail!("a displacement at t = {t} s beside a spring force at t = {tf} s");
            }
            Ok((t, h, fs))
        })
        .collect()
}

/// The points of a run: CalculiX's `(t, h, F_spring)` with the prescribed force of
/// `corners` (linear between them).
pub fn points(raw: &[(f64, f64, f64)], corners: &[(f64, f64)]) -> Vec<Point> {
    raw.iter()
        .map(|&(t, h, fs)| {
            let p = super::at(corners, t).unwrap_or(f64::NAN);
            Point {
                t,
                h,
                p,
                f_contact: p - fs,
            }
        })
        .collect()
}

/// CalculiX's curve as CSV text (`t_s,h_mm,P_N,F_contact_N`).
pub fn points_csv(points: &[Point]) -> String {
    let mut s = String::from("t_s,h_mm,P_N,F_contact_N\n");
    for p in points {
        let _ = writeln!(s, "{:.6},{:.9e},{:.9e},{:.9e}", p.t, p.h, p.p, p.f_contact);
    }
    s
}

/// Reads a curve written by [`points_csv`].
///
/// # Errors
/// A malformed line.
pub fn read_points_csv(text: &str) -> Result<Vec<Point>> {
    text.lines()
        .skip(1)
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let v: Vec<f64> = l
                .split(',')
                .map(|x| x.trim().parse::<f64>())
                .collect::<Result<_, _>>()
                .map_err(|e| anyhow::anyhow!("malformed line `{l}`: {e}"))?;
            match v[..] {
                [t, h, p, f_contact] => Ok(Point { t, h, p, f_contact }),
                _ => bail!("malformed line `{l}`: expected 4 values"),
            }
        })
        .collect()
}

/// Our curve as CSV text (`t_s,h_mm,F_N`).
pub fn ours_csv(curve: &[(f64, f64, f64)]) -> String {
    let mut s = String::from("t_s,h_mm,F_N\n");
    for (t, h, f) in curve {
        let _ = writeln!(s, "{t:.6},{h:.9e},{f:.9e}");
    }
    s
}

/// Reads a curve written by [`ours_csv`].
///
/// # Errors
/// A malformed line.
pub fn read_ours_csv(text: &str) -> Result<Vec<(f64, f64, f64)>> {
    text.lines()
        .skip(1)
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let v: Vec<f64> = l
                .split(',')
                .map(|x| x.trim().parse::<f64>())
                .collect::<Result<_, _>>()
                .map_err(|e| anyhow::anyhow!("malformed line `{l}`: {e}"))?;
            match v[..] {
                [t, h, f] => Ok((t, h, f)),
                _ => bail!("malformed line `{l}`: expected 3 values"),
            }
        })
        .collect()
}

/// Our run of `case` (friction, finite strain) driven by the contact force CalculiX's
/// punch carried at its output times: `(t, h, F)` at every schedule time.
///
/// # Errors
/// A configuration that cannot be loaded, a force that is not > 0, our run failing.
pub fn ours(
    root: &std::path::Path,
    case: &Case,
    friction: f64,
    nlgeom: bool,
    ccx: &[Point],
) -> Result<Vec<(f64, f64, f64)>> {
    let source = indentify_study::source::ConfigSource::Path(root.join(case.example));
    let cfg = source.load(&our_sets(case, friction, nlgeom))?;
    let prepared = cfg.prepare(case.name)?;
    let (law, params) = cfg.law.build()?;
    let opts = cfg.solver.options(false);
    let t: Vec<f64> = std::iter::once(0.0)
        .chain(ccx.iter().map(|p| p.t))
        .collect();
    let f: Vec<f64> = std::iter::once(0.0)
        .chain(ccx.iter().map(|p| p.f_contact))
        .collect();
    let history = LoadHistory::from_force_record(&t, &f)?;
    let mut solver = DirectSolver::new(&prepared.model)?;
    let traj = solver.run_history(&*law, &params, &history, &opts)?;
    Ok(traj
        .schedule_steps()
        .map(|s| (s.t, s.depth, s.force))
        .collect())
}

/// The stem of a load-controlled run: the depth-controlled stem with `-load`
/// (`r1-mu0.1-nlgeom-load`).
pub fn load_stem(case: &str, friction: f64, nlgeom: bool) -> String {
    format!("{}-load", stem(case, friction, nlgeom))
}

/// The stem of a load-controlled run whose CalculiX material under `NLGEOM` is chosen by
/// `elastic` ([`FiniteElastic::suffix`] where it applies to `material`): the files of
/// `cargo xtask calculix --drive force` (`r2-nlgeom-hencky-load` for R2 with our law as
/// CalculiX's user material, `r2-nlgeom-load` with CalculiX's own).
pub fn material_load_stem(
    case: &str,
    friction: f64,
    nlgeom: bool,
    elastic: FiniteElastic,
    material: &Material,
) -> String {
    let suffix = if nlgeom && elastic.applies_to(material) {
        elastic.suffix()
    } else {
        ""
    };
    format!("{}{suffix}-load", stem(case, friction, nlgeom))
}

/// The comparison of one run: the depths at the peak (t = 1 s), at the end of the hold
/// (t = 2 s) and at the end (t = 3 s), ours against CalculiX's, and the worst
/// `|h_ours - h_ccx| / h_max` over every common time.
#[derive(Clone, Debug, PartialEq)]
pub struct Comparison {
    /// `(t, h_ours, h_ccx)` at 1, 2 and 3 s where both exist.
    pub at: Vec<(f64, f64, f64)>,
    /// Worst `|h_ours - h_ccx| / h_max` over the common times, and its time.
    pub worst: (f64, f64),
    /// Largest `F_spring / P` of CalculiX's run (the share of the soft spring).
    pub spring_share: f64,
    /// The last time CalculiX reached (s).
    pub reached: f64,
}

/// Compares our curve with CalculiX's at their common times.
pub fn compare(ccx: &[Point], ours: &[(f64, f64, f64)]) -> Comparison {
    let h_max = ccx.iter().map(|p| p.h).fold(0.0, f64::max);
    let mut worst = (0.0, f64::NAN);
    let mut at = Vec::new();
    for p in ccx {
        let Some(o) = ours.iter().find(|o| (o.0 - p.t).abs() < 1e-6) else {
            continue;
        };
        let d = (o.1 - p.h).abs() / h_max;
        if d > worst.0 {
            worst = (d, p.t);
        }
        if [1.0, 2.0, 3.0].iter().any(|t| (p.t - t).abs() < 1e-6) {
            at.push((p.t, o.1, p.h));
        }
    }
    let spring_share = ccx
        .iter()
        .filter(|p| p.p > 0.0)
        .map(|p| (p.p - p.f_contact) / p.p)
        .fold(0.0, f64::max);
    Comparison {
        at,
        worst,
        spring_share,
        reached: ccx.last().map_or(0.0, |p| p.t),
    }
}

/// A Markdown row of [`Comparison`].
pub fn table_row(stem: &str, c: &Comparison, note: &str) -> String {
    let mut row = format!("| {stem} |");
    for t in [1.0, 2.0, 3.0] {
        match c.at.iter().find(|a| (a.0 - t).abs() < 1e-6) {
            Some(&(_, o, x)) => {
                let _ = write!(
                    row,
                    " {o:.5} / {x:.5} mm: **{:+.2}%** |",
                    100.0 * (o / x - 1.0)
                );
            }
            None => row.push_str(" - |"),
        }
    }
    let _ = write!(
        row,
        " {:.2}% (t = {:.3} s) | {:.2}% | {} | {note} |",
        100.0 * c.worst.0,
        c.worst.1,
        100.0 * c.spring_share,
        if c.reached >= 3.0 - 1e-6 {
            "end".to_string()
        } else {
            format!("t = {:.3} s", c.reached)
        }
    );
    row
}

/// Runs the load-controlled cases: writes the decks `STEM-load.inp`, runs `ccx` (or reuses
/// `STEM-load.csv`), then our run driven by CalculiX's contact force (or reuses
/// `STEM-load-ours.csv`), and returns the comparison as a Markdown table.
///
/// # Errors
/// An unknown case or one without a load-controlled history, a deck that cannot be
/// written.
pub fn run(o: &RunOptions) -> Result<String> {
    std::fs::create_dir_all(&o.out)?;
    let mut table = String::from(
        "| run | h at t = 1 s (peak), ours / ccx | t = 2 s (end of hold) | t = 3 s (unloaded to 0.4 P) | worst \\|dh\\| / h_max | spring share | ccx reached | notes |\n|---|---|---|---|---|---|---|---|\n",
    );
    for name in &o.cases {
        let case = CASES.iter().find(|c| c.name == name).ok_or_else(|| {
            anyhow::anyhow!("unknown case `{name}`: expected r0, r1, r2 or r2-sy0")
        })?;
        let p_max = peak_force(case.name).ok_or_else(|| {
            anyhow::anyhow!(
                "case `{name}` has no load-controlled history: expected r0, r1, r2 or r2-sy0"
            )
        })?;
        let loaded = super::load(&o.root, case)?;
        let history = force_history(p_max)?;
        let corners = force_corners(&history);
        for &nlgeom in &o.kinematics {
            for &mu in &o.frictions {
                let stem = material_load_stem(
                    case.name,
                    mu,
                    nlgeom,
                    o.deck.finite_elastic,
                    &loaded.material,
                );
                let opts = DeckOptions {
                    nlgeom,
                    friction: mu,
                    ..o.deck
                };
                let text = deck(
                    &format!("{} ({}) under a force, {stem}", case.name, case.example),
                    &loaded.prepared.model.mesh,
                    &loaded.prepared.model.punch,
                    &loaded.material,
                    &history,
                    &opts,
                )?;
                std::fs::write(o.out.join(format!("{stem}.inp")), &text)?;
                if o.decks_only {
                    continue;
                }
                let mut notes = Vec::new();
                let ccx_path = o.out.join(format!("{stem}.csv"));
                let ccx = if (o.reuse || o.no_ccx) && ccx_path.exists() {
                    read_points_csv(&std::fs::read_to_string(&ccx_path)?)?
                } else if o.no_ccx {
                    let _ = writeln!(table, "| {stem} | - | - | - | - | - | - | ccx not run |");
                    continue;
                } else {
                    let t0 = std::time::Instant::now();
                    match run_ccx(&o.ccx, &o.out, &stem, &text) {
                        Ok((raw, stopped)) => {
                            eprintln!(
                                "{stem}: ccx in {:.1} s, {} points{}",
                                t0.elapsed().as_secs_f64(),
                                raw.len(),
                                stopped
                                    .as_ref()
                                    .map(|s| format!(", stopped: {s}"))
                                    .unwrap_or_default()
                            );
                            if let Some(s) = stopped {
                                notes.push(format!("ccx stopped: {s}"));
                            }
                            // our run reads the curve as committed (the CSV's digits),
                            // so that xtask/tests/calculix_force.rs repeats it exactly
                            let text = points_csv(&points(&raw, &corners));
                            std::fs::write(&ccx_path, &text)?;
                            read_points_csv(&text)?
                        }
                        Err(e) => {
                            eprintln!("{stem}: {e:#}");
                            let _ = writeln!(
                                table,
                                "| {stem} | - | - | - | - | - | - | ccx failed: {e} |"
                            );
                            continue;
                        }
                    }
                };
                let ours_path = o.out.join(format!("{stem}-ours.csv"));
                let mine = if o.reuse && ours_path.exists() {
                    Some(read_ours_csv(&std::fs::read_to_string(&ours_path)?)?)
                } else {
                    let t0 = std::time::Instant::now();
                    match ours(&o.root, case, mu, nlgeom, &ccx) {
                        Ok(c) => {
                            eprintln!("{stem}: ours in {:.1} s", t0.elapsed().as_secs_f64());
                            std::fs::write(&ours_path, ours_csv(&c))?;
                            Some(c)
                        }
                        Err(e) => {
                            eprintln!("{stem}: ours: {e:#}");
                            notes.push(format!("ours: {e}"));
                            None
                        }
                    }
                };
                let c = compare(&ccx, mine.as_deref().unwrap_or(&[]));
                let _ = writeln!(table, "{}", table_row(&stem, &c, &notes.join("; ")));
            }
        }
    }
    Ok(table)
}

/// Runs `ccx` on a load-controlled deck in a scratch folder under `out`: the points
/// `(t, h, F_spring)` and, if `ccx` stopped before the end, why.
///
/// # Errors
/// `ccx` missing, a `.dat` file without the reference node's displacement.
pub fn run_ccx(
    ccx: &std::path::Path,
    out: &std::path::Path,
    stem: &str,
    deck: &str,
) -> Result<(Vec<Raw>, Option<String>)> {
    super::run_ccx_reading(ccx, (out, stem), deck, "depth", parse_dat)
}
