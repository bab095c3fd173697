//! `cargo xtask fit-cost --proposed-step`: each case fitted with the stop on the proposed
//! step (`StopCriteria::proposed_step`) and without it, back to back, with every free
//! parameter's shift `|on - off| / sigma` and the fit's outcome (converged, undetermined
//! parameters, the adequacy verdict) of both. The rule only ever ends a run early: a run
//! it did not stop is the run without it, step for step, so the run without it is made
//! only when the rule fired (`--both`: always, to check that claim). Also the further
//! single-fit cases this measurement covers (the Levenberg-Marquardt examples of
//! `examples/` and `examples/real/`, synthetic ones with stated noise).

use std::path::Path;

use anyhow::Result;
use indentify_identify::{IdentifyResult, StopReason};
use indentify_study::config::MethodName;
use indentify_study::identify::{IdentifyOptions, Setup};
use serde_json::{Value, json};

/// A further case: name, configuration under the repository root, the multiplicative noise
/// (amplitude, seed) of synthesized data, and whether the method is set to
/// Levenberg-Marquardt (a configuration that fits by BFGS).
pub type Case = (&'static str, &'static str, Option<(f64, u64)>, bool);

/// The further cases.
pub const EXTRA: [Case; 16] = [
    ("r1-noisy", "examples/r1-maxwell.ron", Some((0.02, 1)), true),
    (
        "pdotp-maxwell",
        "examples/pdotp-maxwell.ron",
        Some((0.01, 1)),
        false,
    ),
    (
        "plastic-power-cone",
        "examples/plastic-power-cone.ron",
        Some((0.01, 1)),
        false,
    ),
    (
        "prony-sls",
        "examples/prony-sls.ron",
        Some((0.02, 1)),
        false,
    ),
    (
        "r2-multi-rate",
        "examples/r2-multi-rate.ron",
        Some((0.02, 1)),
        false,
    ),
    ("anon-prony1", "examples/real/anon-prony1.ron", None, false),
    ("anon-prony2", "examples/real/anon-prony2.ron", None, false),
    ("anon-prony3", "examples/real/anon-prony3.ron", None, false),
    (
        "anon-plastic",
        "examples/real/anon-plastic.ron",
        None,
        false,
    ),
    (
        "anon-power-norton",
        "examples/real/anon-power-norton.ron",
        None,
        false,
    ),
    ("ht-plastic", "examples/real/ht-plastic.ron", None, false),
    (
        "ht-voce-plastic",
        "examples/real/ht-voce-plastic.ron",
        None,
        false,
    ),
    ("ht-nh-load", "examples/real/ht-nh-load.ron", None, false),
    (
        "ht-power-norton-joint",
        "examples/real/ht-power-norton-joint.ron",
        None,
        false,
    ),
    (
        "ht-nh-load-joint",
        "examples/real/ht-nh-load-joint.ron",
        None,
        false,
    ),
    (
        "ht-voce-norton-joint",
        "examples/real/ht-voce-norton-joint.ron",
        None,
        false,
    ),
];

/// The options of a further case, `None` for a name that is not one.
pub fn options(root: &Path, case: &str) -> Option<IdentifyOptions> {
    let (_, file, noise, lm) = EXTRA.iter().find(|e| e.0 == case)?;
    let mut o = IdentifyOptions::new(indentify_study::ConfigSource::Path(root.join(file)));
    o.noise = *noise;
    if *lm {
        o.overrides.method = Some(MethodName::Lm);
    }
    Some(o)
}

/// What a fit concluded: converged, the undetermined parameters, each test's adequacy
/// verdict (force-observable and depth-observable tests alike, from the optimizer's final
/// observables).
pub fn outcome(s: &Setup, r: &IdentifyResult) -> Value {
    let undetermined: Vec<&str> = r
        .identifiability
        .as_ref()
        .map(|i| i.undetermined.clone())
        .unwrap_or_default();
    let free = r.params.iter().filter(|p| p.free).count();
    let relative = indentify_study::adequacy::states_relative_noise(r);
    let verdicts: Vec<&str> = s
        .problem
        .tests
        .iter()
        .enumerate()
        .map(|(k, test)| {
            let rows = s.problem.rows_of(k);
            let model = r.forces.get(rows).unwrap_or(&[]);
            let observable = if test.load.is_some() {
                indentify_study::Observable::Depth
            } else {
                indentify_study::Observable::Force
            };
            indentify_study::adequacy::assess_series(
                &test.schedule.t,
                &test.target,
                model,
                observable,
                free,
                relative,
            )
            .map_or("none", |a| a.verdict.as_str())
        })
        .collect();
    json!({
        "converged": r.stop_reason.is_converged(),
        "undetermined": undetermined,
        "adequacy": verdicts,
    })
}

/// `--proposed-step`: each case fitted by `run(case, true)` (the rule on) and, where the
/// rule fired or with `both`, by `run(case, false)` right after; the tables printed, the
/// pairs kept in `json` after every case (an interrupted sweep keeps what it measured).
pub fn sweep(
    cases: &[&str],
    both: bool,
    json: Option<&Path>,
    run: impl Fn(&str, bool) -> Result<Value>,
) -> Result<()> {
    let mut pairs = Vec::new();
    for case in cases {
        let on = run(case, true)?;
        let again = both || on["fired"] == true;
        let off = if again { run(case, false)? } else { on.clone() };
        let p = pair(case, &on, &off, !again);
        eprintln!("{}", table(std::slice::from_ref(&p)));
        pairs.push(p);
        super::write_json(json, &Value::Array(pairs.clone()))?;
    }
    println!("{}", table(&pairs));
    Ok(())
}

/// Whether the rule ended the run.
pub fn fired(r: &IdentifyResult) -> bool {
    matches!(r.stop_reason, StopReason::ProposedBelowSigma { .. })
}

/// The pair of one case from its two measurements (`off` may be the `on` run itself when
/// the rule did not fire): counts, ratios, outcomes and shifts.
pub fn pair(case: &str, on: &Value, off: &Value, same_run: bool) -> Value {
    let empty = Vec::new();
    let off_params = off["params"].as_array().unwrap_or(&empty);
    let mut shifts = Vec::new();
    let mut worst: f64 = 0.0;
    for p in on["params"].as_array().unwrap_or(&empty) {
        let Some(q) = off_params.iter().find(|q| q["name"] == p["name"]) else {
            continue;
        };
        let (va, vb) = (
            p["value"].as_f64().unwrap_or(f64::NAN),
            q["value"].as_f64().unwrap_or(f64::NAN),
        );
        // the default run's deviation (the on run's where it has none); both reported
        let sd_off = q["sd"].as_f64().filter(|v| v.is_finite() && *v > 0.0);
        let sd_on = p["sd"].as_f64().filter(|v| v.is_finite() && *v > 0.0);
        let z = sd_off.or(sd_on).map(|sd| (va - vb).abs() / sd);
        let z_on = sd_on.map(|sd| (va - vb).abs() / sd);
        for v in [z, z_on].into_iter().flatten() {
            worst = worst.max(v);
        }
        shifts.push(json!({
            "name": p["name"], "off": vb, "on": va, "sd_off": sd_off, "sd_on": sd_on,
            "shift_sigma": z, "shift_sigma_on": z_on,
        }));
    }
    json!({
        "case": case,
        "same_run": same_run,
        "fired": on["fired"],
        "off": off,
        "on": on,
        "shifts": shifts,
        "max_shift_sigma": worst,
        "outcome_changed": on["outcome"] != off["outcome"],
    })
}

/// The tables of the pairs: counts and outcomes, then every parameter's shift.
pub fn table(pairs: &[Value]) -> String {
    use std::fmt::Write;
    let mut s = String::from(
        "| case | rule fired | iterations off / on | forward solves off / on | sensitivity off / on | fit / forward off / on | outcome off | on | max abs(shift) / sigma | stop on |\n|---|---|---|---|---|---|---|---|---|---|\n",
    );
    let o = |v: &Value| -> String {
        let u = v["undetermined"]
            .as_array()
            .map(|a| {
                a.iter()
                    .filter_map(Value::as_str)
                    .collect::<Vec<_>>()
                    .join(",")
            })
            .unwrap_or_default();
        format!(
            "{}{}; {}",
            if v["converged"] == true {
                "converged"
            } else {
                "NOT converged"
            },
            if u.is_empty() {
                String::new()
            } else {
                format!(", {u} undetermined")
            },
            v["adequacy"]
        )
    };
    for p in pairs {
        let (on, off) = (&p["on"], &p["off"]);
        let f = |v: &Value| v.as_f64().unwrap_or(f64::NAN);
        let ratio_off = if p["same_run"] == true {
            "(same run)".to_string()
        } else {
            format!("{:.1}", f(&off["ratio"]))
        };
        let _ = writeln!(
            s,
            "| {} | {} | {} / {} | {} / {} | {} / {} | {ratio_off} / {:.1} | {} | {} | {:.3} | {} |",
            p["case"].as_str().unwrap_or(""),
            if p["fired"] == true { "yes" } else { "no" },
            off["iterations"],
            on["iterations"],
            off["forward_solves"],
            on["forward_solves"],
            off["sensitivity_solves"],
            on["sensitivity_solves"],
            f(&on["ratio"]),
            o(&off["outcome"]),
            o(&on["outcome"]),
            f(&p["max_shift_sigma"]),
            on["stop"].as_str().unwrap_or(""),
        );
    }
    s.push_str("\n| case | parameter | off | on | sigma off | sigma on | abs(on - off) / sigma off | / sigma on |\n|---|---|---|---|---|---|---|---|\n");
    for p in pairs {
        for z in p["shifts"].as_array().into_iter().flatten() {
            let g = |k: &str| z[k].as_f64().unwrap_or(f64::NAN);
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} | {} | {} | {} |",
                p["case"].as_str().unwrap_or(""),
                z["name"].as_str().unwrap_or(""),
                super::sig(g("off")),
                super::sig(g("on")),
                super::sd_cell(z["sd_off"].as_f64()),
                super::sd_cell(z["sd_on"].as_f64()),
                super::shift_cell(z["shift_sigma"].as_f64()),
                super::shift_cell(z["shift_sigma_on"].as_f64()),
            );
        }
    }
    s
}
