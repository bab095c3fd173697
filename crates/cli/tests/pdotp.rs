//! `indentify identify examples/pdotp-maxwell.ron` end to end (docs/cli.md, "Loading at a
//! constant Pdot/P"; docs/validation-load-control.md §12): a load-controlled record loaded
//! at constant Pdot/P, held and unloaded, its depth (1% noise, one seeded draw) fitted from
//! the example's start. The run exits 0, says "converged", and result.json's E and eta lie
//! within 2.5 of their standard deviations of the law values that generated the data;
//! result.json's noise model names the depth.

mod common;

use common::{assert_ok, example, indentify, stdout};

#[test]
fn pdotp_example_is_identified_through_the_cli() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let o = indentify(&[
        "identify",
        &example("pdotp-maxwell.ron"),
        "--noise",
        "0.01",
        "--seed",
        "1",
        "--set",
        "specimen.nr=8",
        "--set",
        "specimen.nz=8",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_ok(&o);
    let table = stdout(&o);
    assert!(table.contains("converged"), "{table}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("result.json")).unwrap()).unwrap();
    assert_eq!(v["converged"], true, "{v}");
    assert_eq!(v["observable"], "Depth", "{v}");
    let ident = &v["identifiability"];
    // the stated noise model names the fitted quantity, the depth (it said `% of F`)
    let noise = ident["noise"].as_str().unwrap();
    assert!(noise.contains("% of h"), "{noise}");
    for (name, truth) in [("E", 20000.0), ("eta", 30000.0)] {
        let value = v["parameters"]
            .as_array()
            .unwrap()
            .iter()
            .find(|p| p["name"] == name)
            .unwrap()["value"]
            .as_f64()
            .unwrap();
        let s = ident["std_dev"][name].as_f64().unwrap();
        println!("{name} = {value} (truth {truth}), sigma {s}");
        assert!(s > 0.0 && s < 0.1 * truth, "{name}: sigma {s}");
        assert!(
            (value - truth).abs() <= 2.5 * s,
            "{name} = {value}, truth {truth}, sigma {s}"
        );
    }
}
