//! `indentify laws` / `indentify.laws()` list what the registry builds: every parameter
//! the listing names is accepted by `--set law.NAME=VALUE` on a configuration of every form
//! that has it, reaches the law's parameter of that name, and is one of the law's
//! parameters (the names `identify.params` and `free` take).

use indentify_study::config::{self, Reference};
use indentify_study::laws_list;

/// A value inside the parameter's range different from `v` (so that the set is seen).
fn other(p: &laws_list::ParamEntry, v: f64) -> f64 {
    let w = v * (1.0 + 1e-3) + 1e-6;
    if p.max.is_none_or(|m| w < m) {
        w
    } else {
        v * (1.0 - 1e-3)
    }
}

/// The system shall accept `--set law.NAME` for every listed parameter of every form, and
/// list exactly the parameters each form's built law has.
#[test]
fn every_listed_parameter_is_accepted_by_set() {
    let laws = laws_list::laws().unwrap();
    let forms = laws_list::form_specs().unwrap();
    let mut checked = 0;
    for (label, spec) in &forms {
        let law = laws
            .iter()
            .find(|l| l.variant == spec.variant())
            .expect("a listed law");
        let named = spec.named_params();
        let form = law
            .forms
            .iter()
            .find(|f| label.ends_with(&f.label))
            .expect("a listed form");
        let names: Vec<&str> = named.iter().map(|p| p.0).collect();
        assert_eq!(names, form.parameters, "{label}");
        for (name, v) in &named {
            let p = law.parameters.iter().find(|p| p.name == *name).unwrap();
            assert_eq!(p.set, format!("law.{name}"));
            let w = other(p, *v);
            let mut cfg = Reference::R1Maxwell.config();
            cfg.law = spec.clone();
            let set = format!("{}={w}", p.set);
            let out = config::apply_sets(cfg, std::slice::from_ref(&set))
                .unwrap_or_else(|e| panic!("{label}: --set {set}: {e:#}"));
            let got = out.law.named_params();
            let got = got.iter().find(|q| q.0 == *name).unwrap().1;
            assert_eq!(got, w, "{label}: --set {set}");
            checked += 1;
        }
    }
    // 3 stress-only laws (2 + 3 + 5), Plastic's 10 forms, Prony with two terms (6)
    assert!(checked > 60, "{checked}");
}

/// The JSON of the listing names every registry parameter with its unit and range.
#[test]
fn the_json_listing_has_units_and_ranges() {
    let v = serde_json::to_value(laws_list::laws().unwrap()).unwrap();
    let plastic = v
        .as_array()
        .unwrap()
        .iter()
        .find(|l| l["variant"] == "Plastic")
        .unwrap();
    let h = plastic["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["name"] == "H")
        .unwrap();
    assert_eq!(h["unit"], "MPa");
    assert_eq!(h["range"], "[0, inf)");
    assert_eq!(h["max"], serde_json::Value::Null);
    let kinds: Vec<&str> = plastic["kinds"]
        .as_array()
        .unwrap()
        .iter()
        .map(|k| k["field"].as_str().unwrap())
        .collect();
    assert_eq!(kinds, ["hardening", "rate"]);
}
