//! The default mesh and step study (docs/discretization.md): the force of a configuration on its
//! own mesh and time grid against the same problem refined 2x and 4x in the mesh (each
//! refinement as `indentify_study::discretization::refine_mesher`: counts doubled, gradings
//! square-rooted, nested) and in the steps (`refine_schedule`: segments' steps doubled, or
//! a record's midpoints inserted), with Richardson's extrapolation where the three levels
//! converge monotonically; candidate `Auto()` options measured the same way.
//! `cargo xtask mesh-study` prints the tables of docs/discretization.md.

use std::fmt::Write as _;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use indentify_contact::punch::{AutoOptions, auto_specimen};
use indentify_contact::{DirectSolver, Model, Schedule};
use indentify_study::config::{Config, History, Mesher};
use indentify_study::discretization::{refine_mesher, refine_schedule};

/// One forward run of the study.
#[derive(Clone, Debug)]
pub struct Run {
    /// What the run is (`mesh x2, steps x1`, `Auto(16, 48, 1.5)`).
    pub label: String,
    /// The mesh, described.
    pub mesh: String,
    /// Elements.
    pub elements: usize,
    /// Time steps.
    pub steps: usize,
    /// The force (N) at the probe times.
    pub forces: Vec<f64>,
    /// Wall time of the forward run (s).
    pub seconds: f64,
    /// The largest contact radius of the run (mm).
    pub contact_radius: f64,
}

/// A candidate automatic mesh: the `Auto()` options and the side of the uniform core in
/// contact-radius bounds (1: `auto_specimen`'s core; other values are studied by building
/// the zoned mesher directly).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Candidate {
    /// The `Auto()` options.
    pub options: AutoOptions,
    /// Core side over the contact-radius bound (1 = `auto_specimen`).
    pub core_factor: f64,
}

impl Candidate {
    /// `Auto(N, K, G)` or `Auto(N, K, G), core C a`.
    pub fn label(&self) -> String {
        let o = &self.options;
        let mut s = format!(
            "Auto({}, {}, {})",
            o.elements_in_contact, o.size_factor, o.grading
        );
        if self.core_factor != 1.0 {
            let _ = write!(s, ", core {} a", self.core_factor);
        }
        s
    }

    /// Parses `N:K:G` or `N:K:G:C` (elements in contact, size factor, grading, core factor).
    ///
    /// # Errors
    /// Another shape or a number that does not parse.
    pub fn parse(x: &str) -> Result<Candidate> {
        let p: Vec<&str> = x.split(':').collect();
        let (n, k, g, c) = match p.as_slice() {
            [n, k, g] => (n, k, g, "1"),
            [n, k, g, c] => (n, k, g, *c),
            _ => {
                bail!("--auto: `{x}` is not elements_in_contact:size_factor:grading[:core_factor]")
            }
        };
        Ok(Candidate {
            options: AutoOptions {
                elements_in_contact: n.parse()?,
                size_factor: k.parse()?,
                grading: g.parse()?,
            },
            core_factor: c.parse()?,
        })
    }

    /// The mesher of this candidate for `cfg`'s punch at the depth `h_max`.
    ///
    /// # Errors
    /// Options out of range; a core factor outside [0.5, 4] or one that leaves no far field.
    pub fn mesher(&self, cfg: &Config, h_max: f64) -> Result<Mesher> {
        let mut m = auto_specimen(&cfg.punch, h_max, &self.options)?;
        if !(0.5..=4.0).contains(&self.core_factor) {
            bail!(
                "core factor {}: expected a value in [0.5, 4]",
                self.core_factor
            );
        }
        m.core *= self.core_factor;
        m.validate()?;
        Ok(Mesher::Zoned(m))
    }
}

/// The study of one configuration.
#[derive(Clone, Debug)]
pub struct Study {
    /// The configuration's name.
    pub name: String,
    /// The probe times (s): the schedule's points nearest to 1/6, 1/3, 1/2 and 2/3 of its
    /// duration (0.5, 1, 1.5, 2 s on R0-R2), points of every refined schedule.
    pub times: Vec<f64>,
    /// Mesh refinements at the configuration's steps: x1, x2, x4 (as many as levels).
    pub mesh_series: Vec<Run>,
    /// Step refinements on the configuration's mesh: x1, x2, x4.
    pub step_series: Vec<Run>,
    /// The finest mesh with the finest steps: the reference.
    pub reference: Run,
    /// Candidate meshes (at the configuration's steps and, unless skipped, at the finest
    /// steps).
    pub candidates: Vec<(Run, Option<Run>)>,
    /// The contact-radius bound at the largest depth (mm): the core side of `Auto()`.
    pub a: f64,
    /// The model in words (contact, kinematics).
    pub model: String,
}

/// The mesher refined `k` times.
///
/// # Errors
/// A refinement past the mesher's limits.
pub fn refine_mesher_times(m: &Mesher, k: usize) -> Result<Mesher> {
    let mut m = *m;
    for _ in 0..k {
        m = refine_mesher(&m)?;
    }
    Ok(m)
}

/// The schedule with its steps halved `k` times (segments' steps doubled, or midpoints).
///
/// # Errors
/// A schedule that cannot be refined.
pub fn refine_schedule_times(
    history: Option<&History>,
    base: &Schedule,
    k: usize,
) -> Result<Schedule> {
    let mut s = base.clone();
    let mut h = history.cloned();
    for _ in 0..k {
        let (next, _) = refine_schedule(h.as_ref(), &s)?;
        if let Some(h) = h.as_mut() {
            for seg in &mut h.segments {
                seg.steps *= 2;
            }
        }
        s = next;
    }
    Ok(s)
}

/// The probe times of `schedule`: its points nearest to 1/6, 1/3, 1/2, 2/3 of its end.
pub fn probe_times(schedule: &Schedule) -> Vec<f64> {
    let t_end = schedule.t[schedule.t.len() - 1];
    [1.0 / 6.0, 1.0 / 3.0, 0.5, 2.0 / 3.0]
        .iter()
        .map(|f| {
            let target = f * t_end;
            schedule
                .t
                .iter()
                .copied()
                .min_by(|a, b| (a - target).abs().total_cmp(&(b - target).abs()))
                .unwrap_or(target)
        })
        .collect()
}

/// The force of a trajectory at `t` (a schedule time, matched to 1e-9 s relative).
fn force_at(t_grid: &[f64], forces: &[f64], t: f64) -> Result<f64> {
    let tol = 1e-9 * (1.0 + t.abs());
    t_grid
        .iter()
        .position(|x| (x - t).abs() <= tol)
        .and_then(|i| forces.get(i).copied())
        .ok_or_else(|| anyhow::anyhow!("the run did not reach t = {t} s"))
}

/// One forward run of `cfg`'s law and punch on `mesher` over `schedule`.
///
/// # Errors
/// A mesh, model or run that fails.
pub fn run_one(
    cfg: &Config,
    label: &str,
    mesher: &Mesher,
    schedule: &Schedule,
    times: &[f64],
) -> Result<Run> {
    let (law, params) = cfg.law.build()?;
    let (mesh, _, _) = mesher.build_for(&cfg.punch)?;
    let elements = mesh.elements.len();
    let model = Model::with_contact(mesh, cfg.punch.clone(), cfg.contact)?
        .with_kinematics(cfg.kinematics)?;
    let opts = cfg.solver.options(false);
    let clock = Instant::now();
    let mut solver = DirectSolver::new(&model)?;
    let traj = solver
        .run(&*law, &params, schedule, &opts)
        .with_context(|| format!("{label}: the forward run failed"))?;
    let seconds = clock.elapsed().as_secs_f64();
    let f = traj.forces();
    let forces = times
        .iter()
        .map(|&t| force_at(&schedule.t, &f, t))
        .collect::<Result<Vec<f64>>>()?;
    let contact_radius = traj
        .steps
        .iter()
        .map(|s| s.contact_radius)
        .fold(0.0, f64::max);
    // every run's result as it comes (a long study stopped early keeps what it measured)
    eprintln!(
        "run `{label}` [{}]: {elements} elements, {} steps, F = {forces:?} N at t = {times:?} s, \
         largest contact radius {contact_radius:.6e} mm, {seconds:.2} s",
        mesher.describe(),
        schedule.n_solver_steps()
    );
    Ok(Run {
        contact_radius,
        label: label.to_string(),
        mesh: mesher.describe(),
        elements,
        // the solver's steps: the schedule's with their sub-steps (data.substeps)
        steps: schedule.n_solver_steps(),
        forces,
        seconds,
    })
}

/// Richardson's extrapolation of three values on grids refined by 2: the observed order
/// `p = log2((f1 - f2)/(f2 - f4))` and `f4 + (f4 - f2)/(2^p - 1)`, when the differences
/// have the same sign and shrink (`None` otherwise: no asymptotic range).
pub fn richardson(f1: f64, f2: f64, f4: f64) -> Option<(f64, f64)> {
    let (d1, d2) = (f1 - f2, f2 - f4);
    if d1 == 0.0 || d2 == 0.0 || d1.signum() != d2.signum() || d2.abs() >= d1.abs() {
        return None;
    }
    let p = (d1 / d2).log2();
    Some((p, f4 + (f4 - f2) / (2f64.powf(p) - 1.0)))
}

/// What a study runs.
#[derive(Clone, Debug, PartialEq)]
pub struct StudyOptions {
    /// Refinement levels: 1 (the configuration's run only, against a given `reference`),
    /// 2 (x1, x2) or 3 (x1, x2, x4).
    pub levels: usize,
    /// Candidate `Auto()` meshes (automatic specimens only).
    pub candidates: Vec<Candidate>,
    /// Candidates also at the finest steps.
    pub candidates_fine_steps: bool,
    /// The reference as the finest mesh's force plus the change the finest steps make on
    /// the configuration's own mesh (errors taken as additive), instead of the finest mesh
    /// with the finest steps (when that run is too long).
    pub additive_reference: bool,
    /// A reference measured before (N, at the probe times): no refined runs.
    pub reference: Option<Vec<f64>>,
    /// Run the mesh refinements (false: the step refinements only, against the given
    /// reference or the finest steps).
    pub mesh_series: bool,
}

impl Default for StudyOptions {
    fn default() -> StudyOptions {
        StudyOptions {
            levels: 3,
            candidates: Vec::new(),
            candidates_fine_steps: true,
            additive_reference: false,
            reference: None,
            mesh_series: true,
        }
    }
}

/// Runs the study of `cfg` (already loaded with its overrides): its own run, its mesh and
/// steps refined `levels - 1` times, the reference and the candidate meshes (see
/// [`StudyOptions`]).
///
/// # Errors
/// A configuration that cannot be prepared, a run that fails, `levels` outside [1, 3],
/// one level without a reference, a reference of the wrong length.
pub fn study(cfg: &Config, name: &str, o: &StudyOptions) -> Result<Study> {
    let (levels, candidates, candidates_fine_steps, additive_reference) = (
        o.levels,
        &o.candidates,
        o.candidates_fine_steps,
        o.additive_reference,
    );
    if !(1..=3).contains(&levels) || (levels == 1 && o.reference.is_none()) {
        bail!("--levels {levels}: expected 2 or 3 (1 with a given --reference)");
    }
    let prepared = cfg.prepare(name)?;
    let base_mesher = prepared.mesher;
    let base = prepared.schedule;
    let times = probe_times(&base);
    let history = cfg.history.as_ref();
    let top = levels - 1;
    let mut mesh_series = Vec::new();
    let mesh_levels = if o.mesh_series { levels } else { 1 };
    for k in 0..mesh_levels {
        let m = refine_mesher_times(&base_mesher, k)?;
        let run = run_one(
            cfg,
            &format!("mesh x{}, steps x1", 1 << k),
            &m,
            &base,
            &times,
        )?;
        eprintln!(
            "{name}: {} ({} elements) in {:.1} s",
            run.label, run.elements, run.seconds
        );
        mesh_series.push(run);
    }
    let mut step_series = vec![mesh_series[0].clone()];
    for k in 1..levels {
        let s = refine_schedule_times(history, &base, k)?;
        let run = run_one(
            cfg,
            &format!("mesh x1, steps x{}", 1 << k),
            &base_mesher,
            &s,
            &times,
        )?;
        eprintln!("{name}: {} in {:.1} s", run.label, run.seconds);
        step_series.push(run);
    }
    let fine_schedule = refine_schedule_times(history, &base, top)?;
    let fine_mesher = refine_mesher_times(&base_mesher, top)?;
    let reference = if let Some(r) = &o.reference {
        if r.len() != times.len() {
            bail!(
                "--reference: {} forces given, {} probe times",
                r.len(),
                times.len()
            );
        }
        Run {
            label: "reference (given)".into(),
            mesh: String::new(),
            elements: 0,
            steps: 0,
            forces: r.clone(),
            seconds: 0.0,
            contact_radius: 0.0,
        }
    } else if !o.mesh_series {
        step_series[top].clone()
    } else if additive_reference {
        // the mesh and step errors taken as additive: the finest mesh's force plus the
        // change the finest steps make on the configuration's mesh
        let (m, st, b) = (&mesh_series[top], &step_series[top], &mesh_series[0]);
        Run {
            label: format!("reference: mesh x{0} + (steps x{0} - steps x1)", 1 << top),
            mesh: m.mesh.clone(),
            elements: m.elements,
            steps: st.steps,
            forces: (0..times.len())
                .map(|i| m.forces[i] + st.forces[i] - b.forces[i])
                .collect(),
            seconds: m.seconds + st.seconds,
            contact_radius: m.contact_radius,
        }
    } else {
        let r = run_one(
            cfg,
            &format!("mesh x{0}, steps x{0}", 1 << top),
            &fine_mesher,
            &fine_schedule,
            &times,
        )?;
        eprintln!("{name}: reference in {:.1} s", r.seconds);
        r
    };
    let mut cands = Vec::new();
    if matches!(base_mesher, Mesher::Zoned(_)) {
        let h_max = base.depth.iter().copied().fold(0.0, f64::max);
        for o in candidates {
            let m = o.mesher(cfg, h_max)?;
            let label = o.label();
            let a = run_one(cfg, &format!("{label}, steps x1"), &m, &base, &times)?;
            eprintln!(
                "{name}: {label} ({} elements) in {:.1} s",
                a.elements, a.seconds
            );
            let b = if candidates_fine_steps {
                let b = run_one(
                    cfg,
                    &format!("{label}, steps x{}", 1 << top),
                    &m,
                    &fine_schedule,
                    &times,
                )?;
                eprintln!("{name}: {label}, fine steps in {:.1} s", b.seconds);
                Some(b)
            } else {
                None
            };
            cands.push((a, b));
        }
    }
    Ok(Study {
        name: name.to_string(),
        times,
        mesh_series,
        step_series,
        reference,
        candidates: cands,
        a: cfg
            .punch
            .contact_radius_bound(base.depth.iter().copied().fold(0.0, f64::max)),
        model: cfg.describe_model(),
    })
}

/// `v` with 5 significant digits.
fn sig5(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return v.to_string();
    }
    let digits = (4 - v.abs().log10().floor() as i32).max(0) as usize;
    format!("{v:.digits$}")
}

fn row(s: &mut String, run: &Run, reference: &[f64], base_seconds: f64, a: f64) {
    let _ = write!(
        s,
        "| {} | {} | {} | {:.2} |",
        run.label,
        run.elements,
        run.steps,
        run.contact_radius / a
    );
    for (f, r) in run.forces.iter().zip(reference) {
        let _ = write!(s, " {} ({:+.2}%) |", sig5(*f), 100.0 * (f / r - 1.0));
    }
    let _ = writeln!(
        s,
        " {:.2} s ({:.1}x) |",
        run.seconds,
        run.seconds / base_seconds.max(1e-9)
    );
}

/// The study as Markdown: one table (force and its error against the reference at each
/// probe time, runtime and its ratio to the configuration's own run) and the Richardson
/// estimates.
pub fn render(st: &Study) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "#### {} ({}; a = {} mm)\n",
        st.name,
        st.model,
        sig5(st.a)
    );
    let _ = write!(s, "| run | elements | steps | max contact radius / a |");
    for t in &st.times {
        let _ = write!(s, " F(t = {t:.4} s), N (vs reference) |");
    }
    let _ = writeln!(s, " forward run |");
    let _ = writeln!(s, "|---|---|---|---|{}---|", "---|".repeat(st.times.len()));
    let r = &st.reference.forces;
    let base = st.mesh_series[0].seconds;
    for run in &st.mesh_series {
        row(&mut s, run, r, base, st.a);
    }
    for run in st.step_series.iter().skip(1) {
        row(&mut s, run, r, base, st.a);
    }
    row(&mut s, &st.reference, r, base, st.a);
    for (a, b) in &st.candidates {
        row(&mut s, a, r, base, st.a);
        if let Some(b) = b {
            row(&mut s, b, r, base, st.a);
        }
    }
    if st.mesh_series.len() == 3 {
        let _ = writeln!(s);
        for (what, series) in [("mesh", &st.mesh_series), ("steps", &st.step_series)] {
            let _ = write!(s, "Richardson ({what}, order; extrapolated error of x1):");
            for i in 0..st.times.len() {
                let f: Vec<f64> = series.iter().map(|r| r.forces[i]).collect();
                match richardson(f[0], f[1], f[2]) {
                    Some((p, inf)) => {
                        let _ = write!(s, " p = {p:.2}, {:+.2}%;", 100.0 * (f[0] / inf - 1.0));
                    }
                    None => {
                        let _ = write!(s, " not monotone;");
                    }
                }
            }
            let _ = writeln!(s);
        }
    }
    s
}
