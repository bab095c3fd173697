//! [`Record`], its metadata [`Meta`], and the reader options ([`Format`], [`ReadOptions`]).

use serde::{Deserialize, Serialize};

/// One indentation test: time, depth and force in internal units (s, mm, N).
///
/// `t`, `h` and `f` have the same length (at least 2 after reading) and `t` never
/// decreases. `segment` holds the file's segment ids (Anton Paar `SegmentID`, the Hysitron
/// `.hld` load-function segment of each sample) or the ids set by
/// [`crate::prep::segments`]; `None` when nothing is known.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Record {
    /// Test name: the file's display name, with the test name for multi-test files.
    pub name: String,
    /// Time, s.
    pub t: Vec<f64>,
    /// Depth (displacement into the surface), mm.
    pub h: Vec<f64>,
    /// Force, N.
    pub f: Vec<f64>,
    /// Segment id of each sample, when known.
    pub segment: Option<Vec<u32>>,
    /// What the file says about the test.
    pub meta: Meta,
}

impl Record {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// Whether the record has no samples.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }

    /// Largest depth, mm (NaN for an empty record).
    pub fn h_max(&self) -> f64 {
        self.h.iter().copied().fold(f64::NAN, f64::max)
    }

    /// Largest force, N (NaN for an empty record).
    pub fn f_max(&self) -> f64 {
        self.f.iter().copied().fold(f64::NAN, f64::max)
    }
}

/// A named value with its unit; values read from headers keep the file's unit unless the
/// field's documentation says it is converted.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Quantity {
    /// Name as written (e.g. `EIT`, `Fmax`, `Tip C0`).
    pub name: String,
    /// Value.
    pub value: f64,
    /// Unit (as written, or the internal unit where converted).
    pub unit: String,
}

impl Quantity {
    pub(crate) fn new(name: impl Into<String>, value: f64, unit: impl Into<String>) -> Self {
        Self {
            name: name.into(),
            value,
            unit: unit.into(),
        }
    }
}

/// One segment of a load function as the file declares it (Hysitron `.hld`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LoadSegment {
    /// Segment number as written.
    pub number: u32,
    /// Segment type as written (e.g. `0 LINEAR`).
    pub kind: String,
    /// Begin time, s.
    pub t_begin: f64,
    /// End time, s.
    pub t_end: f64,
    /// Demand at the beginning, in `unit`.
    pub begin: f64,
    /// Demand at the end, in `unit`.
    pub end: f64,
    /// `N` for a force demand, `mm` for a depth demand (converted), else as written.
    pub unit: String,
    /// Declared number of points.
    pub points: Option<u32>,
}

/// The loading protocol as the file states it; rates and limits in internal units.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Protocol {
    /// Control mode or loading type as written (`Load Control`, `Linear Loading`).
    pub control: Option<String>,
    /// Loading rate, converted (`N/s` or `mm/s`).
    pub loading_rate: Option<Quantity>,
    /// Unloading rate, converted (`N/s` or `mm/s`).
    pub unloading_rate: Option<Quantity>,
    /// Maximum load, N.
    pub max_load: Option<f64>,
    /// Maximum depth, mm.
    pub max_depth: Option<f64>,
    /// Hold (pause) at maximum, s.
    pub hold: Option<f64>,
    /// Load-function segments (Hysitron `.hld`).
    pub segments: Vec<LoadSegment>,
}

/// What a file says about its test: identification, protocol, hints for preprocessing and
/// the vendor's own results.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Meta {
    /// The format the bytes were read as.
    pub format: Format,
    /// Instrument (system, head, serial number) as written.
    pub instrument: Option<String>,
    /// Tip name as written.
    pub tip: Option<String>,
    /// Tip radius, mm (spherical tips, when given).
    pub tip_radius: Option<f64>,
    /// Tip area-function coefficients as written (`Tip C0` ... with their units).
    pub tip_area: Vec<Quantity>,
    /// Loading protocol.
    pub protocol: Protocol,
    /// Test name within a multi-test file.
    pub test_name: Option<String>,
    /// Date and time as written.
    pub date: Option<String>,
    /// Acquisition rate, Hz.
    pub acquisition_rate: Option<f64>,
    /// Frame (machine) compliance, mm/N (Hysitron `Machine Comp`).
    pub frame_compliance: Option<f64>,
    /// Thermal-drift rate, mm/s (Hysitron `Drift Rate`).
    pub drift_rate: Option<f64>,
    /// The vendor's results (O&P `EIT`, `HIT`, `hmax`, `Fmax`, ...), as written.
    pub results: Vec<Quantity>,
    /// Other numeric header entries worth reporting (contact threshold, preload, ...), as
    /// written.
    pub other: Vec<Quantity>,
}

/// A file format. `Auto` detects it from the content.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Format {
    /// Detect from the content (see [`crate::detect`]).
    #[default]
    Auto,
    /// Generic delimited table (comma, semicolon, tab or whitespace) with a header.
    Csv,
    /// Anton Paar single-test export (`Measured values` section).
    AntonPaar,
    /// Anton Paar multi-test export (`X_<test>_Time_[s]`, `Y_<test>_Fn_[mN]`, ... side by side).
    AntonPaarMulti,
    /// Hysitron text export (`Number of Points = N`, `Depth (nm)`, `Load (µN)`, `Time (s)`).
    HysitronTxt,
    /// Hysitron native `.hld` (key-value header, load function, data sections).
    Hld,
    /// KLA/Agilent/Keysight workbook (`.xlsx`, `.xls`): a sheet per test.
    Kla,
    /// Micro Materials NanoTest text export: no header, time (s), depth (nm), force (mN).
    MicroMaterials,
}

impl Format {
    /// Name as used in configs and messages.
    pub fn name(self) -> &'static str {
        match self {
            Format::Auto => "auto",
            Format::Csv => "csv",
            Format::AntonPaar => "anton-paar",
            Format::AntonPaarMulti => "anton-paar-multi",
            Format::HysitronTxt => "hysitron-txt",
            Format::Hld => "hld",
            Format::Kla => "kla",
            Format::MicroMaterials => "micro-materials",
        }
    }

    /// The format of a name as accepted by [`Format::name`] (also `AntonPaar`-style spellings).
    pub fn from_name(name: &str) -> Option<Format> {
        let n = name.trim().to_ascii_lowercase().replace(['_', ' '], "-");
        [
            Format::Auto,
            Format::Csv,
            Format::AntonPaar,
            Format::AntonPaarMulti,
            Format::HysitronTxt,
            Format::Hld,
            Format::Kla,
            Format::MicroMaterials,
        ]
        .into_iter()
        .find(|f| f.name() == n || f.name().replace('-', "") == n)
    }
}

/// Options of [`crate::read`].
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ReadOptions {
    /// Format of the bytes; `Auto` detects it.
    pub format: Format,
    /// 1-based test to read from a multi-test file; `None` reads all.
    pub test: Option<usize>,
}
