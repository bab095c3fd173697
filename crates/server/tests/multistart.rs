//! A multi-start through the API (`starts`, `seed`: `indentify identify --starts N --seed
//! S`), over a real loopback socket: the served minima are the study pipeline's, called
//! directly on the run's own config.ron as the CLI calls it (same J and parameters, bit for
//! bit: the starts are seeded and each start's fit is deterministic), the reported fit is
//! the first minimum, and what the CLI refuses is refused with 400.

mod common;

use common::*;
use indentify_study::ConfigSource;
use indentify_study::explore::StartsOptions;
use indentify_study::identify::{self, IdentifyOptions};
use serde_json::json;

#[test]
fn a_served_multi_start_lists_the_pipelines_minima() {
    let s = serve(|_| {});
    let bytes =
        std::fs::read(repo().join("examples/data/anton-paar-unht-berkovich/anonNI.TXT")).unwrap();
    let rid = post(s.addr, "/api/records?name=anonNI.TXT", &bytes).json()["id"]
        .as_str()
        .unwrap()
        .to_string();
    // a multi-start draws its starts in the box: finite bounds (the template has none)
    let sets = [
        "data.preprocessing.resample.n=20",
        "data.substeps=1",
        "identify.params.E.lower=1000",
        "identify.params.E.upper=100000",
        "identify.params.eta.lower=1000",
        "identify.params.eta.upper=10000000",
    ];
    let r = submit(
        s.addr,
        json!({"command": "identify", "record": rid, "max_iter": 3, "no_refine": true,
               "starts": 3, "seed": 7, "sets": sets}),
    );
    assert_eq!(r.status, 202, "{}", r.text());
    let id = r.json()["id"].as_str().unwrap().to_string();
    let v = wait(s.addr, &id);
    assert_ne!(v["status"], "failed", "{v}");
    let cli = v["cli"].as_str().unwrap();
    assert!(cli.contains("--starts 3 --seed 7"), "{cli}");
    let ms = &v["result"]["multistart"];
    assert_eq!(ms["n"], 3, "{ms}");
    assert_eq!(ms["seed"], 7);
    let minima = ms["minima"].as_array().unwrap();
    assert!(!minima.is_empty());
    assert_eq!(ms["runs"].as_array().unwrap().len(), 3);
    // the reported fit is the first (lowest) minimum
    let best = &minima[0];
    assert_eq!(best["J"].as_f64(), v["result"]["J"].as_f64(), "{ms}");
    let free: Vec<f64> = v["result"]["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|p| p["free"] == true)
        .map(|p| p["value"].as_f64().unwrap())
        .collect();
    let values: Vec<f64> = best["values"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert_eq!(values, free);
    // the pipeline called directly on the run's config.ron, as `indentify identify` does
    let dir = s.dir.path().join("ws/runs").join(&id);
    let mut opts = IdentifyOptions::new(ConfigSource::Path(dir.join("config.ron")));
    opts.sets = v["sets"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_str().unwrap().to_string())
        .collect();
    opts.refine = false;
    opts.figures = false;
    opts.overrides.max_iterations = Some(3);
    opts.starts = Some(StartsOptions::new(3, 7));
    let direct = identify::run(&opts, &mut ()).unwrap();
    let dm = direct.multistart.expect("the direct run's multi-start");
    assert_eq!(dm.minima.len(), minima.len());
    for (a, b) in minima.iter().zip(&dm.minima) {
        assert_eq!(a["J"].as_f64().unwrap(), b.cost, "{a}");
        let av: Vec<f64> = a["values"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        assert_eq!(av, b.values);
    }
    // refused as the CLI refuses: 400, the reason
    for (req, what) in [
        (
            json!({"command": "identify", "record": rid, "starts": 0}),
            "starts = 0",
        ),
        (
            json!({"command": "identify", "record": rid, "starts": 201}),
            "1 to 200",
        ),
        (
            json!({"command": "identify", "record": rid, "seed": 3}),
            "seed needs starts",
        ),
        (
            json!({"command": "simulate", "starts": 2}),
            "option of identify",
        ),
    ] {
        let r = submit(s.addr, req.clone());
        assert_eq!(r.status, 400, "{req}: {}", r.text());
        assert!(r.text().contains(what), "{req}: {}", r.text());
    }
}
