//! The figures of `indentify analyze --out DIR` (SVG, written atomically into
//! `DIR/figures/`): per test its main unloading with the power-law fit over the fitted force
//! range (`unloading-K.svg`, the fitted numbers in its notes), and over the file the
//! hardness and the modulus against the contact depth of every analysed unloading
//! (`hardness_depth.svg`, `modulus_depth.svg`: a multi-cycle test's curve, or one point per
//! test). Display units: nm, mN, GPa, mN/nm.

use std::path::{Path, PathBuf};

use indentify_records::{Preprocessing, Record};
use indentify_report::{FigureSize, LineFigure, Series, Style};

use crate::analyze::{AnalyzeOutcome, TestOutcome};
use crate::error::{Error, ErrorKind, Result};
use crate::format::sig;

/// The notes of a test's unloading figure: the fit and the O&P values, display units.
pub fn unloading_notes(t: &TestOutcome) -> Option<Vec<String>> {
    let a = t.analysis.as_ref()?;
    let (u, op) = a.values()?;
    let fit = u.fit.as_ref()?;
    Some(vec![
        format!(
            "F = alpha (h - h_f)^m: m = {}, h_f = {} nm, {} points from {} to {} mN, R² = {}",
            sig(fit.m, 4),
            sig(fit.h_f * 1e6, 5),
            fit.n,
            sig(fit.f_range.0 * 1e3, 4),
            sig(fit.f_range.1 * 1e3, 4),
            sig(fit.r2, 6)
        ),
        format!(
            "S = {} mN/nm, h_c = {} nm, H = {} GPa, E_r = {} GPa, E = {} GPa",
            sig(op.s * 1e-3, 4),
            sig(op.hc * 1e6, 5),
            sig(op.hardness * 1e-3, 4),
            sig(op.er * 1e-3, 4),
            op.e.map_or("-".into(), |e| sig(e * 1e-3, 4))
        ),
    ])
}

/// The unloading figure of test `t` whose preprocessed record is `x`.
fn unloading_figure(t: &TestOutcome, x: &Record) -> Option<LineFigure> {
    let notes = unloading_notes(t)?;
    let (u, _) = t.analysis.as_ref()?.values()?;
    let fit = u.fit.as_ref()?;
    let (_, start, end) = u.samples;
    let end = end.min(x.h.len().saturating_sub(1));
    let data_h: Vec<f64> = x.h[start..=end].iter().map(|h| h * 1e6).collect();
    let data_f: Vec<f64> = x.f[start..=end].iter().map(|f| f * 1e3).collect();
    // the fit over its force range, and its continuation to h_f dashed
    let depth = |f: f64| fit.h_f + (f / fit.alpha).powf(1.0 / fit.m);
    let curve = |lo: f64, hi: f64| -> (Vec<f64>, Vec<f64>) {
        (0..=60)
            .map(|k| {
                let f = lo + (hi - lo) * k as f64 / 60.0;
                (depth(f) * 1e6, f * 1e3)
            })
            .unzip()
    };
    let (fh, ff) = curve(fit.f_range.0, fit.f_range.1);
    let (eh, ef) = curve(0.0, fit.f_range.0);
    Some(LineFigure {
        title: format!(
            "{} {}: unloading {} and its power-law fit",
            t.index, t.test, u.number
        ),
        notes,
        x_label: "depth h [nm]".into(),
        y_label: "force F [mN]".into(),
        series: vec![
            Series {
                label: "unloading (data)".into(),
                x: data_h,
                y: data_f,
                style: Style::Points,
            },
            Series {
                label: "power-law fit (fitted range)".into(),
                x: fh,
                y: ff,
                style: Style::Line,
            },
            Series {
                label: "fit continued to h_f".into(),
                x: eh,
                y: ef,
                style: Style::Dashed,
            },
        ],
    })
}

/// H or E (GPa) against h_c (nm): every analysed unloading, and each test's main one.
fn depth_figure(o: &AnalyzeOutcome, modulus: bool) -> LineFigure {
    let value = |op: &indentify_analysis::OliverPharr| {
        if modulus {
            op.e.unwrap_or(f64::NAN) * 1e-3
        } else {
            op.hardness * 1e-3
        }
    };
    let (mut ax, mut ay, mut mx, mut my) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for t in &o.tests {
        let Some(a) = &t.analysis else { continue };
        for u in &a.unloadings {
            if let Some(op) = &u.op {
                ax.push(op.hc * 1e6);
                ay.push(value(op));
            }
        }
        if let Some((_, op)) = a.values() {
            mx.push(op.hc * 1e6);
            my.push(value(op));
        }
    }
    let (name, label) = if modulus {
        ("indentation modulus E_IT", "E_IT [GPa]")
    } else {
        ("indentation hardness H_IT", "H_IT [GPa]")
    };
    LineFigure {
        title: format!("{name} against contact depth"),
        notes: vec![format!(
            "{}: {} unloadings of {} tests; tip {}, nu {}",
            o.file,
            ax.len(),
            o.tests.len(),
            o.tip.area.describe(),
            o.nu
        )],
        x_label: "contact depth h_c [nm]".into(),
        y_label: label.into(),
        series: vec![
            Series {
                label: "every unloading".into(),
                x: ax,
                y: ay,
                style: Style::Points,
            },
            Series {
                label: "each test's main unloading".into(),
                x: mx,
                y: my,
                style: Style::Dashed,
            },
        ],
    }
}

/// Writes the figures of `o` into `dir/figures/` (atomically); `records` are the tests read
/// (in `o.tests`' order) and `prep` their preprocessing. A test without an analysed
/// unloading has no unloading figure; the H and E figures are skipped when no unloading
/// was analysed.
///
/// # Errors
/// A folder or file that cannot be written, a figure that cannot be drawn.
pub fn write(
    dir: &Path,
    o: &AnalyzeOutcome,
    records: &[Record],
    prep: &Preprocessing,
) -> Result<Vec<PathBuf>> {
    let figures = dir.join("figures");
    let io = |e: anyhow::Error| Error::new(ErrorKind::Io, e);
    crate::atomic::ensure_writable_dir(&figures).map_err(io)?;
    let draw = |f: &LineFigure, path: &Path| -> Result<()> {
        let svg = f.svg(FigureSize::default()).map_err(|e| {
            Error::msg(
                ErrorKind::Io,
                format!("cannot draw {}: {e}", path.display()),
            )
        })?;
        crate::atomic::write(path, svg).map_err(io)
    };
    let mut written = Vec::new();
    for (t, r) in o.tests.iter().zip(records) {
        let Ok((x, _)) = indentify_records::apply(r, prep) else {
            continue;
        };
        if let Some(f) = unloading_figure(t, &x) {
            let p = figures.join(format!("unloading-{}.svg", t.index));
            draw(&f, &p)?;
            written.push(p);
        }
    }
    for (modulus, stem) in [(false, "hardness_depth"), (true, "modulus_depth")] {
        let f = depth_figure(o, modulus);
        if f.series[0].y.iter().any(|v| v.is_finite()) {
            let p = figures.join(format!("{stem}.svg"));
            draw(&f, &p)?;
            written.push(p);
        }
    }
    Ok(written)
}
