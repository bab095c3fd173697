//! `calibrate` through the API, over a real loopback socket: the shipped fused-silica
//! workbook uploaded, calibrated with its modulus and Poisson's ratio, gives the tip file
//! `indentify calibrate` writes byte for byte (the study pipeline called directly on the
//! original file with the CLI's options) and its numbers in calibration.json; that tip.ron
//! stored with `POST /api/tips` is a tip a later run uses; what the CLI refuses is refused.

mod common;

use common::*;
use serde_json::{Value, json};

const SILICA: &str = "examples/data/kla-fused-silica/FusedSilica.xlsx";

/// The R1 template with its `punch` replaced.
fn config_with_punch(punch: &str) -> String {
    let text = indentify_study::templates::template(indentify_study::config::Reference::R1Maxwell);
    text.lines()
        .map(|l| {
            if l.trim_start().starts_with("punch:") {
                format!("    punch: {punch},")
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn a_served_calibration_is_the_clis_and_its_tip_is_usable() {
    let s = serve(|_| {});
    let bytes = std::fs::read(repo().join(SILICA)).unwrap();
    let r = post(s.addr, "/api/records?name=FusedSilica.xlsx", &bytes);
    assert_eq!(r.status, 201, "{}", r.text());
    let rid = r.json()["id"].as_str().unwrap().to_string();
    let r = submit(
        s.addr,
        json!({"command": "calibrate", "record": rid, "modulus": 72, "nu": 0.17}),
    );
    assert_eq!(r.status, 202, "{}", r.text());
    let id = r.json()["id"].as_str().unwrap().to_string();
    let v = wait(s.addr, &id);
    assert_eq!(v["status"], "done", "{v}");
    assert!(
        v["cli"].as_str().unwrap().starts_with(&format!(
            "indentify calibrate ../../records/{rid}/FusedSilica.xlsx --modulus 72 --nu 0.17"
        )),
        "{}",
        v["cli"]
    );
    // the pipeline on the original file with `indentify calibrate`'s options
    let out = tempfile::tempdir().unwrap();
    let mut opts = indentify_server::calibrate::options(repo().join(SILICA), 72.0, 0.17, None, 3);
    opts.out = Some(out.path().join("tip.ron"));
    let direct = indentify_study::analyze::calibrate(&opts).unwrap();
    let served_tip = get(s.addr, &format!("/api/runs/{id}/files/tip.ron")).text();
    let cli_tip = std::fs::read_to_string(out.path().join("tip.ron")).unwrap();
    assert_eq!(served_tip, cli_tip);
    let res = &v["result"];
    assert_eq!(
        res["compliance_used"].as_f64().unwrap(),
        direct.compliance_used
    );
    let coef: Vec<f64> = res["area"]["coefficients"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c.as_f64().unwrap())
        .collect();
    assert_eq!(coef, direct.area.coefficients);
    assert_eq!(
        res["area"]["points"].as_array().unwrap().len(),
        direct.area.n
    );
    assert_eq!(
        v["summary"]["frame_compliance"].as_f64(),
        Some(direct.compliance_used)
    );
    // fused silica: a positive frame compliance, a Berkovich-like leading term
    assert!(direct.compliance_used > 0.0);
    let c0 = coef[0];
    assert!((20.0..30.0).contains(&c0), "C0 = {c0}");
    // the tip stored (POST /api/tips) and used by a later run
    let t = request(
        s.addr,
        "POST",
        "/api/tips?name=tip.ron",
        &[("X-Indentify", "1")],
        served_tip.as_bytes(),
    );
    assert_eq!(t.status, 201, "{}", t.text());
    let tip = t.json();
    assert_eq!(
        tip["frame_compliance"].as_f64(),
        Some(direct.compliance_used)
    );
    let punch = tip["punch"].as_str().unwrap().to_string();
    let r = submit(
        s.addr,
        json!({"command": "simulate", "config": config_with_punch(&punch),
               "sets": ["specimen.nr=6", "specimen.nz=6"]}),
    );
    assert_eq!(r.status, 202, "{}", r.text());
    let sim = wait(s.addr, r.json()["id"].as_str().unwrap());
    assert_eq!(sim["status"], "done", "{sim}");
    // refused: no modulus, nu out of range, no record, a configuration
    for (req, what) in [
        (
            json!({"command": "calibrate", "record": rid, "nu": 0.17}),
            "needs `modulus`",
        ),
        (
            json!({"command": "calibrate", "record": rid, "modulus": 72, "nu": 0.5}),
            "nu = 0.5",
        ),
        (
            json!({"command": "calibrate", "modulus": 72, "nu": 0.17}),
            "needs a record",
        ),
        (
            json!({"command": "calibrate", "record": rid, "modulus": 72, "nu": 0.17, "terms": 9}),
            "terms = 9",
        ),
        (
            json!({"command": "calibrate", "record": rid, "modulus": -1, "nu": 0.17}),
            "modulus = -1",
        ),
    ] {
        let r = submit(s.addr, req.clone());
        assert_eq!(r.status, 400, "{req}: {}", r.text());
        let m: Value = r.json();
        assert!(m["messages"].to_string().contains(what), "{req}: {m}");
    }
}
