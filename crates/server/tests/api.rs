//! The HTTP API over a real loopback socket: records, runs with progress events, results,
//! cancellation, restart, and bad input (malformed configurations with the CLI's messages,
//! garbage and oversized uploads, unknown ids, path traversal, cross-site requests).

mod common;

use common::*;
use indentify_study::ConfigSource;
use serde_json::json;

const RECORD: &str = "examples/data/anton-paar-unht-berkovich/anonNI.TXT";

fn upload(addr: std::net::SocketAddr) -> serde_json::Value {
    let bytes = std::fs::read(repo().join(RECORD)).unwrap();
    let r = post(addr, "/api/records?name=anonNI.TXT", &bytes);
    assert_eq!(r.status, 201, "{}", r.text());
    r.json()
}

#[test]
fn health_page_laws_and_templates() {
    let s = serve(|_| {});
    let h = get(s.addr, "/api/health").json();
    assert_eq!(h["status"], "ok");
    let page = get(s.addr, "/");
    assert_eq!(page.status, 200);
    assert!(page.text().contains("<script src=\"/app.js\""));
    assert!(
        page.header("content-security-policy")
            .unwrap()
            .contains("script-src 'self'")
    );
    assert!(get(s.addr, "/app.js").text().contains("EventSource"));
    let laws = get(s.addr, "/api/laws").json();
    let maxwell = &laws["laws"][1];
    assert_eq!(maxwell["name"], "maxwell");
    assert_eq!(maxwell["params"][2]["name"], "eta");
    // the templates are `indentify init`'s
    let t = get(s.addr, "/api/templates/norton-hoff").text();
    assert_eq!(
        t,
        indentify_study::templates::template(indentify_study::config::Reference::R2NortonHoff)
    );
    let bad = get(s.addr, "/api/templates/hooke");
    assert_eq!(bad.status, 400);
    assert!(
        bad.json()["error"]
            .as_str()
            .unwrap()
            .contains("elastic, maxwell or norton-hoff")
    );
    assert_eq!(get(s.addr, "/api/nothing").status, 404);
}

#[test]
fn a_record_is_read_by_every_reader_and_stored_once() {
    let s = serve(|_| {});
    let info = upload(s.addr);
    assert_eq!(info["format"], "AntonPaar");
    let t = &info["tests"][0];
    assert_eq!(t["points"], 1000);
    assert!((t["h_max"].as_f64().unwrap() - 2.1098e-3).abs() < 1e-6);
    assert_eq!(t["segments"].as_array().unwrap().len(), 5);
    assert!(
        t["preprocessing"]
            .as_array()
            .unwrap()
            .iter()
            .any(|p| p["step"] == "resample")
    );
    let id = info["id"].as_str().unwrap();
    // same bytes, same id, nothing rewritten
    assert_eq!(upload(s.addr)["id"], id);
    let listed = get(s.addr, "/api/records").json();
    assert_eq!(listed["records"].as_array().unwrap().len(), 1);
    assert_eq!(get(s.addr, &format!("/api/records/{id}")).json()["id"], id);
    // a multi-test file and the native Hysitron format
    let multi =
        std::fs::read(repo().join("examples/data/anton-paar-sphere-creep/HT_V_100mN.TXT")).unwrap();
    let m = post(s.addr, "/api/records?name=HT_V_100mN.TXT", &multi).json();
    assert_eq!(m["format"], "AntonPaarMulti");
    assert!(m["tests"].as_array().unwrap().len() > 1);
    let hld = std::fs::read(repo().join("examples/data/hysitron/Exp-50mN_0000.hld")).unwrap();
    assert_eq!(
        post(s.addr, "/api/records?name=Exp-50mN_0000.hld", &hld).json()["format"],
        "Hld"
    );
    // the template of a record names it relative to a run folder
    let t = get(s.addr, &format!("/api/templates/maxwell?record={id}")).text();
    assert!(
        t.contains(&format!("file: \"../../records/{id}/anonNI.TXT\"")),
        "{t}"
    );
}

#[test]
fn bad_uploads_are_refused_and_nothing_is_lost() {
    let s = serve(|o| o.max_upload = 64 * 1024);
    let id = upload(s.addr)["id"].as_str().unwrap().to_string();
    let ws = s.dir.path().join("ws");
    let before = tree(&ws);
    // binary garbage: the reader's message, as the CLI prints it
    let garbage: Vec<u8> = (0..5000u32).map(|i| (i * 7919 % 251) as u8).collect();
    let r = post(s.addr, "/api/records?name=garbage.bin", &garbage);
    assert_eq!(r.status, 400);
    let msgs = r.json()["messages"].clone();
    assert_eq!(msgs[0], "cannot read `garbage.bin` as an instrument record");
    assert!(
        msgs[1].as_str().unwrap().starts_with("garbage.bin"),
        "{msgs}"
    );
    // oversized
    let big = vec![b'1'; 65 * 1024];
    let r = post(s.addr, "/api/records?name=big.csv", &big);
    assert_eq!(r.status, 413, "{}", r.text());
    assert!(
        r.json()["error"]
            .as_str()
            .unwrap()
            .contains("limit of 65536 bytes")
    );
    // empty
    assert_eq!(post(s.addr, "/api/records?name=e.csv", b"").status, 400);
    // a name that climbs: stored under records/<id>/ with its last component only
    let csv = b"t,h,F\n0,0,0\n1,0.001,0.01\n2,0.002,0.03\n";
    let r = post(s.addr, "/api/records?name=..%2F..%2F..%2Fevil.csv", csv);
    assert_eq!(r.status, 201, "{}", r.text());
    let rid = r.json()["id"].as_str().unwrap().to_string();
    assert_eq!(r.json()["file"], "evil.csv");
    let mut after = tree(&ws);
    after.retain(|p| !p.contains(&rid));
    assert_eq!(after, before, "a refused upload wrote or removed something");
    assert!(!s.dir.path().join("evil.csv").exists());
    // unknown and malformed record ids
    assert_eq!(get(s.addr, "/api/records/0000000000000000").status, 404);
    assert_eq!(get(s.addr, "/api/records/..%2F..").status, 404);
    assert_eq!(get(s.addr, &format!("/api/records/{id}")).status, 200);
}

#[test]
fn malformed_requests_get_the_clis_messages() {
    let s = serve(|_| {});
    let cli = |text: &str, sets: &[&str]| {
        let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
        ConfigSource::Text {
            text: text.into(),
            name: "config.ron".into(),
        }
        .load(&sets)
        .unwrap_err()
        .messages()
    };
    let text = "(specimen: Cylinder(radius: 1.0))";
    let r = submit(s.addr, json!({"command": "simulate", "config": text}));
    assert_eq!(r.status, 400);
    assert_eq!(r.json()["kind"], "config");
    assert_eq!(r.json()["messages"], json!(cli(text, &[])));
    let r = submit(
        s.addr,
        json!({"command": "identify", "sets": {"law.E": "oops"}}),
    );
    assert_eq!(r.status, 400);
    assert_eq!(
        r.json()["messages"],
        json!(cli(indentify_study::DEFAULT_CONFIG, &["law.E=oops"]))
    );
    let r = submit(
        s.addr,
        json!({"command": "simulate", "sets": {"law.nu": 0.7}}),
    );
    assert_eq!(r.status, 400);
    assert_eq!(
        r.json()["messages"],
        json!(cli(indentify_study::DEFAULT_CONFIG, &["law.nu=0.7"]))
    );
    let r = submit(s.addr, json!({"command": "gradient"}));
    assert_eq!(r.status, 400);
    assert!(
        r.json()["error"]
            .as_str()
            .unwrap()
            .contains("identify, simulate, analyze, design, batch, map, calibrate")
    );
    let r = submit(s.addr, json!({"command": "simulate", "bogus": 1}));
    assert_eq!(r.status, 400);
    assert!(r.json()["error"].as_str().unwrap().contains("bogus"));
    let r = post(s.addr, "/api/runs", b"{not json");
    assert_eq!(r.status, 400);
    // a record that does not exist, a test out of range, a record with a history config
    let r = submit(
        s.addr,
        json!({"command": "simulate", "record": "0123456789abcdef"}),
    );
    assert_eq!(r.status, 404);
    let id = upload(s.addr)["id"].as_str().unwrap().to_string();
    let r = submit(
        s.addr,
        json!({"command": "simulate", "record": id, "test": 3}),
    );
    assert_eq!(r.status, 400);
    assert!(
        r.json()["error"]
            .as_str()
            .unwrap()
            .contains("test 3 is not a test")
    );
    let r = submit(
        s.addr,
        json!({"command": "simulate", "record": id, "config": indentify_study::DEFAULT_CONFIG}),
    );
    assert_eq!(r.status, 400);
    assert!(
        r.json()["error"]
            .as_str()
            .unwrap()
            .contains("no `data` section")
    );
    // nothing of these reached the workspace
    assert!(tree(&s.dir.path().join("ws/runs")).is_empty());
}

#[test]
fn no_request_reaches_a_file_outside_the_workspace() {
    let s = serve(|_| {});
    std::fs::write(
        s.dir.path().join("secret.txt"),
        "t,h,F\n0,0,0\n1,1e-3,1e-2\n",
    )
    .unwrap();
    let secret = s.dir.path().join("secret.txt").display().to_string();
    let id = upload(s.addr)["id"].as_str().unwrap().to_string();
    for file in [
        secret.as_str(),
        "../../../secret.txt",
        "../../records/../../secret.txt",
        "/etc/passwd",
        "../config.ron",
    ] {
        let r = submit(
            s.addr,
            json!({"command": "simulate", "record": id, "sets": [format!("data.file={file}")]}),
        );
        assert_eq!(r.status, 400, "{file}: {}", r.text());
        assert!(
            r.json()["error"]
                .as_str()
                .unwrap()
                .contains("is not a record of this workspace")
        );
    }
    // a joint configuration naming a file outside
    let joint = std::fs::read_to_string(repo().join("examples/real/ht-nh-joint.ron")).unwrap();
    let r = submit(s.addr, json!({"command": "identify", "config": joint}));
    assert_eq!(r.status, 400, "{}", r.text());
    // a simulate run to own a folder, then its files route
    let r = submit(s.addr, json!({"command": "simulate"}));
    let run = r.json()["id"].as_str().unwrap().to_string();
    wait(s.addr, &run);
    assert_eq!(
        get(s.addr, &format!("/api/runs/{run}/files/config.ron")).status,
        200
    );
    for path in [
        "../../../secret.txt",
        "..%2F..%2F..%2Fsecret.txt",
        "%2e%2e/%2e%2e/%2e%2e/secret.txt",
        ".status.json",
        "a/../../status.json",
        "..\\..\\secret.txt",
        "%2Fetc%2Fpasswd",
    ] {
        let r = get(s.addr, &format!("/api/runs/{run}/files/{path}"));
        assert!(
            r.status == 404 || r.status == 400,
            "{path}: {} {}",
            r.status,
            r.text()
        );
        assert!(!r.text().contains("1e-3"), "{path} leaked the file");
    }
    for bad in ["..", "..%2F..", "R1", "a.b"] {
        assert_eq!(
            get(s.addr, &format!("/api/runs/{bad}")).status,
            404,
            "{bad}"
        );
    }
}

#[test]
fn cross_site_and_foreign_host_requests_are_refused() {
    let s = serve(|_| {});
    let r = request(
        s.addr,
        "POST",
        "/api/runs",
        &[],
        b"{\"command\":\"simulate\"}",
    );
    assert_eq!(r.status, 403);
    let r = request(
        s.addr,
        "POST",
        "/api/runs",
        &[
            ("X-Indentify", "1"),
            ("Origin", "http://evil.example"),
            ("Content-Type", "application/json"),
        ],
        b"{\"command\":\"simulate\"}",
    );
    assert_eq!(r.status, 403);
    let r = request(
        s.addr,
        "GET",
        "/api/health",
        &[("Host", "evil.example:80")],
        b"",
    );
    assert_eq!(r.status, 403);
    let r = request(s.addr, "DELETE", "/api/runs/x", &[], b"");
    assert_eq!(r.status, 403);
    assert!(tree(&s.dir.path().join("ws/runs")).is_empty());
    // with a token: nothing without it, everything with it (header, query, cookie)
    let t = serve(|o| o.token = Some("0123456789abcdef0123".into()));
    assert_eq!(get(t.addr, "/api/health").status, 401);
    assert_eq!(get(t.addr, "/api/health?token=wrong").status, 401);
    let r = get(t.addr, "/?token=0123456789abcdef0123");
    assert_eq!(r.status, 200);
    assert!(r.header("set-cookie").unwrap().contains("HttpOnly"));
    let r = request(
        t.addr,
        "GET",
        "/api/health",
        &[("Authorization", "Bearer 0123456789abcdef0123")],
        b"",
    );
    assert_eq!(r.status, 200);
    let r = request(
        t.addr,
        "GET",
        "/api/runs",
        &[("Cookie", "indentify_token=0123456789abcdef0123")],
        b"",
    );
    assert_eq!(r.status, 200);
    // beyond loopback a token is drawn when none is given
    let mut o = indentify_server::ServeOptions::new(s.dir.path().join("ws2"));
    o.host = "0.0.0.0".parse().unwrap();
    o.port = 0;
    let server = indentify_server::bind(&o).unwrap();
    assert!(server.url.contains("?token="), "{}", server.url);
}

#[test]
fn a_simulation_writes_the_clis_files_and_survives_a_restart() {
    let s = serve(|_| {});
    let r = submit(
        s.addr,
        json!({"command": "simulate", "sets": {"law.E": 25000}}),
    );
    assert_eq!(r.status, 202, "{}", r.text());
    let id = r.json()["id"].as_str().unwrap().to_string();
    let v = wait(s.addr, &id);
    assert_eq!(v["status"], "done", "{v}");
    let dir = s.dir.path().join("ws/runs").join(&id);
    for f in ["config.ron", "curve.csv", "result.json", "status.json"] {
        assert!(dir.join(f).is_file(), "{f}");
    }
    // config.ron is the resolved configuration with the override written in: the CLI
    // simulates it to the same curve
    let cfg = indentify_study::config::load(&dir.join("config.ron"), &[]).unwrap();
    assert_eq!(cfg.law.named_params()[0], ("E", 25000.0));
    let o = indentify_study::simulate::run(&indentify_study::simulate::SimulateOptions::new(
        ConfigSource::Path(dir.join("config.ron")),
    ))
    .unwrap();
    let peak = o.rows.iter().map(|r| r.f).fold(f64::MIN, f64::max);
    assert_eq!(v["result"]["max_force"].as_f64().unwrap(), peak);
    let status: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("status.json")).unwrap()).unwrap();
    assert_eq!(status["status"], "done");
    // cancelling a finished run: a clear answer, nothing removed
    let before = tree(&dir);
    let r = request(
        s.addr,
        "DELETE",
        &format!("/api/runs/{id}"),
        &[("X-Indentify", "1")],
        b"",
    );
    assert_eq!(r.status, 409);
    assert!(r.json()["error"].as_str().unwrap().contains("done already"));
    assert_eq!(tree(&dir), before);
    assert_eq!(
        request(
            s.addr,
            "DELETE",
            "/api/runs/r1-0",
            &[("X-Indentify", "1")],
            b""
        )
        .status,
        404
    );
    // a new server on the same workspace lists the run
    let mut o = indentify_server::ServeOptions::new(s.dir.path().join("ws"));
    o.port = 0;
    let (addr2, _) = indentify_server::bind(&o).unwrap().spawn();
    let listed = get(addr2, "/api/runs").json();
    assert_eq!(listed["runs"][0]["id"], id.as_str());
    assert_eq!(
        get(addr2, &format!("/api/runs/{id}")).json()["result"]["max_force"],
        v["result"]["max_force"]
    );
}

#[test]
fn an_identification_streams_its_progress_and_can_be_cancelled() {
    let s = serve(|_| {});
    // R1 (the embedded default) for 3 iterations, no discretization check
    let r = submit(
        s.addr,
        json!({"command": "identify", "max_iter": 3, "no_refine": true}),
    );
    assert_eq!(r.status, 202, "{}", r.text());
    let id = r.json()["id"].as_str().unwrap().to_string();
    // a second one waits in the queue (one worker) and is cancelled there
    let queued = submit(
        s.addr,
        json!({"command": "identify", "max_iter": 3, "no_refine": true}),
    )
    .json()["id"]
        .as_str()
        .unwrap()
        .to_string();
    let c = request(
        s.addr,
        "DELETE",
        &format!("/api/runs/{queued}"),
        &[("X-Indentify", "1")],
        b"",
    );
    assert_eq!(c.status, 200, "{}", c.text());
    assert_eq!(c.json()["status"], "cancelled");
    let evs = events(s.addr, &id);
    let last = evs.last().unwrap();
    assert_eq!(last["status"], "done", "{last}");
    // one event per iteration at least (0 = the start, then 1..3)
    let iterations: Vec<u64> = evs
        .iter()
        .filter(|e| e["progress"]["cost"].is_number())
        .map(|e| e["progress"]["iteration"].as_u64().unwrap())
        .collect();
    for k in 0..=3 {
        assert!(
            iterations.contains(&k),
            "iteration {k} missing from {iterations:?}"
        );
    }
    assert_eq!(last["progress"]["costs"].as_array().unwrap().len(), 4);
    let v = get(s.addr, &format!("/api/runs/{id}")).json();
    let res = &v["result"];
    assert_eq!(res["iterations"], 3);
    assert_eq!(res["parameters"][0]["name"], "E");
    assert!(res["identifiability"]["singular_values"].is_array());
    let files: Vec<&str> = v["files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["name"].as_str().unwrap())
        .collect();
    for f in [
        "report.md",
        "result.json",
        "history.csv",
        "fit.csv",
        "config.ron",
        "force_depth.svg",
    ] {
        assert!(files.contains(&f), "{f} not in {files:?}");
    }
    assert!(v["message"].as_str().unwrap().contains("did not converge"));
    // the queued one never ran
    let q = get(s.addr, &format!("/api/runs/{queued}")).json();
    assert_eq!(q["status"], "cancelled");
    assert!(q["started"].is_null());
    // a running identification is stopped after its iteration in progress
    let long = submit(s.addr, json!({"command": "identify", "no_refine": true})).json()["id"]
        .as_str()
        .unwrap()
        .to_string();
    loop {
        let v = get(s.addr, &format!("/api/runs/{long}")).json();
        if v["progress"]["cost"].is_number() {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    let c = request(
        s.addr,
        "DELETE",
        &format!("/api/runs/{long}"),
        &[("X-Indentify", "1")],
        b"",
    );
    assert_eq!(c.status, 200, "{}", c.text());
    let v = wait(s.addr, &long);
    assert_eq!(v["status"], "cancelled", "{v}");
    assert!(
        v["result"]["stop_reason"]
            .as_str()
            .unwrap()
            .contains("nterrupt"),
        "{}",
        v["result"]["stop_reason"]
    );
}

/// A bounded load test on loopback: 20 queued simulations and 5 clients following their
/// events. Run with `cargo test -p indentify-server --release --test api -- --ignored --nocapture`.
#[test]
#[ignore]
fn load_20_queued_runs_and_5_event_clients() {
    let s = serve(|o| o.workers = 2);
    let t0 = std::time::Instant::now();
    let ids: Vec<String> = (0..20)
        .map(|k| {
            let r = submit(
                s.addr,
                json!({"command": "simulate", "sets": {"law.E": 20000 + 100 * k}}),
            );
            assert_eq!(r.status, 202);
            r.json()["id"].as_str().unwrap().to_string()
        })
        .collect();
    let submitted = t0.elapsed().as_secs_f64();
    let watchers: Vec<_> = (0..5)
        .map(|k| {
            let addr = s.addr;
            let id = ids[ids.len() - 1 - k].clone();
            // an open page: the page, its script, the runs list, then the run's events
            std::thread::spawn(move || {
                for path in ["/", "/app.js", "/style.css", "/api/runs", "/api/laws"] {
                    assert_eq!(get(addr, path).status, 200, "{path}");
                }
                events(addr, &id).len()
            })
        })
        .collect();
    // the API stays responsive while the queue drains
    let mut worst = 0.0f64;
    while ids.iter().any(|id| {
        !matches!(
            get(s.addr, &format!("/api/runs/{id}")).json()["status"].as_str(),
            Some("done" | "failed")
        )
    }) {
        let t = std::time::Instant::now();
        assert_eq!(get(s.addr, "/api/health").status, 200);
        worst = worst.max(t.elapsed().as_secs_f64());
        std::thread::sleep(std::time::Duration::from_millis(100));
    }
    let total = t0.elapsed().as_secs_f64();
    let n_events: usize = watchers.into_iter().map(|w| w.join().unwrap()).sum();
    for id in &ids {
        assert_eq!(
            get(s.addr, &format!("/api/runs/{id}")).json()["status"],
            "done"
        );
    }
    println!(
        "load: 20 runs submitted in {submitted:.3} s, all done in {total:.2} s; 5 event clients \
         got {n_events} events; slowest /api/health while busy {:.1} ms",
        worst * 1e3
    );
}

/// The server's cost on a run: the same identification (R1, no discretization check) called
/// directly as the CLI calls it and through the API, alternating, in one process. Run with
/// `cargo test -p indentify-server --test api overhead -- --ignored --nocapture`.
#[test]
#[ignore]
fn overhead_of_a_run_through_the_server() {
    let s = serve(|_| {});
    let mut ratios = Vec::new();
    for k in 0..4 {
        let out = s.dir.path().join(format!("direct{k}"));
        let t = std::time::Instant::now();
        let mut opts = indentify_study::identify::IdentifyOptions::new(ConfigSource::Default);
        opts.out = Some(out);
        opts.refine = false;
        indentify_study::identify::run(&opts, &mut ()).unwrap();
        let direct = t.elapsed().as_secs_f64();
        let t = std::time::Instant::now();
        let id = submit(s.addr, json!({"command": "identify", "no_refine": true})).json()["id"]
            .as_str()
            .unwrap()
            .to_string();
        let v = wait(s.addr, &id);
        let served = t.elapsed().as_secs_f64();
        assert_eq!(v["status"], "done");
        ratios.push(served / direct);
        println!(
            "overhead: pair {k}: direct {direct:.3} s, through the server {served:.3} s, ratio {:.3}",
            served / direct
        );
    }
    ratios.sort_by(f64::total_cmp);
    println!(
        "overhead: median ratio {:.3}",
        (ratios[1] + ratios[2]) / 2.0
    );
}
