//! The Oliver-Pharr numbers of a fitted test beside the FE result: `indentify identify`
//! analyses the measured record of a one-test fit as `indentify analyze` does (the
//! configuration's punch as the analysis tip, the fitted `nu`) and reports `E_IT`, `H_IT`,
//! `S`, `h_c` and the tip used beside the fitted `E`, with their difference and why the two
//! may differ (docs/analysis.md, "O&P beside the FE result"). A joint fit gets the same for
//! each test with a measured record (its page and result.json's `tests[k].oliver_pharr`)
//! and a table of them all on its index page ([`joint_markdown`]).

use indentify_analysis::Tip;
use indentify_contact::Punch;
use serde::Serialize;

use crate::first_guess::{OpSummary, analyse_record, tip_for_punch};
use crate::format::sig;

/// Why O&P and the FE fit may differ (one sentence, in the console, result.json and
/// report.md).
pub const WHY_THEY_DIFFER: &str = "O&P takes the contact area from the unloading's elastic \
     stiffness and the tip's area function, so it misses a pile-up (E and H too high) or a \
     sink-in it does not model, treats the unloading as elastic and time-independent while \
     the FE law has its own rate dependence, and uses the ideal (or calibrated) tip where the \
     FE model has the configuration's punch: the two agree only for an elastic, \
     time-independent contact without pile-up.";

/// The O&P values of a fitted test beside the FE result (MPa, N/mm, mm, N).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OpBeside {
    /// The O&P values of the test's main unloading (`None` when it was skipped).
    #[serde(flatten)]
    pub op: Option<OpSummary>,
    /// The analysis tip: the configuration's punch as an area function, or the
    /// calibrated tip file's.
    pub tip: String,
    /// The fitted Young's modulus, MPa (`None` when the law has no `E`).
    #[serde(rename = "E_fe")]
    pub e_fe: Option<f64>,
    /// `100 (E_IT - E_fe) / E_fe`, %.
    #[serde(rename = "E_difference_pct")]
    pub e_difference_pct: Option<f64>,
    /// Why O&P and the FE fit may differ.
    pub why_they_differ: String,
    /// Why there are no O&P values (no unloading, a punch without an area function, ...).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub skipped: Option<String>,
}

/// The analysis tip of a configuration's punch: the calibrated tip file's (read relative
/// to `base`), else [`tip_for_punch`].
///
/// # Errors
/// A punch without an area function (tabulated), an unreadable tip file.
pub fn tip_of(punch: &Punch, base: Option<&std::path::Path>) -> Result<Tip, String> {
    if let Punch::Calibrated { file, .. } = punch {
        let path = crate::config::tip::tip_path(file, base);
        return crate::analyze::read_tip(&path).map_err(|e| e.to_string());
    }
    tip_for_punch(punch).ok_or_else(|| {
        format!(
            "the punch {} has no analysis area function",
            punch.describe()
        )
    })
}

/// The O&P analysis of `record` with the punch's tip and the fitted `nu`, beside the
/// fitted `e_fe`; a record that cannot be analysed (no unloading, ...) gives the values
/// `None` and the reason in `skipped`.
pub fn compare(
    record: &indentify_records::Record,
    punch: &Punch,
    base: Option<&std::path::Path>,
    e_fe: Option<f64>,
    nu: f64,
) -> OpBeside {
    let mut out = OpBeside {
        op: None,
        tip: String::new(),
        e_fe,
        e_difference_pct: None,
        why_they_differ: WHY_THEY_DIFFER.into(),
        skipped: None,
    };
    let tip = match tip_of(punch, base) {
        Ok(t) => t,
        Err(e) => {
            out.skipped = Some(e);
            return out;
        }
    };
    // a tip's name may already be its area function's description (the ideal tips)
    let area = tip.area.describe();
    out.tip = if tip.name.is_empty() || tip.name == area {
        area
    } else {
        format!("{} ({area})", tip.name)
    };
    match analyse_record(record, &tip, nu) {
        Ok(op) => {
            out.e_difference_pct = e_fe.filter(|e| *e > 0.0).map(|e| 100.0 * (op.e - e) / e);
            out.op = Some(op);
        }
        Err(e) => out.skipped = Some(e.to_string()),
    }
    out
}

/// The console lines (two-space indent).
pub fn lines(b: &OpBeside) -> String {
    let Some(op) = &b.op else {
        return format!(
            "  Oliver-Pharr: not analysed ({})\n",
            b.skipped.as_deref().unwrap_or("no reason given")
        );
    };
    let mut s = format!(
        "  Oliver-Pharr of the same test (tip: {}, nu {}): E_IT = {} MPa, H_IT = {} MPa, S = {} \
         N/mm, h_c = {} mm\n",
        b.tip,
        sig(op.nu, 3),
        sig(op.e, 4),
        sig(op.h, 4),
        sig(op.s, 4),
        sig(op.hc, 4)
    );
    if let (Some(e), Some(d)) = (b.e_fe, b.e_difference_pct) {
        s.push_str(&format!(
            "  E_IT vs the fitted E = {} MPa: {}{} %\n",
            sig(e, 4),
            if d >= 0.0 { "+" } else { "" },
            sig(d, 3)
        ));
    }
    s.push_str(&format!("  why they may differ: {}\n", b.why_they_differ));
    s
}

/// The report.md section.
pub fn markdown(b: &OpBeside) -> String {
    let mut s = String::from("## Oliver-Pharr beside the FE result\n\n");
    let Some(op) = &b.op else {
        s.push_str(&format!(
            "Not analysed: {}.\n",
            b.skipped.as_deref().unwrap_or("no reason given")
        ));
        return s;
    };
    s.push_str(&format!(
        "The same test analysed as `indentify analyze` does (tip: {}, sample nu {}).\n\n",
        b.tip,
        sig(op.nu, 3)
    ));
    s.push_str("| quantity | Oliver-Pharr | FE fit | difference |\n|---|---|---|---|\n");
    s.push_str(&format!(
        "| E (MPa) | {} | {} | {} |\n",
        sig(op.e, 4),
        b.e_fe.map_or("-".into(), |e| sig(e, 4)),
        b.e_difference_pct
            .map_or("-".into(), |d| format!("{} %", sig(d, 3)))
    ));
    s.push_str(&format!("| H_IT (MPa) | {} | - | - |\n", sig(op.h, 4)));
    s.push_str(&format!("| E_r (MPa) | {} | - | - |\n", sig(op.er, 4)));
    s.push_str(&format!("| S (N/mm) | {} | - | - |\n", sig(op.s, 4)));
    s.push_str(&format!("| h_c (mm) | {} | - | - |\n", sig(op.hc, 4)));
    s.push_str(&format!(
        "| h_max (mm), F_max (N) | {}, {} | - | - |\n\n",
        sig(op.hmax, 4),
        sig(op.fmax, 4)
    ));
    s.push_str(&format!("Why they may differ: {}\n", b.why_they_differ));
    s
}

/// The joint index's section: each test's O&P beside the shared fitted `E` (a test with
/// synthesized data has none and is left out; nothing when no test has a record).
pub fn joint_markdown(tests: &[crate::identify::TestFit]) -> String {
    let with: Vec<(&str, &OpBeside)> = tests
        .iter()
        .filter_map(|t| Some((t.name.as_str(), t.oliver_pharr.as_ref()?)))
        .collect();
    let Some((_, first)) = with.first() else {
        return String::new();
    };
    let mut s = String::from("\n## Oliver-Pharr beside the FE result\n\n");
    s.push_str(&format!(
        "Each test's record analysed as `indentify analyze` does (its punch as the tip), \
         beside the shared fitted E = {} MPa.\n\n",
        first.e_fe.map_or("-".into(), |e| sig(e, 4))
    ));
    s.push_str(
        "| test | tip | E_IT (MPa) | difference to the fitted E | H_IT (MPa) | S (N/mm) | h_c \
         (mm) |\n|---|---|---:|---:|---:|---:|---:|\n",
    );
    for (name, b) in &with {
        match &b.op {
            Some(op) => s.push_str(&format!(
                "| {name} | {} | {} | {} | {} | {} | {} |\n",
                b.tip,
                sig(op.e, 4),
                b.e_difference_pct
                    .map_or("-".into(), |d| format!("{} %", sig(d, 3))),
                sig(op.h, 4),
                sig(op.s, 4),
                sig(op.hc, 4)
            )),
            None => s.push_str(&format!(
                "| {name} | {} | not analysed: {} | | | | |\n",
                b.tip,
                b.skipped
                    .as_deref()
                    .unwrap_or("no reason given")
                    .replace('|', "\\|")
            )),
        }
    }
    s.push_str(&format!(
        "\nWhy they may differ: {}\n",
        first.why_they_differ
    ));
    s
}
