//! The commands beyond identify and simulate, over a real loopback socket: `analyze`
//! (compared with the study pipeline called directly, as the CLI calls it), joint fits of
//! tests of a multi-test record, `batch` with its indents published as they finish,
//! `design` and `map`; and what each refuses (4xx with the CLI's kind of message,
//! nothing written).

mod common;

use common::*;
use serde_json::{Value, json};

const BERKOVICH: &str = "examples/data/anton-paar-unht-berkovich/anonNI.TXT";
const MULTI: &str = "examples/data/anton-paar-sphere-creep/HT_V_100mN.TXT";

fn upload(addr: std::net::SocketAddr, rel: &str) -> String {
    let bytes = std::fs::read(repo().join(rel)).unwrap();
    let name = rel.rsplit('/').next().unwrap();
    let r = post(addr, &format!("/api/records?name={name}"), &bytes);
    assert_eq!(r.status, 201, "{}", r.text());
    r.json()["id"].as_str().unwrap().to_string()
}

fn run_id(r: &Resp) -> String {
    assert_eq!(r.status, 202, "{}", r.text());
    r.json()["id"].as_str().unwrap().to_string()
}

/// A refused request: its status, a message containing `what`, and no new run folder.
fn refused(s: &Served, req: Value, status: u16, what: &str) {
    let runs = s.dir.path().join("ws/runs");
    // the run folders (a finished run's last status.json may still be landing inside its own)
    let folders = || {
        let mut v: Vec<String> = std::fs::read_dir(&runs)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    };
    let before = folders();
    let r = submit(s.addr, req.clone());
    assert_eq!(r.status, status, "{req}: {}", r.text());
    let msg = r.json()["messages"].to_string();
    assert!(msg.contains(what), "{req}: `{what}` not in {msg}");
    assert_eq!(folders(), before, "{req} wrote a run folder");
}

/// A small, fast fit of a record: 20 resampled points, one sub-step, `iters` iterations.
fn small(iters: usize) -> Value {
    json!([
        "data.preprocessing.resample.n=20",
        "data.substeps=1",
        format!("identify.stop.max_iterations={iters}")
    ])
}

#[test]
fn analyze_gives_the_pipelines_oliver_pharr_values() {
    let s = serve(|_| {});
    let rid = upload(s.addr, BERKOVICH);
    let id = run_id(&submit(
        s.addr,
        json!({"command": "analyze", "record": rid, "tip": "berkovich", "nu": 0.25}),
    ));
    let v = wait(s.addr, &id);
    assert_eq!(v["status"], "done", "{v}");
    assert!(
        v["cli"]
            .as_str()
            .unwrap()
            .starts_with("indentify analyze ../../records/")
    );
    // the same analysis called directly (as `indentify analyze FILE --nu 0.25` does)
    let mut opts = indentify_study::analyze::AnalyzeOptions::new(repo().join(BERKOVICH));
    opts.nu = 0.25;
    let direct = indentify_study::analyze::run(&opts).unwrap();
    let served = v["result"]["tests"].as_array().unwrap();
    assert_eq!(served.len(), direct.tests.len());
    for (a, b) in served.iter().zip(&direct.tests) {
        let e = b.values.e.expect("the direct analysis gives E");
        assert!(e > 0.0);
        assert_eq!(a["E"].as_f64().unwrap(), e, "{a}");
        assert_eq!(a["H"].as_f64(), b.values.h);
    }
    let files: Vec<&str> = v["files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["name"].as_str().unwrap())
        .collect();
    assert!(files.contains(&"analysis.json") && files.contains(&"analysis.csv"));
    // refused: no record, an unknown tip, nu out of range, a configuration
    refused(
        &s,
        json!({"command": "analyze"}),
        400,
        "analyze needs a record",
    );
    refused(
        &s,
        json!({"command": "analyze", "record": rid, "tip": "pyramid"}),
        400,
        "expected berkovich, cone:HALF_ANGLE_DEG",
    );
    refused(
        &s,
        json!({"command": "analyze", "record": rid, "nu": 0.7}),
        400,
        "[0, 0.5)",
    );
    refused(
        &s,
        json!({"command": "analyze", "record": rid, "sets": ["law.E=1"]}),
        400,
        "takes no configuration",
    );
    // a finished analysis cannot be cancelled; a running one answers why not
    let r = request(
        s.addr,
        "DELETE",
        &format!("/api/runs/{id}"),
        &[("X-Indentify", "1")],
        b"",
    );
    assert_eq!(r.status, 409);
}

#[test]
fn a_joint_fit_of_picked_tests_of_a_record() {
    let s = serve(|_| {});
    let rid = upload(s.addr, MULTI);
    let id = run_id(&submit(
        s.addr,
        json!({"command": "identify", "record": rid, "no_refine": true,
               "tests": [{"test": 1}, {"test": 3, "weight": 2.5}], "sets": small(1)}),
    ));
    let v = wait(s.addr, &id);
    assert_eq!(v["status"], "done", "{v}");
    // config.ron is a joint configuration of tests 1 and 3 of the record, the CLI's input
    let dir = s.dir.path().join("ws/runs").join(&id);
    let cfg = indentify_study::ConfigSource::Path(dir.join("config.ron"))
        .load(&[])
        .unwrap();
    let tests = cfg.tests.as_ref().expect("a joint configuration");
    assert_eq!(tests.len(), 2);
    let picked: Vec<Option<usize>> = tests
        .iter()
        .map(|t| t.data.as_ref().unwrap().test)
        .collect();
    assert_eq!(picked, [Some(1), Some(3)]);
    assert_eq!(tests[0].weight, None);
    assert_eq!(tests[1].weight, Some(2.5));
    assert!(tests.iter().all(|t| {
        let d = t.data.as_ref().unwrap();
        d.file.starts_with("../../records/") && d.substeps == 1
    }));
    assert!(v["result"]["J"].as_f64().unwrap().is_finite());
    // a page per test, as the CLI writes for a joint fit
    let files = v["files"].to_string();
    assert!(
        files.contains("test-1/") && files.contains("test-2/"),
        "{files}"
    );
    // refused: a test the record does not hold, twice the same, a bad weight, simulate
    for (tests, what) in [
        (json!([{"test": 1}, {"test": 9}]), "is not a test of record"),
        (json!([{"test": 2}, {"test": 2}]), "picked twice"),
        (
            json!([{"test": 1}, {"test": 2, "weight": -1}]),
            "expected a number > 0",
        ),
    ] {
        refused(
            &s,
            json!({"command": "identify", "record": rid, "tests": tests}),
            400,
            what,
        );
    }
    refused(
        &s,
        json!({"command": "simulate", "record": rid, "tests": [{"test": 1}, {"test": 2}]}),
        400,
        "for identify and map",
    );
}

#[test]
fn a_batch_publishes_each_indent_as_it_finishes() {
    let s = serve(|_| {});
    let rid = upload(s.addr, MULTI);
    let id = run_id(&submit(
        s.addr,
        json!({"command": "batch", "record": rid, "sets": small(1)}),
    ));
    let evs = events(s.addr, &id);
    let last = evs.last().unwrap();
    assert_eq!(last["status"], "done", "{last}");
    // the map fills in: an event with some indents finished and others still pending
    let partial = evs.iter().any(|e| {
        let ind = e["progress"]["indents"].as_array();
        ind.is_some_and(|i| {
            i.iter().any(|x| x["state"] == "pending") && i.iter().any(|x| x["state"] != "pending")
        })
    });
    assert!(partial, "no event showed a partly filled map");
    let ind = last["progress"]["indents"].as_array().unwrap();
    assert_eq!(ind.len(), 4);
    for (k, i) in ind.iter().enumerate() {
        assert_eq!(i["id"], format!("test-{}", k + 1));
        assert!(
            matches!(i["state"].as_str(), Some("converged" | "not_converged")),
            "{i}"
        );
        assert_eq!(i["names"][0], "E");
        // each indent one request away
        let r = get(
            s.addr,
            &format!("/api/runs/{id}/files/indents/test-{}/result.json", k + 1),
        );
        assert_eq!(r.status, 200);
        assert_eq!(
            r.json()["parameters"][0]["value"].as_f64(),
            i["values"][0].as_f64()
        );
    }
    let v = get(s.addr, &format!("/api/runs/{id}")).json();
    assert_eq!(
        v["result"]["ids"].as_array().unwrap().len(),
        4,
        "batch.json"
    );
    let results = get(s.addr, &format!("/api/runs/{id}/files/results.csv"));
    assert_eq!(results.status, 200);
    assert_eq!(results.text().lines().count(), 5, "{}", results.text());

    // a manifest: two indents, placed, the data named by record id
    let m = "id,data,test,x,y\na1,,1,0,0\nb2,RID,4,0.05,0\n".replace("RID", &rid);
    let id = run_id(&submit(
        s.addr,
        json!({"command": "batch", "record": rid, "manifest": m, "sets": small(1)}),
    ));
    let v = wait(s.addr, &id);
    assert_eq!(v["status"], "done", "{v}");
    let ind = v["progress"]["indents"].as_array().unwrap();
    assert_eq!(ind.len(), 2);
    assert_eq!(ind[1]["x"].as_f64(), Some(0.05));
    // refused manifests: a config column, an unknown record, an id study refuses
    for (m, what) in [
        ("id,config\na,x.ron\n".to_string(), "`config` column"),
        (
            "id,data\na,0123456789abcdef\n".to_string(),
            "is not a record",
        ),
        ("id,test\na b,1\n".to_string(), "is not allowed"),
        // no path from a manifest reaches the filesystem: `data` names records by id
        (
            "id,data\na,../../../../etc/passwd\n".to_string(),
            "is not a record",
        ),
    ] {
        refused(
            &s,
            json!({"command": "batch", "record": rid, "manifest": m}),
            400,
            what,
        );
    }
    refused(&s, json!({"command": "batch"}), 400, "batch needs a record");
}

#[test]
fn design_ranks_its_candidates_and_map_computes_a_cost_map() {
    let s = serve(|o| o.workers = 2);
    // the design template (examples/r2-design.ron) on a coarse mesh
    let t = get(s.addr, "/api/templates/design");
    assert_eq!(t.status, 200);
    assert!(t.text().contains("design:"));
    let design = run_id(&submit(
        s.addr,
        json!({"command": "design", "sets": ["specimen.nr=6", "specimen.nz=6"]}),
    ));
    // R1 (the default) mapped over E and eta, 3 x 3, through its law values
    let map = run_id(&submit(
        s.addr,
        json!({"command": "map", "pair": ["E", "eta"], "grid": 3, "through": "law"}),
    ));
    let v = wait(s.addr, &design);
    assert_eq!(v["status"], "done", "{v}");
    let n = v["result"]["candidates"].as_array().unwrap().len();
    assert!(n >= 3);
    let mut rank: Vec<u64> = v["result"]["rank_d"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_u64().unwrap())
        .collect();
    rank.sort_unstable();
    assert_eq!(rank, (0..n as u64).collect::<Vec<_>>());
    let v = wait(s.addr, &map);
    assert_eq!(v["status"], "done", "{v}");
    let j = v["result"]["J"].as_array().unwrap();
    assert_eq!(j.len(), 9);
    // through the law values (synthesized data without noise): J = 0 at the centre
    assert!(
        v["result"]["J"][4].as_f64().unwrap() <= 1e-20,
        "{}",
        v["result"]
    );
    assert!(j.iter().all(|x| x.as_f64().unwrap() >= 0.0));
    assert!(v["cli"].as_str().unwrap().contains("--pair E,eta --grid 3"));
    // refused
    refused(
        &s,
        json!({"command": "design", "config": indentify_study::DEFAULT_CONFIG}),
        400,
        "no `design` section",
    );
    refused(
        &s,
        json!({"command": "map", "pair": ["E"]}),
        400,
        "map needs `pair`",
    );
    refused(
        &s,
        json!({"command": "map", "pair": ["E", "eta"], "grid": 99}),
        400,
        "3 to 41",
    );
    refused(
        &s,
        json!({"command": "map", "pair": ["E", "eta"], "through": "middle"}),
        400,
        "expected fit, law or start",
    );
}

#[test]
fn profiles_of_a_fit_are_in_its_result() {
    let s = serve(|_| {});
    let rid = upload(s.addr, BERKOVICH);
    // the elastic law on the record: one free parameter (E), so its profile is a row of
    // forward solves at fixed E
    let t = get(s.addr, &format!("/api/templates/elastic?record={rid}"));
    assert_eq!(t.status, 200);
    let id = run_id(&submit(
        s.addr,
        json!({"command": "identify", "config": t.text(), "no_refine": true, "profiles": true,
               "sets": small(20)}),
    ));
    let v = wait(s.addr, &id);
    assert_eq!(v["status"], "done", "{v}");
    assert!(v["cli"].as_str().unwrap().ends_with("--profiles"));
    let p = &v["result"]["profiles"][0];
    assert_eq!(p["name"], "E", "{}", v["result"]);
    let j = v["result"]["J"].as_f64().unwrap();
    assert_eq!(p["J"].as_f64(), Some(j));
    assert!(p["threshold"].as_f64().unwrap() > 0.0);
    let pts = p["points"].as_array().unwrap();
    assert!(pts.len() >= 3, "{p}");
    // J along the profile is never below the optimum's (to the fit's tolerance), and
    // the optimum is among the points
    for q in pts {
        assert!(q[1].as_f64().unwrap() >= j * (1.0 - 1e-6), "{q} below {j}");
    }
    let e = p["value"].as_f64().unwrap();
    assert!(pts.iter().any(|q| q[0].as_f64() == Some(e)));
}

#[test]
fn a_running_batch_can_be_cancelled_and_keeps_what_finished() {
    let s = serve(|_| {});
    let rid = upload(s.addr, MULTI);
    let id = run_id(&submit(
        s.addr,
        json!({"command": "batch", "record": rid, "sets": small(30)}),
    ));
    for _ in 0..2000 {
        if get(s.addr, &format!("/api/runs/{id}")).json()["status"] == "running" {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    let r = request(
        s.addr,
        "DELETE",
        &format!("/api/runs/{id}"),
        &[("X-Indentify", "1")],
        b"",
    );
    assert_eq!(r.status, 200, "{}", r.text());
    assert!(
        r.json()["message"]
            .as_str()
            .unwrap()
            .contains("cancel asked")
    );
    let v = wait(s.addr, &id);
    assert_eq!(v["status"], "cancelled", "{v}");
    assert!(
        v["message"].as_str().unwrap().contains("indents finished"),
        "{v}"
    );
    // an indent that finished has its files, one never started has none; one the cancel
    // interrupted may have stopped before or after writing its status (a race the batch
    // reports as `interrupted` either way)
    for i in v["progress"]["indents"].as_array().unwrap() {
        let path = format!(
            "/api/runs/{id}/files/indents/{}/status.json",
            i["id"].as_str().unwrap()
        );
        let has = get(s.addr, &path).status == 200;
        match i["state"].as_str().unwrap() {
            "pending" => assert!(!has, "{i}"),
            "interrupted" => {}
            _ => assert!(has, "{i}"),
        }
    }
}
