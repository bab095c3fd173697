//! `DELETE /api/runs/{id}` on a running run of every command beyond identify and batch
//! (those are in api.rs and commands.rs): simulate, analyze, design, map and the profile
//! likelihoods of an identification, over a real loopback socket. Each ends `cancelled`
//! with a message saying what was kept (a simulation stops mid-forward, between steps); design and map write nothing. The latency from
//! the `DELETE` to the final status is printed (`--nocapture`) and not asserted: it is
//! measured, and its worst case stated, in docs/web.md.

mod common;

use std::time::{Duration, Instant};

use common::*;
use indentify_study::simulate::{self, SimulateOptions};
use indentify_study::{Cancel, ConfigSource};
use serde_json::{Value, json};

const BERKOVICH: &str = "examples/data/anton-paar-unht-berkovich/anonNI.TXT";
const KLA: &str = "examples/data/kla-fused-silica/FusedSilica.xlsx";

fn upload(addr: std::net::SocketAddr, rel: &str) -> String {
    let bytes = std::fs::read(repo().join(rel)).unwrap();
    let name = rel.rsplit('/').next().unwrap();
    let r = post(addr, &format!("/api/records?name={name}"), &bytes);
    assert_eq!(r.status, 201, "{}", r.text());
    r.json()["id"].as_str().unwrap().to_string()
}

fn start(s: &Served, req: Value) -> String {
    let r = submit(s.addr, req);
    assert_eq!(r.status, 202, "{}", r.text());
    r.json()["id"].as_str().unwrap().to_string()
}

/// Polls `id` until `ready` holds for its status (or it finished: `false`).
fn until(s: &Served, id: &str, ready: impl Fn(&Value) -> bool) -> bool {
    loop {
        let v = get(s.addr, &format!("/api/runs/{id}")).json();
        if ready(&v) {
            return true;
        }
        if matches!(v["status"].as_str(), Some("done" | "failed" | "cancelled")) {
            return false;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
}

fn delete(s: &Served, id: &str) -> Resp {
    request(
        s.addr,
        "DELETE",
        &format!("/api/runs/{id}"),
        &[("X-Indentify", "1")],
        b"",
    )
}

/// Cancels the running `id`: 200 with `cancel asked` and `stops` in the message, then the
/// run ends `cancelled`; returns its final status and the latency.
fn cancel_running(s: &Served, id: &str, stops: &str) -> (Value, Duration) {
    let t = Instant::now();
    let r = delete(s, id);
    assert_eq!(r.status, 200, "{}", r.text());
    let m = r.json()["message"].as_str().unwrap().to_string();
    // the run answers when it stops, or has stopped already (a fast stop point)
    assert!(
        (m.starts_with("cancel asked") && m.contains(stops)) || m.starts_with("cancelled"),
        "{m}"
    );
    let v = wait(s.addr, id);
    let latency = t.elapsed();
    assert_eq!(v["status"], "cancelled", "{v}");
    assert!(v["error"].is_null(), "{v}");
    // a second DELETE: the run is finished, nothing to cancel
    let again = delete(s, id);
    assert_eq!(again.status, 409, "{}", again.text());
    assert!(
        again.text().contains("cancelled already"),
        "{}",
        again.text()
    );
    eprintln!(
        "{}: cancel -> cancelled in {:.3} s",
        v["command"],
        latency.as_secs_f64()
    );
    (v, latency)
}

fn files(v: &Value) -> Vec<String> {
    v["files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["name"].as_str().unwrap().to_string())
        .collect()
}

#[test]
fn a_running_simulation_stops_mid_forward_and_keeps_its_curve() {
    // not cancelled, the stoppable forward run gives the plain one's bits (R1)
    let opts = SimulateOptions::new(ConfigSource::Text {
        text: indentify_study::DEFAULT_CONFIG.to_string(),
        name: "r1.ron".into(),
    });
    let plain = simulate::run(&opts).unwrap();
    let stoppable = simulate::run_cancellable(&opts, &Cancel::default()).unwrap();
    let bits = |o: &simulate::SimulateOutcome| -> Vec<(u64, u64, u64)> {
        o.rows
            .iter()
            .map(|r| (r.t.to_bits(), r.h.to_bits(), r.f.to_bits()))
            .collect()
    };
    assert_eq!(bits(&plain), bits(&stoppable));
    // a stop asked before the first step: a stress-only law (R1's Maxwell, through its
    // fast law path) and a law with internal variables (a Prony series, through the
    // material path) both end at step 1 with the stop as the reason, nothing solved
    let raised = Cancel::default();
    raised.raise();
    let prony = std::fs::read_to_string(repo().join("examples/prony-sls.ron")).unwrap();
    for (text, name) in [
        (indentify_study::DEFAULT_CONFIG.to_string(), "r1.ron"),
        (prony, "prony-sls.ron"),
    ] {
        let o = simulate::run_cancellable(
            &SimulateOptions::new(ConfigSource::Text {
                text,
                name: name.into(),
            }),
            &raised,
        )
        .unwrap();
        let why = o.failure.as_deref().unwrap_or_default();
        assert!(
            why.contains("stopped on request during step 1"),
            "{name}: {why}"
        );
        assert_eq!(o.rows.len(), 1, "{name}: only the initial state");
    }
    // a longer forward run (R1 in 3 x 300 steps), cancelled while it runs
    let sets = json!([
        "history.segments.0.steps=300",
        "history.segments.1.steps=300",
        "history.segments.2.steps=300"
    ]);
    let s = serve(|_| {});
    let id = start(&s, json!({"command": "simulate", "sets": sets}));
    assert!(
        until(&s, &id, |v| v["status"] == "running"),
        "finished first"
    );
    std::thread::sleep(Duration::from_millis(300));
    let (v, latency) = cancel_running(&s, &id, "step in progress");
    let msg = v["message"].as_str().unwrap();
    assert!(
        msg.contains("stopped on request") && msg.contains("curve.csv"),
        "{msg}"
    );
    // it stopped mid-forward: fewer steps than the schedule's, the curve up to there kept
    let r = &v["result"];
    let (steps, all) = (
        r["steps"].as_u64().unwrap(),
        r["schedule_steps"].as_u64().unwrap(),
    );
    assert!(steps < all, "{r}");
    let f = files(&v);
    assert!(f.contains(&"curve.csv".to_string()), "{f:?}");
    let csv = get(s.addr, &format!("/api/runs/{id}/files/curve.csv")).text();
    assert_eq!(csv.lines().count() as u64, steps + 2, "header + rows");
    // the same run to its end, as the latency was before (the rest of the forward run)
    let t = Instant::now();
    let full = start(&s, json!({"command": "simulate", "sets": sets}));
    let done = wait(s.addr, &full);
    assert_eq!(done["status"], "done", "{done}");
    eprintln!(
        "simulate: cancelled after {steps} of {all} steps in {:.3} s; the whole run takes \
         {:.3} s",
        latency.as_secs_f64(),
        t.elapsed().as_secs_f64()
    );
}

#[test]
fn a_running_design_stops_after_its_candidates_in_progress() {
    let s = serve(|_| {});
    // examples/r2-design.ron (the default design)
    let id = start(&s, json!({"command": "design"}));
    assert!(
        until(&s, &id, |v| v["status"] == "running"),
        "finished first"
    );
    let (v, _) = cancel_running(&s, &id, "candidates in progress");
    assert!(
        v["message"].as_str().unwrap().contains("nothing written"),
        "{v}"
    );
    let f = files(&v);
    assert!(
        !f.contains(&"design.json".to_string()) && !f.contains(&"design.md".to_string()),
        "{f:?}"
    );
    assert!(v["result"].is_null(), "{v}");
}

#[test]
fn a_running_cost_map_stops_after_its_grid_points_in_progress() {
    let s = serve(|_| {});
    let rid = upload(s.addr, BERKOVICH);
    // 41 x 41 points through the law's values (no fit first): minutes in a debug build
    let id = start(
        &s,
        json!({"command": "map", "record": rid, "pair": ["E", "eta"], "grid": 41,
               "through": "law", "sets": ["data.preprocessing.resample.n=20", "data.substeps=1"]}),
    );
    assert!(
        until(&s, &id, |v| v["status"] == "running"
            && v["progress"]["stage"] == "mapping"),
        "finished first"
    );
    // let it be inside its grid
    std::thread::sleep(Duration::from_millis(500));
    let (v, _) = cancel_running(&s, &id, "grid points");
    assert!(
        v["message"].as_str().unwrap().contains("nothing written"),
        "{v}"
    );
    let f = files(&v);
    assert!(!f.iter().any(|n| n.starts_with("map.")), "{f:?}");
}

#[test]
fn an_identification_cancelled_in_its_profiles_keeps_the_fit_without_profiles() {
    let s = serve(|_| {});
    let rid = upload(s.addr, BERKOVICH);
    let id = start(
        &s,
        json!({"command": "identify", "record": rid, "max_iter": 1, "no_refine": true,
               "profiles": true,
               "sets": ["data.preprocessing.resample.n=20", "data.substeps=1"]}),
    );
    // the fit's one iteration is published: the profiles follow
    assert!(
        until(&s, &id, |v| v["progress"]["iteration"] == 1),
        "finished first"
    );
    let (v, _) = cancel_running(&s, &id, "profile");
    // the fit is kept (result.json, report.md) and has no profiles
    let f = files(&v);
    assert!(f.contains(&"result.json".to_string()), "{f:?}");
    assert!(
        v["result"]["profiles"].is_null(),
        "{}",
        v["result"]["profiles"]
    );
    assert!(v["message"].as_str().unwrap().contains("cancelled"), "{v}");
}

#[test]
fn a_running_analysis_ends_cancelled_after_its_pass() {
    let s = serve(|_| {});
    let rid = upload(s.addr, KLA);
    // an analysis takes ~0.1 s: submit until a DELETE lands while one runs
    let mut caught = None;
    for _ in 0..50 {
        let id = start(&s, json!({"command": "analyze", "record": rid}));
        if !until(&s, &id, |v| v["status"] == "running") {
            continue;
        }
        let r = delete(&s, &id);
        if r.status == 409 {
            // finished in between
            assert!(r.text().contains("already"), "{}", r.text());
            continue;
        }
        assert_eq!(r.status, 200, "{}", r.text());
        assert!(r.json()["message"].as_str().unwrap().contains("analysis"));
        caught = Some(wait(s.addr, &id));
        break;
    }
    let v = caught.expect("no DELETE landed while an analysis ran (50 tries)");
    assert_eq!(v["status"], "cancelled", "{v}");
    assert!(
        v["message"].as_str().unwrap().contains("tables are kept"),
        "{v}"
    );
    assert!(files(&v).contains(&"analysis.json".to_string()));
}
