//! The identification report of `indentify identify`: `report.md` and `report.json`
//! (indentify_report's [`Report`]) and its figures as SVG and PNG (force-depth,
//! force-time, convergence; depth-time instead of force-time under load control, where
//! the depth is fitted), written into the report directory.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use indentify_identify::{IdentifyResult, IterationRecord};
use indentify_report::{
    BoundHit, Convergence, Correlation, Curves, DisplayUnit, Figure, FigureSize, FitQuality,
    NameValue, Observable, Parameter, PreprocessingStep, Report, Source,
};

use crate::config::Measured;

/// What the report is made of, besides the result.
pub struct Inputs<'a> {
    /// Title line.
    pub title: String,
    /// The data's file (or description) and test.
    pub file: String,
    /// Test label ("" for single-test files).
    pub test: String,
    /// The measured record, if any (metadata and preprocessing).
    pub measured: Option<&'a Measured>,
    /// What is fitted: the force, or the depth under load control (then `h` is the force
    /// and the `f_*` series are depths).
    pub observable: Observable,
    /// Schedule times (s).
    pub t: &'a [f64],
    /// Depths (mm); under load control the force at the result (N).
    pub h: &'a [f64],
    /// Data at the schedule times: force (N), or depth (mm) under load control.
    pub f_data: &'a [f64],
    /// The simulated observable at the start.
    pub f_start: &'a [f64],
    /// The simulated observable at the end.
    pub f_final: &'a [f64],
    /// The iteration history (history.csv).
    pub history: &'a [IterationRecord],
    /// Where the model is stretched or the data fall short.
    pub warnings: &'a [String],
    /// The discretization error of the fit, if estimated.
    pub discretization: Option<indentify_report::DiscretizationSummary>,
    /// Sections appended to report.md (Markdown, e.g. multi-start and profiles).
    pub extra_markdown: String,
}

/// The files written.
pub struct Written {
    /// report.md.
    pub markdown: PathBuf,
    /// report.json.
    pub json: PathBuf,
    /// Figures (SVG and PNG).
    pub figures: Vec<PathBuf>,
    /// Fit quality of the final curve.
    pub fit: FitQuality,
}

/// How a parameter is shown: in its internal unit (MPa, MPa s, ...), as on the terminal
/// and in result.json, so that one number reads the same everywhere.
fn display_unit(unit: &str, _value: f64) -> DisplayUnit {
    DisplayUnit::internal(unit)
}

/// The file's metadata worth a line in the report.
fn metadata(m: &Measured) -> Vec<NameValue> {
    let meta = &m.raw.meta;
    let mut out = vec![NameValue::new("format", meta.format.name())];
    let mut opt = |name: &str, v: &Option<String>| {
        if let Some(v) = v {
            out.push(NameValue::new(name, v.clone()));
        }
    };
    opt("instrument", &meta.instrument);
    opt("tip", &meta.tip);
    opt("date", &meta.date);
    opt("control", &meta.protocol.control);
    if let Some(r) = meta.tip_radius {
        out.push(NameValue::new("tip radius", format!("{} um", r * 1e3)));
    }
    if let Some(r) = meta.acquisition_rate {
        out.push(NameValue::new("acquisition rate", format!("{r} Hz")));
    }
    if let Some(c) = meta.frame_compliance {
        out.push(NameValue::new(
            "frame compliance (file)",
            format!("{} nm/mN", c * 1e3),
        ));
    }
    if let Some(d) = meta.drift_rate {
        out.push(NameValue::new(
            "drift rate (file)",
            format!("{} nm/s", d * 1e6),
        ));
    }
    for q in &meta.results {
        out.push(NameValue::new(
            format!("vendor: {}", q.name),
            format!("{} {}", q.value, q.unit),
        ));
    }
    out.push(NameValue::new(
        "samples",
        format!(
            "{} read, {} after preprocessing",
            m.raw.t.len(),
            m.record.t.len()
        ),
    ));
    out
}

/// The report's parameter rows: values, bounds hit, and the standard deviations that are finite.
fn parameters(result: &IdentifyResult) -> Vec<Parameter> {
    let id = result.identifiability.as_ref();
    result
        .params
        .iter()
        .map(|p| {
            let std_dev = id.and_then(|i| {
                i.names
                    .iter()
                    .position(|n| *n == p.name)
                    .map(|k| i.std_dev[k])
                    .filter(|s| s.is_finite())
            });
            Parameter {
                name: p.name.to_string(),
                unit: display_unit(p.unit, p.value),
                start: p.start,
                value: p.value,
                lower: p.free.then_some(p.lower),
                upper: p.free.then_some(p.upper),
                at_bound: if p.at_lower {
                    Some(BoundHit::Lower)
                } else if p.at_upper {
                    Some(BoundHit::Upper)
                } else {
                    None
                },
                fixed: !p.free,
                std_dev,
            }
        })
        .collect()
}

/// The report's identifiability summary of `i`.
fn summary(i: &indentify_identify::Identifiability) -> indentify_report::IdentifiabilitySummary {
    indentify_report::IdentifiabilitySummary {
        names: i.names.iter().map(|n| n.to_string()).collect(),
        singular_values: i.singular_values.clone(),
        directions: i.directions.clone(),
        condition: i.condition_text(),
        weakest: i.weakest_direction(),
        undetermined: i
            .undetermined
            .iter()
            .zip(&i.reasons)
            .map(|(n, r)| indentify_report::Undetermined {
                name: n.to_string(),
                reason: r.clone(),
            })
            .collect(),
        advice: if i.undetermined.is_empty() {
            String::new()
        } else {
            let advice = indentify_identify::StopReason::UNDETERMINED_ADVICE;
            match i.intervals_text() {
                Some(t) => format!("{advice}; {t}"),
                None => advice.to_string(),
            }
        },
    }
}

/// Builds the report, renders it and its figures into `dir`.
///
/// # Errors
/// A report that cannot be rendered (no finite point in a series), an unwritable file.
pub fn write(dir: &Path, result: &IdentifyResult, inputs: &Inputs<'_>) -> Result<Written> {
    let fit = FitQuality::compute(inputs.f_data, inputs.f_final)
        .context("cannot measure the quality of the fit")?;
    let id = result.identifiability.as_ref();
    let parameters = parameters(result);
    // the determined parameters only: an undetermined one has no correlation to show
    let correlation = id.map(|i| {
        let keep: Vec<usize> = (0..i.names.len())
            .filter(|&k| !i.is_undetermined(i.names[k]))
            .collect();
        Correlation {
            names: keep.iter().map(|&k| i.names[k].to_string()).collect(),
            matrix: keep
                .iter()
                .map(|&a| keep.iter().map(|&b| i.correlation[a][b]).collect())
                .collect(),
        }
    });
    let identifiability = id.map(summary);
    let preprocessing = inputs.measured.map_or_else(Vec::new, |m| {
        m.applied
            .iter()
            .map(|a| PreprocessingStep::new(a.step.clone(), a.description.clone()))
            .collect()
    });
    let history = inputs
        .history
        .iter()
        .map(|r| indentify_report::IterationRecord {
            iteration: r.iteration,
            cost: r.cost,
            grad_norm: Some(r.grad_norm),
            params: r.params.clone(),
        })
        .collect();
    let mut report = Report {
        title: inputs.title.clone(),
        source: Source {
            file: inputs.file.clone(),
            test: inputs.test.clone(),
            metadata: inputs.measured.map_or_else(Vec::new, metadata),
        },
        law: result.law.to_string(),
        parameters,
        correlation,
        convergence: Convergence {
            stop_reason: result.stop_reason.to_string(),
            iterations: result.iterations,
            forward_solves: result.forward_solves,
            adjoint_solves: result.adjoint_solves,
            wall_time_s: result.seconds,
            converged: Some(result.stop_reason.is_converged()),
        },
        fit,
        preprocessing,
        curves: match inputs.observable {
            Observable::Force => Curves::with_auto_units(
                inputs.t.to_vec(),
                inputs.h.to_vec(),
                inputs.f_data.to_vec(),
                Some(inputs.f_start.to_vec()),
                inputs.f_final.to_vec(),
            ),
            Observable::Depth => Curves::depth_observed(
                inputs.t.to_vec(),
                inputs.h.to_vec(),
                inputs.f_data.to_vec(),
                Some(inputs.f_start.to_vec()),
                inputs.f_final.to_vec(),
            ),
        },
        history,
        figures: Vec::new(),
        warnings: inputs.warnings.to_vec(),
        discretization: inputs.discretization.clone(),
        identifiability,
        // the residuals of this curve against its record's own noise
        // (standardized by a stated multiplicative noise, as the console's)
        adequacy: crate::adequacy::assess_series(
            inputs.t,
            inputs.f_data,
            inputs.f_final,
            inputs.observable,
            result.params.iter().filter(|p| p.free).count(),
            crate::adequacy::states_relative_noise(result),
        ),
    };
    let mut figures = Vec::new();
    let mut links = Vec::new();
    for fig in [Figure::ForceDepth, Figure::ForceTime, Figure::Convergence] {
        if fig == Figure::Convergence && report.history.len() < 2 {
            continue;
        }
        let stem = fig.file_stem_for(inputs.observable);
        let svg = report
            .figure_svg(fig, FigureSize::default())
            .with_context(|| format!("cannot draw the {stem} figure"))?;
        let png = report
            .figure_png(fig, FigureSize::default())
            .with_context(|| format!("cannot draw the {stem} figure"))?;
        for (ext, bytes) in [("svg", svg.into_bytes()), ("png", png)] {
            let path = dir.join(format!("{stem}.{ext}"));
            crate::atomic::write(&path, bytes)
                .with_context(|| format!("cannot write `{}`", path.display()))?;
            figures.push(path);
        }
        links.push(fig.link_for(inputs.observable, format!("{stem}.svg")));
    }
    report.figures = links;
    let markdown = dir.join("report.md");
    let mut md = report.to_markdown();
    if !inputs.extra_markdown.is_empty() {
        md.push('\n');
        md.push_str(&inputs.extra_markdown);
    }
    crate::atomic::write(&markdown, md)
        .with_context(|| format!("cannot write `{}`", markdown.display()))?;
    let json = dir.join("report.json");
    let text = report.to_json().context("cannot represent the report")?;
    crate::atomic::write(&json, text + "\n")
        .with_context(|| format!("cannot write `{}`", json.display()))?;
    Ok(Written {
        markdown,
        json,
        figures,
        fit,
    })
}
