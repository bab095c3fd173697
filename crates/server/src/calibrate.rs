//! `calibrate` as a run: the frame compliance and the ISO area function fitted on an
//! uploaded reference record (fused silica) of known modulus, by the study pipeline
//! `indentify calibrate` calls, with the same options; the run writes `tip.ron` (the tip
//! file the CLI writes, to be stored with `POST /api/tips`) and `calibration.json` (what
//! `indentify calibrate --json` prints).

use indentify_study::analyze::{self, CalibrateOptions};
use serde_json::json;

use crate::api::ApiError;
use crate::jobs::{Prepared, record_file};
use crate::runs::{End, ErrorBody, RecordRef, Run, RunRequest, Status, error_body};

/// The most area coefficients (as `indentify calibrate --terms`).
const MAX_TERMS: usize = 6;

fn bad(msg: String) -> ApiError {
    ApiError::bad_request("config", vec![msg])
}

/// Checks a calibrate request: a record, `modulus` (GPa) and `nu` required, `terms` 1 to
/// 6, no configuration; nothing to write but the command line.
pub(crate) fn prepare(
    req: &RunRequest,
    record: Option<&RecordRef>,
    sets: &[String],
) -> Result<Prepared, ApiError> {
    let Some((_, rel, _)) = record else {
        return Err(bad(
            "calibrate needs a record of the reference (fused silica): upload the file (POST \
             /api/records) and give its id as `record`"
                .into(),
        ));
    };
    if req.config.is_some() || !sets.is_empty() {
        return Err(bad(
            "calibrate takes no configuration and no `sets`: give `modulus` (GPa), `nu`, and \
             optionally `test` and `terms`"
                .into(),
        ));
    }
    let Some(e) = req.modulus else {
        return Err(bad(
            "calibrate needs `modulus`: the reference's Young's modulus in GPa (fused silica 72)"
                .into(),
        ));
    };
    if !(e.is_finite() && e > 0.0) {
        return Err(bad(format!(
            "modulus = {e} is not allowed: expected the reference's Young's modulus > 0 (GPa)"
        )));
    }
    let Some(nu) = req.nu else {
        return Err(bad(
            "calibrate needs `nu`: the reference's Poisson's ratio (fused silica 0.17)".into(),
        ));
    };
    if !(0.0..0.5).contains(&nu) {
        return Err(bad(format!(
            "nu = {nu} is not allowed: expected Poisson's ratio in [0, 0.5)"
        )));
    }
    let terms = req.terms.unwrap_or(3);
    if !(1..=MAX_TERMS).contains(&terms) {
        return Err(bad(format!(
            "terms = {terms} is not allowed: expected 1 to {MAX_TERMS} area coefficients"
        )));
    }
    let mut cli =
        format!("indentify calibrate {rel} --modulus {e} --nu {nu} --terms {terms} --out tip.ron");
    if let Some(k) = req.test {
        cli.push_str(&format!(" --tests {k}"));
    }
    Ok(Prepared {
        files: Vec::new(),
        sets: Vec::new(),
        cli,
    })
}

/// The options `indentify calibrate FILE --modulus E --nu NU [--tests K] --terms N` passes
/// to the pipeline (the modulus from GPa to MPa).
pub fn options(
    file: std::path::PathBuf,
    modulus_gpa: f64,
    nu: f64,
    test: Option<usize>,
    terms: usize,
) -> CalibrateOptions {
    CalibrateOptions {
        tests: test.map(|k| vec![k]),
        terms,
        ..CalibrateOptions::new(file, modulus_gpa * 1e3, nu)
    }
}

/// Executes a calibrate run: tip.ron and calibration.json in the run's folder.
pub(crate) fn run(run: &Run) -> Result<End, ErrorBody> {
    run.update(true, |m| m.progress.stage = "calibrating".into());
    let req = &run.spec.req;
    let mut opts = options(
        record_file(run)?,
        req.modulus.unwrap_or_default(),
        req.nu.unwrap_or_default(),
        req.test,
        req.terms.unwrap_or(3),
    );
    opts.out = Some(run.dir.join("tip.ron"));
    let o = analyze::calibrate(&opts).map_err(|e| error_body(&e))?;
    let io = |e: String| ErrorBody {
        kind: "io".into(),
        messages: vec![e],
    };
    let mut value = serde_json::to_value(&o).map_err(|e| io(e.to_string()))?;
    // the file as the run's folder names it (the pipeline's is an absolute path)
    value["written"] = json!("tip.ron");
    let text = serde_json::to_string_pretty(&value).map_err(|e| io(e.to_string()))?;
    indentify_study::atomic::write(&run.dir.join("calibration.json"), text + "\n")
        .map_err(|e| io(format!("{e:#}")))?;
    let summary = json!({
        "command": "calibrate", "frame_compliance": o.compliance_used,
        "coefficients": o.area.coefficients, "points": o.area.n, "rms_rel": o.area.rms_rel,
        "radius": o.area.radius, "tip": "tip.ron", "seconds": o.seconds,
    });
    let message = (!o.area.warnings.is_empty() || !o.skipped.is_empty()).then(|| {
        let mut m = o.area.warnings.clone();
        if !o.skipped.is_empty() {
            m.push(format!(
                "{} test(s) or unloading(s) skipped",
                o.skipped.len()
            ));
        }
        m.join("; ")
    });
    Ok((Status::Done, Some(summary), None, message))
}
