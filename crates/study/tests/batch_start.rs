//! FE `batch` fits that start from the Oliver-Pharr analysis of each indent's own record
//! (the manifest's `start` column, `oliver-pharr`): on the shipped Anton Paar Berkovich
//! record (`anon-maxwell.ron`), the indent's free parameters start at
//! `start_from_analysis::starts` of its record (`E` = `analyze`'s `E_IT`), a row without the
//! column keeps the configuration's starts, a row whose configuration has no record fails
//! alone with the reason, and an unknown start is refused naming the line.

mod common;

use common::examples;
use std::path::Path;

use indentify_study::ConfigSource;
use indentify_study::batch::{self, BatchOptions, State};
use indentify_study::start_from_analysis::starts;

/// result.json's start values of an indent, by parameter name.
fn json_starts(out: &Path, id: &str) -> Vec<(String, f64)> {
    let text = std::fs::read(out.join("indents").join(id).join("result.json")).unwrap();
    let v: serde_json::Value = serde_json::from_slice(&text).unwrap();
    v["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| {
            (
                p["name"].as_str().unwrap().to_string(),
                p["start"].as_f64().unwrap(),
            )
        })
        .collect()
}

#[test]
fn batch_indents_start_from_their_own_analysis() {
    let tmp = tempfile::tempdir().unwrap();
    let ex = examples().canonicalize().unwrap();
    let maxwell = ex.join("real/anon-maxwell.ron");
    let manifest = tmp.path().join("manifest.csv");
    std::fs::write(
        &manifest,
        format!(
            "id,config,start,data.preprocessing.resample.n,specimen.elements_in_contact\n\
             op,{m},oliver-pharr,16,4\n\
             cfg,{m},,16,4\n\
             synthetic,{r1},oliver-pharr,,\n",
            m = maxwell.display(),
            r1 = ex.join("r1-maxwell.ron").display()
        ),
    )
    .unwrap();
    let out = tmp.path().join("out");
    let mut opts = BatchOptions::new(manifest.clone(), out.clone());
    opts.jobs = 1;
    opts.overrides.max_iterations = Some(1);
    let s = batch::run(&opts, &()).unwrap();
    assert_eq!(s.total, 3);

    // the analysis' starts, as `identify(start="oliver-pharr")` takes them
    let sets = vec![
        "data.preprocessing.resample.n=16".to_string(),
        "specimen.elements_in_contact=4".to_string(),
    ];
    let expected = starts(&ConfigSource::Path(maxwell.clone()), &sets, None).unwrap();
    let names: Vec<&str> = expected.starts.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["E", "eta"]);
    let op = json_starts(&out, "op");
    for (n, v) in &expected.starts {
        let got = op.iter().find(|(m, _)| m == n).unwrap().1;
        assert!((got - v).abs() <= 1e-12 * v.abs(), "{n}: {got} vs {v}");
    }
    // E starts at the O&P E_IT (not the configuration's 2000 MPa)
    assert!((expected.starts[0].1 - expected.guess.op.e).abs() <= 1e-12 * expected.guess.op.e);
    // the row without `start` keeps the configuration's values
    let cfg = json_starts(&out, "cfg");
    let config_e = cfg.iter().find(|(n, _)| n == "E").unwrap().1;
    assert!(
        (config_e - expected.starts[0].1).abs() > 1e-3 * config_e,
        "the configuration's start {config_e} is not the analysis'"
    );
    for id in ["op", "cfg"] {
        let st = batch::read_status(&out, id).unwrap();
        assert!(
            matches!(st.state, State::Converged | State::NotConverged),
            "{id}: {:?} {}",
            st.state,
            st.message
        );
    }
    // synthesized data have no record to analyse: that indent fails alone, saying why
    let st = batch::read_status(&out, "synthetic").unwrap();
    assert_eq!(st.state, State::Failed);
    assert!(
        st.message.contains("Oliver-Pharr") && st.message.contains("no `data` record"),
        "{}",
        st.message
    );
}

#[test]
fn an_unknown_start_is_refused_naming_the_line() {
    let tmp = tempfile::tempdir().unwrap();
    let manifest = tmp.path().join("m.csv");
    std::fs::write(&manifest, "id,config,start\na,c.ron,oliver\n").unwrap();
    let e = batch::read_manifest(&manifest, None).unwrap_err();
    let msg = e.messages().join(": ");
    assert!(
        msg.contains("m.csv:2") && msg.contains("column `start`") && msg.contains("oliver-pharr"),
        "{msg}"
    );
}
