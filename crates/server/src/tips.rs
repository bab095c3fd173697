//! Calibrated tips uploaded from the browser: the `TIP.ron` that `indentify calibrate`
//! writes (area function, optional frame compliance), checked as study reads it (RON with
//! the line of an error, ranges, an area function that is a punch) before anything is
//! stored, kept as `tips/<id>/tip.ron`; a configuration names it as
//! `punch: Calibrated(file: "../../tips/<id>/tip.ron")` (relative to its run folder), and
//! no other tip path is served.

use serde_json::{Value, json};

use crate::api::ApiError;
use crate::workspace::{Workspace, content_id};

/// The largest tip file taken (a tip file is a few lines).
pub const MAX_TIP_BYTES: usize = 64 * 1024;

/// The file name of a stored tip in its folder.
pub const TIP_FILE: &str = "tip.ron";

/// How a configuration in a run folder names stored tip `id`.
pub fn relative_path(id: &str) -> String {
    format!("../../tips/{id}/{TIP_FILE}")
}

fn refused(msg: String) -> ApiError {
    ApiError::bad_request("config", vec![msg])
}

/// Checks and stores an uploaded tip file; the same bytes again give the same id.
///
/// # Errors
/// 400 for a file that is too large, not UTF-8, not a tip (RON line and message), out of
/// range, or whose area function is not a punch; 500 when it cannot be written.
pub fn store(ws: &Workspace, name: &str, bytes: &[u8]) -> Result<Value, ApiError> {
    if bytes.len() > MAX_TIP_BYTES {
        return Err(refused(format!(
            "the tip file `{name}` has {} bytes: a tip file (`indentify calibrate`'s TIP.ron) \
             has at most {MAX_TIP_BYTES}",
            bytes.len()
        )));
    }
    let text = std::str::from_utf8(bytes).map_err(|e| {
        refused(format!(
            "the tip file `{name}` is not text (UTF-8): {e}; expected the RON of `indentify \
             calibrate`, e.g. (area: Iso(coefficients: [24.5]))"
        ))
    })?;
    let tip: indentify_study::Tip = ron::from_str(text).map_err(|e| {
        refused(format!(
            "{name}:{}: {} (expected the RON of `indentify calibrate`, e.g. (area: \
             Iso(coefficients: [24.5])))",
            e.span.start.line, e.code
        ))
    })?;
    tip.validate()
        .map_err(|e| refused(format!("{name}: {e}")))?;
    indentify_study::config::tip::area_profile(&tip.area)
        .map_err(|e| refused(format!("{name}: tip.area: {e:#}")))?;
    let id = content_id(bytes);
    let dir = ws.tips().join(&id);
    std::fs::create_dir_all(&dir).map_err(ApiError::io)?;
    indentify_study::atomic::write(&dir.join(TIP_FILE), bytes).map_err(ApiError::internal)?;
    Ok(json!({
        "id": id,
        "name": name,
        "file": relative_path(&id),
        "punch": format!("Calibrated(file: \"{}\")", relative_path(&id)),
        "frame_compliance": tip.frame_compliance,
        "bytes": bytes.len(),
    }))
}

/// The stored tips: `{id, file, punch, bytes}` each.
pub fn list(ws: &Workspace) -> Vec<Value> {
    let Ok(entries) = std::fs::read_dir(ws.tips()) else {
        return Vec::new();
    };
    let mut out: Vec<Value> = entries
        .flatten()
        .filter_map(|e| {
            let id = e.file_name().to_string_lossy().into_owned();
            let meta = std::fs::metadata(e.path().join(TIP_FILE)).ok()?;
            crate::workspace::valid_id(&id).then(|| {
                json!({"id": id, "file": relative_path(&id),
                       "punch": format!("Calibrated(file: \"{}\")", relative_path(&id)),
                       "bytes": meta.len()})
            })
        })
        .collect();
    out.sort_by(|a, b| a["id"].as_str().cmp(&b["id"].as_str()));
    out
}
