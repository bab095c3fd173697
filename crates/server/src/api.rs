//! The HTTP API (docs/web.md): routes, handlers, errors as JSON, and the guards that every
//! request passes (token, Host and Origin checks, a custom header on state-changing requests).

use std::sync::Arc;

use axum::Router;
use axum::body::{Body, Bytes};
use axum::extract::{DefaultBodyLimit, Path, Query, Request, State};
use axum::http::{HeaderMap, HeaderValue, Method, StatusCode, header};
use axum::middleware::{self, Next};
use axum::response::sse::{Event, KeepAlive, Sse};
use axum::response::{IntoResponse, Response};
use axum::routing::get;
use indentify_study::config::Reference;
use serde::Deserialize;
use serde_json::{Value, json};

use crate::records;
use crate::runs::{RunRequest, Runs};
use crate::workspace::safe_relative;

/// An error answered as `{"error": first message, "kind", "messages": [...]}`.
#[derive(Debug)]
pub struct ApiError {
    status: StatusCode,
    kind: String,
    messages: Vec<String>,
}

impl ApiError {
    /// An error with `status`, `kind` and the message chain.
    pub fn new(status: StatusCode, kind: &str, messages: Vec<String>) -> ApiError {
        ApiError {
            status,
            kind: kind.to_string(),
            messages,
        }
    }

    /// 400.
    pub fn bad_request(kind: &str, messages: Vec<String>) -> ApiError {
        ApiError::new(StatusCode::BAD_REQUEST, kind, messages)
    }

    /// 404.
    pub fn not_found(msg: String) -> ApiError {
        ApiError::new(StatusCode::NOT_FOUND, "not_found", vec![msg])
    }

    /// 500 (a file the server could not write).
    pub fn io(e: std::io::Error) -> ApiError {
        ApiError::new(StatusCode::INTERNAL_SERVER_ERROR, "io", vec![e.to_string()])
    }

    /// 500.
    pub fn internal(e: impl std::fmt::Display) -> ApiError {
        ApiError::new(
            StatusCode::INTERNAL_SERVER_ERROR,
            "internal",
            vec![format!("{e:#}")],
        )
    }

    /// A study error as the CLI prints it; input errors (configuration, data) are a 400.
    pub fn study(e: &indentify_study::Error) -> ApiError {
        use indentify_study::ErrorKind as K;
        let status = match e.kind() {
            K::Config | K::Data => StatusCode::BAD_REQUEST,
            K::Solver => StatusCode::UNPROCESSABLE_ENTITY,
            K::Io => StatusCode::INTERNAL_SERVER_ERROR,
        };
        ApiError::new(status, e.kind().name(), e.messages())
    }

    /// The status code.
    pub fn status(&self) -> StatusCode {
        self.status
    }
}

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
        let body = json!({
            "error": self.messages.first().cloned().unwrap_or_default(),
            "kind": self.kind,
            "messages": self.messages,
        });
        (self.status, axum::Json(body)).into_response()
    }
}

/// What the handlers share.
pub struct AppState {
    /// The runs and the workspace.
    pub runs: Arc<Runs>,
    /// The token every request must carry (set when listening beyond loopback).
    pub token: Option<String>,
    /// Whether the server listens on loopback only (then the Host header must name it).
    pub loopback: bool,
    /// Largest upload (bytes).
    pub max_upload: usize,
}

type Shared = State<Arc<AppState>>;

/// The application: the page and the API under the guards.
pub fn router(state: Arc<AppState>) -> Router {
    let api = Router::new()
        .route("/api/health", get(health))
        .route("/api/laws", get(laws))
        .route("/api/templates/{law}", get(template))
        .route("/api/records", get(list_records).post(upload))
        .route("/api/records/{id}", get(get_record))
        .route("/api/tips", get(list_tips).post(upload_tip))
        .route("/api/runs", get(list_runs).post(submit))
        .route("/api/runs/{id}", get(get_run).delete(cancel))
        .route("/api/runs/{id}/events", get(events))
        .route("/api/runs/{id}/files", get(list_files))
        .route("/api/runs/{id}/files/{*path}", get(get_file))
        .layer(DefaultBodyLimit::max(state.max_upload));
    Router::new()
        .route("/", get(crate::page::index))
        .route("/app.js", get(crate::page::script))
        .route("/style.css", get(crate::page::style))
        .merge(api)
        .fallback(|| async { ApiError::not_found("no such page or API route".into()) })
        .layer(middleware::from_fn_with_state(Arc::clone(&state), guard))
        .with_state(state)
}

/// The header a state-changing request must carry (a cross-site form cannot set it, and a
/// cross-site script cannot without a CORS preflight, which this server never grants).
pub const CSRF_HEADER: &str = "x-indentify";

/// The token's cookie, set when the page is opened with `?token=`.
const TOKEN_COOKIE: &str = "indentify_token";

fn header_str(h: &HeaderMap, name: impl header::AsHeaderName) -> Option<&str> {
    h.get(name).and_then(|v| v.to_str().ok())
}

/// The host part of `host[:port]` (IPv6 in brackets kept).
fn host_name(hostport: &str) -> &str {
    if hostport.starts_with('[') {
        return hostport.split(']').next().map_or(hostport, |h| &h[1..]);
    }
    hostport.split(':').next().unwrap_or(hostport)
}

fn forbidden(msg: &str) -> Response {
    ApiError::new(StatusCode::FORBIDDEN, "forbidden", vec![msg.to_string()]).into_response()
}

/// Token, Host and Origin checks; state-changing requests need [`CSRF_HEADER`].
async fn guard(State(st): Shared, req: Request, next: Next) -> Response {
    let h = req.headers();
    let host = header_str(h, header::HOST).unwrap_or("");
    if st.loopback && !matches!(host_name(host), "127.0.0.1" | "localhost" | "::1") {
        // DNS rebinding: a page of another site resolved to 127.0.0.1
        return forbidden(
            "this server answers only requests addressed to 127.0.0.1 or localhost (Host header)",
        );
    }
    let mut set_cookie = None;
    if let Some(token) = &st.token {
        let query_token = req.uri().query().and_then(|q| {
            q.split('&')
                .find_map(|kv| kv.strip_prefix("token="))
                .map(String::from)
        });
        let bearer = header_str(h, header::AUTHORIZATION)
            .and_then(|v| v.strip_prefix("Bearer "))
            .map(String::from);
        let cookie = header_str(h, header::COOKIE).and_then(|c| {
            c.split(';')
                .find_map(|kv| kv.trim().strip_prefix("indentify_token="))
                .map(String::from)
        });
        let given = [&query_token, &bearer, &cookie];
        if !given
            .iter()
            .any(|g| g.as_deref().is_some_and(|g| eq_const(g, token)))
        {
            return ApiError::new(
                StatusCode::UNAUTHORIZED,
                "unauthorized",
                vec![
                    "a token is required: open the URL the server printed (…/?token=…) or send \
                     `Authorization: Bearer TOKEN`"
                        .into(),
                ],
            )
            .into_response();
        }
        if query_token.is_some() && cookie.is_none() {
            set_cookie = Some(format!(
                "{TOKEN_COOKIE}={token}; HttpOnly; SameSite=Strict; Path=/"
            ));
        }
    }
    let changes = !matches!(*req.method(), Method::GET | Method::HEAD | Method::OPTIONS);
    if changes {
        if h.get(CSRF_HEADER).is_none() {
            return forbidden(
                "state-changing requests need the header `X-Indentify: 1` (protection against \
                 cross-site requests)",
            );
        }
        if let Some(origin) = header_str(h, header::ORIGIN) {
            let origin_host = origin.split("://").nth(1).unwrap_or("");
            if origin_host != host {
                return forbidden("the request's Origin is not this server: refused");
            }
        }
    }
    let mut resp = next.run(req).await;
    let hs = resp.headers_mut();
    hs.insert(
        "x-content-type-options",
        HeaderValue::from_static("nosniff"),
    );
    hs.insert("x-frame-options", HeaderValue::from_static("DENY"));
    if !hs.contains_key("content-security-policy") {
        hs.insert(
            "content-security-policy",
            HeaderValue::from_static(
                "default-src 'self'; img-src 'self' data:; style-src 'self'; script-src 'self'; \
             frame-ancestors 'none'",
            ),
        );
    }
    if let Some(c) = set_cookie.and_then(|c| HeaderValue::from_str(&c).ok()) {
        hs.insert(header::SET_COOKIE, c);
    }
    resp
}

/// Compares without stopping at the first difference.
fn eq_const(a: &str, b: &str) -> bool {
    a.len() == b.len()
        && a.bytes()
            .zip(b.bytes())
            .fold(0u8, |acc, (x, y)| acc | (x ^ y))
            == 0
}

async fn blocking<T: Send + 'static>(
    f: impl FnOnce() -> Result<T, ApiError> + Send + 'static,
) -> Result<T, ApiError> {
    tokio::task::spawn_blocking(f)
        .await
        .map_err(ApiError::internal)?
}

async fn health(State(st): Shared) -> axum::Json<Value> {
    axum::Json(json!({
        "status": "ok",
        "version": env!("CARGO_PKG_VERSION"),
        "workspace": st.runs.workspace().root(),
        "queued": st.runs.queued(),
        "max_upload": st.max_upload,
        "commands": crate::runs::COMMANDS,
    }))
}

/// Every law with its parameters, units and admissible ranges.
async fn laws() -> axum::Json<Value> {
    let laws: Vec<Value> = ["elastic", "maxwell", "norton-hoff"]
        .iter()
        .filter_map(|n| indentify_study::law_by_name(n).map(|l| (n, l)))
        .map(|(n, l)| {
            let params: Vec<Value> = l
                .params()
                .iter()
                .map(|p| {
                    json!({"name": p.name, "unit": p.unit, "description": p.description,
                           "range": p.range_text()})
                })
                .collect();
            json!({"name": n, "params": params})
        })
        .collect();
    axum::Json(json!({ "laws": laws }))
}

fn reference(law: &str) -> Result<Reference, ApiError> {
    match law {
        "elastic" => Ok(Reference::R0Elastic),
        "maxwell" => Ok(Reference::R1Maxwell),
        "norton-hoff" => Ok(Reference::R2NortonHoff),
        _ => Err(ApiError::bad_request(
            "config",
            vec![format!(
                "unknown law `{law}`: expected elastic, maxwell or norton-hoff"
            )],
        )),
    }
}

/// The `init --data` template of a stored record (`rel`: its path from a run folder).
///
/// # Errors
/// An unreadable record file (500) or a malformed tip (400).
pub fn record_template(
    r: Reference,
    rel: &str,
    info: &Value,
    test: Option<usize>,
    tip: Option<&str>,
) -> Result<String, ApiError> {
    let tests: Vec<String> = info["tests"]
        .as_array()
        .map(|t| {
            t.iter()
                .map(|t| t["name"].as_str().unwrap_or("").to_string())
                .collect()
        })
        .unwrap_or_default();
    let k = test.unwrap_or(1);
    let stated = info["tests"][k.saturating_sub(1)]["tip"].as_str();
    let radius = info["tests"][k.saturating_sub(1)]["tip_radius"].as_f64();
    let (punch, punch_source) = match (tip, stated) {
        (Some(t), _) => {
            let p = indentify_study::templates::parse_tip(t)
                .map_err(|e| ApiError::bad_request("config", vec![format!("tip: {e:#}")]))?;
            let d = p.describe();
            (p, format!("{d} (tip {t})"))
        }
        (None, Some(s)) => {
            match indentify_study::templates::tip_from_metadata(&indentify_study::records::Meta {
                tip: Some(s.to_string()),
                tip_radius: radius,
                ..Default::default()
            }) {
                Some(p) => {
                    let d = p.describe();
                    (p, format!("{d}, as the file states"))
                }
                None => berkovich(),
            }
        }
        (None, None) => berkovich(),
    };
    let d = indentify_study::templates::DataTemplate {
        file: rel.to_string(),
        test: (tests.len() > 1).then_some(k),
        tests: if tests.len() > 1 { tests } else { Vec::new() },
        punch,
        punch_source,
    };
    Ok(indentify_study::templates::data_template(r, &d))
}

fn berkovich() -> (indentify_study::Punch, String) {
    (
        indentify_study::Punch::Berkovich { tip_radius: None },
        "Berkovich, assumed: the file does not state its tip (choose a tip, or edit `punch`)"
            .to_string(),
    )
}

#[derive(Deserialize)]
struct TemplateQuery {
    record: Option<String>,
    test: Option<usize>,
    tip: Option<String>,
}

async fn template(
    State(st): Shared,
    Path(law): Path<String>,
    Query(q): Query<TemplateQuery>,
) -> Result<Response, ApiError> {
    if law == "design" {
        // the candidates to rank: examples/r2-design.ron
        return Ok((
            [(header::CONTENT_TYPE, "text/plain; charset=utf-8")],
            crate::jobs::DESIGN_TEMPLATE,
        )
            .into_response());
    }
    let r = reference(&law)?;
    let text = match &q.record {
        None => indentify_study::templates::template(r),
        Some(id) => {
            let ws = st.runs.workspace();
            let info = records::load(ws, id)?;
            let n = info["tests"].as_array().map_or(0, Vec::len);
            if let Some(k) = q.test {
                if k == 0 || k > n {
                    return Err(ApiError::bad_request(
                        "data",
                        vec![format!(
                            "test {k} is not a test of record `{id}` (1 to {n})"
                        )],
                    ));
                }
            }
            let (rel, _) = records::file_of(ws, id)?;
            record_template(r, &rel, &info, q.test, q.tip.as_deref())?
        }
    };
    Ok(([(header::CONTENT_TYPE, "text/plain; charset=utf-8")], text).into_response())
}

async fn list_records(State(st): Shared) -> Result<axum::Json<Value>, ApiError> {
    let runs = Arc::clone(&st.runs);
    let list = blocking(move || Ok(records::list(runs.workspace()))).await?;
    Ok(axum::Json(json!({ "records": list })))
}

async fn list_tips(State(st): Shared) -> Result<axum::Json<Value>, ApiError> {
    let runs = Arc::clone(&st.runs);
    let list = blocking(move || Ok(crate::tips::list(runs.workspace()))).await?;
    Ok(axum::Json(json!({ "tips": list })))
}

/// `POST /api/tips?name=TIP.ron`: a calibrated tip file (`indentify calibrate`'s RON).
async fn upload_tip(
    State(st): Shared,
    Query(q): Query<UploadQuery>,
    body: Result<Bytes, axum::extract::rejection::BytesRejection>,
) -> Result<(StatusCode, axum::Json<Value>), ApiError> {
    let body = body.map_err(|e| ApiError::new(e.status(), "data", vec![e.body_text()]))?;
    let name = q.name.unwrap_or_else(|| "tip.ron".into());
    let runs = Arc::clone(&st.runs);
    let info = blocking(move || crate::tips::store(runs.workspace(), &name, &body)).await?;
    Ok((StatusCode::CREATED, axum::Json(info)))
}

#[derive(Deserialize)]
struct UploadQuery {
    name: Option<String>,
}

async fn upload(
    State(st): Shared,
    Query(q): Query<UploadQuery>,
    body: Result<Bytes, axum::extract::rejection::BytesRejection>,
) -> Result<(StatusCode, axum::Json<Value>), ApiError> {
    let body = body.map_err(|e| {
        if e.status() == StatusCode::PAYLOAD_TOO_LARGE {
            ApiError::new(
                StatusCode::PAYLOAD_TOO_LARGE,
                "data",
                vec![format!(
                    "the upload is larger than the limit of {} bytes (serve --max-upload-mb): \
                     nothing was stored",
                    st.max_upload
                )],
            )
        } else {
            ApiError::bad_request("data", vec![e.body_text()])
        }
    })?;
    if body.is_empty() {
        return Err(ApiError::bad_request(
            "data",
            vec!["the upload is empty: send the file's bytes as the request body".into()],
        ));
    }
    let name = q.name.unwrap_or_else(|| "record.txt".into());
    let runs = Arc::clone(&st.runs);
    let info = blocking(move || records::store(runs.workspace(), &name, &body)).await?;
    Ok((StatusCode::CREATED, axum::Json(info)))
}

async fn get_record(
    State(st): Shared,
    Path(id): Path<String>,
) -> Result<axum::Json<Value>, ApiError> {
    let runs = Arc::clone(&st.runs);
    Ok(axum::Json(
        blocking(move || records::load(runs.workspace(), &id)).await?,
    ))
}

async fn list_runs(State(st): Shared) -> axum::Json<Value> {
    axum::Json(json!({ "runs": st.runs.list() }))
}

async fn submit(
    State(st): Shared,
    body: Result<axum::Json<RunRequest>, axum::extract::rejection::JsonRejection>,
) -> Result<(StatusCode, axum::Json<Value>), ApiError> {
    let axum::Json(req) = body.map_err(|e| {
        ApiError::bad_request(
            "config",
            vec![format!("malformed request: {}", e.body_text())],
        )
    })?;
    let runs = Arc::clone(&st.runs);
    let id = blocking(move || runs.submit(req)).await?;
    Ok((StatusCode::ACCEPTED, axum::Json(json!({ "id": id }))))
}

async fn get_run(State(st): Shared, Path(id): Path<String>) -> Result<axum::Json<Value>, ApiError> {
    let run = st.runs.get(&id)?;
    blocking(move || {
        let meta = run.meta();
        let result = std::fs::read(run.dir().join(crate::runs::result_file(&meta.command)))
            .ok()
            .and_then(|b| serde_json::from_slice::<Value>(&b).ok());
        let mut v = serde_json::to_value(&meta).map_err(ApiError::internal)?;
        v["result"] = result.unwrap_or(Value::Null);
        v["files"] = Value::Array(crate::runs::files(run.dir()));
        Ok(axum::Json(v))
    })
    .await
}

async fn cancel(State(st): Shared, Path(id): Path<String>) -> Result<axum::Json<Value>, ApiError> {
    let runs = Arc::clone(&st.runs);
    let meta = blocking(move || runs.cancel(&id)).await?;
    Ok(axum::Json(
        serde_json::to_value(meta).map_err(ApiError::internal)?,
    ))
}

/// Server-sent events: the run's status.json as JSON, at once and at every change; the
/// stream ends after the final status.
async fn events(State(st): Shared, Path(id): Path<String>) -> Result<Response, ApiError> {
    let run = st.runs.get(&id)?;
    let rx = run.subscribe();
    let first = serde_json::to_string(&run.meta()).unwrap_or_default();
    let state = (Some(first), rx, false, run);
    let stream = futures_util::stream::unfold(state, |(first, mut rx, done, run)| async move {
        if done {
            return None;
        }
        let text = match first {
            Some(t) => t,
            None => match rx.recv().await {
                Ok(t) => t.as_str().to_string(),
                Err(tokio::sync::broadcast::error::RecvError::Lagged(_)) => {
                    serde_json::to_string(&run.meta()).unwrap_or_default()
                }
                Err(tokio::sync::broadcast::error::RecvError::Closed) => return None,
            },
        };
        let is_final = serde_json::from_str::<Value>(&text)
            .ok()
            .and_then(|v| v["status"].as_str().map(String::from))
            .is_some_and(|s| matches!(s.as_str(), "done" | "failed" | "cancelled"));
        let ev = Event::default().event("status").data(text);
        Some((
            Ok::<_, std::convert::Infallible>(ev),
            (None, rx, is_final, run),
        ))
    });
    Ok(Sse::new(stream)
        .keep_alive(KeepAlive::default())
        .into_response())
}

async fn list_files(
    State(st): Shared,
    Path(id): Path<String>,
) -> Result<axum::Json<Value>, ApiError> {
    let run = st.runs.get(&id)?;
    Ok(axum::Json(
        json!({ "files": crate::runs::files(run.dir()) }),
    ))
}

fn content_type(name: &str) -> &'static str {
    let ext = name.rsplit('.').next().unwrap_or("").to_ascii_lowercase();
    match ext.as_str() {
        "json" => "application/json",
        "md" => "text/markdown; charset=utf-8",
        "csv" => "text/csv; charset=utf-8",
        "ron" | "txt" => "text/plain; charset=utf-8",
        "svg" => "image/svg+xml",
        "png" => "image/png",
        _ => "application/octet-stream",
    }
}

async fn get_file(
    State(st): Shared,
    Path((id, path)): Path<(String, String)>,
) -> Result<Response, ApiError> {
    let run = st.runs.get(&id)?;
    let rel = safe_relative(&path)
        .ok_or_else(|| ApiError::not_found(format!("no file `{path}` in run `{id}`")))?;
    let full = run.dir().join(&rel);
    let bytes = blocking(move || {
        // resolved, it must still be inside the run's folder
        let real = full
            .canonicalize()
            .map_err(|_| ApiError::not_found(format!("no file `{path}` in run `{id}`")))?;
        let dir = run.dir().canonicalize().map_err(ApiError::io)?;
        if !real.starts_with(&dir) || !real.is_file() {
            return Err(ApiError::not_found(format!(
                "no file `{path}` in run `{id}`"
            )));
        }
        std::fs::read(&real).map_err(ApiError::io)
    })
    .await?;
    let name = rel.to_string_lossy().into_owned();
    let ct = content_type(&name);
    let mut resp = Response::new(Body::from(bytes));
    resp.headers_mut()
        .insert(header::CONTENT_TYPE, HeaderValue::from_static(ct));
    if ct.starts_with("image/svg") {
        // a figure may be opened on its own: no scripts in it
        resp.headers_mut().insert(
            "content-security-policy",
            HeaderValue::from_static("default-src 'none'; style-src 'unsafe-inline'"),
        );
    }
    Ok(resp)
}
