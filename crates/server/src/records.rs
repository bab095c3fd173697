//! Uploaded instrument records: read with the same readers as the CLI (every format of
//! `indentify_records`), stored as `records/<id>/<name>` with `record.json` (its tests,
//! segments, the default preprocessing's account and a thinned curve for the page).

use serde::Serialize;
use serde_json::Value;

use crate::api::ApiError;
use crate::workspace::{Workspace, content_id, sanitize_name};

/// Points of each curve kept in `record.json` for the page's plot.
const PLOT_POINTS: usize = 400;

/// One test of a record, as the page shows it.
#[derive(Debug, Serialize)]
struct TestInfo {
    /// 1-based index (`data.test`).
    index: usize,
    name: String,
    points: usize,
    /// s
    duration: f64,
    /// mm
    h_max: f64,
    /// N
    f_max: f64,
    tip: Option<String>,
    /// mm, when the file states a tip radius
    tip_radius: Option<f64>,
    segments: Vec<SegmentInfo>,
    /// The default preprocessing (as `init --data` writes it: 60 resampled points).
    preprocessing: Vec<StepInfo>,
    preprocessing_error: Option<String>,
    /// Thinned raw curve: t (s), h (mm), F (N).
    curve: Curve,
}

#[derive(Debug, Serialize)]
struct SegmentInfo {
    id: u32,
    samples: usize,
    t0: f64,
    t1: f64,
}

#[derive(Debug, Serialize)]
struct StepInfo {
    step: String,
    description: String,
}

#[derive(Debug, Serialize)]
struct Curve {
    t: Vec<f64>,
    h: Vec<f64>,
    f: Vec<f64>,
}

/// Every `k`-th sample (first and last kept) so that at most [`PLOT_POINTS`] remain.
fn thin(v: &[f64]) -> Vec<f64> {
    let k = v.len().div_ceil(PLOT_POINTS).max(1);
    let mut out: Vec<f64> = v.iter().step_by(k).copied().collect();
    if let Some(&last) = v.last() {
        if (v.len() - 1) % k != 0 {
            out.push(last);
        }
    }
    out
}

fn segments(r: &indentify_study::records::Record) -> Vec<SegmentInfo> {
    let Some(ids) = &r.segment else {
        return Vec::new();
    };
    let mut out: Vec<SegmentInfo> = Vec::new();
    for (i, &id) in ids.iter().enumerate() {
        match out.last_mut() {
            Some(s) if s.id == id => {
                s.samples += 1;
                s.t1 = r.t[i];
            }
            _ => out.push(SegmentInfo {
                id,
                samples: 1,
                t0: r.t[i],
                t1: r.t[i],
            }),
        }
    }
    out
}

/// The description of every test of `bytes` (read as the CLI reads a `data.file`).
///
/// # Errors
/// The reader's message (file, line, what was expected), as a 400.
fn describe(bytes: &[u8], name: &str) -> Result<Vec<TestInfo>, ApiError> {
    let records =
        indentify_study::records::read(bytes, name, &Default::default()).map_err(|e| {
            ApiError::bad_request(
                "data",
                vec![
                    format!("cannot read `{name}` as an instrument record"),
                    e.to_string(),
                ],
            )
        })?;
    let prep = indentify_study::records::Preprocessing {
        resample: Some(indentify_study::records::Resample {
            n: 60,
            ..indentify_study::records::Resample::default()
        }),
        ..indentify_study::records::Preprocessing::default()
    };
    Ok(records
        .iter()
        .enumerate()
        .map(|(k, r)| {
            let (steps, error) = match indentify_study::records::apply(r, &prep) {
                Ok((_, applied)) => (
                    applied
                        .into_iter()
                        .map(|a| StepInfo {
                            step: a.step,
                            description: a.description,
                        })
                        .collect(),
                    None,
                ),
                Err(e) => (Vec::new(), Some(e.to_string())),
            };
            TestInfo {
                index: k + 1,
                name: r.meta.test_name.clone().unwrap_or_else(|| r.name.clone()),
                points: r.len(),
                duration: r.t.last().copied().unwrap_or(0.0) - r.t.first().copied().unwrap_or(0.0),
                h_max: r.h_max(),
                f_max: r.f.iter().copied().fold(f64::NAN, f64::max),
                tip: r.meta.tip.clone(),
                tip_radius: r.meta.tip_radius,
                segments: segments(r),
                preprocessing: steps,
                preprocessing_error: error,
                curve: Curve {
                    t: thin(&r.t),
                    h: thin(&r.h),
                    f: thin(&r.f),
                },
            }
        })
        .collect())
}

/// Reads and stores an upload; an identical file uploaded again gets the same id and is
/// not rewritten. Nothing is written for a file the readers refuse.
///
/// # Errors
/// An unreadable record (400, the reader's message), a name clash of different content
/// under one id (409), a write failure (500).
pub fn store(ws: &Workspace, name: &str, bytes: &[u8]) -> Result<Value, ApiError> {
    let name = sanitize_name(name);
    let id = content_id(bytes);
    let dir = ws
        .record_dir(&id)
        .ok_or_else(|| ApiError::internal("bad record id"))?;
    let meta = dir.join("record.json");
    if meta.is_file() {
        let existing = std::fs::read(&meta).map_err(ApiError::io)?;
        let v: Value = serde_json::from_slice(&existing).map_err(ApiError::internal)?;
        let file = v["file"].as_str().unwrap_or_default();
        let same = std::fs::read(dir.join(file)).is_ok_and(|b| b == bytes);
        if same {
            return Ok(v);
        }
        return Err(ApiError::new(
            axum::http::StatusCode::CONFLICT,
            "data",
            vec![format!(
                "record {id} exists with other content (a hash collision): rename nothing, \
                 upload the file again with one byte changed"
            )],
        ));
    }
    let tests = describe(bytes, &name)?;
    let format = format!("{:?}", indentify_study::records::detect(bytes));
    let info = serde_json::json!({
        "id": id,
        "name": name,
        "file": name,
        "format": format,
        "bytes": bytes.len(),
        "uploaded": crate::runs::now(),
        "tests": tests,
    });
    std::fs::create_dir_all(&dir).map_err(ApiError::io)?;
    let result = (|| {
        indentify_study::atomic::write(&dir.join(&name), bytes)?;
        indentify_study::atomic::write(&meta, serde_json::to_vec(&info)?)
    })();
    if let Err(e) = result {
        let _ = std::fs::remove_dir_all(&dir);
        return Err(ApiError::internal(e));
    }
    Ok(info)
}

/// `record.json` of record `id`.
///
/// # Errors
/// An invalid or unknown id (404).
pub fn load(ws: &Workspace, id: &str) -> Result<Value, ApiError> {
    let dir = ws
        .record_dir(id)
        .ok_or_else(|| ApiError::not_found(format!("no record `{id}` (ids are 16 hex digits)")))?;
    let bytes = std::fs::read(dir.join("record.json"))
        .map_err(|_| ApiError::not_found(format!("no record `{id}` in this workspace")))?;
    serde_json::from_slice(&bytes).map_err(ApiError::internal)
}

/// The stored file of record `id`, relative to `base` (a run folder two levels below the
/// workspace root: `../../records/<id>/<name>`), and its absolute path.
///
/// # Errors
/// As [`load`].
pub fn file_of(ws: &Workspace, id: &str) -> Result<(String, std::path::PathBuf), ApiError> {
    let v = load(ws, id)?;
    let name = v["file"].as_str().unwrap_or_default();
    let safe = sanitize_name(name);
    let path = ws.records().join(id).join(&safe);
    if safe != name || !path.is_file() {
        return Err(ApiError::not_found(format!("record `{id}` has no file")));
    }
    Ok((format!("../../records/{id}/{safe}"), path))
}

/// Every stored record's summary (id, name, format, tests' names), newest first.
pub fn list(ws: &Workspace) -> Vec<Value> {
    let mut out: Vec<Value> = std::fs::read_dir(ws.records())
        .into_iter()
        .flatten()
        .flatten()
        .filter_map(|e| {
            let id = e.file_name().to_string_lossy().into_owned();
            let v = load(ws, &id).ok()?;
            let tests: Vec<Value> = v["tests"]
                .as_array()
                .map(|t| {
                    t.iter()
                        .map(|t| serde_json::json!({"index": t["index"], "name": t["name"]}))
                        .collect()
                })
                .unwrap_or_default();
            Some(serde_json::json!({
                "id": v["id"], "name": v["name"], "format": v["format"], "bytes": v["bytes"],
                "uploaded": v["uploaded"], "tests": tests,
            }))
        })
        .collect();
    out.sort_by(|a, b| {
        b["uploaded"]
            .as_f64()
            .partial_cmp(&a["uploaded"].as_f64())
            .unwrap_or(std::cmp::Ordering::Equal)
    });
    out
}
