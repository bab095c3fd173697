//! Figures of the cost around a fit: a profile likelihood ([`ProfileFigure`]: the statistic
//! `2 (J - J*) / s^2` against one parameter, with the chi-square level and the interval's
//! ends) and a 2D cost map ([`CostMapFigure`]: `log10 J` over two parameters as colored
//! cells with contour lines, like the paper's Figs. 4 and 11, the optimum marked), as SVG
//! text or PNG bytes.

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::error::ReportError;
use crate::map::viridis;
use crate::plot::{FigureSize, encode_png, ensure_font};
use crate::units::fmt_tick;

/// A profile likelihood of one parameter.
#[derive(Debug, Clone, PartialEq)]
pub struct ProfileFigure {
    /// Parameter name.
    pub name: String,
    /// Its unit.
    pub unit: String,
    /// Parameter values, increasing.
    pub values: Vec<f64>,
    /// `2 (J - J*) / s^2` at each value.
    pub statistic: Vec<f64>,
    /// The chi-square level drawn as a horizontal line (3.841 for 95%).
    pub level: f64,
    /// The optimum (marked).
    pub optimum: f64,
    /// The interval's ends (vertical dashed lines).
    pub interval: (f64, f64),
    /// Logarithmic value axis (used when the values span more than a decade).
    pub log_x: bool,
}

/// `log10 J` over a grid of two parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct CostMapFigure {
    /// Title.
    pub title: String,
    /// Horizontal axis label (name and unit).
    pub x_label: String,
    /// Vertical axis label.
    pub y_label: String,
    /// Grid values of the horizontal parameter, increasing.
    pub x: Vec<f64>,
    /// Grid values of the vertical parameter, increasing.
    pub y: Vec<f64>,
    /// `J` at `(x[i], y[j])` as `cost[j * x.len() + i]` (non-finite: a failed solve, grey).
    pub cost: Vec<f64>,
    /// Logarithmic horizontal axis (used when the values span more than a decade).
    pub log_x: bool,
    /// Logarithmic vertical axis (likewise).
    pub log_y: bool,
    /// Points to mark (x, y, label), e.g. the optimum.
    pub marks: Vec<(f64, f64, String)>,
    /// Contour levels (values of `log10 J`); empty: 12 levels evenly spread over the finite
    /// range.
    pub levels: Vec<f64>,
    /// The unit of `J` shown on the colour bar (`N^2`; empty: none).
    pub cost_unit: String,
}

/// Where a cost map's mark label starts, in pixels from the mark (right of and above the
/// cross's 8-pixel arms).
const MARK_LABEL_OFFSET: (i32, i32) = (11, -24);

fn draw_err(figure: &'static str, e: impl std::fmt::Display) -> ReportError {
    ReportError::Draw {
        figure,
        message: e.to_string(),
    }
}

fn svg_of(
    size: FigureSize,
    draw: impl FnOnce(&DrawingArea<SVGBackend<'_>, Shift>) -> Result<(), String>,
    figure: &'static str,
) -> Result<String, ReportError> {
    size.check()?;
    ensure_font()?;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (size.width, size.height)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| draw_err(figure, e))?;
        draw(&root).map_err(|e| draw_err(figure, e))?;
        root.present().map_err(|e| draw_err(figure, e))?;
    }
    Ok(svg)
}

fn png_of(
    size: FigureSize,
    draw: impl FnOnce(&DrawingArea<BitMapBackend<'_>, Shift>) -> Result<(), String>,
    figure: &'static str,
) -> Result<Vec<u8>, ReportError> {
    size.check()?;
    ensure_font()?;
    let (w, h) = (size.width, size.height);
    let mut rgb = vec![0u8; w as usize * h as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| draw_err(figure, e))?;
        draw(&root).map_err(|e| draw_err(figure, e))?;
        root.present().map_err(|e| draw_err(figure, e))?;
    }
    encode_png(&rgb, w, h)
}

impl ProfileFigure {
    fn check(&self) -> Result<(), ReportError> {
        if self.statistic.len() != self.values.len() {
            return Err(ReportError::Length {
                what: "profile values and statistic",
                expected: self.values.len(),
                got: self.statistic.len(),
            });
        }
        if !self
            .values
            .iter()
            .zip(&self.statistic)
            .any(|(v, s)| v.is_finite() && s.is_finite())
        {
            return Err(ReportError::Empty {
                what: "profile points",
            });
        }
        Ok(())
    }

    /// The figure as an SVG document.
    ///
    /// # Errors
    /// [`ReportError::Length`], [`ReportError::Empty`], [`ReportError::Size`],
    /// [`ReportError::Draw`].
    pub fn svg(&self, size: FigureSize) -> Result<String, ReportError> {
        self.check()?;
        svg_of(size, |root| self.draw(root), "profile")
    }

    /// The figure as PNG bytes.
    ///
    /// # Errors
    /// As [`ProfileFigure::svg`], and [`ReportError::Png`].
    pub fn png(&self, size: FigureSize) -> Result<Vec<u8>, ReportError> {
        self.check()?;
        png_of(size, |root| self.draw(root), "profile")
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        let pts: Vec<(f64, f64)> = self
            .values
            .iter()
            .zip(&self.statistic)
            .filter(|(v, s)| v.is_finite() && s.is_finite() && (!self.log_x || **v > 0.0))
            .map(|(v, s)| (*v, *s))
            .collect();
        let (mut x0, mut x1) = pts
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
                (a.min(p.0), b.max(p.0))
            });
        if x1 <= x0 {
            let d = if x0 == 0.0 { 1.0 } else { 0.05 * x0.abs() };
            x0 -= d;
            x1 += d;
        }
        let top = pts
            .iter()
            .map(|p| p.1)
            .fold(self.level * 1.5, f64::max)
            .min(self.level * 6.0);
        let bottom = pts.iter().map(|p| p.1).fold(0.0, f64::min);
        let unit = if self.unit == "-" || self.unit.is_empty() {
            String::new()
        } else {
            format!(" ({})", self.unit)
        };
        let caption = format!("profile likelihood of {}", self.name);
        let x_desc = format!("{}{unit}", self.name);
        let mut chart = ChartBuilder::on(root);
        chart
            .caption(caption, ("sans-serif", 22))
            .margin(14)
            .x_label_area_size(42)
            .y_label_area_size(64);
        let lvl = self.level;
        let (lo, hi) = self.interval;
        macro_rules! body {
            ($chart:expr) => {{
                let mut c = $chart;
                c.configure_mesh()
                    .x_desc(x_desc.as_str())
                    .y_desc("2 (J - J*) / s²")
                    .label_style(("sans-serif", 15))
                    .x_label_formatter(&|v| fmt_tick(*v))
                    .y_label_formatter(&|v| fmt_tick(*v))
                    .draw()
                    .map_err(|e| e.to_string())?;
                let clip = |s: f64| s.min(top);
                c.draw_series(LineSeries::new(
                    pts.iter().map(|p| (p.0, clip(p.1))),
                    RGBColor(31, 119, 180).stroke_width(2),
                ))
                .map_err(|e| e.to_string())?;
                c.draw_series(
                    pts.iter()
                        .map(|p| Circle::new((p.0, clip(p.1)), 3, RGBColor(31, 119, 180).filled())),
                )
                .map_err(|e| e.to_string())?;
                c.draw_series(LineSeries::new(
                    [(x0, lvl), (x1, lvl)],
                    RGBColor(214, 39, 40).stroke_width(1),
                ))
                .map_err(|e| e.to_string())?
                .label(format!("chi2_1(0.95) = {lvl:.3}"))
                .legend(|(x, y)| PathElement::new([(x, y), (x + 18, y)], RGBColor(214, 39, 40)));
                for v in [lo, hi] {
                    if v.is_finite() && v > x0 && v < x1 {
                        c.draw_series(DashedLineSeries::new(
                            [(v, bottom), (v, top)],
                            6,
                            4,
                            RGBColor(90, 90, 90).stroke_width(1),
                        ))
                        .map_err(|e| e.to_string())?;
                    }
                }
                if self.optimum.is_finite() {
                    c.draw_series([Cross::new((self.optimum, 0.0), 7, BLACK.stroke_width(2))])
                        .map_err(|e| e.to_string())?;
                }
                c.configure_series_labels()
                    .background_style(WHITE.mix(0.8))
                    .border_style(BLACK)
                    .label_font(("sans-serif", 14))
                    .position(SeriesLabelPosition::UpperMiddle)
                    .draw()
                    .map_err(|e| e.to_string())?;
            }};
        }
        // a log axis over less than a decade has no labelled ticks: linear then
        if self.log_x && x0 > 0.0 && x1 / x0 > 10.0 {
            body!(
                chart
                    .build_cartesian_2d((x0..x1).log_scale(), bottom..top)
                    .map_err(|e| e.to_string())?
            );
        } else {
            body!(
                chart
                    .build_cartesian_2d(x0..x1, bottom..top)
                    .map_err(|e| e.to_string())?
            );
        }
        Ok(())
    }
}

/// A contour segment: two points in grid-index coordinates `(i, j)` (fractional).
type Segment = ((f64, f64), (f64, f64));

/// Marching squares on `f[j * nx + i]`: the segments of the level line `f = level`, in
/// fractional grid indices. Cells with a non-finite corner are skipped; the saddle cases
/// are resolved by the cell-centre mean.
pub fn contour_segments(f: &[f64], nx: usize, ny: usize, level: f64) -> Vec<Segment> {
    let mut out = Vec::new();
    if nx < 2 || ny < 2 || f.len() != nx * ny {
        return out;
    }
    for j in 0..ny - 1 {
        for i in 0..nx - 1 {
            // corners counter-clockwise from (i, j)
            let c = [
                (i as f64, j as f64, f[j * nx + i]),
                (i as f64 + 1.0, j as f64, f[j * nx + i + 1]),
                (i as f64 + 1.0, j as f64 + 1.0, f[(j + 1) * nx + i + 1]),
                (i as f64, j as f64 + 1.0, f[(j + 1) * nx + i]),
            ];
            if c.iter().any(|p| !p.2.is_finite()) {
                continue;
            }
            // crossing points on the four edges
            let mut cross: Vec<(usize, (f64, f64))> = Vec::new();
            for e in 0..4 {
                let (a, b) = (c[e], c[(e + 1) % 4]);
                if (a.2 < level) != (b.2 < level) {
                    let t = (level - a.2) / (b.2 - a.2);
                    cross.push((e, (a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1))));
                }
            }
            match cross.len() {
                2 => out.push((cross[0].1, cross[1].1)),
                4 => {
                    let centre = c.iter().map(|p| p.2).sum::<f64>() / 4.0;
                    // corner 0 on the same side as the centre: join edges (0,1) and (2,3)
                    if (centre < level) == (c[0].2 < level) {
                        out.push((cross[0].1, cross[1].1));
                        out.push((cross[2].1, cross[3].1));
                    } else {
                        out.push((cross[3].1, cross[0].1));
                        out.push((cross[1].1, cross[2].1));
                    }
                }
                _ => {}
            }
        }
    }
    out
}

impl CostMapFigure {
    fn check(&self) -> Result<(), ReportError> {
        let (nx, ny) = (self.x.len(), self.y.len());
        if self.cost.len() != nx * ny {
            return Err(ReportError::Length {
                what: "cost map values (x.len() * y.len())",
                expected: nx * ny,
                got: self.cost.len(),
            });
        }
        if nx < 2 || ny < 2 {
            return Err(ReportError::Empty {
                what: "cost map grid (at least 2 x 2)",
            });
        }
        if !self.cost.iter().any(|v| v.is_finite() && *v > 0.0) {
            return Err(ReportError::Empty {
                what: "cost map values",
            });
        }
        Ok(())
    }

    /// The figure as an SVG document.
    ///
    /// # Errors
    /// [`ReportError::Length`], [`ReportError::Empty`], [`ReportError::Size`],
    /// [`ReportError::Draw`].
    pub fn svg(&self, size: FigureSize) -> Result<String, ReportError> {
        self.check()?;
        svg_of(size, |root| self.draw(root), "cost map")
    }

    /// The figure as PNG bytes.
    ///
    /// # Errors
    /// As [`CostMapFigure::svg`], and [`ReportError::Png`].
    pub fn png(&self, size: FigureSize) -> Result<Vec<u8>, ReportError> {
        self.check()?;
        png_of(size, |root| self.draw(root), "cost map")
    }

    /// `log10 J` per grid point (NaN where `J` is not finite: a failed solve; `J = 0`, the
    /// exact minimum of noise-free data, and round-off below it clamped to the lowest
    /// positive value, so they take the bottom colour and not the failed solves' grey),
    /// the colour range and the contour levels.
    fn log_cost(&self) -> (Vec<f64>, f64, f64, Vec<f64>) {
        let (lo, hi) = self
            .cost
            .iter()
            .filter(|v| v.is_finite() && **v > 0.0)
            .map(|v| v.log10())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                (a.min(v), b.max(v))
            });
        let lg: Vec<f64> = self
            .cost
            .iter()
            .map(|&v| {
                if !v.is_finite() {
                    f64::NAN
                } else if v > 0.0 {
                    v.log10()
                } else {
                    lo
                }
            })
            .collect();
        let hi = if hi > lo { hi } else { lo + 1.0 };
        let levels = if self.levels.is_empty() {
            (1..=12).map(|k| lo + (hi - lo) * k as f64 / 13.0).collect()
        } else {
            self.levels.clone()
        };
        (lg, lo, hi, levels)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        let (nx, ny) = (self.x.len(), self.y.len());
        let (lg, lo, hi, levels) = self.log_cost();
        // cell edges halfway between grid values (geometric mean on a log axis)
        let edges = |v: &[f64], log: bool| -> Vec<f64> {
            let mid = |a: f64, b: f64| {
                if log && a > 0.0 && b > 0.0 {
                    (a * b).sqrt()
                } else {
                    0.5 * (a + b)
                }
            };
            let n = v.len();
            let mut e = Vec::with_capacity(n + 1);
            let first = if log && v[0] > 0.0 && v[1] > 0.0 {
                v[0] * v[0] / mid(v[0], v[1])
            } else {
                v[0] - (mid(v[0], v[1]) - v[0])
            };
            e.push(first);
            for k in 0..n - 1 {
                e.push(mid(v[k], v[k + 1]));
            }
            let last = if log && v[n - 1] > 0.0 && v[n - 2] > 0.0 {
                v[n - 1] * v[n - 1] / mid(v[n - 2], v[n - 1])
            } else {
                v[n - 1] + (v[n - 1] - mid(v[n - 2], v[n - 1]))
            };
            e.push(last);
            e
        };
        // a log axis over less than a decade has no labelled ticks: linear then
        let decade = |v: &[f64]| v.iter().all(|v| *v > 0.0) && v[v.len() - 1] / v[0] > 10.0;
        let log_x = self.log_x && decade(&self.x);
        let log_y = self.log_y && decade(&self.y);
        let ex = edges(&self.x, log_x);
        let ey = edges(&self.y, log_y);
        let (w, _) = root.dim_in_pixel();
        let (plot, bar) = root.split_horizontally(w.saturating_sub(120));
        // grid index -> physical coordinate (interpolated in the axis' own scale)
        let at = |v: &[f64], log: bool, t: f64| -> f64 {
            let k = (t.floor() as usize).min(v.len() - 2);
            let f = t - k as f64;
            if log {
                (v[k].ln() + f * (v[k + 1].ln() - v[k].ln())).exp()
            } else {
                v[k] + f * (v[k + 1] - v[k])
            }
        };
        let segments: Vec<(usize, Segment)> = levels
            .iter()
            .enumerate()
            .flat_map(|(l, &level)| {
                contour_segments(&lg, nx, ny, level)
                    .into_iter()
                    .map(move |s| (l, s))
            })
            .collect();
        let mut chart = ChartBuilder::on(&plot);
        chart
            .caption(&self.title, ("sans-serif", 20))
            .margin(12)
            .x_label_area_size(42)
            .y_label_area_size(70);
        let (xr, yr) = ((ex[0], ex[nx]), (ey[0], ey[ny]));
        macro_rules! body {
            ($chart:expr) => {{
                let mut c = $chart;
                c.configure_mesh()
                    .disable_mesh()
                    .x_desc(self.x_label.as_str())
                    .y_desc(self.y_label.as_str())
                    .label_style(("sans-serif", 15))
                    .x_label_formatter(&|v| fmt_tick(*v))
                    .y_label_formatter(&|v| fmt_tick(*v))
                    .draw()
                    .map_err(|e| e.to_string())?;
                let cells = (0..ny)
                    .flat_map(|j| (0..nx).map(move |i| (i, j)))
                    .map(|(i, j)| {
                        let v = lg[j * nx + i];
                        let color = if v.is_finite() {
                            viridis((v - lo) / (hi - lo)).filled()
                        } else {
                            RGBColor(200, 200, 200).filled()
                        };
                        Rectangle::new([(ex[i], ey[j]), (ex[i + 1], ey[j + 1])], color)
                    });
                c.draw_series(cells).map_err(|e| e.to_string())?;
                for (_, (a, b)) in &segments {
                    c.draw_series(LineSeries::new(
                        [
                            (at(&self.x, log_x, a.0), at(&self.y, log_y, a.1)),
                            (at(&self.x, log_x, b.0), at(&self.y, log_y, b.1)),
                        ],
                        WHITE.mix(0.85).stroke_width(1),
                    ))
                    .map_err(|e| e.to_string())?;
                }
                for (x, y, label) in &self.marks {
                    // the label beside the cross, on a white box, never over its centre
                    let font = ("sans-serif", 15).into_font().color(&RED);
                    let (tw, th) = plot
                        .estimate_text_size(label, &font)
                        .map_err(|e| e.to_string())?;
                    let (tw, th) = (tw as i32, th as i32);
                    let (ox, oy) = MARK_LABEL_OFFSET;
                    c.draw_series([EmptyElement::at((*x, *y))
                        + Cross::new((0, 0), 8, RED.stroke_width(3))
                        + Rectangle::new(
                            [(ox - 2, oy - 1), (ox + tw + 2, oy + th + 1)],
                            WHITE.mix(0.8).filled(),
                        )
                        + Text::new(label.clone(), (ox, oy), font)])
                        .map_err(|e| e.to_string())?;
                }
            }};
        }
        match (log_x, log_y) {
            (true, true) => body!(
                chart
                    .build_cartesian_2d((xr.0..xr.1).log_scale(), (yr.0..yr.1).log_scale())
                    .map_err(|e| e.to_string())?
            ),
            (true, false) => body!(
                chart
                    .build_cartesian_2d((xr.0..xr.1).log_scale(), yr.0..yr.1)
                    .map_err(|e| e.to_string())?
            ),
            (false, true) => body!(
                chart
                    .build_cartesian_2d(xr.0..xr.1, (yr.0..yr.1).log_scale())
                    .map_err(|e| e.to_string())?
            ),
            (false, false) => body!(
                chart
                    .build_cartesian_2d(xr.0..xr.1, yr.0..yr.1)
                    .map_err(|e| e.to_string())?
            ),
        }
        // color bar of log10 J, with J's unit
        let bar_caption = if self.cost_unit.is_empty() {
            "log10 J".to_string()
        } else {
            format!("log10 J [{}]", self.cost_unit)
        };
        let mut bar_chart = ChartBuilder::on(&bar)
            .caption(bar_caption, ("sans-serif", 15))
            .margin_top(20)
            .margin_bottom(52)
            .margin_right(10)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..1.0, lo..hi)
            .map_err(|e| e.to_string())?;
        bar_chart
            .configure_mesh()
            .disable_mesh()
            .disable_x_axis()
            .y_label_style(("sans-serif", 14))
            .y_label_formatter(&|v| format!("{v:.1}"))
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
}

#[cfg(test)]
mod tests {
    use super::*;

    /// For f = x^2 + y^2 on a grid, the level line f = r^2 shall be the circle of radius r:
    /// every contour point lies on it to the chord error of linear interpolation.
    #[test]
    fn marching_squares_traces_a_circle() {
        let n = 41;
        let h = 0.1;
        let coord = |k: f64| -2.0 + h * k;
        let f: Vec<f64> = (0..n * n)
            .map(|p| {
                let (i, j) = ((p % n) as f64, (p / n) as f64);
                coord(i).powi(2) + coord(j).powi(2)
            })
            .collect();
        let segs = contour_segments(&f, n, n, 1.0);
        assert!(segs.len() > 50, "{} segments", segs.len());
        for (a, b) in &segs {
            for p in [a, b] {
                let r = (coord(p.0).powi(2) + coord(p.1).powi(2)).sqrt();
                // linear interpolation of r^2 along an edge of length h: error <= h^2 / 8
                assert!((r - 1.0).abs() < h * h, "r = {r}");
            }
        }
        // a level outside the range has no line; a cell with a NaN corner is skipped
        assert!(contour_segments(&f, n, n, 100.0).is_empty());
        let mut g = f.clone();
        g[20 * n + 30] = f64::NAN;
        assert!(contour_segments(&g, n, n, 1.0).len() <= segs.len());
    }

    #[test]
    fn both_figures_render_and_bad_input_is_an_error() {
        let x: Vec<f64> = (0..5).map(|k| 1000.0 * 1.5f64.powi(k)).collect();
        let y: Vec<f64> = (0..4).map(|k| 1.0 + k as f64).collect();
        let cost: Vec<f64> = (0..20).map(|p| 1.0 + p as f64).collect();
        let map = CostMapFigure {
            title: "J(E, m)".into(),
            x_label: "E (MPa)".into(),
            y_label: "m (-)".into(),
            x,
            y,
            cost,
            log_x: true,
            log_y: false,
            marks: vec![(2000.0, 2.0, "optimum".into())],
            levels: vec![],
            cost_unit: "N^2".into(),
        };
        let svg = map.svg(FigureSize::default()).unwrap();
        assert!(svg.contains("E (MPa)") && svg.contains("log10 J [N^2]"));
        let png = map.png(FigureSize::default()).unwrap();
        assert_eq!(&png[1..4], b"PNG");
        let mut bad = map.clone();
        bad.cost.pop();
        assert!(matches!(
            bad.svg(FigureSize::default()),
            Err(ReportError::Length { .. })
        ));
        let prof = ProfileFigure {
            name: "K".into(),
            unit: "MPa s^(1/m)".into(),
            values: vec![1.0, 2.0, 3.0],
            statistic: vec![5.0, 0.0, 4.5],
            level: 3.841,
            optimum: 2.0,
            interval: (1.3, 2.8),
            log_x: true,
        };
        assert!(
            prof.svg(FigureSize::default())
                .unwrap()
                .contains("profile likelihood of K")
        );
        assert_eq!(&prof.png(FigureSize::default()).unwrap()[1..4], b"PNG");
        let mut empty = prof.clone();
        empty.statistic = vec![f64::NAN; 3];
        assert!(matches!(
            empty.svg(FigureSize::default()),
            Err(ReportError::Empty { .. })
        ));
    }

    /// Noise-free data give J = 0 at the law's point: that cell takes the colour map's
    /// bottom colour, never the grey of a failed solve; a failed solve stays grey; the
    /// mark's label sits beside its cross, not over it; the colour bar names J's unit.
    #[test]
    fn zero_cost_is_the_bottom_colour_and_labels_clear_the_mark() {
        let x: Vec<f64> = (0..3).map(|k| 1.0 + k as f64).collect();
        let y = x.clone();
        let mut cost: Vec<f64> = (0..9).map(|p| 10.0 * (p as f64 - 4.0).powi(2)).collect();
        assert_eq!(cost[4], 0.0);
        let grey = "#C8C8C8";
        let mut map = CostMapFigure {
            title: "J".into(),
            x_label: "a".into(),
            y_label: "b".into(),
            x,
            y,
            cost: cost.clone(),
            log_x: false,
            log_y: false,
            marks: vec![(2.0, 2.0, "law".into())],
            levels: vec![],
            cost_unit: "N^2".into(),
        };
        let svg = map.svg(FigureSize::default()).unwrap();
        assert!(!svg.contains(grey), "the J = 0 cell is grey");
        assert!(svg.contains("#440154"), "no bottom colour");
        assert!(svg.contains("log10 J [N^2]"));
        cost[0] = f64::NAN;
        map.cost = cost;
        assert!(map.svg(FigureSize::default()).unwrap().contains(grey));
        let (lg, ..) = map.log_cost();
        assert_eq!(lg[4], lg[1].min(lg[3]));
        // the label starts beyond the cross's arms (8 px from its centre)
        let attr = |tag: &str, name: &str| -> f64 {
            let k = tag.find(&format!(" {name}=\"")).unwrap() + name.len() + 3;
            tag[k..].split('"').next().unwrap().parse().unwrap()
        };
        let arm = svg
            .lines()
            .find(|l| l.starts_with("<line") && l.contains("#FF0000"))
            .expect("the cross");
        let centre = (
            0.5 * (attr(arm, "x1") + attr(arm, "x2")),
            0.5 * (attr(arm, "y1") + attr(arm, "y2")),
        );
        let k = svg.find("\nlaw\n").expect("the label");
        let text = svg[..k].rsplit("<text").next().unwrap();
        let (tx, ty) = (attr(text, "x"), attr(text, "y"));
        assert!(
            tx > centre.0 + 8.0 || ty + 12.0 < centre.1 - 8.0,
            "label at ({tx}, {ty}) over the mark at {centre:?}"
        );
    }
}
