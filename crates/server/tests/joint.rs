//! A joint fit of tests of several records through the API (`tests: [{record, test,
//! weight}]`), over a real loopback socket: config.ron is the joint configuration (each
//! test's own file, a test whose file states another tip with that tip as its punch), the
//! served result is the study pipeline's called directly on that config.ron as
//! `indentify identify config.ron` calls it, bit for bit (J, every parameter, every test's
//! share of J), with each test's fit in `fit.csv` and `test-K/`; and what the CLI would
//! refuse is refused with nothing written.

mod common;

use common::*;
use indentify_study::ConfigSource;
use indentify_study::identify::{self, IdentifyOptions};
use serde_json::{Value, json};

const BERKOVICH: &str = "examples/data/anton-paar-unht-berkovich/anonNI.TXT";
const MULTI: &str = "examples/data/anton-paar-sphere-creep/HT_V_100mN.TXT";
const HLD: &str = "examples/data/hysitron/Exp-50mN_0000.hld";

fn upload(addr: std::net::SocketAddr, rel: &str) -> String {
    let bytes = std::fs::read(repo().join(rel)).unwrap();
    let name = rel.rsplit('/').next().unwrap();
    let r = post(addr, &format!("/api/records?name={name}"), &bytes);
    assert_eq!(r.status, 201, "{}", r.text());
    r.json()["id"].as_str().unwrap().to_string()
}

fn folders(s: &Served) -> usize {
    std::fs::read_dir(s.dir.path().join("ws/runs")).map_or(0, |d| d.count())
}

#[test]
fn a_joint_fit_across_records_is_the_pipelines_bit_for_bit() {
    let s = serve(|_| {});
    let a = upload(s.addr, BERKOVICH);
    let b = upload(s.addr, MULTI);
    let c = upload(s.addr, HLD);
    let sets = json!([
        "data.preprocessing.resample.n=20",
        "data.substeps=1",
        "identify.stop.max_iterations=1"
    ]);
    let r = submit(
        s.addr,
        json!({"command": "identify", "no_refine": true, "sets": sets,
               "tests": [{"record": a, "test": 1},
                         {"record": b, "test": 1},
                         {"record": b, "test": 3, "weight": 2.5},
                         {"record": c, "test": 1}]}),
    );
    assert_eq!(r.status, 202, "{}", r.text());
    let id = r.json()["id"].as_str().unwrap().to_string();
    let v = wait(s.addr, &id);
    assert_eq!(v["status"], "done", "{v}");
    // the run's record is the first pick's
    assert_eq!(v["record"], a.as_str());
    // config.ron: one test per pick, each reading its own record
    let dir = s.dir.path().join("ws/runs").join(&id);
    let cfg = ConfigSource::Path(dir.join("config.ron"))
        .load(&[])
        .unwrap();
    let tests = cfg.tests.as_ref().expect("a joint configuration");
    assert_eq!(tests.len(), 4);
    let files: Vec<(&str, Option<usize>)> = tests
        .iter()
        .map(|t| {
            let d = t.data.as_ref().unwrap();
            (d.file.as_str(), d.test)
        })
        .collect();
    assert!(
        files[0].0.ends_with(&format!("{a}/anonNI.TXT")),
        "{files:?}"
    );
    assert!(
        files[1].0.ends_with(&format!("{b}/HT_V_100mN.TXT")),
        "{files:?}"
    );
    assert_eq!((files[1].1, files[2].1), (Some(1), Some(3)));
    assert!(
        files[3].0.ends_with(&format!("{c}/Exp-50mN_0000.hld")),
        "{files:?}"
    );
    // a Hysitron file of another format: detected, not the Anton Paar reader
    assert_eq!(
        format!("{:?}", tests[3].data.as_ref().unwrap().format),
        format!("{:?}", indentify_study::records::Format::default())
    );
    assert_eq!(tests[2].weight, Some(2.5));
    // the Anton Paar files state no tip: their tests take the configuration's punch; the
    // Hysitron file states its own ("Tip ID: Tip", which no template recognizes: the
    // Berkovich the templates assume), given as that test's punch
    assert!(tests[..3].iter().all(|t| t.punch.is_none()), "{tests:?}");
    let p = format!("{:?}", tests[3].punch.as_ref().expect("the file's tip"));
    assert!(p.contains("Berkovich"), "{p}");
    // the pipeline called directly on config.ron, as `indentify identify config.ron`
    let mut opts = IdentifyOptions::new(ConfigSource::Path(dir.join("config.ron")));
    opts.refine = false;
    opts.figures = false;
    let direct = identify::run(&opts, &mut ()).unwrap();
    let res = &v["result"];
    assert_eq!(res["J"].as_f64().unwrap(), direct.result.cost, "{res}");
    let served: Vec<f64> = res["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["value"].as_f64().unwrap())
        .collect();
    let values: Vec<f64> = direct.result.params.iter().map(|p| p.value).collect();
    assert_eq!(served, values);
    // each test's share of J, its label naming its file, its own fit page
    let st = res["tests"].as_array().unwrap();
    assert_eq!(st.len(), 4);
    for (t, d) in st.iter().zip(&direct.tests) {
        assert_eq!(t["wJ"].as_f64().unwrap(), d.cost);
        assert_eq!(t["name"].as_str().unwrap(), d.name);
    }
    assert!(
        st[0]["name"].as_str().unwrap().contains("anonNI.TXT"),
        "{st:?}"
    );
    assert!(
        st[2]["name"].as_str().unwrap().contains("HT_V_100mN.TXT"),
        "{st:?}"
    );
    assert!(
        st[3]["name"]
            .as_str()
            .unwrap()
            .contains("Exp-50mN_0000.hld"),
        "{st:?}"
    );
    let listed = v["files"].to_string();
    for k in 1..=4 {
        assert!(listed.contains(&format!("test-{k}/")), "{listed}");
    }
    let fit = get(s.addr, &format!("/api/runs/{id}/files/fit.csv")).text();
    assert!(fit.starts_with("test,t,h,F_data,F_start,F_final"), "{fit}");
    for k in 1..=4 {
        assert!(
            fit.lines().any(|l| l.starts_with(&format!("{k},"))),
            "test {k}"
        );
    }
    // the identifiability of the joint fit: sigma or an undetermined mark per free one
    let ident = &res["identifiability"];
    for p in res["parameters"].as_array().unwrap() {
        if p["free"] == true {
            let name = p["name"].as_str().unwrap();
            let marked = ident["undetermined"]
                .as_array()
                .unwrap()
                .iter()
                .any(|u| u == name);
            assert!(marked || ident["std_dev"][name].is_number(), "{ident}");
        }
    }
    // refused, nothing written: an unknown record, a test it lacks, a test picked twice
    for (tests, status, what) in [
        (
            json!([{"record": a, "test": 1}, {"record": "0123456789abcdef", "test": 1}]),
            404,
            "no record",
        ),
        (
            json!([{"record": a, "test": 1}, {"record": b, "test": 5}]),
            400,
            "is not a test of record",
        ),
        (
            json!([{"record": b, "test": 2}, {"record": a, "test": 1}, {"record": b, "test": 2}]),
            400,
            "picked twice",
        ),
    ] {
        let before = folders(&s);
        let req: Value = json!({"command": "identify", "tests": tests});
        let r = submit(s.addr, req.clone());
        assert_eq!(r.status, status, "{req}: {}", r.text());
        assert!(r.text().contains(what), "{req}: {}", r.text());
        assert_eq!(folders(&s), before, "{req} wrote a run folder");
    }
}
