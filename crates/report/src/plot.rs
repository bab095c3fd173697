//! Figures of a [`Report`] (force-depth, force-time, convergence) as SVG text or PNG bytes.
//!
//! Text is drawn with DejaVu Sans embedded in the binary (registered with plotters as
//! "sans-serif"), so nothing depends on system fonts.

use std::ops::Range;
use std::sync::OnceLock;

use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::{FontStyle, register_font};

use crate::error::ReportError;
use crate::model::{FigureLink, Observable, Report};
use crate::units::{fmt_axis_tick, fmt_log_tick};

/// One of the report's figures.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Figure {
    /// Force vs depth: data, fit with the start parameters, fit with the identified ones.
    ForceDepth,
    /// Force vs time, the same three curves.
    ForceTime,
    /// Cost J (log scale) vs iteration, and each free parameter relative to its final
    /// value vs iteration.
    Convergence,
}

impl Figure {
    /// All figures, in report order.
    pub const ALL: [Figure; 3] = [Figure::ForceDepth, Figure::ForceTime, Figure::Convergence];

    /// A file stem for the figure ("force_depth", "force_time", "convergence").
    pub fn file_stem(self) -> &'static str {
        match self {
            Figure::ForceDepth => "force_depth",
            Figure::ForceTime => "force_time",
            Figure::Convergence => "convergence",
        }
    }

    /// A Markdown link to this figure stored at `path` (relative to the Markdown file).
    pub fn link(self, path: impl Into<String>) -> FigureLink {
        FigureLink::new(self.caption(), path)
    }

    /// The file stem of this figure for a fit of `observable`: under load control
    /// ([`Observable::Depth`]) the time figure shows the depth ("depth_time").
    pub fn file_stem_for(self, observable: Observable) -> &'static str {
        match (self, observable) {
            (Figure::ForceTime, Observable::Depth) => "depth_time",
            _ => self.file_stem(),
        }
    }

    /// The caption of this figure for a fit of `observable` ("depth vs time" under load
    /// control).
    pub fn caption_for(self, observable: Observable) -> &'static str {
        match (self, observable) {
            (Figure::ForceTime, Observable::Depth) => "depth vs time",
            _ => self.caption(),
        }
    }

    /// [`Figure::link`] with the caption of [`Figure::caption_for`].
    pub fn link_for(self, observable: Observable, path: impl Into<String>) -> FigureLink {
        FigureLink::new(self.caption_for(observable), path)
    }

    /// A caption for the figure ("force vs depth", ...).
    pub fn caption(self) -> &'static str {
        match self {
            Figure::ForceDepth => "force vs depth",
            Figure::ForceTime => "force vs time",
            Figure::Convergence => "convergence",
        }
    }
}

/// Figure size in pixels (SVG user units). Each side must be in 100..=4000.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FigureSize {
    /// Width, px.
    pub width: u32,
    /// Height, px.
    pub height: u32,
}

impl Default for FigureSize {
    /// 900 x 600 px.
    fn default() -> Self {
        Self {
            width: 900,
            height: 600,
        }
    }
}

impl FigureSize {
    pub(crate) fn check(self) -> Result<(), ReportError> {
        let ok = |v: u32| (100..=4000).contains(&v);
        if ok(self.width) && ok(self.height) {
            Ok(())
        } else {
            Err(ReportError::Size {
                width: self.width,
                height: self.height,
            })
        }
    }
}

/// Measured data.
const DATA: RGBColor = RGBColor(40, 40, 40);
/// Fit with the start parameters.
const START: RGBColor = RGBColor(31, 119, 180);
/// Fit with the identified parameters.
const FINAL: RGBColor = RGBColor(214, 39, 40);
/// Parameter histories (tab10 without the colors above).
const PALETTE: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
];
/// Data series longer than this are drawn as a thin line instead of markers.
const MAX_MARKERS: usize = 400;

impl Report {
    /// `figure` as an SVG document.
    ///
    /// # Errors
    /// - [`ReportError::Size`] for a side outside 100..=4000 px,
    /// - [`ReportError::Length`] if the curves' series differ in length,
    /// - [`ReportError::Empty`] if a series has no finite point (non-finite points are
    ///   skipped; J <= 0 is skipped on the log axis),
    /// - [`ReportError::Font`] / [`ReportError::Draw`] if plotters fails.
    pub fn figure_svg(&self, figure: Figure, size: FigureSize) -> Result<String, ReportError> {
        size.check()?;
        ensure_font()?;
        let mut svg = String::new();
        {
            let root =
                SVGBackend::with_string(&mut svg, (size.width, size.height)).into_drawing_area();
            draw(self, figure, &root)?;
            root.present().map_err(|e| draw_err(figure, e))?;
        }
        Ok(svg)
    }

    /// `figure` as PNG bytes (8-bit RGB).
    ///
    /// # Errors
    /// As [`Report::figure_svg`], and [`ReportError::Png`] if encoding fails.
    pub fn figure_png(&self, figure: Figure, size: FigureSize) -> Result<Vec<u8>, ReportError> {
        size.check()?;
        ensure_font()?;
        let (w, h) = (size.width, size.height);
        let mut rgb = vec![0u8; w as usize * h as usize * 3];
        {
            let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
            draw(self, figure, &root)?;
            root.present().map_err(|e| draw_err(figure, e))?;
        }
        encode_png(&rgb, w, h)
    }
}

pub(crate) fn encode_png(rgb: &[u8], w: u32, h: u32) -> Result<Vec<u8>, ReportError> {
    let mut out = Vec::new();
    let png_err = |e: png::EncodingError| ReportError::Png(e.to_string());
    {
        let mut enc = png::Encoder::new(&mut out, w, h);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut writer = enc.write_header().map_err(png_err)?;
        writer.write_image_data(rgb).map_err(png_err)?;
        writer.finish().map_err(png_err)?;
    }
    Ok(out)
}

/// Registers DejaVu Sans as "sans-serif" once per process.
pub(crate) fn ensure_font() -> Result<(), ReportError> {
    static FONT: OnceLock<bool> = OnceLock::new();
    let ok = *FONT.get_or_init(|| {
        register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular()).is_ok()
    });
    if ok { Ok(()) } else { Err(ReportError::Font) }
}

fn draw_err(figure: Figure, e: impl std::fmt::Display) -> ReportError {
    ReportError::Draw {
        figure: figure.file_stem(),
        message: e.to_string(),
    }
}

/// Points `(x[i], y[i])` with both coordinates finite.
fn finite_pairs(
    what: &'static str,
    x: &[f64],
    y: &[f64],
    fx: f64,
    fy: f64,
) -> Result<Vec<(f64, f64)>, ReportError> {
    let pts: Vec<(f64, f64)> = x
        .iter()
        .zip(y)
        .map(|(&x, &y)| (x * fx, y * fy))
        .filter(|(x, y)| x.is_finite() && y.is_finite())
        .collect();
    if pts.is_empty() {
        return Err(ReportError::Empty { what });
    }
    Ok(pts)
}

/// Range covering `values` with 5 % margins (a unit-wide range around a single value).
fn padded(values: impl Iterator<Item = f64>) -> Range<f64> {
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    });
    let span = hi - lo;
    if !(span > 0.0) {
        let d = if lo.abs() > 0.0 { 0.1 * lo.abs() } else { 1.0 };
        return (lo - d)..(hi + d);
    }
    (lo - 0.05 * span)..(hi + 0.05 * span)
}

/// Font sizes scaled with the figure.
struct Fonts {
    caption: f64,
    label: f64,
    tick: f64,
}

impl Fonts {
    fn for_area<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>) -> Self {
        let (w, h) = root.dim_in_pixel();
        let s = (f64::from(w) / 900.0).min(f64::from(h) / 600.0).max(0.4);
        // Shrink with the figure, but not below legible sizes.
        Self {
            caption: (22.0 * s).max(15.0),
            label: (17.0 * s).max(13.0),
            tick: (14.0 * s).max(11.0),
        }
    }
}

fn draw<DB: DrawingBackend>(
    report: &Report,
    figure: Figure,
    root: &DrawingArea<DB, Shift>,
) -> Result<(), ReportError> {
    root.fill(&WHITE).map_err(|e| draw_err(figure, e))?;
    match figure {
        Figure::ForceDepth | Figure::ForceTime => draw_force(report, figure, root),
        Figure::Convergence => draw_convergence(report, root),
    }
}

fn draw_force<DB: DrawingBackend>(
    report: &Report,
    figure: Figure,
    root: &DrawingArea<DB, Shift>,
) -> Result<(), ReportError> {
    let c = &report.curves;
    c.check_lengths()?;
    let err = |e| draw_err(figure, e);
    let force_depth = figure == Figure::ForceDepth;
    let (fx, x_desc) = if force_depth {
        (
            c.depth_unit.factor,
            format!("depth h [{}]", c.depth_unit.label),
        )
    } else {
        (1.0, "time t [s]".to_string())
    };
    // the y axis: the force against the depth; the observable (force or depth) in time
    let yu = if force_depth {
        &c.force_unit
    } else {
        c.observed_unit()
    };
    let ff = yu.factor;
    let y_desc = if force_depth {
        format!("force F [{}]", c.force_unit.label)
    } else {
        let o = c.observable;
        format!("{} {} [{}]", o.name(), o.symbol(), yu.label)
    };
    let pairs = |what: &'static str, series: &[f64]| {
        if force_depth {
            let (x, y) = c.depth_force(series);
            finite_pairs(what, x, y, fx, ff)
        } else {
            finite_pairs(what, &c.t, series, fx, ff)
        }
    };
    let data = pairs("curves.f_data", &c.f_data)?;
    let fin = pairs("curves.f_final", &c.f_final)?;
    let start = match &c.f_start {
        Some(s) => Some(pairs("curves.f_start", s)?),
        None => None,
    };
    let all = || {
        data.iter()
            .chain(&fin)
            .chain(start.iter().flatten())
            .copied()
    };
    let xr = padded(all().map(|p| p.0));
    let yr = padded(all().map(|p| p.1));
    let xm = xr.start.abs().max(xr.end.abs());
    let ym = yr.start.abs().max(yr.end.abs());
    let mut lines: Vec<&[(f64, f64)]> = vec![&data, &fin];
    if let Some(s) = &start {
        lines.push(s);
    }
    let corner = legend_corner(&lines, &xr, &yr);

    let fonts = Fonts::for_area(root);
    let caption = title(report, figure);
    // A header with the caption and, in small type, what was identified and how well.
    let (w, h) = root.dim_in_pixel();
    let note_px = fonts.tick * 0.9;
    // about 0.55 em a character in DejaVu Sans
    let max_chars = (f64::from(root.dim_in_pixel().0) / (note_px * 0.55)) as usize;
    let notes = header_notes(report, max_chars.max(40));
    let head =
        (fonts.label * 0.8 + fonts.caption * 1.3 + note_px * 1.3 * notes.len() as f64) as u32;
    let (header, body) = root.split_vertically(head.min(h / 3));
    let centre = i32::try_from(w / 2).unwrap_or(0);
    let top = (fonts.label * 0.8) as i32;
    header
        .draw(&Text::new(
            caption,
            (centre, top),
            ("sans-serif", fonts.caption)
                .into_font()
                .color(&BLACK)
                .pos(Pos::new(HPos::Center, VPos::Top)),
        ))
        .map_err(err)?;
    let grey = RGBColor(80, 80, 80);
    for (i, (line, caveat)) in notes.into_iter().enumerate() {
        let y = top + (fonts.caption * 1.3 + note_px * 1.3 * i as f64) as i32;
        header
            .draw(&Text::new(
                line,
                (centre, y),
                ("sans-serif", note_px)
                    .into_font()
                    .color(if caveat { &CAVEAT } else { &grey })
                    .pos(Pos::new(HPos::Center, VPos::Top)),
            ))
            .map_err(err)?;
    }
    let (main, residual_area) = if figure == Figure::ForceTime {
        let (_, bh) = body.dim_in_pixel();
        let (a, b) = body.split_vertically(bh * 7 / 10);
        (a, Some(b))
    } else {
        (body, None)
    };
    let root = &main;
    let (x_desc, x_area) = if residual_area.is_some() {
        (String::new(), fonts.label * 1.8)
    } else {
        (x_desc, fonts.label * 3.2)
    };
    let mut chart = ChartBuilder::on(root)
        .margin(fonts.label)
        .margin_top(0.0)
        .x_label_area_size(x_area)
        .y_label_area_size(fonts.label * 5.0)
        .build_cartesian_2d(xr, yr)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .y_labels(y_label_count(root, fonts.tick))
        .x_label_formatter(&|v| fmt_axis_tick(*v, xm))
        .y_label_formatter(&|v| fmt_axis_tick(*v, ym))
        .label_style(("sans-serif", fonts.tick))
        .axis_desc_style(("sans-serif", fonts.label))
        .light_line_style(RGBColor(238, 238, 238))
        .bold_line_style(RGBColor(210, 210, 210))
        .draw()
        .map_err(err)?;

    let marker = (fonts.tick / 4.0).max(2.0);
    if data.len() <= MAX_MARKERS {
        chart
            .draw_series(
                data.iter()
                    .map(|&p| Circle::new(p, marker, DATA.stroke_width(1))),
            )
            .map_err(err)?
            .label("data")
            .legend(move |(x, y)| Circle::new((x + 10, y), marker, DATA.stroke_width(1)));
    } else {
        chart
            .draw_series(LineSeries::new(data.iter().copied(), DATA.stroke_width(1)))
            .map_err(err)?
            .label("data")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], DATA.stroke_width(1)));
    }
    if let Some(start) = start {
        let style = START.stroke_width(2);
        let dash = (fonts.tick * 0.6) as u32;
        chart
            .draw_series(DashedLineSeries::new(start, dash, dash / 2 + 1, style))
            .map_err(err)?
            .label("fit, start parameters")
            .legend(move |(x, y)| DashedPathElement::new(vec![(x, y), (x + 20, y)], 6, 3, style));
    }
    let style = FINAL.stroke_width(2);
    chart
        .draw_series(LineSeries::new(fin, style))
        .map_err(err)?
        .label("fit, identified parameters")
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], style));
    if data.len() <= MAX_MARKERS {
        // Markers again, above the fits (the first pass only fixed the legend order).
        chart
            .draw_series(
                data.iter()
                    .map(|&p| Circle::new(p, marker, DATA.stroke_width(1))),
            )
            .map_err(err)?;
    }
    chart
        .configure_series_labels()
        .position(corner)
        .label_font(("sans-serif", fonts.tick))
        .background_style(WHITE.mix(0.85))
        .border_style(RGBColor(160, 160, 160))
        .draw()
        .map_err(err)?;
    if let Some(area) = residual_area {
        draw_residuals(report, &area, &fonts, fx, ff).map_err(err)?;
    }
    Ok(())
}

/// The colour of the header's caveat lines (dark red).
const CAVEAT: RGBColor = RGBColor(170, 20, 20);

/// The header's lines, each with whether it is a caveat: the identified values with their
/// ± σ, the fit's numbers and the source, then the report's caveats ([`Report::caveats`]:
/// not converged, systematic residuals, discretization beyond σ, undetermined, at a bound),
/// so that a figure pasted alone carries the console's verdict.
fn header_notes(report: &Report, max_chars: usize) -> Vec<(String, bool)> {
    let mut notes: Vec<(String, bool)> = wrap(&identified_label(report), max_chars)
        .into_iter()
        .map(|l| (l, false))
        .collect();
    notes.push((fit_note(report), false));
    let caveats = report.caveats();
    if !caveats.is_empty() {
        let text = format!("CAVEAT: {}", caveats.join("; "));
        notes.extend(wrap(&text, max_chars).into_iter().map(|l| (l, true)));
    }
    notes
}

/// `text` cut at spaces into lines of at most `max` characters (a longer word stays whole).
fn wrap(text: &str, max: usize) -> Vec<String> {
    let mut lines = Vec::new();
    let mut line = String::new();
    for word in text.split(' ') {
        if !line.is_empty() && line.chars().count() + 1 + word.chars().count() > max {
            lines.push(std::mem::take(&mut line));
        }
        if !line.is_empty() {
            line.push(' ');
        }
        line.push_str(word);
    }
    if !line.is_empty() {
        lines.push(line);
    }
    lines
}

/// `identified: E = 1683 ± 12 MPa, eta = 1.033e5 ± 2.1e3 MPa s` (the free parameters, in
/// the report's display units; `sY = 8.776 MPa undetermined`, `m = 30.00 at upper bound`;
/// `last iterate (NOT converged):` instead of `identified:` when the run did not converge).
fn identified_label(report: &Report) -> String {
    let free: Vec<String> = report
        .parameters
        .iter()
        .filter(|p| !p.fixed)
        .map(|p| {
            let v = p.value * p.unit.factor;
            let unit = if p.unit.label == "-" {
                String::new()
            } else {
                format!(" {}", p.unit.label)
            };
            let sd = p.std_dev.map(|s| s * p.unit.factor.abs());
            let status = if report.is_undetermined(&p.name) {
                " undetermined".to_string()
            } else {
                match p.at_bound {
                    Some(crate::model::BoundHit::Lower) => " at lower bound".to_string(),
                    Some(crate::model::BoundHit::Upper) => " at upper bound".to_string(),
                    None => String::new(),
                }
            };
            let pm = match sd {
                Some(s) if s.is_finite() && !report.is_undetermined(&p.name) => {
                    format!(" ± {}", short_sd(s))
                }
                _ => String::new(),
            };
            format!("{} = {}{pm}{unit}{status}", p.name, short_value(v))
        })
        .collect();
    if free.is_empty() {
        "no free parameter".to_string()
    } else if report.convergence.converged == Some(false) {
        format!("last iterate (NOT converged): {}", free.join(", "))
    } else {
        format!("identified: {}", free.join(", "))
    }
}

/// Two significant digits of a standard deviation.
fn short_sd(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 || !a.is_finite() {
        return format!("{v}");
    }
    if !(1e-2..1e5).contains(&a) {
        return format!("{v:.1e}");
    }
    let decimals = (1 - a.log10().floor() as i32).max(0) as usize;
    format!("{v:.decimals$}")
}

/// Four significant digits, in exponent notation outside [0.01, 1e5).
fn short_value(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 || !a.is_finite() {
        return format!("{v}");
    }
    if !(1e-2..1e5).contains(&a) {
        return format!("{v:.3e}");
    }
    let decimals = (3 - a.log10().floor() as i32).max(0) as usize;
    format!("{v:.decimals$}")
}

/// `R² = 0.9781, RMS residual 4.90% of F_max (60 points); anonNI.TXT, test 1` (`h_max`
/// when the depth is the observable).
fn fit_note(report: &Report) -> String {
    let f = &report.fit;
    let file = report
        .source
        .file
        .rsplit(['/', '\\'])
        .next()
        .unwrap_or(&report.source.file)
        .to_string();
    let mut note = format!(
        "R\u{b2} = {:.4}, RMS residual {:.2}% of {}_max ({} points)",
        f.r2,
        100.0 * f.rms_rel,
        report.curves.observable.symbol(),
        f.n
    );
    if !file.is_empty() {
        note.push_str(&format!("; {file}"));
        if !report.source.test.is_empty() {
            note.push_str(&format!(", {}", report.source.test));
        }
    }
    note
}

/// The residual panel under the force-time curves: `F_fit - F_data` over time, with the
/// zero line, in the force figure's unit.
fn draw_residuals<DB: DrawingBackend>(
    report: &Report,
    area: &DrawingArea<DB, Shift>,
    fonts: &Fonts,
    fx: f64,
    ff: f64,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let c = &report.curves;
    let pts: Vec<(f64, f64)> =
        c.t.iter()
            .zip(c.f_final.iter().zip(&c.f_data))
            .map(|(&t, (&m, &d))| (t * fx, (m - d) * ff))
            .filter(|(t, r)| t.is_finite() && r.is_finite())
            .collect();
    if pts.is_empty() {
        return Ok(());
    }
    let xr = padded(pts.iter().map(|p| p.0));
    let rmax = pts.iter().map(|p| p.1.abs()).fold(0.0, f64::max);
    let rmax = if rmax > 0.0 { rmax * 1.1 } else { 1.0 };
    let xm = xr.start.abs().max(xr.end.abs());
    let mut chart = ChartBuilder::on(area)
        .margin(fonts.label)
        .margin_top(0.0)
        .x_label_area_size(fonts.label * 3.2)
        .y_label_area_size(fonts.label * 5.0)
        .build_cartesian_2d(xr.clone(), -rmax..rmax)?;
    chart
        .configure_mesh()
        .x_desc("time t [s]")
        .y_desc(format!("fit - data [{}]", c.observed_unit().label))
        .y_labels(5)
        .x_label_formatter(&|v| fmt_axis_tick(*v, xm))
        .y_label_formatter(&|v| fmt_axis_tick(*v, rmax))
        .label_style(("sans-serif", fonts.tick))
        .axis_desc_style(("sans-serif", fonts.label))
        .light_line_style(RGBColor(238, 238, 238))
        .bold_line_style(RGBColor(210, 210, 210))
        .draw()?;
    chart.draw_series(LineSeries::new(
        vec![(xr.start, 0.0), (xr.end, 0.0)],
        RGBColor(120, 120, 120).stroke_width(1),
    ))?;
    chart.draw_series(LineSeries::new(pts.iter().copied(), FINAL.stroke_width(1)))?;
    let marker = (fonts.tick / 5.0).max(1.5);
    chart.draw_series(pts.iter().map(|&p| Circle::new(p, marker, FINAL.filled())))?;
    Ok(())
}

fn draw_convergence<DB: DrawingBackend>(
    report: &Report,
    root: &DrawingArea<DB, Shift>,
) -> Result<(), ReportError> {
    let figure = Figure::Convergence;
    let err = |e| draw_err(figure, e);
    let cost: Vec<(f64, f64)> = report
        .history
        .iter()
        .map(|r| (r.iteration as f64, r.cost))
        .filter(|(_, j)| j.is_finite() && *j > 0.0)
        .collect();
    if cost.is_empty() {
        return Err(ReportError::Empty {
            what: "history.cost (finite, > 0)",
        });
    }
    // Each free parameter relative to its final value.
    let mut rel: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    for (k, p) in report.parameters.iter().enumerate() {
        if p.fixed || !p.value.is_finite() || p.value == 0.0 {
            continue;
        }
        let pts: Vec<(f64, f64)> = report
            .history
            .iter()
            .filter_map(|r| r.params.get(k).map(|v| (r.iteration as f64, v / p.value)))
            .filter(|(_, v)| v.is_finite())
            .collect();
        if !pts.is_empty() {
            rel.push((format!("{} / {}_final", p.name, p.name), pts));
        }
    }

    let fonts = Fonts::for_area(root);
    let title = title(report, figure);
    let titled = root
        .titled(&title, ("sans-serif", fonts.caption))
        .map_err(err)?;
    let (top, bottom) = if rel.is_empty() {
        (titled, None)
    } else {
        let (_, h) = titled.dim_in_pixel();
        let (a, b) = titled.split_vertically(h / 2);
        (a, Some(b))
    };

    let iters = padded(
        cost.iter()
            .map(|p| p.0)
            .chain(rel.iter().flat_map(|r| r.1.iter().map(|p| p.0))),
    );
    let (jlo, jhi) = cost.iter().fold((f64::INFINITY, 0.0_f64), |(lo, hi), p| {
        (lo.min(p.1), hi.max(p.1))
    });
    // At least two decades (so that at least two decade ticks carry labels), with a
    // margin of a fifth of a decade at each end.
    let (jlo, jhi) = if jhi / jlo < 100.0 {
        let mid = (jlo * jhi).sqrt();
        (mid / 10.0, mid * 10.0)
    } else {
        (jlo / 10f64.powf(0.2), jhi * 10f64.powf(0.2))
    };
    let xs = iters.end - iters.start;
    // About one label per iteration, at most 12.
    let n_iter_labels = (xs.round() as usize + 1).clamp(2, 12);
    {
        let mut chart = ChartBuilder::on(&top)
            .margin(fonts.label)
            .x_label_area_size(fonts.tick * 2.2)
            .y_label_area_size(fonts.label * 5.0)
            .build_cartesian_2d(iters.clone(), (jlo..jhi).log_scale())
            .map_err(err)?;
        chart
            .configure_mesh()
            .y_desc("cost J (N²)")
            .x_labels(n_iter_labels)
            .y_labels(y_label_count(&top, fonts.tick))
            .x_label_formatter(&|v| iteration_tick(*v, xs))
            .y_label_formatter(&|v| fmt_log_tick(*v, jlo, jhi))
            .label_style(("sans-serif", fonts.tick))
            .axis_desc_style(("sans-serif", fonts.label))
            .light_line_style(RGBColor(238, 238, 238))
            .bold_line_style(RGBColor(210, 210, 210))
            .draw()
            .map_err(err)?;
        let style = FINAL.stroke_width(2);
        let marker = (fonts.tick / 4.0).max(2.0);
        chart
            .draw_series(LineSeries::new(cost.iter().copied(), style))
            .map_err(err)?
            .label("J")
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], style));
        chart
            .draw_series(cost.iter().map(|&p| Circle::new(p, marker, FINAL.filled())))
            .map_err(err)?;
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .label_font(("sans-serif", fonts.tick))
            .background_style(WHITE.mix(0.85))
            .border_style(RGBColor(160, 160, 160))
            .draw()
            .map_err(err)?;
    }
    let Some(bottom) = bottom else {
        return Ok(());
    };
    let yr = padded(
        rel.iter()
            .flat_map(|r| r.1.iter().map(|p| p.1))
            .chain([1.0]),
    );
    let ym = yr.start.abs().max(yr.end.abs());
    let lines: Vec<&[(f64, f64)]> = rel.iter().map(|r| r.1.as_slice()).collect();
    let corner = legend_corner(&lines, &iters, &yr);
    let mut chart = ChartBuilder::on(&bottom)
        .margin(fonts.label)
        .x_label_area_size(fonts.label * 3.2)
        .y_label_area_size(fonts.label * 5.0)
        .build_cartesian_2d(iters.clone(), yr)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("iteration")
        .y_desc("parameter / final value")
        .x_labels(n_iter_labels)
        .y_labels(y_label_count(&bottom, fonts.tick))
        .x_label_formatter(&|v| iteration_tick(*v, xs))
        .y_label_formatter(&|v| fmt_axis_tick(*v, ym))
        .label_style(("sans-serif", fonts.tick))
        .axis_desc_style(("sans-serif", fonts.label))
        .light_line_style(RGBColor(238, 238, 238))
        .bold_line_style(RGBColor(210, 210, 210))
        .draw()
        .map_err(err)?;
    for (i, (name, pts)) in rel.into_iter().enumerate() {
        let color = PALETTE[i % PALETTE.len()];
        let style = color.stroke_width(2);
        chart
            .draw_series(LineSeries::new(pts, style))
            .map_err(err)?
            .label(name)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], style));
    }
    chart
        .configure_series_labels()
        .position(corner)
        .label_font(("sans-serif", fonts.tick))
        .background_style(WHITE.mix(0.85))
        .border_style(RGBColor(160, 160, 160))
        .draw()
        .map_err(err)?;
    Ok(())
}

/// The legend corner whose box (40 % of the width, 35 % of the height) is crossed least
/// by the polylines `series`; ties go to the earlier corner in upper-left, upper-right,
/// lower-right, lower-left order.
fn legend_corner(
    series: &[&[(f64, f64)]],
    xr: &Range<f64>,
    yr: &Range<f64>,
) -> SeriesLabelPosition {
    // Segments are sampled so that a line crossing a corner counts, not only its vertices.
    const SUB: usize = 8;
    let mut counts = [0usize; 4];
    let mut add = |x: f64, y: f64| {
        let u = (x - xr.start) / (xr.end - xr.start);
        let v = (y - yr.start) / (yr.end - yr.start);
        let (left, right, low, up) = (u < 0.4, u > 0.6, v < 0.35, v > 0.65);
        counts[0] += usize::from(left && up);
        counts[1] += usize::from(right && up);
        counts[2] += usize::from(right && low);
        counts[3] += usize::from(left && low);
    };
    for s in series {
        if let Some(&(x, y)) = s.first() {
            add(x, y);
        }
        for w in s.windows(2) {
            let ((x0, y0), (x1, y1)) = (w[0], w[1]);
            for k in 1..=SUB {
                let a = k as f64 / SUB as f64;
                add(x0 + a * (x1 - x0), y0 + a * (y1 - y0));
            }
        }
    }
    let corners = [
        SeriesLabelPosition::UpperLeft,
        SeriesLabelPosition::UpperRight,
        SeriesLabelPosition::LowerRight,
        SeriesLabelPosition::LowerLeft,
    ];
    let best = (0..4).min_by_key(|&i| counts[i]).unwrap_or(0);
    corners[best].clone()
}

/// About one y tick label per four text heights of the area, 3 to 10.
fn y_label_count<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, tick: f64) -> usize {
    let (_, h) = area.dim_in_pixel();
    ((f64::from(h) / (4.0 * tick)) as usize).clamp(3, 10)
}

/// Iteration ticks: integers only.
fn iteration_tick(v: f64, span: f64) -> String {
    let v = snap_zero(v, span);
    if (v - v.round()).abs() < 1e-9 {
        format!("{}", v.round() as i64)
    } else {
        String::new()
    }
}

/// Tick values that are zero up to round-off (`1e-17` on a unit-wide axis) print as 0.
fn snap_zero(v: f64, span: f64) -> f64 {
    if v.abs() < 1e-9 * span { 0.0 } else { v }
}

/// `law: caption, test T` (without the test when the source names none).
fn title(report: &Report, figure: Figure) -> String {
    let test = report.source.test.trim();
    let o = report.curves.observable;
    if test.is_empty() {
        format!("{}: {}", report.law, figure.caption_for(o))
    } else {
        format!("{}: {}, test {test}", report.law, figure.caption_for(o))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn legend_avoids_occupied_corners() {
        let r = 0.0..1.0;
        // Loading curve from lower left to upper right: upper left is free.
        let diag: Vec<(f64, f64)> = (0..=10)
            .map(|i| (i as f64 / 10.0, i as f64 / 10.0))
            .collect();
        assert_eq!(
            legend_corner(&[&diag], &r, &r),
            SeriesLabelPosition::UpperLeft
        );
        // Fast rise then slow decay: the upper left is taken, the lower right too.
        let peak: Vec<(f64, f64)> = vec![(0.0, 0.0), (0.1, 1.0), (1.0, 0.1)];
        assert_eq!(
            legend_corner(&[&peak], &r, &r),
            SeriesLabelPosition::UpperRight
        );
    }

    /// Header lines are cut at spaces to the figure's width; joined again they are the
    /// text (a long stop reason overflowed the sphere record's caveat line).
    #[test]
    fn header_lines_wrap_at_spaces() {
        let text = "CAVEAT: NOT converged (relative decrease below tolerance, but the data do \
                    not determine K); systematic residuals";
        let lines = wrap(text, 30);
        assert!(lines.len() > 2 && lines.iter().all(|l| l.chars().count() <= 30));
        assert_eq!(lines.join(" "), text);
        assert_eq!(wrap("a_very_long_word b", 5), ["a_very_long_word", "b"]);
    }

    #[test]
    fn iteration_ticks_are_integers() {
        assert_eq!(iteration_tick(2.0, 10.0), "2");
        assert_eq!(iteration_tick(2.5, 10.0), "");
        assert_eq!(iteration_tick(-1e-17, 10.0), "0");
    }
}
