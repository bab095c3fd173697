//! The RON configuration of a simulation (specimen, punch, law, history, solver options),
//! its `--set key.path=value` overrides and its validation, with errors naming the field.
//!
//! Loading goes text -> typed [`Config`] (serde/ron, `deny_unknown_fields` everywhere, so
//! a mistyped or missing field is an error with `file:line:column` and the field's dotted
//! path) -> `--set` overrides (through a `serde_json::Value`, so any scalar can be reached
//! by its path) -> [`Config::validate`], which asks each library to check its own inputs.

mod design;
mod identify;
mod law;
pub mod tip;

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, anyhow, bail};
use indentify_contact::punch::{AutoOptions, Rim, auto_specimen, treat_rim};
use indentify_contact::{
    ContactKind, Kinematics, LoadHistory, Model, Punch, Schedule, SegmentSpec, SolverOptions,
};
use indentify_mesh::{CylinderMesher, Mesh, ZonedCylinderMesher};
use indentify_records::{Applied, Format, Preprocessing, ReadOptions, Record};

use crate::format::sig;
use serde::{Deserialize, Serialize};
use serde_json::Value;

pub use design::{Candidate, DesignSection};
pub use identify::{
    BfgsStartName, CoarseToFineSetting, DEFAULT_LM_DAMPING, DEFAULT_LM_RADIUS, DEFAULT_LM_SUBSPACE,
    DEFAULT_PROPOSED_STEP, IdentifySection, LmDampingName, MethodName, NoiseSetting, Overrides,
    ParamSetting, ScalingName, fixed_item, instrument_of, instrumented, name_value,
};
pub use law::{BuiltLaw, LawSpec, law_forms, spec_text};

/// A whole simulation: what `indentify simulate` reads.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename = "config")]
pub struct Config {
    /// The cylindrical specimen and its mesh.
    pub specimen: Specimen,
    /// The rigid punch (the contact crate's own type).
    pub punch: Punch,
    /// The direction of the contact constraint: `Vertical` (the paper's formulation),
    /// `Normal` (the displaced node's gap along the punch's normal) or
    /// `Normal(friction: mu)` (with Coulomb friction; on the command line
    /// `--set "contact=Normal(friction: 0.2)"`, then `--set contact.friction=0.3`).
    /// Left out, it is `Vertical` for a depth `history` and `Normal` for measured data
    /// (see [`Config::resolve_model_defaults`]; the loaders apply it).
    #[serde(default)]
    pub contact: ContactKind,
    /// The kinematics: `Small` (the paper's) or `Finite` (total-Lagrangian, the laws in
    /// logarithmic strain space; needs `contact: Normal`, frictionless or with friction).
    /// Left out, it is `Small` for a depth `history` and `Finite` for measured data whose
    /// contact is `Normal` (with or without friction, [`Config::resolve_model_defaults`]).
    #[serde(default)]
    pub kinematics: Kinematics,
    /// The constitutive law and its parameters.
    pub law: LawSpec,
    /// The depth history of the punch; omitted when `data` gives a measured record, whose
    /// depth then drives the simulation.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub history: Option<History>,
    /// A measured record (instrument file) whose preprocessed depth drives the simulation
    /// and whose force is the data to fit (the paper's formulation).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub data: Option<DataSection>,
    /// Numerical options of the direct solver (optional, defaults from [`SolverOptions`]).
    #[serde(default)]
    pub solver: SolverConfig,
    /// What `indentify identify` identifies and how (optional; see [`IdentifySection`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub identify: Option<IdentifySection>,
    /// A joint fit: several tests sharing the law's parameters, each with its own
    /// `history` or `data` and optionally its own `specimen`, `punch`, `contact` and
    /// `weight` (the top-level specimen, punch and contact are the defaults). With
    /// `tests`, the top level has neither `history` nor `data`. See [`TestSpec`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tests: Option<Vec<TestSpec>>,
    /// Candidate protocols that `indentify design` ranks (see [`DesignSection`]);
    /// ignored by the other commands.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub design: Option<DesignSection>,
    /// The folder relative to which `data.file` is found (the configuration file's own);
    /// not part of the file.
    #[serde(skip)]
    pub base_dir: Option<PathBuf>,
}

/// One test of a joint fit (`tests: [...]`): what differs from the top level. A test
/// gives exactly one of `history` and `data`; `specimen`, `punch` and `contact` default to
/// the top-level ones; `weight` (its factor `w_k` in `J = sum_k w_k J_k`) defaults to
/// `1 / (n_k F_max,k^2)` (`n_k` data points, largest data force `F_max,k`), so that every
/// test counts about equally whatever its force scale and number of points.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename = "test")]
pub struct TestSpec {
    /// A label for reports (default `test K`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// The specimen of this test (default: the top-level one).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub specimen: Option<Specimen>,
    /// The punch of this test (default: the top-level one).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub punch: Option<Punch>,
    /// The contact direction of this test (default: the top-level one).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub contact: Option<ContactKind>,
    /// The depth history of this test (or `data`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub history: Option<History>,
    /// The measured record of this test (or `history`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub data: Option<DataSection>,
    /// Its weight `w_k > 0` in the joint cost (default `1 / (n_k F_max,k^2)`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub weight: Option<f64>,
}

/// A measured record: the file, its format and test, and its preprocessing (the records
/// crate's own option types).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename = "data")]
pub struct DataSection {
    /// The instrument file, relative to the configuration file's folder.
    pub file: String,
    /// Its format (`Auto` detects it from the content).
    #[serde(default)]
    pub format: Format,
    /// The test of a multi-test file, from 1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub test: Option<usize>,
    /// What the record prescribes: `Depth` (default) or `Force` (load control: the
    /// record's force drives the punch; `simulate` only for now).
    #[serde(default, skip_serializing_if = "Drive::is_depth")]
    pub drive: Drive,
    /// Drift, zero point, compliance, segments and resampling (defaults: zero point and
    /// segments on, no resampling).
    #[serde(default)]
    pub preprocessing: Preprocessing,
    /// Equal sub-steps of the forward solve between consecutive points of the preprocessed
    /// record (the depth interpolated linearly): the force is still compared with the data
    /// at the record's points only, and the gradient stays exact. An integer in
    /// `[1, MAX_DATA_SUBSTEPS]`; default [`DEFAULT_SUBSTEPS`] (docs/discretization.md).
    #[serde(
        default = "default_substeps",
        deserialize_with = "deserialize_substeps"
    )]
    pub substeps: usize,
}

/// The default [`DataSection::substeps`]: the forward solve of a measured record takes
/// this many sub-steps between its points (with the records resampled to 60 points, every
/// probe of the three real examples within 1% of the step-converged force;
/// docs/discretization.md).
pub const DEFAULT_SUBSTEPS: usize = 2;

/// The most sub-steps `data.substeps` allows (beyond, resample the record to more points).
pub const MAX_DATA_SUBSTEPS: usize = 100;

fn default_substeps() -> usize {
    DEFAULT_SUBSTEPS
}

/// `data.substeps`, refused outside `[1, MAX_DATA_SUBSTEPS]` while parsing (so that the error
/// carries the file, line and column).
fn deserialize_substeps<'de, D: serde::Deserializer<'de>>(d: D) -> Result<usize, D::Error> {
    let k = u64::deserialize(d)?;
    let max = MAX_DATA_SUBSTEPS;
    match usize::try_from(k) {
        Ok(k) if (1..=max).contains(&k) => Ok(k),
        _ => Err(serde::de::Error::custom(format!(
            "data.substeps = {k} is not allowed: expected an integer in [1, {max}] (the \
             forward solve's equal sub-steps between consecutive record points)"
        ))),
    }
}

/// A measured record read and preprocessed.
#[derive(Clone, Debug)]
pub struct Measured {
    /// The file as found.
    pub path: PathBuf,
    /// The record as read (internal units).
    pub raw: Record,
    /// The record after preprocessing: its depth drives the simulation, its force is fitted.
    pub record: Record,
    /// The preprocessing steps as applied, with their numbers.
    pub applied: Vec<Applied>,
    /// What is missing or made up: a record without unloading, up-sampling.
    pub warnings: Vec<String>,
}

impl Measured {
    /// `` `FILE` (anton-paar, test 1)``.
    pub fn label(&self) -> String {
        format!(
            "`{}` ({}{})",
            self.path.display(),
            self.raw.meta.format.name(),
            self.raw
                .meta
                .test_name
                .as_ref()
                .map_or(String::new(), |t| format!(", test {t}"))
        )
    }

    /// `` `FILE` (anton-paar, test 1): 1000 samples -> 60 points (zero point: ...; ...)``.
    pub fn summary(&self) -> String {
        let steps: Vec<String> = self
            .applied
            .iter()
            .map(|a| format!("{}: {}", a.step, a.description))
            .collect();
        format!(
            "{}: {} samples -> {} points, h_max {:.4e} mm, F_max {:.4e} N{}",
            self.label(),
            self.raw.t.len(),
            self.record.t.len(),
            self.record.h_max(),
            self.record.f_max(),
            if steps.is_empty() {
                String::new()
            } else {
                format!("\n    preprocessing: {}", steps.join("\n    "))
            }
        )
    }
}

impl DataSection {
    /// The file's path: absolute, or relative to `base`.
    pub fn path(&self, base: Option<&Path>) -> PathBuf {
        let p = PathBuf::from(&self.file);
        match base {
            Some(b) if p.is_relative() => b.join(p),
            _ => p,
        }
    }

    /// Reads and preprocesses the record.
    ///
    /// # Errors
    /// An unreadable file, a reader's error (file, line, what was expected), a
    /// preprocessing error, or a record that cannot drive a simulation.
    pub fn load(&self, base: Option<&Path>) -> Result<Measured> {
        let path = self.path(base);
        let shown = path.display().to_string();
        let bytes = std::fs::read(&path).with_context(|| {
            format!("cannot read the data file `{shown}` (data.file, relative to the configuration's folder)")
        })?;
        let opts = ReadOptions {
            format: self.format,
            test: self.test,
        };
        let raw = indentify_records::read_one(&bytes, &shown, &opts)?;
        let (record, applied) = indentify_records::apply(&raw, &self.preprocessing)
            .with_context(|| format!("cannot preprocess `{shown}` (data.preprocessing)"))?;
        let mut warnings = Vec::new();
        if let Some(rs) = &self.preprocessing.resample {
            if rs.n > raw.t.len() {
                warnings.push(format!(
                    "`{shown}` has {} samples and data.preprocessing.resample asks for {} points: \
                     they are interpolated between the samples and add no information (resample \
                     to at most {} points)",
                    raw.t.len(),
                    rs.n,
                    raw.t.len()
                ));
            }
        }
        // Unloading shows in the force: a plastic imprint can keep the final depth near
        // the maximum (h_f / h_max of 0.6 to 0.95 for metals) while the force returns to zero.
        let (f_peak, f_end) = (raw.f_max(), raw.f.last().copied().unwrap_or(0.0));
        if f_peak > 0.0 && f_end > 0.5 * f_peak {
            warnings.push(format!(
                "`{shown}` ends at {:.0}% of its maximum force: no unloading (a truncated record, \
                 or a test stopped early); the elastic unloading is what determines E best",
                100.0 * f_end / f_peak
            ));
        }
        for w in &warnings {
            tracing::warn!("warning: {w}");
        }
        if raw.meta.format == Format::Csv && (raw.h_max() > 1.0 || raw.f_max() > 100.0) {
            tracing::warn!(
                "warning: `{shown}` reaches a depth of {} mm and a force of {} N: if its columns \
                 are in nm, um, mN or uN, say so in the header (`Depth (nm)`, `Load (mN)`); a \
                 column without a unit is read in mm, N and s",
                short(raw.h_max()),
                short(raw.f_max())
            );
        }
        if let Some(i) = (1..record.t.len()).find(|&i| !(record.t[i] > record.t[i - 1])) {
            bail!(
                "`{shown}`: points {} and {i} (after preprocessing) have the times {} s and {} s: \
                 the simulation needs increasing times; resampling averages repeated times \
                 (data.preprocessing.resample: (n: 60))",
                i - 1,
                record.t[i - 1],
                record.t[i]
            );
        }
        if record.t.len() < 3 {
            bail!(
                "`{shown}` has {} points after preprocessing: expected at least 3 to drive a \
                 simulation (data.preprocessing.resample.n)",
                record.t.len()
            );
        }
        if !(record.h_max() > 0.0) {
            bail!(
                "`{shown}`: the depth never becomes positive after preprocessing (max {} mm): \
                 no indentation to simulate",
                record.h_max()
            );
        }
        Ok(Measured {
            path,
            raw,
            record,
            applied,
            warnings,
        })
    }
}

/// The specimen: a cylinder given by its sizes and its mesh, or sized and meshed
/// automatically from the punch and the maximum depth of the history (instrument scale).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename = "specimen")]
pub enum Specimen {
    /// Cylinder `0 <= r <= radius`, `-height <= z <= 0` (mm), `nr x nz` Q8 elements
    /// graded towards the axis and the top surface; mirrors [`CylinderMesher`]. Under a
    /// flat punch, the element boundary nearest to its radius is moved onto it and the
    /// rim gets quarter-point elements ([`Mesher::build_for`]).
    Cylinder {
        /// Radius (mm).
        radius: f64,
        /// Height (mm).
        height: f64,
        /// Elements along r.
        nr: usize,
        /// Elements along z.
        nz: usize,
        /// Size ratio of neighbouring elements along r (1 = uniform).
        grading_r: f64,
        /// Size ratio of neighbouring elements along z (1 = uniform).
        grading_z: f64,
    },
    /// Radius = height = `size_factor` contact-radius bounds at the maximum depth, a
    /// uniform core of `elements_in_contact` squares per side under the punch, graded
    /// beyond (the contact crate's [`indentify_contact::punch::auto_specimen`]); every field
    /// optional.
    Auto {
        /// Element edges across the contact-radius bound, in [2, 64] (default 12).
        #[serde(default = "auto_elements_in_contact")]
        elements_in_contact: usize,
        /// Specimen size over the contact-radius bound, in [5, 10000] (default 48).
        #[serde(default = "auto_size_factor")]
        size_factor: f64,
        /// Largest size ratio of neighbouring elements outside the core, in [1.05, 3]
        /// (default 1.5).
        #[serde(default = "auto_grading")]
        grading: f64,
    },
}

fn auto_elements_in_contact() -> usize {
    AutoOptions::default().elements_in_contact
}

fn auto_size_factor() -> f64 {
    AutoOptions::default().size_factor
}

fn auto_grading() -> f64 {
    AutoOptions::default().grading
}

/// A [`Specimen`] as the library types it stands for.
enum SpecimenKind {
    Cylinder(CylinderMesher),
    Auto(AutoOptions),
}

impl Specimen {
    fn kind(&self) -> SpecimenKind {
        match *self {
            Specimen::Cylinder {
                radius,
                height,
                nr,
                nz,
                grading_r,
                grading_z,
            } => SpecimenKind::Cylinder(CylinderMesher {
                radius,
                height,
                nr,
                nz,
                grading_r,
                grading_z,
            }),
            Specimen::Auto {
                elements_in_contact,
                size_factor,
                grading,
            } => SpecimenKind::Auto(AutoOptions {
                elements_in_contact,
                size_factor,
                grading,
            }),
        }
    }

    /// Checks what can be checked before the depth history is known.
    ///
    /// # Errors
    /// The first field out of range, naming `specimen.<field>`.
    pub fn validate(&self) -> Result<()> {
        match self.kind() {
            SpecimenKind::Cylinder(m) => m.validate()?,
            SpecimenKind::Auto(o) => o.validate()?,
        }
        Ok(())
    }

    /// The mesher for this specimen under `punch` pressed to at most `h_max` (mm).
    ///
    /// # Errors
    /// Invalid sizes or options; for `Auto`, a maximum depth that is not positive.
    pub fn mesher(&self, punch: &Punch, h_max: f64) -> Result<Mesher> {
        Ok(match self.kind() {
            SpecimenKind::Cylinder(m) => {
                m.validate()?;
                Mesher::Cylinder(m)
            }
            SpecimenKind::Auto(options) => {
                Mesher::Zoned(auto_specimen(punch, h_max, &options).with_context(|| {
                    format!(
                        "cannot size the automatic specimen for {} at the maximum depth \
                         {h_max} mm of the history",
                        punch.describe()
                    )
                })?)
            }
        })
    }
}

/// `v` to 4 significant digits without trailing zeros (`0.3`, `2.812e-4`).
fn short(v: f64) -> String {
    sig(v, 4)
        .parse::<f64>()
        .map_or_else(|_| v.to_string(), |x| x.to_string())
}

/// The mesher a [`Specimen`] resolves to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Mesher {
    /// Geometric grading from the axis and the top.
    Cylinder(CylinderMesher),
    /// Uniform core under the punch, graded far field.
    Zoned(ZonedCylinderMesher),
}

impl Mesher {
    /// The specimen's radius and height (mm).
    pub fn size(&self) -> (f64, f64) {
        match self {
            Mesher::Cylinder(m) => (m.radius, m.height),
            Mesher::Zoned(m) => (m.radius, m.height),
        }
    }

    /// The mesh.
    ///
    /// # Errors
    /// The mesher's own checks.
    pub fn build(&self) -> Result<Mesh> {
        Ok(match self {
            Mesher::Cylinder(m) => m.build()?,
            Mesher::Zoned(m) => m.build()?,
        })
    }

    /// The mesh for `punch`. A flat punch's rim is a singular point of the solution: for a
    /// [`Punch::Flat`] of radius `a` inside a `Cylinder` specimen, the element boundary
    /// nearest to `a` is moved onto it (by at most half an element, so that the contact
    /// zone, a set of nodes, ends at the nominal radius; the automatic specimen's core is
    /// `a` already), then quarter-point singular elements are put around the rim node
    /// ([`treat_rim`]). Other punches get the mesher's mesh unchanged.
    ///
    /// Returns the mesh, the radius of the moved element boundary before the move (if
    /// any) and what was done at the rim.
    ///
    /// # Errors
    /// The mesher's own checks; a rim element that the treatment would invert.
    pub fn build_for(&self, punch: &Punch) -> Result<(Mesh, Option<f64>, Rim)> {
        let (mesh, moved) = match (self, punch) {
            (Mesher::Cylinder(m), Punch::Flat { radius }) if *radius < m.radius && m.nr >= 2 => {
                m.build_through(*radius)?
            }
            _ => (self.build()?, None),
        };
        let (mesh, rim) = treat_rim(mesh, punch)?;
        Ok((mesh, moved, rim))
    }

    /// `20 x 20 Q8 (radius 10 mm, height 10 mm, smallest element 1.6e-2 x 1.6e-2 mm)`.
    pub fn describe(&self) -> String {
        let (nr, nz, radius, height, dr, dz) = match self {
            Mesher::Cylinder(m) => {
                let (dr, dz) = m.smallest_sizes();
                (m.nr, m.nz, m.radius, m.height, dr, dz)
            }
            Mesher::Zoned(m) => {
                let (nr, nz) = m.counts().unwrap_or((0, 0));
                let h = m.core / m.core_elements as f64;
                (nr, nz, m.radius, m.height, h, h)
            }
        };
        let kind = match self {
            Mesher::Cylinder(_) => "graded cylinder",
            Mesher::Zoned(m) => {
                return format!(
                    "automatic cylinder {nr} x {nz} Q8 (radius = height = {} mm, uniform core \
                     {} mm of {} x {} elements of {:.3e} mm, graded beyond)",
                    short(radius),
                    short(m.core),
                    m.core_elements,
                    m.core_elements,
                    dr
                );
            }
        };
        format!(
            "{kind} {nr} x {nz} Q8 (radius {} mm, height {} mm, smallest element {dr:.3e} x \
             {dz:.3e} mm)",
            short(radius),
            short(height)
        )
    }
}

/// The punch's history: consecutive segments from `t = 0`, `h = 0`, each prescribing the
/// depth `(duration, depth, steps)` or the force, linearly `(duration, force, steps)` or
/// at a constant `Pdot/P` `(force, pdot_over_p, steps)` (load control, docs/theory.md §13).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename = "history")]
pub struct History {
    /// Segments (the contact crate's own type).
    pub segments: Vec<SegmentSpec>,
}

/// What a measured record prescribes (`data.drive`): its depth (the force is the
/// observable, the default) or its force (load control: the depth is the observable).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Drive {
    /// The record's depth drives the punch.
    #[default]
    Depth,
    /// The record's force drives the punch (load control).
    Force,
}

impl Drive {
    fn is_depth(&self) -> bool {
        *self == Drive::Depth
    }
}

/// Why a load-controlled configuration is refused by the commands that drive by depth
/// only (`batch`, `map`'s synthetic data, the discretization study, ...).
const LOAD_CONTROL_ONLY_SIMULATE: &str = "load control is supported by `simulate`, \
    `identify`, `check`, `gradient` and `gradient-check`: this command drives by depth \
    only; drive by depth or use one of those";

/// Numerical options of the direct solver; every field is optional and defaults to
/// [`SolverOptions::default`]. Whether fields are recorded is decided by the command.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields, rename = "solver")]
pub struct SolverConfig {
    /// Relative tolerance on the equilibrium residual.
    pub residual_tol: f64,
    /// Maximum global Newton iterations per step.
    pub max_iterations: usize,
    /// Maximum number of successive halvings of a failing step.
    pub max_cuts: u32,
    /// Relative residual below which the active set is checked before full convergence.
    pub active_set_check_tol: f64,
    /// Relative penetration tolerance before a node is activated.
    pub gap_tol: f64,
    /// Relative tensile-reaction tolerance before a node is released.
    pub lambda_tol: f64,
}

impl Default for SolverConfig {
    fn default() -> Self {
        let d = SolverOptions::default();
        SolverConfig {
            residual_tol: d.residual_tol,
            max_iterations: d.max_iterations,
            max_cuts: d.max_cuts,
            active_set_check_tol: d.active_set_check_tol,
            gap_tol: d.gap_tol,
            lambda_tol: d.lambda_tol,
        }
    }
}

impl SolverConfig {
    /// The solver options, recording fields when `record_fields`.
    pub fn options(&self, record_fields: bool) -> SolverOptions {
        SolverOptions {
            residual_tol: self.residual_tol,
            max_iterations: self.max_iterations,
            max_cuts: self.max_cuts,
            active_set_check_tol: self.active_set_check_tol,
            gap_tol: self.gap_tol,
            lambda_tol: self.lambda_tol,
            record_fields,
            ..SolverOptions::default()
        }
    }

    /// Checks the ranges (the contact crate does not check its options).
    ///
    /// # Errors
    /// The first field out of range, its value and what is allowed.
    pub fn validate(&self) -> Result<()> {
        let tol = |field: &str, v: f64, strict: bool| {
            if v.is_finite() && (v > 0.0 || (!strict && v == 0.0)) && v < 1.0 {
                Ok(())
            } else {
                let lo = if strict { "(0" } else { "[0" };
                Err(anyhow!(
                    "solver.{field} = {v} is not allowed: expected a tolerance in {lo}, 1)"
                ))
            }
        };
        tol("residual_tol", self.residual_tol, true)?;
        tol("active_set_check_tol", self.active_set_check_tol, false)?;
        tol("gap_tol", self.gap_tol, false)?;
        tol("lambda_tol", self.lambda_tol, false)?;
        if !(1..=10_000).contains(&self.max_iterations) {
            bail!(
                "solver.max_iterations = {} is not allowed: expected an integer in [1, 10000]",
                self.max_iterations
            );
        }
        if self.max_cuts > 30 {
            bail!(
                "solver.max_cuts = {} is not allowed: expected an integer in [0, 30]",
                self.max_cuts
            );
        }
        Ok(())
    }
}

/// The reference problems of docs/theory.md §11 (and the `init` templates).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reference {
    /// R0: elastic, E = 20000 MPa, nu = 0.3 (Sneddon's cone).
    R0Elastic,
    /// R1: Maxwell, E = 20000 MPa, nu = 0.3, eta = 30000 MPa s.
    R1Maxwell,
    /// R2: Norton-Hoff, E = 1e5 MPa, nu = 0.3, K = 1500 MPa s^(1/m), m = 5, sY = 500 MPa.
    R2NortonHoff,
}

impl Reference {
    /// All reference problems.
    pub const ALL: [Reference; 3] = [
        Reference::R0Elastic,
        Reference::R1Maxwell,
        Reference::R2NortonHoff,
    ];

    /// Id and one-line title, e.g. `R0 of docs/theory.md §11: elastic cone indentation`.
    pub fn title(&self) -> &'static str {
        match self {
            Reference::R0Elastic => {
                "R0 of docs/theory.md §11: elastic cone indentation (Sneddon's solution)"
            }
            Reference::R1Maxwell => {
                "R1 of docs/theory.md §11: Maxwell viscoelastic cone indentation"
            }
            Reference::R2NortonHoff => {
                "R2 of docs/theory.md §11: Norton-Hoff viscoplastic cone indentation"
            }
        }
    }

    /// File name of the shipped example, e.g. `r0-elastic.ron`.
    pub fn example_file(&self) -> &'static str {
        match self {
            Reference::R0Elastic => "r0-elastic.ron",
            Reference::R1Maxwell => "r1-maxwell.ron",
            Reference::R2NortonHoff => "r2-norton-hoff.ron",
        }
    }

    /// The configuration: cylinder 10 x 10 mm, 20 x 20 Q8 graded 1.3 towards the axis and
    /// the top, cone of half-angle 68 deg, trapezoid 0 -> 0.1 mm in 1 s, hold 1 s, unload
    /// in 1 s, 30 steps per segment.
    pub fn config(&self) -> Config {
        let law = match self {
            Reference::R0Elastic => LawSpec::numbers("Elastic", &[("E", 20000.0), ("nu", 0.3)]),
            Reference::R1Maxwell => {
                LawSpec::numbers("Maxwell", &[("E", 20000.0), ("nu", 0.3), ("eta", 30000.0)])
            }
            Reference::R2NortonHoff => LawSpec::numbers(
                "NortonHoff",
                &[
                    ("E", 1e5),
                    ("nu", 0.3),
                    ("K", 1500.0),
                    ("m", 5.0),
                    ("sY", 500.0),
                ],
            ),
        }
        .expect("the reference laws are in the registry");
        let mesh = CylinderMesher::REFERENCE;
        Config {
            specimen: Specimen::Cylinder {
                radius: mesh.radius,
                height: mesh.height,
                nr: mesh.nr,
                nz: mesh.nz,
                grading_r: mesh.grading_r,
                grading_z: mesh.grading_z,
            },
            punch: Punch::Cone {
                half_angle_deg: 68.0,
            },
            contact: ContactKind::Vertical,
            kinematics: Kinematics::Small,
            law,
            history: Some(History {
                segments: indentify_contact::trapezoid(0.1, 1.0, 1.0, 1.0, 30)
                    .into_iter()
                    .map(Into::into)
                    .collect(),
            }),
            data: None,
            solver: SolverConfig::default(),
            identify: Some(self.identify_section()),
            tests: None,
            design: None,
            base_dir: None,
        }
    }

    /// The identification of the reference problem (nu fixed at 0.3, log scaling; BFGS with
    /// Armijo backtracking, Levenberg-Marquardt for R2) from the paper's first starting point: R1 Table I
    /// `(E, eta) = (4000, 70000)`, R2 Table III test 1 `(E, K, m, sY) = (130000, 800, 2, 1000)`;
    /// R0 from `E = 4000`. Bounds as in `cargo xtask paper-tables`.
    pub fn identify_section(&self) -> IdentifySection {
        let free = |start: f64, lower: f64, upper: f64| ParamSetting::Free {
            start: Some(start),
            lower: Some(lower),
            upper: Some(upper),
            scaling: Some(ScalingName::Log),
        };
        let nu = ParamSetting::Fixed { value: Some(0.3) };
        let params: Vec<(&str, ParamSetting)> = match self {
            Reference::R0Elastic => vec![("E", free(4000.0, 1e3, 1e6)), ("nu", nu)],
            Reference::R1Maxwell => vec![
                ("E", free(4000.0, 1e3, 1e6)),
                ("nu", nu),
                ("eta", free(70000.0, 1e3, 1e7)),
            ],
            Reference::R2NortonHoff => vec![
                ("E", free(130000.0, 1e4, 1e6)),
                ("nu", nu),
                ("K", free(800.0, 10.0, 1e5)),
                ("m", free(2.0, 1.1, 30.0)),
                ("sY", free(1000.0, 1.0, 5000.0)),
            ],
        };
        IdentifySection {
            params: params
                .into_iter()
                .map(|(n, s)| (n.to_string(), s))
                .collect(),
            // R2's m-sY valley takes BFGS 40-60 iterations; LM on the sensitivity Jacobian
            // about 10 (docs/paper-tables.md)
            method: if *self == Reference::R2NortonHoff {
                MethodName::Lm
            } else {
                MethodName::Bfgs
            },
            ..IdentifySection::default()
        }
    }
}

impl Config {
    /// Checks every input through the library that owns it: mesh sizes and counts,
    /// punch geometry, law parameters, history, solver options.
    ///
    /// # Errors
    /// The first invalid input, naming its field, value and what is allowed.
    pub fn validate(&self) -> Result<()> {
        if let Some(d) = &self.design {
            d.validate()?;
        }
        if let Some(tests) = &self.tests {
            return self.validate_joint(tests);
        }
        self.specimen.validate()?;
        self.punch.validate()?;
        self.law.material()?;
        if let Some(&(_, nu)) = self.law.named_params().iter().find(|(n, _)| *n == "nu") {
            if nu > NU_MAX {
                bail!(
                    "law.nu = {nu} is beyond what the displacement (Q8) elements solve: expected \
                     a value in (-1, {NU_MAX}]; nearer 0.5 the elements lock and Newton cannot \
                     reach solver.residual_tol (for a nearly incompressible material, use \
                     {NU_MAX}: F (1 - nu^2) at {NU_MAX} is within 1% of its value at 0.3 on R0)"
                );
            }
        }
        match (&self.history, &self.data) {
            (Some(_), None) => {
                // load-controlled segments are valid here; the commands that cannot run
                // them refuse them ([`Config::prepare`])
                self.load_history()?;
            }
            (None, Some(d)) => {
                if d.file.trim().is_empty() {
                    bail!("data.file is empty: expected the path of an instrument file");
                }
                if d.test == Some(0) {
                    bail!("data.test = 0 is not allowed: tests are numbered from 1");
                }
            }
            (None, None) => bail!(
                "neither `history` nor `data` is given: expected a depth history \
                 (history: (segments: [...])) or a measured record whose depth drives the \
                 simulation (data: (file: \"...\"))"
            ),
            (Some(_), Some(_)) => bail!(
                "both `history` and `data` are given: with a measured record its depth drives \
                 the simulation; remove `history` (or `data`)"
            ),
        }
        self.kinematics.check_contact(self.contact)?;
        self.solver.validate()?;
        if let Some(id) = &self.identify {
            id.validate(&self.law)?;
        }
        Ok(())
    }

    /// [`Config::validate`] of a joint configuration: a non-empty list, no top-level
    /// `history` or `data`, every test valid as a one-test configuration, weights finite
    /// and > 0.
    fn validate_joint(&self, tests: &[TestSpec]) -> Result<()> {
        if tests.is_empty() {
            bail!(
                "`tests` is empty: expected a list of at least one test, each with its own \
                 `history` or `data`, e.g. tests: [(history: (segments: [...])), ...]; or \
                 remove `tests` and give `history` or `data` at the top level"
            );
        }
        for (field, given) in [
            ("history", self.history.is_some()),
            ("data", self.data.is_some()),
        ] {
            if given {
                bail!(
                    "both `tests` and a top-level `{field}` are given, which is ambiguous: with \
                     `tests`, each test gives its own `history` or `data` \
                     (tests[K].{field}); move the top-level `{field}` into the tests or remove \
                     `tests`"
                );
            }
        }
        for (k, t) in tests.iter().enumerate() {
            if let Some(w) = t.weight {
                if !(w.is_finite() && w > 0.0) {
                    bail!(
                        "tests[{k}].weight = {w} is not allowed: expected a finite number > 0 \
                         (or no weight: the default 1/(n F_max^2) makes every test count \
                         equally)"
                    );
                }
            }
            if t.history.is_none() && t.data.is_none() {
                bail!(
                    "tests[{k}] has neither `history` nor `data`: expected its depth history \
                     (history: (segments: [...])) or a measured record (data: (file: \"...\"))"
                );
            }
            if t.history.is_some() && t.data.is_some() {
                bail!(
                    "tests[{k}] has both `history` and `data`: with a measured record its depth \
                     drives the simulation; remove one of them"
                );
            }
            self.test_config(k)?
                .validate()
                .with_context(|| format!("in tests[{k}]"))?;
        }
        if let Some(id) = &self.identify {
            id.validate(&self.law)?;
        }
        Ok(())
    }

    /// Whether the data are measured records: a top-level `data` section, or one in a test.
    pub fn is_measured(&self) -> bool {
        self.data.is_some()
            || self
                .tests
                .as_ref()
                .is_some_and(|t| t.iter().any(|t| t.data.is_some()))
    }

    /// Fills the model's fields that the configuration does not state (`stated`):
    ///
    /// - with a depth `history` (the reference problems, the paper's tables), the paper's
    ///   model: `contact: Vertical`, `kinematics: Small` (the serde defaults, kept);
    /// - with measured data ([`Config::is_measured`]), the physical model:
    ///   `contact: Normal` (frictionless, the gap along the punch's normal in the current
    ///   configuration) and `kinematics: Finite`, which together describe the material
    ///   under a real indenter (docs/validation-finite-strain.md); a stated friction
    ///   (`Normal(friction: mu)`) keeps `Finite` too, and the kinematics stays `Small`
    ///   only if a stated contact (top level or a test's) is `Vertical`, which finite
    ///   strain does not support.
    ///
    /// Friction stays opt-in: no default coefficient is supported by the shipped data.
    pub fn resolve_model_defaults(&mut self, stated: StatedModel) {
        if !self.is_measured() {
            return;
        }
        if !stated.contact {
            self.contact = ContactKind::Normal;
        }
        if !stated.kinematics {
            let normal = std::iter::once(self.contact)
                .chain(self.tests.iter().flatten().filter_map(|t| t.contact))
                .all(|c| c.is_normal());
            self.kinematics = if normal {
                Kinematics::Finite
            } else {
                Kinematics::Small
            };
        }
    }

    /// The model in words: `normal contact, finite strain (the default for measured data)`.
    pub fn describe_model(&self) -> String {
        let contact = match self.contact {
            ContactKind::Vertical => "vertical contact (the paper's)".to_string(),
            ContactKind::Normal => "frictionless normal contact".to_string(),
            other => format!("normal contact with Coulomb friction {}", other.friction()),
        };
        let kinematics = match self.kinematics {
            Kinematics::Small => "small strain",
            Kinematics::Finite => "finite strain",
        };
        format!("{contact}, {kinematics}")
    }

    /// The number of tests: the length of `tests`, or 1.
    pub fn n_tests(&self) -> usize {
        self.tests.as_ref().map_or(1, Vec::len)
    }

    /// Test `k` (from 0) of a joint configuration as a one-test configuration: its own
    /// history or data, specimen, punch and contact (defaulting to the top-level ones),
    /// the shared law, solver and identify sections.
    ///
    /// # Errors
    /// A configuration without `tests`, or `k` out of range.
    pub fn test_config(&self, k: usize) -> Result<Config> {
        let tests = self
            .tests
            .as_ref()
            .ok_or_else(|| anyhow!("the configuration has no `tests`"))?;
        let t = tests.get(k).ok_or_else(|| {
            anyhow!(
                "there is no tests[{k}]: the configuration has {} tests (tests[0] to tests[{}])",
                tests.len(),
                tests.len().saturating_sub(1)
            )
        })?;
        Ok(Config {
            specimen: t.specimen.unwrap_or(self.specimen),
            punch: t.punch.clone().unwrap_or_else(|| self.punch.clone()),
            contact: t.contact.unwrap_or(self.contact),
            kinematics: self.kinematics,
            law: self.law.clone(),
            history: t.history.clone(),
            data: t.data.clone(),
            solver: self.solver,
            identify: self.identify.clone(),
            tests: None,
            design: None,
            base_dir: self.base_dir.clone(),
        })
    }

    /// The label of test `k` (from 0): its `name`, or `test K+1`.
    pub fn test_name(&self, k: usize) -> String {
        self.tests
            .as_ref()
            .and_then(|t| t.get(k))
            .and_then(|t| t.name.clone())
            .unwrap_or_else(|| format!("test {}", k + 1))
    }

    /// Every test as a one-test configuration, with the name its runs and messages use:
    /// the configuration itself named `name`, or each test of a joint configuration
    /// ([`Config::test_config`]) named `name [label]` ([`Config::test_name`]).
    ///
    /// # Errors
    /// None for a valid configuration (a joint one's tests are checked when it loads).
    pub fn one_test_configs(&self, name: &str) -> Result<Vec<(String, Config)>> {
        match &self.tests {
            None => Ok(vec![(name.to_string(), self.clone())]),
            Some(tests) => (0..tests.len())
                .map(|k| {
                    let sub = self
                        .test_config(k)
                        .with_context(|| format!("in tests[{k}] of `{name}`"))?;
                    Ok((format!("{name} [{}]", self.test_name(k)), sub))
                })
                .collect(),
        }
    }

    /// The one-test configuration a command that runs one test works on: `self` without
    /// `tests` (and no `test` asked), or test `test` (from 1) of a joint configuration.
    ///
    /// # Errors
    /// A joint configuration without `test` (naming `--test` and the range), a `test` out
    /// of range, or a `test` asked of a configuration without `tests`.
    pub fn one_test(self, test: Option<usize>, command: &str, name: &str) -> Result<Config> {
        match (self.tests.as_ref().map(Vec::len), test) {
            (None, None) => Ok(self),
            (None, Some(k)) => {
                bail!("--test {k} is not allowed: `{name}` has no `tests` list (it is one test)")
            }
            (Some(n), None) => bail!(
                "`{name}` is a joint configuration of {n} tests (`tests`): `{command}` works on \
                 one test at a time; choose it with --test K (1 to {n})"
            ),
            (Some(n), Some(k)) if k == 0 || k > n => {
                bail!("--test {k} is not allowed: `{name}` has {n} tests, numbered 1 to {n}")
            }
            (Some(_), Some(k)) => self.test_config(k - 1),
        }
    }

    /// The discrete time schedule of the prescribed history (`history`).
    ///
    /// # Errors
    /// No `history` (a configuration driven by `data`), an empty history, a non-positive
    /// duration, zero steps or a non-finite depth, a load-controlled segment
    /// (`history.segments[].force`: [`Config::load_history`]).
    pub fn schedule(&self) -> Result<Schedule> {
        let h = self.load_history()?;
        if let Some(i) = self
            .history
            .iter()
            .flat_map(|h| &h.segments)
            .position(|s| s.force.is_some())
        {
            bail!("`history.segments[{i}].force`: {LOAD_CONTROL_ONLY_SIMULATE}");
        }
        Ok(h.schedule)
    }

    /// The prescribed history (`history`), whose segments may prescribe the force.
    ///
    /// # Errors
    /// No `history`, or an invalid one (a segment with both or neither of `depth` and
    /// `force`, a force that is not > 0, and the errors of [`Config::schedule`]).
    pub fn load_history(&self) -> Result<LoadHistory> {
        let h = self.history.as_ref().ok_or_else(|| {
            anyhow!("the configuration has no `history`: its depth comes from `data`")
        })?;
        Ok(LoadHistory::from_specs(&h.segments)?)
    }

    /// The schedule (from `history`, or from the preprocessed record of `data`), the
    /// mesher and the model, ready to solve; `data_file` replaces `data.file`.
    ///
    /// # Errors
    /// An invalid history or record, an invalid specimen, a mesh or model that cannot be
    /// built.
    pub fn prepare(&self, name: &str) -> Result<Prepared> {
        if let Some(d) = &self.data {
            if d.drive == Drive::Force {
                bail!("`data.drive: Force` in `{name}`: {LOAD_CONTROL_ONLY_SIMULATE}");
            }
        }
        // refuses load-controlled segments, naming them
        if self.data.is_none() {
            self.schedule()?;
        }
        Ok(self.prepare_driven(name)?.0)
    }

    /// As [`Config::prepare`], with load control: the history of a load-controlled
    /// configuration (`history` with `force` segments, or `data.drive: Force`: the
    /// record's force prescribed at its points) beside the prepared model, whose
    /// `schedule` then holds the times (and the prescribed depths only).
    ///
    /// # Errors
    /// As [`Config::prepare`]; a load-controlled record without a positive force column;
    /// a load-controlled history without a depth to size an automatic specimen.
    pub fn prepare_driven(&self, name: &str) -> Result<(Prepared, Option<LoadHistory>)> {
        let mut load = None;
        let resolved = tip::resolve(&self.punch, self.base_dir.as_deref())
            .with_context(|| format!("cannot use the punch of `{name}`"))?;
        let punch = &resolved.punch;
        let (schedule, measured) = match &self.data {
            Some(d) if d.drive == Drive::Force => {
                let d = with_tip_compliance(d, &resolved)?;
                let m = d
                    .load(self.base_dir.as_deref())
                    .with_context(|| DataFailure(format!("cannot use the data of `{name}`")))?;
                let (t, f) = (&m.record.t, &m.record.f);
                if f.len() != t.len() || f.iter().skip(1).all(|&x| x == 0.0) {
                    bail!(DataFailure(format!(
                        "`data.drive: Force`: the record `{}` has no force column to \
                         prescribe (load control needs the force at every point)",
                        m.path.display()
                    )));
                }
                let h = LoadHistory::from_force_record(t, f).with_context(|| {
                    DataFailure(format!(
                        "the force of the record `{}` cannot drive a load-controlled \
                         simulation (`data.drive: Force`)",
                        m.path.display()
                    ))
                })?;
                // the measured depth sizes the specimen (the depth is not prescribed)
                let s = Schedule::from_record(t, &m.record.h)?;
                load = Some(h);
                (s, Some(m))
            }
            Some(d) => {
                let d = with_tip_compliance(d, &resolved)?;
                let m = d
                    .load(self.base_dir.as_deref())
                    .with_context(|| DataFailure(format!("cannot use the data of `{name}`")))?;
                let s = Schedule::from_record(&m.record.t, &m.record.h)
                    .and_then(|s| s.with_uniform_substeps(d.substeps))
                    .with_context(|| {
                        DataFailure(format!(
                            "the record `{}` cannot drive a simulation",
                            m.path.display()
                        ))
                    })?;
                (s, Some(m))
            }
            None => {
                let h = self.load_history()?;
                let s = h.schedule.clone();
                if h.is_load_controlled() {
                    load = Some(h);
                }
                (s, None)
            }
        };
        let h_max = schedule.depth.iter().copied().fold(0.0, f64::max);
        if load.is_some() && h_max <= 0.0 && matches!(self.specimen.kind(), SpecimenKind::Auto(_)) {
            bail!(
                "`history` of `{name}` prescribes no positive depth: the automatic specimen \
                 of a load-controlled history is sized by its depth-controlled segments (e.g. \
                 the approach); add one, or give `specimen: Cylinder(...)`"
            );
        }
        let mesher = self.specimen.mesher(punch, h_max)?;
        let (radius, height) = mesher.size();
        let mut warnings = validity(punch, h_max, radius, height, name)?;
        for w in &warnings {
            tracing::warn!("warning: {w}");
        }
        if let Some(m) = &measured {
            warnings.extend(m.warnings.iter().cloned());
            if let Some(w) = force_plausibility(&self.punch, m) {
                tracing::warn!("warning: {w}");
                warnings.push(w);
            }
        }
        let (mesh, moved, rim) = mesher
            .build_for(punch)
            .with_context(|| format!("cannot mesh the specimen of `{name}`"))?;
        if let (Some(from), Punch::Flat { radius }) = (moved, punch) {
            tracing::info!(
                "{name}: the element boundary at r = {} mm moved to the flat punch's radius {} mm \
                 (a corner node at its rim)",
                short(from),
                short(*radius)
            );
        }
        match &rim {
            Rim::Smooth => {}
            Rim::QuarterPoint { .. } => tracing::debug!("{name}: {}", rim.describe()),
            Rim::OffCorner { .. } => tracing::warn!("warning: {name}: {}", rim.describe()),
        }
        let model = Model::with_contact(mesh, punch.clone(), self.contact)
            .and_then(|m| m.with_kinematics(self.kinematics))
            .with_context(|| format!("cannot build the model of `{name}`"))?;
        Ok((
            Prepared {
                schedule,
                mesher,
                model,
                rim,
                measured,
                warnings,
            },
            load,
        ))
    }
}

/// `d` with the calibrated tip's frame compliance as its compliance correction (when the
/// tip file gives one and `data.preprocessing.compliance` is `Off`, its default).
///
/// # Errors
/// Both the tip file and `data.preprocessing.compliance` give a frame compliance.
fn with_tip_compliance(d: &DataSection, tip: &tip::ResolvedPunch) -> Result<DataSection> {
    use indentify_records::Correction;
    let mut d = d.clone();
    if let Some(c) = tip.frame_compliance {
        if d.preprocessing.compliance != Correction::Off {
            bail!(
                "the tip file `{}` gives a frame compliance ({c} mm/N) and \
                 data.preprocessing.compliance is {:?}: give one of them (remove \
                 data.preprocessing.compliance to use the tip's)",
                tip.file.as_deref().unwrap_or(Path::new("?")).display(),
                d.preprocessing.compliance
            );
        }
        d.preprocessing.compliance = Correction::Value(c);
    }
    Ok(d)
}

/// Mean contact pressures (MPa) beyond which a record's force cannot be right for its
/// depth and tip: above 2e5 MPa (200 GPa, twice the hardness of diamond) or below 1e-5 MPa
/// (10 Pa, softer than the softest gels).
pub const PLAUSIBLE_PRESSURE: (f64, f64) = (1e-5, 2e5);

/// A warning when the record's largest force, over the tip's projected area at the depth
/// where it is reached (`pi a^2`, `a` the profile's radius at that depth), is a mean
/// pressure no material gives ([`PLAUSIBLE_PRESSURE`]): typically a force column in the
/// wrong unit (`Fn (kN)` for mN).
pub fn force_plausibility(punch: &Punch, m: &Measured) -> Option<String> {
    let raw = &m.raw;
    let (i, f) = raw
        .f
        .iter()
        .copied()
        .enumerate()
        .fold((0, f64::NEG_INFINITY), |best, (i, f)| {
            if f > best.1 { (i, f) } else { best }
        });
    let h = raw.h.get(i).copied()?;
    let a = punch.intersection_radius(h);
    if !(f > 0.0 && h > 0.0 && a.is_finite() && a > 0.0) {
        return None;
    }
    let p = f / (std::f64::consts::PI * a * a);
    let (low, high) = PLAUSIBLE_PRESSURE;
    if p >= low && p <= high {
        return None;
    }
    Some(format!(
        "`{}`: its largest force {} N at a depth of {} mm gives a mean pressure of {} MPa on \
         the tip ({}), {} any material (plausible: {} to {} MPa): check the force and depth \
         units of the file's header (e.g. `Fn (mN)`, `Depth (nm)`)",
        m.path.display(),
        short(f),
        short(h),
        short(p),
        punch.describe(),
        if p > high {
            "harder than"
        } else {
            "softer than"
        },
        short(low),
        short(high)
    ))
}

/// The context of an error of [`Config::prepare`] that lies in the measured record (not in
/// the configuration): front ends classify it as a data error.
#[derive(Debug)]
pub struct DataFailure(pub String);

impl std::fmt::Display for DataFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

/// What a configuration resolves to before solving.
#[derive(Debug)]
pub struct Prepared {
    /// The depth history on the time grid.
    pub schedule: Schedule,
    /// The specimen's mesher.
    pub mesher: Mesher,
    /// The meshed specimen and the punch.
    pub model: Model,
    /// What was done at a flat punch's rim ([`Mesher::build_for`]).
    pub rim: Rim,
    /// The measured record driving the schedule, if the configuration has `data`.
    pub measured: Option<Measured>,
    /// Where the model is stretched beyond its validity (also logged as warnings).
    pub warnings: Vec<String>,
}

/// Largest Poisson's ratio the displacement-based Q8 elements are trusted with: the
/// normalized elastic force `F (1 - nu^2)` of R0 is 318.4, 319.0 and 320.5 N at nu = 0.49,
/// 0.495 and 0.499 (317.2 N at 0.3; locking begins), and at 0.4999 Newton no longer
/// reaches a relative residual of 1e-10.
pub const NU_MAX: f64 = 0.499;

/// Largest representative strain (Tabor: `0.2 cot(alpha)` for a cone, `0.2 a / R` for a
/// sphere) under which the small-strain model is taken as valid without a warning.
pub const REPRESENTATIVE_STRAIN_LIMIT: f64 = 0.1;

/// Refuses what cannot be right (a depth reaching the specimen's bottom, a contact zone
/// that may reach its outer radius, a sphere pushed past its radius) and returns warnings
/// where the small-strain model is stretched (a sphere deeper than 0.3 R, a representative
/// strain beyond [`REPRESENTATIVE_STRAIN_LIMIT`]).
///
/// # Errors
/// The refusals, each with the size it would need.
pub fn validity(
    punch: &Punch,
    h_max: f64,
    radius: f64,
    height: f64,
    name: &str,
) -> Result<Vec<String>> {
    if !(h_max.is_finite()) {
        bail!("{name}: the maximum depth {h_max} mm is not finite");
    }
    if h_max >= 0.5 * height {
        bail!(
            "{name}: the punch goes {} mm deep into a specimen {} mm high: the depth must stay \
             a small fraction of the height (the bottom is fixed); give specimen.height >= {} \
             mm (20 times the depth), or use specimen: Auto()",
            short(h_max),
            short(height),
            short(20.0 * h_max)
        );
    }
    let a = punch.contact_radius_bound(h_max);
    if !(a < radius) {
        bail!(
            "{name}: at the depth {} mm the contact may spread over {} mm, and the specimen's \
             radius is {} mm: the contact would reach its outer edge; give specimen.radius >= \
             {} mm (10 contact radii), or use specimen: Auto()",
            short(h_max),
            short(a),
            short(radius),
            short(10.0 * a)
        );
    }
    if let Punch::Calibrated {
        area: Some(p),
        file,
    } = punch
    {
        if h_max >= p.depth_limit() {
            bail!(
                "{name}: the calibrated tip `{file}` ends at the depth {} mm (its area function \
                 stops growing there) and the punch goes {} mm deep",
                short(p.depth_limit()),
                short(h_max)
            );
        }
    }
    let mut warnings = Vec::new();
    let equivalent = punch.equivalent();
    if let Punch::Sphere { radius: r } = &equivalent {
        if h_max >= *r {
            bail!(
                "{name}: the sphere of radius {} mm is pushed {} mm deep, past its own radius: \
                 its profile ends there; keep the depth below about 0.3 R",
                short(*r),
                short(h_max)
            );
        }
        if h_max > 0.3 * r {
            let a = (h_max * (2.0 * r - h_max)).sqrt();
            warnings.push(format!(
                "{name}: the sphere goes {} R deep (h = {} mm, R = {} mm): beyond about 0.3 R \
                 the small-strain model is stretched (representative strain 0.2 a/R = {:.0}%)",
                short(h_max / r),
                short(h_max),
                short(*r),
                100.0 * 0.2 * a / r
            ));
        }
    }
    if let Some(alpha) = equivalent.half_angle_deg() {
        let strain = 0.2 / alpha.to_radians().tan();
        if strain > REPRESENTATIVE_STRAIN_LIMIT {
            warnings.push(format!(
                "{name}: a cone of half-angle {} deg has a representative strain of {:.0}% \
                 (0.2 cot(alpha)), beyond the {:.0}% where the small-strain model holds",
                short(alpha),
                100.0 * strain,
                100.0 * REPRESENTATIVE_STRAIN_LIMIT
            ));
        }
    }
    Ok(warnings)
}

/// Reads, overrides and validates the configuration file `path`.
///
/// # Errors
/// An unreadable file, a syntax or type error (with `file:line:column` and the field),
/// an invalid `--set`, or an invalid value.
pub fn load(path: &Path, sets: &[String]) -> Result<Config> {
    let name = path.display().to_string();
    let src = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read the configuration file `{name}`"))?;
    let mut cfg = load_str(&src, &name, sets)?;
    cfg.base_dir = Some(
        path.parent()
            .map_or_else(|| PathBuf::from("."), Path::to_path_buf),
    );
    Ok(cfg)
}

/// [`load`] on the text `src` of a configuration called `name`.
///
/// # Errors
/// As [`load`].
pub fn load_str(src: &str, name: &str, sets: &[String]) -> Result<Config> {
    let config = parse(src, name)?;
    let stated = StatedModel::of_ron(src).with_sets(sets);
    let mut config = apply_sets(config, sets)?;
    config.resolve_model_defaults(stated);
    let via = if sets.is_empty() {
        String::new()
    } else {
        format!(" (after --set {})", sets.join(" --set "))
    };
    config
        .validate()
        .with_context(|| format!("invalid configuration `{name}`{via}"))?;
    Ok(config)
}

/// Which of the model's fields (`contact`, `kinematics`) a configuration states; the others
/// take the defaults of [`Config::resolve_model_defaults`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StatedModel {
    /// `contact` is given (in the file or by `--set`).
    pub contact: bool,
    /// `kinematics` is given.
    pub kinematics: bool,
}

/// The model's keys of a RON configuration, the other fields skipped.
#[derive(Deserialize)]
#[serde(rename = "config")]
struct ModelKeys {
    #[serde(default)]
    contact: Option<serde::de::IgnoredAny>,
    #[serde(default)]
    kinematics: Option<serde::de::IgnoredAny>,
}

impl StatedModel {
    /// Both fields stated: the configuration is taken as it is.
    pub const ALL: StatedModel = StatedModel {
        contact: true,
        kinematics: true,
    };

    /// The fields the RON text `src` gives at its top level (none if it does not parse:
    /// the parse error is reported by [`parse`]).
    pub fn of_ron(src: &str) -> StatedModel {
        ron::Options::default()
            .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
            .from_str::<ModelKeys>(src)
            .map(|k| StatedModel {
                contact: k.contact.is_some(),
                kinematics: k.kinematics.is_some(),
            })
            .unwrap_or_default()
    }

    /// The fields a value (a Python dict's structure) gives at its top level.
    pub fn of_value(value: &Value) -> StatedModel {
        StatedModel {
            contact: value.get("contact").is_some(),
            kinematics: value.get("kinematics").is_some(),
        }
    }

    /// These plus the fields `--set` overrides (`contact=...`, `contact.friction=...`,
    /// `kinematics=...`).
    pub fn with_sets(self, sets: &[String]) -> StatedModel {
        let sets_field = |field: &str| {
            sets.iter().any(|s| {
                let key = s.split_once('=').map_or(s.as_str(), |(k, _)| k).trim();
                key == field || key.starts_with(&format!("{field}."))
            })
        };
        StatedModel {
            contact: self.contact || sets_field("contact"),
            kinematics: self.kinematics || sets_field("kinematics"),
        }
    }
}

/// Whether `src` writes the specimen in the form before `Cylinder`/`Auto` existed.
fn old_specimen_syntax(src: &str) -> bool {
    src.lines()
        .map(|l| l.split("//").next().unwrap_or(""))
        .any(|l| {
            l.split_once("specimen:")
                .is_some_and(|(_, rest)| rest.trim_start().starts_with('('))
        })
}

/// Parses a RON configuration; `name` (the file name) prefixes error positions.
///
/// # Errors
/// Syntax and type errors as `name:line:column: message (at `dotted.path`)`, followed by
/// the offending source line.
pub fn parse(src: &str, name: &str) -> Result<Config> {
    ron::Options::default()
        .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
        .from_str::<Config>(src)
        .map_err(|e| {
            let mut msg = describe_ron_error(src, name, &e);
            if old_specimen_syntax(src) {
                msg.push_str(
                    "\nhint: `specimen` is now `Cylinder(radius: .., height: .., nr: .., nz: .., \
                     grading_r: .., grading_z: ..)` or `Auto()`: write `specimen: Cylinder(` \
                     where the file has `specimen: (`",
                );
            }
            anyhow!(msg)
        })
        .with_context(|| format!("cannot parse the configuration `{name}`"))
}

/// `name:line:col: message (at `path`)` and the source line with a caret.
fn describe_ron_error(src: &str, name: &str, e: &ron::error::SpannedError) -> String {
    use ron::error::Error as E;
    let pos = e.span.start;
    let mut msg = format!("{name}:{}:{}: {}", pos.line, pos.col, e.code);
    let (outer, key) = field_path_at(src, pos.line, pos.col);
    let join = |last: &str| {
        let mut parts = outer.clone();
        parts.push(last.to_string());
        parts.join(".")
    };
    let location = match &e.code {
        // the position is at the unknown key itself, or at the end of the incomplete struct
        E::NoSuchStructField { found, .. } => format!("at `{}`", join(found)),
        E::MissingStructField { field, .. } => format!("`{}` is required", join(field)),
        _ => match key {
            Some(k) => format!("at `{}`", join(&k)),
            None if outer.is_empty() => "at the top level".into(),
            None => format!("in `{}`", outer.join(".")),
        },
    };
    msg.push_str(&format!(" ({location})"));
    // `nr: 20.5`: the integer 20 was read, then `.5` is where a comma should be
    let before: String = src
        .lines()
        .nth(pos.line.saturating_sub(1))
        .map(|l| l.chars().take(pos.col.saturating_sub(1)).collect())
        .unwrap_or_default();
    let after: String = src
        .lines()
        .nth(pos.line.saturating_sub(1))
        .map(|l| l.chars().skip(pos.col.saturating_sub(1)).take(2).collect())
        .unwrap_or_default();
    if matches!(e.code, E::ExpectedComma | E::ExpectedStructLikeEnd)
        && before.trim_end().ends_with(|c: char| c.is_ascii_digit())
        && (after.starts_with('.') || after.starts_with('e') || after.starts_with('E'))
    {
        msg.push_str(": this field takes an integer (a whole number such as 20), not a decimal");
    }
    if let Some(text) = src.lines().nth(pos.line.saturating_sub(1)) {
        let gutter = pos.line.to_string();
        let caret_at: String = text
            .chars()
            .take(pos.col.saturating_sub(1))
            .map(|c| if c == '\t' { '\t' } else { ' ' })
            .collect();
        msg.push_str(&format!(
            "\n {gutter} | {text}\n {} | {caret_at}^",
            " ".repeat(gutter.len())
        ));
    }
    msg
}

/// Where 1-based `line`/`col` (in characters) of RON text lies: the dotted path of the
/// enclosing struct or list (`history.segments.1`) and the last field key seen in the
/// innermost struct (`duration`), if any. A light tokenizer: identifiers followed by `:`
/// are struct fields, commas count list elements, enum variant names are skipped.
fn field_path_at(src: &str, line: usize, col: usize) -> (Vec<String>, Option<String>) {
    #[derive(Debug)]
    enum Frame {
        Struct(Option<String>),
        List(usize),
    }
    // characters up to the position
    let mut upto = String::new();
    for (i, l) in src.split('\n').enumerate() {
        if i + 1 < line {
            upto.push_str(l);
            upto.push('\n');
        } else {
            upto.extend(l.chars().take(col.saturating_sub(1)));
            break;
        }
    }
    let chars: Vec<char> = upto.chars().collect();
    let mut stack: Vec<Frame> = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        if c == '/' && chars.get(i + 1) == Some(&'/') {
            while i < chars.len() && chars[i] != '\n' {
                i += 1;
            }
        } else if c == '/' && chars.get(i + 1) == Some(&'*') {
            i += 2;
            while i + 1 < chars.len() && !(chars[i] == '*' && chars[i + 1] == '/') {
                i += 1;
            }
            i += 2;
        } else if c == '"' {
            i += 1;
            while i < chars.len() && chars[i] != '"' {
                i += if chars[i] == '\\' { 2 } else { 1 };
            }
            i += 1;
        } else if c == '(' || c == '{' {
            stack.push(Frame::Struct(None));
            i += 1;
        } else if c == '[' {
            stack.push(Frame::List(0));
            i += 1;
        } else if c == ')' || c == '}' || c == ']' {
            stack.pop();
            i += 1;
        } else if c == ',' {
            if let Some(Frame::List(n)) = stack.last_mut() {
                *n += 1;
            }
            i += 1;
        } else if c.is_alphabetic() || c == '_' {
            let start = i;
            while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            let ident: String = chars[start..i].iter().collect();
            let mut j = i;
            while j < chars.len() && chars[j].is_whitespace() {
                j += 1;
            }
            if chars.get(j) == Some(&':') {
                if let Some(Frame::Struct(key)) = stack.last_mut() {
                    *key = Some(ident);
                }
            }
        } else {
            i += 1;
        }
    }
    let key = match stack.pop() {
        Some(Frame::Struct(key)) => key,
        Some(list @ Frame::List(_)) => {
            stack.push(list);
            None
        }
        None => None,
    };
    let outer = stack
        .iter()
        .filter_map(|f| match f {
            Frame::Struct(key) => key.clone(),
            Frame::List(n) => Some(n.to_string()),
        })
        .collect();
    (outer, key)
}

/// Applies `--set key.path=value` overrides in order.
///
/// # Errors
/// A malformed override, an unknown path (listing the keys available where it failed), a
/// path to a non-scalar, or a value of the wrong type.
pub fn apply_sets(config: Config, sets: &[String]) -> Result<Config> {
    if sets.is_empty() {
        return Ok(config);
    }
    let mut value = serde_json::to_value(&config).context("cannot represent the configuration")?;
    for set in sets {
        let (path, text) = set.split_once('=').ok_or_else(|| {
            anyhow!("--set `{set}` is not of the form key.path=value (e.g. --set law.E=25000)")
        })?;
        let path = law_set_path(&config.law, path.trim());
        set_scalar(&mut value, &path, text.trim())
            .with_context(|| format!("cannot apply --set {set}"))?;
    }
    serde_json::from_value(value).map_err(|e| {
        anyhow!(
            "the configuration after --set {} is invalid: {e}",
            sets.join(" --set ")
        )
    })
}

/// `law.<parameter>` by the registry's parameter name (`law.n` -> `law.hardening.n`,
/// `law.g2` -> `law.terms.1.g`); any other path unchanged.
fn law_set_path(law: &LawSpec, path: &str) -> String {
    let Some(rest) = path.strip_prefix("law.") else {
        return path.to_string();
    };
    if rest.contains('.') || law.fields().iter().any(|(n, _)| n == rest) {
        return path.to_string();
    }
    law.param_path(rest)
        .map_or_else(|| path.to_string(), |p| format!("law.{p}"))
}

/// Replaces the scalar at dotted `path` of `root` by `text`, parsed like the old value.
fn set_scalar(root: &mut Value, path: &str, text: &str) -> Result<()> {
    if path.is_empty() {
        bail!("empty key path; available keys: {}", keys_of(root));
    }
    let mut node = root;
    let mut here = String::new();
    for key in path.split('.') {
        node = descend(node, key, &here)?;
        if !here.is_empty() {
            here.push('.');
        }
        here.push_str(key);
    }
    let new = match &*node {
        Value::Number(n) if n.is_f64() => {
            let v: f64 = text.parse().map_err(|_| {
                anyhow!("`{path}` holds a number, and `{text}` is not one (e.g. 2.5e4)")
            })?;
            Value::from(serde_json::Number::from_f64(v).ok_or_else(|| {
                anyhow!("`{path}` = {text} is not allowed: expected a finite number")
            })?)
        }
        Value::Number(_) => {
            let v: u64 = text.parse().map_err(|_| {
                anyhow!("`{path}` holds a non-negative integer, and `{text}` is not one")
            })?;
            Value::from(v)
        }
        Value::Bool(_) => Value::Bool(text.parse().map_err(|_| {
            anyhow!("`{path}` holds a boolean, and `{text}` is neither true nor false")
        })?),
        Value::String(_) => Value::String(text.to_string()),
        // an optional value left out (`start` of a free parameter): a number, else text
        Value::Null => match (text.parse::<u64>(), text.parse::<f64>()) {
            (Ok(v), _) => Value::from(v),
            (_, Ok(v)) if v.is_finite() => Value::from(v),
            _ => Value::String(text.to_string()),
        },
        other => bail!(
            "`{path}` is not a scalar: it holds {}; set one of its scalars instead",
            match other {
                Value::Array(a) => format!("a list of {} (keys 0..{})", a.len(), a.len()),
                _ => format!("the keys {}", keys_of(other)),
            }
        ),
    };
    *node = new;
    Ok(())
}

/// The child `key` of `node`: an object field, a list index, or a field of the single
/// variant an externally tagged enum holds (`punch.half_angle_deg` for `{"Cone": {...}}`).
fn descend<'a>(node: &'a mut Value, key: &str, here: &str) -> Result<&'a mut Value> {
    let at = if here.is_empty() {
        "the top level".to_string()
    } else {
        format!("`{here}`")
    };
    let listing = keys_of(node);
    match node {
        Value::Object(map) => {
            if map.contains_key(key) {
                return Ok(map.get_mut(key).expect("key checked just above"));
            }
            if map.len() == 1 {
                let (variant, inner) = map.iter_mut().next().expect("one entry");
                let is_variant = variant.starts_with(|c: char| c.is_ascii_uppercase());
                if let (true, Value::Object(fields)) = (is_variant, inner) {
                    let fields_listing = names(fields.keys().map(String::as_str));
                    return fields.get_mut(key).ok_or_else(|| {
                        anyhow!(
                            "unknown key `{key}` at {at} ({variant}); available keys: \
                             {fields_listing}"
                        )
                    });
                }
            }
            bail!("unknown key `{key}` at {at}; available keys: {listing}")
        }
        Value::Array(list) => {
            let n = list.len();
            let i: usize = key.parse().map_err(|_| {
                anyhow!("`{key}` is not an index of the list at {at}; available keys: 0..{n}")
            })?;
            list.get_mut(i).ok_or_else(|| {
                anyhow!("index {i} is out of the list at {at}, which has {n} elements (0..{n})")
            })
        }
        _ => bail!("unknown key `{key}`: {at} is a scalar and has no keys"),
    }
}

/// The keys of an object (or of its single enum variant's fields), or `0..n` for a list.
fn keys_of(node: &Value) -> String {
    match node {
        Value::Object(map) => match map.iter().next() {
            Some((variant, Value::Object(fields)))
                if map.len() == 1 && variant.starts_with(|c: char| c.is_ascii_uppercase()) =>
            {
                format!(
                    "{} (of {variant})",
                    names(fields.keys().map(String::as_str))
                )
            }
            _ => names(map.keys().map(String::as_str)),
        },
        Value::Array(a) => format!("0..{}", a.len()),
        _ => "none (a scalar)".into(),
    }
}

/// `a, b, c` from names.
fn names<'a>(it: impl Iterator<Item = &'a str>) -> String {
    it.collect::<Vec<_>>().join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn r0() -> Config {
        Reference::R0Elastic.config()
    }

    fn r0_text() -> String {
        crate::templates::template(Reference::R0Elastic)
    }

    fn set(cfg: Config, s: &str) -> Result<Config> {
        apply_sets(cfg, &[s.to_string()])
    }

    #[test]
    fn shipped_examples_are_the_reference_problems() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples");
        for r in Reference::ALL {
            let path = dir.join(r.example_file());
            let src = std::fs::read_to_string(&path).unwrap();
            let cfg = parse(&src, r.example_file()).unwrap();
            assert_eq!(cfg, r.config(), "{}", r.example_file());
        }
    }

    #[test]
    fn set_reaches_law_mesh_punch_history_and_solver() {
        let c = set(r0(), "law.E=25000").unwrap();
        assert_eq!(
            c.law,
            LawSpec::numbers("Elastic", &[("E", 25000.0), ("nu", 0.3)]).unwrap()
        );
        let c = set(c, "specimen.nr=10").unwrap();
        assert!(matches!(c.specimen, Specimen::Cylinder { nr: 10, .. }));
        let c = set(c, "punch.half_angle_deg=70.3").unwrap();
        assert_eq!(
            c.punch,
            Punch::Cone {
                half_angle_deg: 70.3
            }
        );
        let c = set(c, "history.segments.0.depth=0.2").unwrap();
        assert_eq!(c.history.as_ref().unwrap().segments[0].depth, Some(0.2));
        let c = set(c, "solver.max_cuts=3").unwrap();
        assert_eq!(c.solver.max_cuts, 3);
        let c = set(c, "punch.Cone.half_angle_deg=60").unwrap();
        assert_eq!(
            c.punch,
            Punch::Cone {
                half_angle_deg: 60.0
            }
        );
    }

    /// `contact` reads `Vertical`, `Normal` and `Normal(friction: mu)` in RON and through
    /// `--set`; a negative, NaN or infinite friction is refused naming the field, the
    /// value and what is allowed; configurations round-trip.
    #[test]
    fn contact_friction_parses_and_bad_values_are_refused() {
        let c = set(r0(), "contact=Normal").unwrap();
        assert_eq!(c.contact, ContactKind::Normal);
        let c = set(r0(), "contact=Normal(friction: 0.2)").unwrap();
        assert_eq!(c.contact, ContactKind::NormalFriction { friction: 0.2 });
        let c = set(c, "contact.friction=0.3").unwrap();
        assert_eq!(c.contact, ContactKind::NormalFriction { friction: 0.3 });
        let text = ron::ser::to_string(&c).unwrap();
        assert!(text.contains("Normal(friction:0.3)"), "{text}");
        assert_eq!(parse(&text, "round-trip").unwrap(), c);
        for bad in ["-0.1", "NaN", "inf"] {
            let e = format!(
                "{:#}",
                set(r0(), &format!("contact=Normal(friction: {bad})")).unwrap_err()
            );
            assert!(
                e.contains("contact.friction") && e.contains(">= 0"),
                "{bad}: {e}"
            );
        }
        let text = ron::ser::to_string(&r0()).unwrap();
        let with = text.replace("contact:Vertical", "contact:Normal(friction:-0.5)");
        assert_ne!(with, text);
        let e = format!("{:#}", parse(&with, "bad.ron").unwrap_err());
        assert!(e.contains("contact.friction") && e.contains("-0.5"), "{e}");
        let with = text.replace("contact:Vertical", "contact:Normal(friction:0.1)");
        assert_eq!(
            parse(&with, "good.ron").unwrap().contact,
            ContactKind::NormalFriction { friction: 0.1 }
        );
        let with = text.replace("contact:Vertical", "contact:Normal");
        assert_eq!(parse(&with, "n.ron").unwrap().contact, ContactKind::Normal);
    }

    #[test]
    fn set_errors_name_the_path_and_the_choices() {
        let e = format!("{:#}", set(r0(), "law.G=1").unwrap_err());
        assert!(e.contains("`G`") && e.contains("E, nu"), "{e}");
        let e = format!("{:#}", set(r0(), "speciman.nr=1").unwrap_err());
        assert!(
            e.contains("history, identify, kinematics, law, punch, solver, specimen"),
            "{e}"
        );
        let e = format!("{:#}", set(r0(), "specimen.nr=2.5").unwrap_err());
        assert!(e.contains("specimen.nr") && e.contains("integer"), "{e}");
        let e = format!("{:#}", set(r0(), "law.E=abc").unwrap_err());
        assert!(e.contains("law.E") && e.contains("abc"), "{e}");
        let e = format!("{:#}", set(r0(), "history.segments.7.depth=1").unwrap_err());
        assert!(e.contains("0..3"), "{e}");
        let e = format!("{:#}", set(r0(), "history=1").unwrap_err());
        assert!(e.contains("segments"), "{e}");
        let e = format!("{:#}", set(r0(), "law.E").unwrap_err());
        assert!(e.contains("key.path=value"), "{e}");
    }

    #[test]
    fn flat_punch_gets_a_corner_and_quarter_points_at_its_rim() {
        let rc = indentify_mesh::cylinder::graded_positions(10.0, 20, 1.3);
        let mut cfg = r0();
        // between two element boundaries of R0's graded grid (0.2024 and 0.2790 mm), nearer
        // to the outer one
        cfg.punch = Punch::Flat { radius: 0.25 };
        let p = cfg.prepare("flat").unwrap();
        let Rim::QuarterPoint { node, moved } = &p.rim else {
            panic!("{:?}", p.rim);
        };
        let mesh = &p.model.mesh;
        assert_eq!(mesh.nodes[*node], [0.25, 0.0]);
        assert_eq!(mesh.node_set("top")[14], *node);
        assert_eq!(moved.len(), 3);
        mesh.check_quality().unwrap();
        let (_, from, _) = p.mesher.build_for(&cfg.punch).unwrap();
        assert_eq!(from, Some(rc[7]));
        // on a boundary already: nothing moved
        let (m, from, rim) = p.mesher.build_for(&Punch::Flat { radius: rc[6] }).unwrap();
        assert!(from.is_none() && matches!(rim, Rim::QuarterPoint { .. }));
        assert_eq!(m.nodes[m.node_set("top")[12]], [rc[6], 0.0]);
        // the automatic specimen's core is the radius; cones are left alone
        cfg.specimen = Specimen::Auto {
            elements_in_contact: 8,
            size_factor: 48.0,
            grading: 1.5,
        };
        assert!(matches!(
            cfg.prepare("auto").unwrap().rim,
            Rim::QuarterPoint { .. }
        ));
        let p = r0().prepare("r0").unwrap();
        assert_eq!(p.rim, Rim::Smooth);
        assert_eq!(p.model.mesh, p.mesher.build().unwrap());
        // a punch wider than the specimen: refused, with the size it needs
        let mut wide = r0();
        wide.punch = Punch::Flat { radius: 12.0 };
        let e = format!("{:#}", wide.prepare("wide").map(|_| ()).unwrap_err());
        assert!(
            e.contains("would reach its outer edge") && e.contains("specimen.radius >= 120 mm"),
            "{e}"
        );
    }

    #[test]
    fn a_decimal_for_an_integer_says_an_integer_is_expected() {
        let src = r0_text().replace("nr: 20,", "nr: 20.5,");
        let e = format!("{:#}", parse(&src, "x.ron").unwrap_err());
        assert!(e.contains("takes an integer"), "{e}");
        assert!(e.contains("specimen.nr"), "{e}");
    }

    #[test]
    fn ron_errors_carry_position_and_field_path() {
        let src = "(\n  specimen: Cylinder(radius: 10.0, height: 10.0, nr: -1, nz: 20, grading_r: 1.3, grading_z: 1.3),\n)";
        let e = format!("{:#}", parse(src, "x.ron").unwrap_err());
        assert!(e.contains("x.ron:2:") && e.contains("specimen.nr"), "{e}");
        let src = std::fs::read_to_string(
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/r0-elastic.ron"),
        )
        .unwrap();
        let bad = src.replacen("depth: 0.0", "depth: \"deep\"", 1);
        let e = format!("{:#}", parse(&bad, "x.ron").unwrap_err());
        assert!(e.contains("history.segments.2.depth"), "{e}");
    }

    #[test]
    fn field_path_tracks_structs_lists_and_variants() {
        let src = "(a: (b: 1, c: [ (d: 1), (d: 2, e: X(f: 3)) ]))";
        let col = src.find("3)").unwrap() + 1;
        let (outer, key) = field_path_at(src, 1, col);
        assert_eq!(outer.join("."), "a.c.1.e");
        assert_eq!(key.as_deref(), Some("f"));
        let (outer, key) = field_path_at(src, 1, src.find("(d: 2").unwrap() + 1);
        assert_eq!((outer.join("."), key), ("a.c.1".to_string(), None));
    }

    #[test]
    fn law_parameters_follow_the_library_order_and_ranges() {
        let (law, p) = r0().law.build().unwrap();
        let names: Vec<_> = law.params().iter().map(|i| i.name).collect();
        assert_eq!(names, ["E", "nu"]);
        assert_eq!(p, [20000.0, 0.3]);
        let e = LawSpec::numbers("Elastic", &[("E", 1.0), ("nu", 0.5)])
            .unwrap_err()
            .to_string();
        assert!(e.contains("law.nu = 0.5") && e.contains("(-1, 0.5)"), "{e}");
    }

    /// A measured-data configuration (the file need not exist: nothing is read) with the
    /// model lines `extra` at the top level.
    fn measured(extra: &str) -> String {
        format!(
            "(specimen: Auto(), punch: Berkovich(), {extra} \
             law: Maxwell(E: 2000.0, nu: 0.3, eta: 100000.0), data: (file: \"x.txt\"))"
        )
    }

    #[test]
    fn measured_data_take_the_physical_model_unless_stated() {
        let model = |src: &str, sets: &[&str]| {
            let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
            let c = load_str(src, "m.ron", &sets).unwrap();
            (c.contact, c.kinematics)
        };
        use ContactKind::{Normal, Vertical};
        use Kinematics::{Finite, Small};
        // a depth history keeps the paper's model
        assert_eq!(model(&r0_text(), &[]), (Vertical, Small));
        assert_eq!(model(&measured(""), &[]), (Normal, Finite));
        assert_eq!(
            model(&measured("contact: Vertical,"), &[]),
            (Vertical, Small)
        );
        assert_eq!(model(&measured("kinematics: Small,"), &[]), (Normal, Small));
        assert_eq!(model(&measured("contact: Normal,"), &[]), (Normal, Finite));
        assert_eq!(
            model(&measured(""), &["contact=Vertical"]),
            (Vertical, Small)
        );
        assert_eq!(model(&measured(""), &["kinematics=Small"]), (Normal, Small));
        // friction is opt-in, and a stated friction keeps finite strain
        let (c, k) = model(&measured(""), &["contact=Normal(friction: 0.1)"]);
        assert_eq!((c.friction(), k), (0.1, Finite));
        let (c, k) = model(&measured("contact: Normal(friction: 0.2),"), &[]);
        assert_eq!((c.friction(), k), (0.2, Finite));
        let (c, k) = model(
            &measured("contact: Normal(friction: 0.2),"),
            &["kinematics=Small"],
        );
        assert_eq!((c.friction(), k), (0.2, Small));
        // a depth history with friction keeps the paper's small strain
        let (c, k) = model(&r0_text(), &["contact=Normal(friction: 0.1)"]);
        assert_eq!((c.friction(), k), (0.1, Small));
        // a stated finite strain with vertical contact is refused, not changed
        let e = load_str(
            &measured("contact: Vertical, kinematics: Finite,"),
            "m.ron",
            &[],
        )
        .unwrap_err();
        assert!(format!("{e:#}").contains("Normal"), "{e:#}");
        // the value form (a Python dict) follows the same rule
        let value = serde_json::to_value(parse(&measured(""), "m.ron").unwrap()).unwrap();
        let mut without = value.clone();
        let obj = without.as_object_mut().unwrap();
        obj.remove("contact");
        obj.remove("kinematics");
        assert_eq!(StatedModel::of_value(&without), StatedModel::default());
        assert_eq!(StatedModel::of_value(&value), StatedModel::ALL);
        let from_value = crate::ConfigSource::Value {
            value: without,
            name: "dict".into(),
        }
        .load(&[])
        .unwrap();
        assert_eq!(
            (from_value.contact, from_value.kinematics),
            (Normal, Finite)
        );
        assert_eq!(
            from_value.describe_model(),
            "frictionless normal contact, finite strain"
        );
    }
}
