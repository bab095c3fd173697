//! A plain x-y figure of a few series (points, lines, dashed lines) with a caption, axis
//! labels, a legend and notes under the caption, as SVG text or PNG bytes: the figures of
//! the Oliver-Pharr analysis (an unloading with its power-law fit over the fitted range,
//! hardness and modulus against depth).

use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::error::ReportError;
use crate::plot::{FigureSize, encode_png, ensure_font};
use crate::units::fmt_tick;

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Style {
    /// Small circles at the points.
    Points,
    /// A solid line through the points.
    Line,
    /// A dashed line through the points.
    Dashed,
}

/// One series of a [`LineFigure`].
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend label.
    pub label: String,
    /// Abscissae (display units).
    pub x: Vec<f64>,
    /// Ordinates (display units).
    pub y: Vec<f64>,
    /// How it is drawn.
    pub style: Style,
}

/// An x-y figure.
#[derive(Debug, Clone, PartialEq)]
pub struct LineFigure {
    /// Caption.
    pub title: String,
    /// Lines of small text under the caption (the fitted numbers).
    pub notes: Vec<String>,
    /// x axis label with its unit, e.g. `depth h [nm]`.
    pub x_label: String,
    /// y axis label with its unit.
    pub y_label: String,
    /// The series (non-finite points are skipped).
    pub series: Vec<Series>,
}

const COLORS: [RGBColor; 5] = [
    RGBColor(40, 40, 40),
    RGBColor(214, 39, 40),
    RGBColor(31, 119, 180),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
];

impl LineFigure {
    /// The figure as an SVG document.
    ///
    /// # Errors
    /// [`ReportError::Size`], [`ReportError::Length`] when a series' x and y differ in
    /// length, [`ReportError::Empty`] without a finite point, [`ReportError::Draw`].
    pub fn svg(&self, size: FigureSize) -> Result<String, ReportError> {
        size.check()?;
        ensure_font()?;
        self.check()?;
        let mut svg = String::new();
        {
            let root =
                SVGBackend::with_string(&mut svg, (size.width, size.height)).into_drawing_area();
            self.draw(&root).map_err(draw_err)?;
            root.present().map_err(draw_err)?;
        }
        Ok(svg)
    }

    /// The figure as PNG bytes.
    ///
    /// # Errors
    /// As [`LineFigure::svg`], and [`ReportError::Png`].
    pub fn png(&self, size: FigureSize) -> Result<Vec<u8>, ReportError> {
        size.check()?;
        ensure_font()?;
        self.check()?;
        let (w, h) = (size.width, size.height);
        let mut rgb = vec![0u8; w as usize * h as usize * 3];
        {
            let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
            self.draw(&root).map_err(draw_err)?;
            root.present().map_err(draw_err)?;
        }
        encode_png(&rgb, w, h)
    }

    fn check(&self) -> Result<(), ReportError> {
        for s in &self.series {
            if s.x.len() != s.y.len() {
                return Err(ReportError::Length {
                    what: "series x and y",
                    expected: s.x.len(),
                    got: s.y.len(),
                });
            }
        }
        if self.points().next().is_none() {
            return Err(ReportError::Empty {
                what: "figure series",
            });
        }
        Ok(())
    }

    fn points(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        self.series
            .iter()
            .flat_map(|s| s.x.iter().copied().zip(s.y.iter().copied()))
            .filter(|(x, y)| x.is_finite() && y.is_finite())
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
        root.fill(&WHITE).map_err(e)?;
        let (w, h) = root.dim_in_pixel();
        let s = (f64::from(w) / 900.0).min(f64::from(h) / 600.0).max(0.4);
        let (caption, label, tick) = (
            (22.0 * s).max(15.0),
            (17.0 * s).max(13.0),
            (14.0 * s).max(11.0),
        );
        let note = tick * 0.9;
        let head = (caption * 1.6 + note * 1.3 * self.notes.len() as f64) as u32;
        let (header, body) = root.split_vertically(head.min(h / 3));
        let centre = i32::try_from(w / 2).unwrap_or(0);
        header
            .draw(&Text::new(
                self.title.clone(),
                (centre, (caption * 0.3) as i32),
                ("sans-serif", caption)
                    .into_font()
                    .color(&BLACK)
                    .pos(Pos::new(HPos::Center, VPos::Top)),
            ))
            .map_err(e)?;
        for (i, n) in self.notes.iter().enumerate() {
            header
                .draw(&Text::new(
                    n.clone(),
                    (centre, (caption * 1.5 + note * 1.3 * i as f64) as i32),
                    ("sans-serif", note)
                        .into_font()
                        .color(&RGBColor(80, 80, 80))
                        .pos(Pos::new(HPos::Center, VPos::Top)),
                ))
                .map_err(e)?;
        }
        let range = |v: Vec<f64>| {
            let (lo, hi) = v
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                    (a.min(x), b.max(x))
                });
            let span = hi - lo;
            if span > 0.0 {
                (lo - 0.05 * span)..(hi + 0.05 * span)
            } else {
                let d = if lo.abs() > 0.0 { 0.1 * lo.abs() } else { 1.0 };
                (lo - d)..(hi + d)
            }
        };
        let xr = range(self.points().map(|p| p.0).collect());
        let yr = range(self.points().map(|p| p.1).collect());
        let mut chart = ChartBuilder::on(&body)
            .margin((12.0 * s) as u32)
            .x_label_area_size((label * 2.6) as u32)
            .y_label_area_size((label * 4.2) as u32)
            .build_cartesian_2d(xr, yr)
            .map_err(e)?;
        chart
            .configure_mesh()
            .x_desc(self.x_label.clone())
            .y_desc(self.y_label.clone())
            .axis_desc_style(("sans-serif", label))
            .label_style(("sans-serif", tick))
            .x_label_formatter(&|v| fmt_tick(*v))
            .y_label_formatter(&|v| fmt_tick(*v))
            .light_line_style(RGBColor(235, 235, 235))
            .draw()
            .map_err(e)?;
        for (k, sr) in self.series.iter().enumerate() {
            let color = COLORS[k % COLORS.len()];
            let pts: Vec<(f64, f64)> =
                sr.x.iter()
                    .copied()
                    .zip(sr.y.iter().copied())
                    .filter(|(x, y)| x.is_finite() && y.is_finite())
                    .collect();
            let width = (2.0 * s).max(1.0) as u32;
            let anno =
                match sr.style {
                    Style::Points => chart
                        .draw_series(pts.iter().map(|&p| {
                            Circle::new(p, (3.0 * s).max(2.0) as i32, color.stroke_width(1))
                        }))
                        .map_err(e)?,
                    Style::Line => chart
                        .draw_series(LineSeries::new(pts, color.stroke_width(width)))
                        .map_err(e)?,
                    Style::Dashed => chart
                        .draw_series(std::iter::once(DashedPathElement::new(
                            pts,
                            (8.0 * s) as u32,
                            (5.0 * s) as u32,
                            color.stroke_width(width),
                        )))
                        .map_err(e)?,
                };
            anno.label(sr.label.clone()).legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
            });
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(RGBColor(180, 180, 180))
            .label_font(("sans-serif", tick))
            .position(SeriesLabelPosition::UpperLeft)
            .draw()
            .map_err(e)?;
        Ok(())
    }
}

fn draw_err(e: impl std::fmt::Display) -> ReportError {
    ReportError::Draw {
        figure: "line figure",
        message: e.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fig() -> LineFigure {
        LineFigure {
            title: "unloading 1".into(),
            notes: vec!["m = 1.5, S = 0.2 mN/nm".into()],
            x_label: "depth h [nm]".into(),
            y_label: "force F [mN]".into(),
            series: vec![
                Series {
                    label: "data".into(),
                    x: vec![1.0, 2.0, 3.0],
                    y: vec![1.0, 4.0, 9.0],
                    style: Style::Points,
                },
                Series {
                    label: "fit".into(),
                    x: vec![1.0, 3.0],
                    y: vec![1.0, 9.0],
                    style: Style::Dashed,
                },
            ],
        }
    }

    #[test]
    fn the_figure_carries_its_labels_and_notes() {
        let svg = fig().svg(FigureSize::default()).unwrap();
        for t in [
            "unloading 1",
            "m = 1.5, S = 0.2 mN/nm",
            "depth h [nm]",
            "force F [mN]",
            "fit",
        ] {
            assert!(svg.contains(t), "{t}");
        }
        assert!(
            fig()
                .png(FigureSize::default())
                .unwrap()
                .starts_with(b"\x89PNG")
        );
    }

    #[test]
    fn bad_series_are_errors() {
        let mut f = fig();
        f.series[0].y.pop();
        assert!(matches!(
            f.svg(FigureSize::default()),
            Err(ReportError::Length { .. })
        ));
        let mut f = fig();
        for s in &mut f.series {
            s.y.iter_mut().for_each(|v| *v = f64::NAN);
        }
        assert!(matches!(
            f.svg(FigureSize::default()),
            Err(ReportError::Empty { .. })
        ));
    }
}
