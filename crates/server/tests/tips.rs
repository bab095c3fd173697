//! Calibrated tips from the browser, over a real loopback socket: `POST /api/tips` takes
//! `indentify calibrate`'s TIP.ron (checked before it is stored), a configuration names it
//! as `punch: Calibrated(file: "../../tips/ID/tip.ron")`, and every other tip path is
//! refused (traversal, absolute paths, a record, another file of the tip's folder). The
//! reference: an ideal-Berkovich area function (A = 24.5 h_c^2 alone) runs as its
//! area-equivalent cone, tan(theta)^2 pi = 24.5, to round-off.

mod common;

use common::*;
use serde_json::{Value, json};

const IDEAL: &str = "(name: \"ideal Berkovich\", area: Iso(coefficients: [24.5]))";

/// The R1 template with its `punch` replaced.
fn config_with_punch(punch: &str) -> String {
    let text = indentify_study::templates::template(indentify_study::config::Reference::R1Maxwell);
    let out: Vec<String> = text
        .lines()
        .map(|l| {
            if l.trim_start().starts_with("punch:") {
                format!("    punch: {punch},")
            } else {
                l.to_string()
            }
        })
        .collect();
    assert!(out.iter().any(|l| l.contains(punch)));
    out.join("\n")
}

fn simulate(punch: &str) -> Value {
    json!({"command": "simulate", "config": config_with_punch(punch),
           "sets": ["specimen.nr=6", "specimen.nz=6"]})
}

fn forces(s: &Served, id: &str) -> Vec<f64> {
    let v = wait(s.addr, id);
    assert_eq!(v["status"], "done", "{v}");
    let csv = get(s.addr, &format!("/api/runs/{id}/files/curve.csv")).text();
    let mut lines = csv.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let k = head.iter().position(|h| *h == "F").unwrap();
    lines
        .map(|l| l.split(',').nth(k).unwrap().parse().unwrap())
        .collect()
}

fn tip_upload(s: &Served, name: &str, bytes: &[u8]) -> Resp {
    request(
        s.addr,
        "POST",
        &format!("/api/tips?name={name}"),
        &[("X-Indentify", "1")],
        bytes,
    )
}

#[test]
fn an_uploaded_ideal_berkovich_tip_runs_as_its_cone() {
    let s = serve(|_| {});
    let r = tip_upload(&s, "TIP.ron", IDEAL.as_bytes());
    assert_eq!(r.status, 201, "{}", r.text());
    let tip = r.json();
    let id = tip["id"].as_str().unwrap().to_string();
    let punch = tip["punch"].as_str().unwrap().to_string();
    assert_eq!(
        punch,
        format!("Calibrated(file: \"../../tips/{id}/tip.ron\")")
    );
    // the same bytes again: the same id; listed
    assert_eq!(
        tip_upload(&s, "TIP.ron", IDEAL.as_bytes()).json()["id"],
        tip["id"]
    );
    let list = get(s.addr, "/api/tips").json();
    assert_eq!(list["tips"].as_array().unwrap().len(), 1, "{list}");
    // served simulations: the calibrated tip and its area-equivalent cone
    let theta = (24.5 / std::f64::consts::PI).sqrt().atan().to_degrees();
    let cal = submit(s.addr, simulate(&punch));
    assert_eq!(cal.status, 202, "{}", cal.text());
    let cone = submit(
        s.addr,
        simulate(&format!("Cone(half_angle_deg: {theta:?})")),
    );
    assert_eq!(cone.status, 202, "{}", cone.text());
    let a = forces(&s, cal.json()["id"].as_str().unwrap());
    let b = forces(&s, cone.json()["id"].as_str().unwrap());
    assert_eq!(a.len(), b.len());
    let fmax = b.iter().copied().fold(0.0, f64::max);
    assert!(fmax > 0.0);
    let worst = a
        .iter()
        .zip(&b)
        .map(|(x, y)| (x - y).abs() / fmax)
        .fold(0.0, f64::max);
    // curve.csv holds the forces to its printed digits
    assert!(worst < 1e-9, "largest difference {worst:e} of F_max");
    // the run folder's config.ron repeats it from the CLI: the tip path is relative to it
    let dir = s
        .dir
        .path()
        .join("ws/runs")
        .join(cal.json()["id"].as_str().unwrap());
    let cfg = std::fs::read_to_string(dir.join("config.ron")).unwrap();
    assert!(cfg.contains(&format!("../../tips/{id}/tip.ron")), "{cfg}");
    assert!(dir.join("../../tips").join(&id).join("tip.ron").is_file());
}

#[test]
fn tip_paths_outside_the_workspaces_tips_are_refused() {
    let s = serve(|_| {});
    let id = tip_upload(&s, "TIP.ron", IDEAL.as_bytes()).json()["id"]
        .as_str()
        .unwrap()
        .to_string();
    let rec = post(
        s.addr,
        "/api/records?name=anonNI.TXT",
        &std::fs::read(repo().join("examples/data/anton-paar-unht-berkovich/anonNI.TXT")).unwrap(),
    )
    .json()["id"]
        .as_str()
        .unwrap()
        .to_string();
    // a file that exists beside the workspace, to be sure a refusal is not a missing file
    std::fs::write(s.dir.path().join("tip.ron"), IDEAL).unwrap();
    let outside = s.dir.path().join("tip.ron").display().to_string();
    for file in [
        "tip.ron".to_string(),
        "../../../tip.ron".to_string(),
        outside,
        "/etc/passwd".to_string(),
        format!("../../tips/{id}/../../../tip.ron"),
        format!("../../tips/{id}/../{id}/../../records/{rec}/anonNI.TXT"),
        format!("../../records/{rec}/anonNI.TXT"),
        format!("../../tips/{id}"),
        "../../tips/0123456789abcdef/tip.ron".to_string(),
    ] {
        let runs_before = std::fs::read_dir(s.dir.path().join("ws/runs"))
            .unwrap()
            .count();
        let r = submit(s.addr, simulate(&format!("Calibrated(file: {file:?})")));
        assert_eq!(r.status, 400, "{file}: {}", r.text());
        assert!(
            r.text().contains("is not a tip of this workspace"),
            "{file}: {}",
            r.text()
        );
        let runs_after = std::fs::read_dir(s.dir.path().join("ws/runs"))
            .unwrap()
            .count();
        assert_eq!(runs_before, runs_after, "{file} wrote a run folder");
    }
    // bad tip files: named with the line or the field; nothing stored
    for (bytes, what) in [
        (&b"(area: Iso(coefficients: [24.5])"[..], "TIP.ron:1:"),
        (&b"(area: Iso(coefficients: []))"[..], "TIP.ron"),
        (&b"\xff\xfe garbage"[..], "not text"),
        (&b"(area: Flat(radius: 0.01))"[..], "TIP.ron"),
    ] {
        let r = tip_upload(&s, "TIP.ron", bytes);
        assert_eq!(r.status, 400, "{}", r.text());
        assert!(r.text().contains(what), "{what}: {}", r.text());
    }
    let big = vec![b' '; 100 * 1024];
    let r = tip_upload(&s, "TIP.ron", &big);
    assert_eq!(r.status, 400, "{}", r.text());
    assert_eq!(
        get(s.addr, "/api/tips").json()["tips"]
            .as_array()
            .unwrap()
            .len(),
        1
    );
    // a tip name with a path in it is only a label: the file is stored as tips/ID/tip.ron
    let r = tip_upload(&s, "../../evil.ron", b"(area: Iso(coefficients: [24.4]))");
    assert_eq!(r.status, 201, "{}", r.text());
    assert!(!s.dir.path().join("evil.ron").exists());
    assert!(!s.dir.path().join("ws/evil.ron").exists());
}
