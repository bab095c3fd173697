//! Figures of a map of indents: a heat map of one quantity over the indents' positions
//! (one colored cell per indent, a color bar, missing indents hatched in grey) and its
//! histogram, as SVG text or PNG bytes.

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::error::ReportError;
use crate::plot::{FigureSize, encode_png, ensure_font};
use crate::units::fmt_tick;

/// One quantity over the indents of a map.
#[derive(Debug, Clone, PartialEq)]
pub struct MapData {
    /// Title, e.g. "E (MPa)".
    pub title: String,
    /// Positions (any unit, the same for x and y).
    pub x: Vec<f64>,
    /// Positions.
    pub y: Vec<f64>,
    /// The quantity at each indent; NaN where the indent failed or has no value.
    pub values: Vec<f64>,
    /// The positions' unit, shown on the axes (`x [mm]`); empty: none.
    pub position_unit: String,
}

/// The two map figures.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MapFigure {
    /// Colored cells at the indents' positions.
    HeatMap,
    /// Histogram of the finite values (20 bins).
    Histogram,
}

impl MapFigure {
    fn name(self) -> &'static str {
        match self {
            MapFigure::HeatMap => "heat map",
            MapFigure::Histogram => "histogram",
        }
    }
}

impl MapData {
    /// `figure` as an SVG document.
    ///
    /// # Errors
    /// [`ReportError::Length`] when x, y and values differ in length, [`ReportError::Empty`]
    /// without a finite value, [`ReportError::Size`], [`ReportError::Draw`].
    pub fn svg(&self, figure: MapFigure, size: FigureSize) -> Result<String, ReportError> {
        size.check()?;
        ensure_font()?;
        self.check()?;
        let mut svg = String::new();
        {
            let root =
                SVGBackend::with_string(&mut svg, (size.width, size.height)).into_drawing_area();
            self.draw(figure, &root)?;
            root.present().map_err(|e| draw_err(figure, e))?;
        }
        Ok(svg)
    }

    /// `figure` as PNG bytes.
    ///
    /// # Errors
    /// As [`MapData::svg`], and [`ReportError::Png`].
    pub fn png(&self, figure: MapFigure, size: FigureSize) -> Result<Vec<u8>, ReportError> {
        size.check()?;
        ensure_font()?;
        self.check()?;
        let (w, h) = (size.width, size.height);
        let mut rgb = vec![0u8; w as usize * h as usize * 3];
        {
            let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
            self.draw(figure, &root)?;
            root.present().map_err(|e| draw_err(figure, e))?;
        }
        encode_png(&rgb, w, h)
    }

    fn check(&self) -> Result<(), ReportError> {
        let n = self.values.len();
        if self.x.len() != n || self.y.len() != n {
            return Err(ReportError::Length {
                what: "map x, y and values",
                expected: n,
                got: self.x.len().min(self.y.len()),
            });
        }
        if !self.values.iter().any(|v| v.is_finite()) {
            return Err(ReportError::Empty { what: "map values" });
        }
        Ok(())
    }

    fn range(&self) -> (f64, f64) {
        let (lo, hi) = self
            .values
            .iter()
            .filter(|v| v.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        if hi > lo {
            (lo, hi)
        } else {
            let d = if lo == 0.0 { 1.0 } else { 0.05 * lo.abs() };
            (lo - d, hi + d)
        }
    }

    fn draw<DB: DrawingBackend>(
        &self,
        figure: MapFigure,
        root: &DrawingArea<DB, Shift>,
    ) -> Result<(), ReportError> {
        root.fill(&WHITE).map_err(|e| draw_err(figure, e))?;
        match figure {
            MapFigure::HeatMap => self.draw_heat_map(root),
            MapFigure::Histogram => self.draw_histogram(root),
        }
        .map_err(|e| draw_err(figure, e))
    }

    fn draw_heat_map<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
    ) -> Result<(), String> {
        let (lo, hi) = self.range();
        let spacing = |v: &[f64]| {
            let mut s: Vec<f64> = v.to_vec();
            s.sort_by(f64::total_cmp);
            s.dedup();
            s.windows(2)
                .map(|w| w[1] - w[0])
                .filter(|d| *d > 0.0)
                .fold(f64::INFINITY, f64::min)
        };
        let (dx, dy) = (spacing(&self.x), spacing(&self.y));
        let d = match (dx.is_finite(), dy.is_finite()) {
            (true, true) => (dx, dy),
            (true, false) => (dx, dx),
            (false, true) => (dy, dy),
            (false, false) => (1.0, 1.0),
        };
        let min = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
        let max = |v: &[f64]| v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let mut xr = (min(&self.x) - d.0 / 2.0)..(max(&self.x) + d.0 / 2.0);
        let mut yr = (min(&self.y) - d.1 / 2.0)..(max(&self.y) + d.1 / 2.0);
        let (w, _) = root.dim_in_pixel();
        let (plot, bar) = root.split_horizontally(w.saturating_sub(130));
        let plot = plot
            .titled(&self.title, ("sans-serif", 22))
            .map_err(|e| e.to_string())?;
        // equal aspect: one length per pixel on both axes, the shorter span widened about
        // its centre (the plotting area is the area less the margins and label areas)
        let (pw, ph) = plot.dim_in_pixel();
        let (margin, x_area, y_area) = (12u32, 40u32, 60u32);
        let px = f64::from(pw.saturating_sub(2 * margin + y_area).max(1));
        let py = f64::from(ph.saturating_sub(2 * margin + x_area).max(1));
        let (sx, sy) = (xr.end - xr.start, yr.end - yr.start);
        let per_pixel = (sx / px).max(sy / py);
        let widen = |r: &mut std::ops::Range<f64>, pixels: f64| {
            let (c, half) = (0.5 * (r.start + r.end), 0.5 * per_pixel * pixels);
            *r = (c - half)..(c + half);
        };
        widen(&mut xr, px);
        widen(&mut yr, py);
        let mut chart = ChartBuilder::on(&plot)
            .margin(margin)
            .x_label_area_size(x_area)
            .y_label_area_size(y_area)
            .build_cartesian_2d(xr, yr)
            .map_err(|e| e.to_string())?;
        let axis = |name: &str| {
            if self.position_unit.is_empty() {
                name.to_string()
            } else {
                format!("{name} [{}]", self.position_unit)
            }
        };
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc(axis("x"))
            .y_desc(axis("y"))
            .label_style(("sans-serif", 15))
            .x_label_formatter(&|v| fmt_tick(*v))
            .y_label_formatter(&|v| fmt_tick(*v))
            .draw()
            .map_err(|e| e.to_string())?;
        let cells = (0..self.values.len()).map(|i| {
            let (x, y, v) = (self.x[i], self.y[i], self.values[i]);
            let color = if v.is_finite() {
                viridis((v - lo) / (hi - lo)).filled()
            } else {
                RGBColor(200, 200, 200).filled()
            };
            Rectangle::new(
                [
                    (x - d.0 / 2.0, y - d.1 / 2.0),
                    (x + d.0 / 2.0, y + d.1 / 2.0),
                ],
                color,
            )
        });
        chart.draw_series(cells).map_err(|e| e.to_string())?;
        // color bar
        let mut bar_chart = ChartBuilder::on(&bar)
            .margin_top(50)
            .margin_bottom(52)
            .margin_right(10)
            .y_label_area_size(80)
            .build_cartesian_2d(0.0..1.0, lo..hi)
            .map_err(|e| e.to_string())?;
        bar_chart
            .configure_mesh()
            .disable_mesh()
            .disable_x_axis()
            .y_label_style(("sans-serif", 15))
            .y_label_formatter(&|v| fmt_tick(*v))
            .draw()
            .map_err(|e| e.to_string())?;
        let n = 64;
        bar_chart
            .draw_series((0..n).map(|k| {
                let (a, b) = (k as f64 / n as f64, (k + 1) as f64 / n as f64);
                Rectangle::new(
                    [(0.0, lo + a * (hi - lo)), (1.0, lo + b * (hi - lo))],
                    viridis((a + b) / 2.0).filled(),
                )
            }))
            .map_err(|e| e.to_string())?;
        Ok(())
    }

    fn draw_histogram<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
    ) -> Result<(), String> {
        let (lo, hi) = self.range();
        let bins = 20usize;
        let mut counts = vec![0usize; bins];
        for v in self.values.iter().filter(|v| v.is_finite()) {
            let k = (((v - lo) / (hi - lo)) * bins as f64).floor() as isize;
            counts[k.clamp(0, bins as isize - 1) as usize] += 1;
        }
        let top = counts.iter().copied().max().unwrap_or(1).max(1) as f64 * 1.1;
        let missing = self.values.iter().filter(|v| !v.is_finite()).count();
        let caption = if missing > 0 {
            format!("{} ({missing} without a value)", self.title)
        } else {
            self.title.clone()
        };
        let mut chart = ChartBuilder::on(root)
            .caption(caption, ("sans-serif", 22))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(lo..hi, 0.0..top)
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .disable_x_mesh()
            .x_desc(&self.title)
            .y_desc("indents")
            .label_style(("sans-serif", 15))
            .x_label_formatter(&|v| fmt_tick(*v))
            .y_label_formatter(&|v| format!("{v:.0}"))
            .draw()
            .map_err(|e| e.to_string())?;
        let w = (hi - lo) / bins as f64;
        chart
            .draw_series(counts.iter().enumerate().map(|(k, &c)| {
                let a = lo + k as f64 * w;
                Rectangle::new(
                    [(a, 0.0), (a + w, c as f64)],
                    RGBColor(31, 119, 180).filled(),
                )
            }))
            .map_err(|e| e.to_string())?;
        Ok(())
    }
}

fn draw_err(figure: MapFigure, e: impl std::fmt::Display) -> ReportError {
    ReportError::Draw {
        figure: figure.name(),
        message: e.to_string(),
    }
}

/// The viridis color map at `t` in [0, 1] (piecewise linear through 6 of its colors).
pub(crate) fn viridis(t: f64) -> RGBColor {
    const STOPS: [(u8, u8, u8); 6] = [
        (68, 1, 84),
        (65, 68, 135),
        (42, 120, 142),
        (34, 168, 132),
        (122, 209, 81),
        (253, 231, 37),
    ];
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let s = t * (STOPS.len() - 1) as f64;
    let k = (s.floor() as usize).min(STOPS.len() - 2);
    let f = s - k as f64;
    let mix = |a: u8, b: u8| (a as f64 + f * (b as f64 - a as f64)).round() as u8;
    let (a, b) = (STOPS[k], STOPS[k + 1]);
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid() -> MapData {
        let mut m = MapData {
            title: "E (MPa)".into(),
            x: vec![],
            y: vec![],
            values: vec![],
            position_unit: "mm".into(),
        };
        for i in 0..4 {
            for j in 0..3 {
                m.x.push(i as f64 * 0.01);
                m.y.push(j as f64 * 0.01);
                m.values.push(if i < 2 { 20000.0 } else { 60000.0 });
            }
        }
        m.values[5] = f64::NAN;
        m
    }

    #[test]
    fn both_figures_render_as_svg_and_png() {
        let m = grid();
        for fig in [MapFigure::HeatMap, MapFigure::Histogram] {
            let svg = m.svg(fig, FigureSize::default()).unwrap();
            assert!(svg.contains("E (MPa)"), "{fig:?}");
            let png = m.png(fig, FigureSize::default()).unwrap();
            assert_eq!(&png[1..4], b"PNG");
        }
        // the two phases get the two ends of the color map
        let svg = m.svg(MapFigure::HeatMap, FigureSize::default()).unwrap();
        assert!(svg.contains("#440154") && svg.contains("#FDE725"), "{svg}");
    }

    /// The heat map's axes carry the positions' unit and one length per pixel on both
    /// axes: the cells of a square grid are squares.
    #[test]
    fn heat_maps_have_units_and_equal_aspect() {
        // a 2 x 8 strip: without the equal aspect its cells would be 4 times as tall as wide
        let mut m = grid();
        (m.x, m.y, m.values) = (vec![], vec![], vec![]);
        for i in 0..2 {
            for j in 0..8 {
                m.x.push(i as f64 * 0.01);
                m.y.push(j as f64 * 0.01);
                m.values.push(if j < 4 { 1.0 } else { 2.0 });
            }
        }
        let svg = m.svg(MapFigure::HeatMap, FigureSize::default()).unwrap();
        assert!(svg.contains("x [mm]") && svg.contains("y [mm]"), "{svg}");
        let attr = |tag: &str, name: &str| -> f64 {
            let k = tag.find(&format!(" {name}=\"")).unwrap() + name.len() + 3;
            tag[k..].split('"').next().unwrap().parse().unwrap()
        };
        let cells: Vec<&str> = svg
            .lines()
            .filter(|l| l.starts_with("<rect") && l.contains("#440154"))
            .collect();
        assert!(!cells.is_empty());
        for c in cells {
            let (w, h) = (attr(c, "width"), attr(c, "height"));
            assert!((w - h).abs() <= 1.5, "cell {w} x {h}: {c}");
        }
    }

    #[test]
    fn bad_maps_are_errors() {
        let mut m = grid();
        m.x.pop();
        assert!(matches!(
            m.svg(MapFigure::HeatMap, FigureSize::default()),
            Err(ReportError::Length { .. })
        ));
        let mut m = grid();
        m.values.iter_mut().for_each(|v| *v = f64::NAN);
        assert!(matches!(
            m.png(MapFigure::Histogram, FigureSize::default()),
            Err(ReportError::Empty { .. })
        ));
    }
}
