//! Markdown rendering of a [`Report`].

use std::fmt::Write;

use crate::adequacy::{Adequacy, Verdict};
use crate::model::{
    BoundHit, DiscretizationSummary, IdentifiabilitySummary, Observable, Parameter, Report,
};
use crate::units::{DisplayUnit, fmt_sig};

/// Writing to a `String` cannot fail; this drops the `fmt::Result`.
macro_rules! line {
    ($out:expr) => {
        $out.push('\n')
    };
    ($out:expr, $($arg:tt)*) => {{
        let _ = writeln!($out, $($arg)*);
    }};
}

/// Histories longer than this show their first and last `HISTORY_EDGE` rows only.
const HISTORY_MAX_ROWS: usize = 24;
const HISTORY_EDGE: usize = 10;

impl Report {
    /// The report as Markdown: source, parameter table, correlation, fit quality,
    /// convergence (with the iteration history), preprocessing and figure links.
    ///
    /// Parameters are shown in their [`Parameter::unit`], forces and depths in the
    /// curves' display units. Missing values print as empty cells.
    pub fn to_markdown(&self) -> String {
        let mut out = String::new();
        line!(out, "# {}", escape(&self.title));
        line!(out);
        if let Some(a) = self.adequacy.as_ref().filter(|a| systematic(a)) {
            line!(out, "> **Warning:** {}", escape(&a.message));
            line!(out);
        }
        for w in &self.warnings {
            line!(out, "> **Warning:** {}", escape(w));
            line!(out);
        }
        self.source_section(&mut out);
        self.parameter_section(&mut out);
        if let Some(i) = &self.identifiability {
            identifiability_section(&mut out, i);
        }
        if let Some(d) = &self.discretization {
            out.push_str(&self.discretization_section(d));
        }
        self.fit_section(&mut out);
        if let Some(a) = &self.adequacy {
            adequacy_section(&mut out, a, self.curves.observable);
        }
        self.convergence_section(&mut out);
        self.preprocessing_section(&mut out);
        self.figure_section(&mut out);
        out
    }

    /// The section `## Discretization error` for this report's parameters: the fit
    /// re-run on `d.refined` (mesh and steps), its force change (`rms_rel` of F_max, largest
    /// `max_abs` N), and per parameter (law order) the shift `c_refined - c_fit` it
    /// implies (`None`: fixed or undetermined) beside the standard deviation.
    fn discretization_section(&self, d: &DiscretizationSummary) -> String {
        let (refined, rms_rel, max_abs, shift, seconds) =
            (&d.refined, d.rms_rel, d.max_abs, &d.shift, d.seconds);
        let mut out = String::new();
        let fu = self.curves.observed_unit();
        let (o, y) = (
            self.curves.observable.name(),
            self.curves.observable.symbol(),
        );
        line!(out, "## Discretization error");
        line!(out);
        line!(
            out,
            "The forward problem re-run at the optimum on {}: the {o} changes by RMS {}% \
             of {y}_max (largest {} {}), {} s. The shift is what the refined discretization \
             would identify from the same data minus the fit, to first order: \
             `delta_c = -(S^T W S)^-1 S^T W delta_{y}`.",
            escape(refined),
            fmt_sig(100.0 * rms_rel),
            fmt_sig(fu.show(max_abs)),
            escape(&fu.label),
            fmt_sig(seconds)
        );
        line!(out);
        line!(
            out,
            "| parameter | value | ± σ | disc. shift | shift / σ | unit |"
        );
        line!(out, "|---|--:|--:|--:|--:|---|");
        for (k, p) in self.parameters.iter().enumerate() {
            if p.fixed {
                continue;
            }
            let u = &p.unit;
            let s = shift.get(k).copied().flatten();
            let ratio = match (s, p.std_dev) {
                (Some(s), Some(sd)) if sd > 0.0 => {
                    let r = s.abs() / sd;
                    if r > 1.0 {
                        format!("**{}**", fmt_sig(r))
                    } else {
                        fmt_sig(r)
                    }
                }
                _ => String::new(),
            };
            line!(
                out,
                "| {} | {} | {} | {} | {} | {} |",
                escape(&p.name),
                shown(u, Some(p.value)),
                shown(u, p.std_dev),
                s.map_or_else(|| "undetermined".to_string(), |s| fmt_sig(u.show(s))),
                ratio,
                escape(&u.label)
            );
        }
        line!(out);
        out
    }

    fn source_section(&self, out: &mut String) {
        line!(out, "| | |");
        line!(out, "|---|---|");
        line!(
            out,
            "| data file | `{}` |",
            self.source.file.replace('`', "'")
        );
        line!(out, "| test | {} |", escape(&self.source.test));
        line!(out, "| law | {} |", escape(&self.law));
        for m in &self.source.metadata {
            line!(out, "| {} | {} |", escape(&m.name), escape(&m.value));
        }
        let c = &self.curves;
        let max_abs = |v: &[f64]| {
            v.iter()
                .filter(|x| x.is_finite())
                .fold(0.0_f64, |m, x| m.max(x.abs()))
        };
        let t_end =
            c.t.iter()
                .copied()
                .filter(|x| x.is_finite())
                .fold(0.0, f64::max);
        let (h, f) = c.depth_force(&c.f_data);
        line!(
            out,
            "| curve | {} points, {} s, h_max {} {}, F_max {} {} |",
            c.t.len(),
            fmt_sig(t_end),
            fmt_sig(c.depth_unit.show(max_abs(h))),
            escape(&c.depth_unit.label),
            fmt_sig(c.force_unit.show(max_abs(f))),
            escape(&c.force_unit.label)
        );
        if c.observable == Observable::Depth {
            line!(
                out,
                "| observable | the depth (load control: the force is prescribed, the fit's \
                 cost is on the depth residuals, J = 1/2 sum w (h - h_data)^2) |"
            );
        }
        line!(out);
    }

    fn parameter_section(&self, out: &mut String) {
        line!(out, "## Identified parameters");
        line!(out);
        let conditional = self.adequacy.as_ref().is_some_and(systematic);
        line!(
            out,
            "| parameter | value | ± σ{} | unit | start | lower bound | upper bound | status |",
            if conditional { " \\*" } else { "" }
        );
        line!(out, "|---|--:|--:|---|--:|--:|--:|---|");
        for p in &self.parameters {
            let u = &p.unit;
            let undetermined = self.is_undetermined(&p.name);
            line!(
                out,
                "| {} | {} | {} | {} | {} | {} | {} | {}{} |",
                escape(&p.name),
                shown(u, Some(p.value)),
                if undetermined {
                    "undetermined".to_string()
                } else {
                    shown(u, p.std_dev)
                },
                escape(&u.label),
                shown(u, Some(p.start)),
                shown(u, p.lower),
                shown(u, p.upper),
                status(p),
                if undetermined {
                    ", **undetermined**"
                } else {
                    ""
                }
            );
        }
        line!(out);
        if conditional {
            line!(
                out,
                "\\* conditional on a law that fits: the residuals are systematic (see Model \
                 adequacy), so the true uncertainty is larger by an unknown amount."
            );
            line!(out);
        }
        if let Some(c) = &self.correlation {
            // undetermined parameters have no correlation to show
            let keep: Vec<usize> = (0..c.names.len())
                .filter(|&k| !self.is_undetermined(&c.names[k]))
                .collect();
            if keep.len() < 2 {
                return;
            }
            line!(out, "Correlation of the identified parameters:");
            line!(out);
            let mut head = String::from("| |");
            let mut rule = String::from("|---|");
            for &k in &keep {
                let _ = write!(head, " {} |", escape(&c.names[k]));
                rule.push_str("--:|");
            }
            line!(out, "{head}");
            line!(out, "{rule}");
            for &a in &keep {
                let mut l = format!("| {} |", escape(&c.names[a]));
                for &b in &keep {
                    let v = c.matrix[a][b];
                    if v.is_finite() {
                        let _ = write!(l, " {v:.3} |");
                    } else {
                        l.push_str(" |");
                    }
                }
                line!(out, "{l}");
            }
            line!(out);
        }
    }

    fn fit_section(&self, out: &mut String) {
        let f = &self.fit;
        let fu = self.curves.observed_unit();
        let (o, y) = (
            self.curves.observable.name(),
            self.curves.observable.symbol(),
        );
        line!(out, "## Fit quality");
        line!(out);
        line!(out, "| measure | value |");
        line!(out, "|---|--:|");
        line!(out, "| R² of the {o} | {:.6} |", f.r2);
        line!(
            out,
            "| RMS {o} residual | {} {} |",
            fmt_sig(fu.show(f.rms)),
            escape(&fu.label)
        );
        line!(out, "| RMS / {y}_max | {} % |", fmt_sig(100.0 * f.rms_rel));
        line!(
            out,
            "| max abs residual | {} {} |",
            fmt_sig(fu.show(f.max_abs)),
            escape(&fu.label)
        );
        line!(out, "| points | {} |", f.n);
        line!(out);
    }

    fn convergence_section(&self, out: &mut String) {
        let c = &self.convergence;
        line!(out, "## Convergence");
        line!(out);
        line!(out, "- stop reason: {}", escape(&c.stop_reason));
        line!(out, "- iterations: {}", c.iterations);
        line!(
            out,
            "- solves: {} forward, {} adjoint",
            c.forward_solves,
            c.adjoint_solves
        );
        line!(out, "- wall time: {} s", fmt_sig(c.wall_time_s));
        if let (Some(first), Some(last)) = (self.history.first(), self.history.last()) {
            let ratio = if first.cost > 0.0 && last.cost.is_finite() {
                format!(" (factor {})", fmt_sig(last.cost / first.cost))
            } else {
                String::new()
            };
            line!(
                out,
                "- cost J: {} → {}{ratio}",
                fmt_sig(first.cost),
                fmt_sig(last.cost)
            );
        }
        line!(out);
        if self.history.is_empty() {
            return;
        }
        let mut head = String::from("| iteration | J | \\|grad\\| |");
        let mut rule = String::from("|--:|--:|--:|");
        for p in &self.parameters {
            let _ = write!(head, " {} [{}] |", escape(&p.name), escape(&p.unit.label));
            rule.push_str("--:|");
        }
        line!(out, "{head}");
        line!(out, "{rule}");
        let n = self.history.len();
        for (i, r) in self.history.iter().enumerate() {
            if n > HISTORY_MAX_ROWS && i == HISTORY_EDGE {
                let mut l = String::from("| … | | |");
                for _ in &self.parameters {
                    l.push_str(" |");
                }
                line!(out, "{l}");
            }
            if n > HISTORY_MAX_ROWS && i >= HISTORY_EDGE && i < n - HISTORY_EDGE {
                continue;
            }
            let mut l = format!(
                "| {} | {} | {} |",
                r.iteration,
                fmt_sig(r.cost),
                r.grad_norm.map(fmt_sig).unwrap_or_default()
            );
            for (k, p) in self.parameters.iter().enumerate() {
                let _ = write!(l, " {} |", shown(&p.unit, r.params.get(k).copied()));
            }
            line!(out, "{l}");
        }
        line!(out);
    }

    fn preprocessing_section(&self, out: &mut String) {
        line!(out, "## Preprocessing");
        line!(out);
        if self.preprocessing.is_empty() {
            line!(out, "None: the curve was used as read.");
        }
        for (i, s) in self.preprocessing.iter().enumerate() {
            line!(
                out,
                "{}. **{}**: {}",
                i + 1,
                escape(&s.name),
                escape(&s.description)
            );
        }
        line!(out);
    }

    fn figure_section(&self, out: &mut String) {
        if self.figures.is_empty() {
            return;
        }
        line!(out, "## Figures");
        line!(out);
        for f in &self.figures {
            line!(
                out,
                "![{}]({})",
                escape(&f.caption),
                f.path.replace(' ', "%20")
            );
            line!(out);
        }
    }
}

impl Report {
    /// Whether the identifiability analysis found parameter `name` undetermined.
    pub fn is_undetermined(&self, name: &str) -> bool {
        self.identifiability
            .as_ref()
            .is_some_and(|i| i.is_undetermined(name))
    }
}

/// `## Identifiability`: the undetermined parameters first (with the reason and what to
/// do), the weakest direction in words, then the singular values and their directions.
fn identifiability_section(out: &mut String, i: &IdentifiabilitySummary) {
    line!(out, "## Identifiability");
    line!(out);
    if i.undetermined.is_empty() {
        line!(out, "Every free parameter is determined by the data.");
    } else {
        line!(out, "**Not determined by the data:**");
        line!(out);
        for u in &i.undetermined {
            line!(out, "- **{}**: {}", escape(&u.name), escape(&u.reason));
        }
        line!(out);
        if !i.advice.is_empty() {
            line!(out, "What to do: {}.", escape(&i.advice));
        }
    }
    line!(out);
    if let Some(w) = &i.weakest {
        line!(out, "Weakest direction: {}.", escape(w));
        line!(out);
    }
    line!(
        out,
        "Singular values of the scaled sensitivity matrix S (weighted dF/dy, y = ln c for \
         log-scaled parameters) and the combination of parameters each one determines; \
         condition number of S^T S: {}.",
        escape(&i.condition)
    );
    line!(out);
    let mut head = String::from("| j | s_j | s_j / s_1 |");
    let mut rule = String::from("|--:|--:|--:|");
    for n in &i.names {
        let _ = write!(head, " {} |", escape(n));
        rule.push_str("--:|");
    }
    line!(out, "{head}");
    line!(out, "{rule}");
    let s1 = i.singular_values.first().copied().unwrap_or(0.0);
    for (j, (s, v)) in i.singular_values.iter().zip(&i.directions).enumerate() {
        let mut l = format!(
            "| {} | {} | {} |",
            j + 1,
            fmt_sig(*s),
            if s1 > 0.0 {
                fmt_sig(s / s1)
            } else {
                String::new()
            }
        );
        for x in v {
            let _ = write!(l, " {x:+.3} |");
        }
        line!(out, "{l}");
    }
    line!(out);
}

/// A value in `unit`, 4 significant digits; empty for `None`.
fn shown(unit: &DisplayUnit, v: Option<f64>) -> String {
    v.map(|v| fmt_sig(unit.show(v))).unwrap_or_default()
}

fn status(p: &Parameter) -> &'static str {
    match (p.fixed, p.at_bound) {
        (true, _) => "fixed",
        (false, None) => "free",
        (false, Some(BoundHit::Lower)) => "free, **at lower bound**",
        (false, Some(BoundHit::Upper)) => "free, **at upper bound**",
    }
}

/// Keeps user text from breaking table cells or lines.
fn escape(s: &str) -> String {
    s.replace('|', "\\|").replace(['\n', '\r'], " ")
}

fn systematic(a: &Adequacy) -> bool {
    a.verdict == Verdict::Systematic
}

/// The section `## Model adequacy`: the residuals against the record's own noise and their
/// structure, with the verdict (statistics and thresholds in `docs/adequacy.md`).
fn adequacy_section(out: &mut String, a: &Adequacy, observable: Observable) {
    // the statistics are in the observable's internal unit
    let unit = match observable {
        _ if a.relative => {
            "(fraction of the fitted value: residuals standardized by the stated multiplicative noise)"
        }
        Observable::Force => "N",
        Observable::Depth => "mm",
    };
    let est = |e: &Option<crate::adequacy::NoiseEstimate>| match e {
        Some(e) => format!(
            "{} {unit} ({}, lag-1 of its differences {:.2})",
            fmt_sig(e.sigma),
            if e.resolved {
                "resolved"
            } else {
                "upper bound"
            },
            e.lag1
        ),
        None => "not estimated".to_string(),
    };
    line!(out, "## Model adequacy");
    line!(out);
    let verdict = a.verdict.as_str();
    let why = a
        .message
        .strip_prefix(&format!("{verdict}: "))
        .unwrap_or(&a.message);
    line!(out, "**{verdict}**: {}", escape(why));
    line!(out);
    line!(out, "| statistic | value | limit |");
    line!(out, "|---|--:|--:|");
    line!(
        out,
        "| record noise σ_rec (third differences) | {} {unit}{} | |",
        fmt_sig(a.sigma_record),
        if a.noise_resolved {
            ""
        } else {
            " (upper bound)"
        }
    );
    line!(
        out,
        "| noise of the measured {} | {} | |",
        observable.name(),
        est(&a.sigma_data)
    );
    line!(
        out,
        "| high-frequency noise of the residuals | {} | |",
        est(&a.sigma_residual)
    );
    line!(
        out,
        "| RMS residual / σ_rec | {:.3} | z ≤ {} ({} unresolved) |",
        a.ratio,
        crate::adequacy::Z_LIMIT,
        crate::adequacy::RATIO_LIMIT_UNRESOLVED
    );
    line!(
        out,
        "| χ² / dof | {} / {} (z = {:.2}) | |",
        fmt_sig(a.chi2),
        a.dof,
        a.z_ratio
    );
    line!(
        out,
        "| runs of one sign | {} ({:.1} expected, z = {:.2}) | z ≥ -{} |",
        a.runs,
        a.runs_expected,
        a.runs_z,
        crate::adequacy::Z_LIMIT
    );
    line!(out, "| lag-1 autocorrelation | {:.3} | |", a.lag1);
    line!(out, "| Durbin-Watson | {:.3} | |", a.durbin_watson);
    line!(
        out,
        "| Ljung-Box Q ({} lags) | {} (z = {:.2}) | z ≤ {} |",
        a.ljung_box_lags,
        fmt_sig(a.ljung_box),
        a.z_ljung_box,
        crate::adequacy::Z_LIMIT
    );
    line!(out, "| points, free parameters | {}, {} | |", a.n, a.free);
    line!(out);
}
