//! A minimal hand-written SVG line plot (axes, ticks, legend, solid / dashed lines and
//! markers): enough for the paper's indentation-curve figures, no fonts or system
//! libraries needed.

use std::fmt::Write;

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Style {
    /// Solid line.
    Solid,
    /// Dashed line.
    Dashed,
    /// Circles at the points, no line.
    Markers,
}

/// One data series.
#[derive(Clone, Debug)]
pub struct Series {
    /// Legend text.
    pub name: String,
    /// Points `(x, y)`.
    pub points: Vec<(f64, f64)>,
    /// Drawing style.
    pub style: Style,
    /// CSS colour.
    pub color: &'static str,
}

/// A plot: title, axis labels, series, and whether y is logarithmic.
#[derive(Clone, Debug)]
pub struct Plot {
    /// Title above the frame.
    pub title: String,
    /// x-axis label.
    pub x_label: String,
    /// y-axis label.
    pub y_label: String,
    /// The series.
    pub series: Vec<Series>,
    /// Log-scale y axis (positive values only).
    pub log_y: bool,
}

/// "Nice" tick positions covering `[lo, hi]` (about 5 ticks).
fn ticks(lo: f64, hi: f64) -> Vec<f64> {
    let span = (hi - lo).max(1e-300);
    let raw = span / 5.0;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 2.5, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| span / s <= 6.0)
        .unwrap_or(10.0 * mag);
    let mut t = (lo / step).ceil() * step;
    let mut out = Vec::new();
    while t <= hi + 1e-9 * span {
        out.push(if t.abs() < 1e-12 * span { 0.0 } else { t });
        t += step;
    }
    out
}

fn label(v: f64) -> String {
    if v == 0.0 {
        "0".into()
    } else if v.abs() >= 1e4 || v.abs() < 1e-2 {
        format!("{v:.0e}")
    } else {
        let s = format!("{v:.3}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    }
}

impl Plot {
    /// The axes' ranges `(x0, x1, y0, y1)` over the finite points (`y` as log10 with
    /// `log_y`): a zero-width range widened by 1, a linear `y` from 0 with 5% headroom, a
    /// logarithmic one to whole decades.
    fn range(&self) -> (f64, f64, f64, f64) {
        let ty = |v: f64| if self.log_y { v.max(1e-300).log10() } else { v };
        let pts = self.series.iter().flat_map(|s| s.points.iter());
        let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for &(x, y) in pts {
            if !x.is_finite() || !y.is_finite() || (self.log_y && y <= 0.0) {
                continue;
            }
            x0 = x0.min(x);
            x1 = x1.max(x);
            y0 = y0.min(ty(y));
            y1 = y1.max(ty(y));
        }
        if x1 <= x0 {
            x1 = x0 + 1.0;
        }
        if y1 <= y0 {
            y1 = y0 + 1.0;
        }
        if !self.log_y {
            y0 = y0.min(0.0);
            y1 += 0.05 * (y1 - y0);
        } else {
            y0 = y0.floor();
            y1 = y1.ceil();
        }
        (x0, x1, y0, y1)
    }

    /// Renders the plot as a standalone SVG document (640 x 420 px).
    pub fn render(&self) -> String {
        let (w, h) = (640.0, 420.0);
        let (ml, mr, mt, mb) = (70.0, 20.0, 40.0, 55.0);
        let ty = |v: f64| if self.log_y { v.max(1e-300).log10() } else { v };
        let (x0, x1, y0, y1) = self.range();
        let px = |x: f64| ml + (x - x0) / (x1 - x0) * (w - ml - mr);
        let py = |y: f64| h - mb - (ty(y) - y0) / (y1 - y0) * (h - mt - mb);
        let pyt = |t: f64| h - mb - (t - y0) / (y1 - y0) * (h - mt - mb);
        let mut s = String::new();
        let _ = writeln!(
            s,
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="sans-serif" font-size="12">"#
        );
        let _ = writeln!(s, r#"<rect width="{w}" height="{h}" fill="white"/>"#);
        let _ = writeln!(
            s,
            r#"<text x="{}" y="22" text-anchor="middle" font-size="14">{}</text>"#,
            w / 2.0,
            esc(&self.title)
        );
        // frame and ticks
        let _ = writeln!(
            s,
            r#"<rect x="{ml}" y="{mt}" width="{}" height="{}" fill="none" stroke="black"/>"#,
            w - ml - mr,
            h - mt - mb
        );
        for t in ticks(x0, x1) {
            let x = px(t);
            let _ = writeln!(
                s,
                r##"<line x1="{x:.1}" y1="{}" x2="{x:.1}" y2="{mt}" stroke="#ddd"/><text x="{x:.1}" y="{}" text-anchor="middle">{}</text>"##,
                h - mb,
                h - mb + 16.0,
                label(t)
            );
        }
        let yt: Vec<f64> = if self.log_y {
            (y0 as i64..=y1 as i64).map(|e| e as f64).collect()
        } else {
            ticks(y0, y1)
        };
        for t in yt {
            let y = pyt(t);
            let text = if self.log_y {
                format!("1e{t}")
            } else {
                label(t)
            };
            let _ = writeln!(
                s,
                r##"<line x1="{ml}" y1="{y:.1}" x2="{}" y2="{y:.1}" stroke="#ddd"/><text x="{}" y="{:.1}" text-anchor="end">{text}</text>"##,
                w - mr,
                ml - 6.0,
                y + 4.0
            );
        }
        let _ = writeln!(
            s,
            r#"<text x="{}" y="{}" text-anchor="middle">{}</text>"#,
            (ml + w - mr) / 2.0,
            h - 12.0,
            esc(&self.x_label)
        );
        let _ = writeln!(
            s,
            r#"<text x="16" y="{}" text-anchor="middle" transform="rotate(-90 16 {})">{}</text>"#,
            (mt + h - mb) / 2.0,
            (mt + h - mb) / 2.0,
            esc(&self.y_label)
        );
        // series
        for (k, ser) in self.series.iter().enumerate() {
            let valid: Vec<(f64, f64)> = ser
                .points
                .iter()
                .filter(|(x, y)| x.is_finite() && y.is_finite() && (!self.log_y || *y > 0.0))
                .map(|&(x, y)| (px(x), py(y)))
                .collect();
            match ser.style {
                Style::Markers => {
                    for (x, y) in &valid {
                        let _ = writeln!(
                            s,
                            r#"<circle cx="{x:.1}" cy="{y:.1}" r="2.5" fill="none" stroke="{}"/>"#,
                            ser.color
                        );
                    }
                }
                Style::Solid | Style::Dashed => {
                    let d: Vec<String> = valid
                        .iter()
                        .map(|(x, y)| format!("{x:.1},{y:.1}"))
                        .collect();
                    let dash = if ser.style == Style::Dashed {
                        r#" stroke-dasharray="6 4""#
                    } else {
                        ""
                    };
                    let _ = writeln!(
                        s,
                        r#"<polyline points="{}" fill="none" stroke="{}" stroke-width="1.6"{dash}/>"#,
                        d.join(" "),
                        ser.color
                    );
                }
            }
            legend_entry(&mut s, k, ser, ml, mt);
        }
        s.push_str("</svg>\n");
        s
    }
}

/// The legend line of series `k`, in the upper left corner where rising curves leave room.
fn legend_entry(s: &mut String, k: usize, ser: &Series, ml: f64, mt: f64) {
    // legend in the upper left corner, where rising curves leave room
    let ly = mt + 16.0 + 16.0 * k as f64;
    let lx = ml + 10.0;
    match ser.style {
        Style::Markers => {
            let _ = writeln!(
                s,
                r#"<circle cx="{}" cy="{}" r="2.5" fill="none" stroke="{}"/>"#,
                lx + 12.0,
                ly - 4.0,
                ser.color
            );
        }
        _ => {
            let dash = if ser.style == Style::Dashed {
                r#" stroke-dasharray="6 4""#
            } else {
                ""
            };
            let _ = writeln!(
                s,
                r#"<line x1="{lx}" y1="{}" x2="{}" y2="{}" stroke="{}" stroke-width="1.6"{dash}/>"#,
                ly - 4.0,
                lx + 24.0,
                ly - 4.0,
                ser.color
            );
        }
    }
    let _ = writeln!(
        s,
        r#"<text x="{}" y="{ly}">{}</text>"#,
        lx + 30.0,
        esc(&ser.name)
    );
}

fn esc(t: &str) -> String {
    t.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_cover_the_range_with_round_steps() {
        let t = ticks(0.0, 1.0);
        assert_eq!(t.len(), 6);
        assert!((t[5] - 1.0).abs() < 1e-12);
        let t = ticks(0.0, 306.0);
        assert_eq!(t, vec![0.0, 100.0, 200.0, 300.0]);
    }

    #[test]
    fn a_plot_renders_to_well_formed_svg() {
        let p = Plot {
            title: "F <test>".into(),
            x_label: "h (mm)".into(),
            y_label: "F (N)".into(),
            series: vec![Series {
                name: "a".into(),
                points: vec![(0.0, 0.0), (1.0, 2.0)],
                style: Style::Dashed,
                color: "red",
            }],
            log_y: false,
        };
        let s = p.render();
        assert!(s.starts_with("<svg") && s.ends_with("</svg>\n"));
        assert!(s.contains("F &lt;test&gt;"));
        assert!(s.contains("stroke-dasharray"));
    }
}
