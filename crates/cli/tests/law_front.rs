//! The laws' front ends: `indentify laws [--json]` lists what the registry builds (the
//! same data as `study::laws_list`, which Python's `indentify.laws()` returns), and
//! `init <plastic-*|prony> --data` starts from the record's Oliver-Pharr analysis.

mod common;

use common::{assert_ok, indentify, stdout};

/// The system shall print the registry's listing: the JSON equals the study layer's
/// listing (the registry's), and the text names every law and every parameter's `--set`
/// form.
#[test]
fn laws_lists_the_registry() {
    let o = indentify(&["laws", "--json"]);
    assert_ok(&o);
    let printed: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let listing = serde_json::to_value(indentify_study::laws_list::laws().unwrap()).unwrap();
    assert_eq!(printed, listing);
    let o = indentify(&["laws"]);
    assert_ok(&o);
    let text = stdout(&o);
    for v in indentify_study::laws_list::laws().unwrap() {
        assert!(
            text.contains(&format!("{} ({})", v.variant, v.name)),
            "{text}"
        );
        for p in &v.parameters {
            assert!(
                text.contains(&format!("    {}", p.name)),
                "{}: {text}",
                p.name
            );
        }
    }
    assert!(
        text.contains("hardening: one of Linear(H), Power(n), Voce(Q, b)"),
        "{text}"
    );
    assert!(
        text.contains("rate: omitted (rate-independent), or Norton(K, m)"),
        "{text}"
    );
}

/// The number after `key` (`sY: 412.5,`) in the template's `law` section.
fn law_value(text: &str, key: &str) -> f64 {
    let law = &text[text.find("law: ").expect("law")..];
    let at = law.find(&format!("{key}: ")).expect(key) + key.len() + 2;
    let end = law[at..].find([',', ')', '\n']).unwrap() + at;
    law[at..end].trim().parse().unwrap()
}

/// The system shall start `init plastic-norton --data` from the record's Oliver-Pharr
/// analysis: E = E_IT, and sY, K such that the law's Dao power hardening at Tabor's
/// representative strain 0.08 plus the Norton overstress at the hold's strain rate is
/// H/3 (the closed form written here, not the guess's code); the template checks.
#[test]
fn init_plastic_data_reproduces_h_over_3_through_the_flow_rule() {
    let file = common::examples()
        .join("data/anton-paar-sphere-creep/HT_V_100mN.TXT")
        .display()
        .to_string();
    let args = [
        "init",
        "plastic-norton",
        "--data",
        &file,
        "--test",
        "3",
        "--tip",
        "sphere:0.01",
    ];
    let o = indentify(&args);
    assert_ok(&o);
    let text = stdout(&o);
    assert!(text.contains("Tabor"), "{text}");
    let tip = indentify_study::first_guess::tip_for_punch(&indentify_study::Punch::Sphere {
        radius: 0.01,
    })
    .unwrap();
    let op =
        indentify_study::first_guess::analyse_file(std::path::Path::new(&file), Some(3), &tip, 0.3)
            .unwrap();
    let (e, s_y, n, k, m) = (
        law_value(&text, "E"),
        law_value(&text, "sY"),
        law_value(&text, "n"),
        law_value(&text, "K"),
        law_value(&text, "m"),
    );
    assert!((e / op.e - 1.0).abs() < 1e-6, "E {e} vs {}", op.e);
    let rate = op.strain_rate.expect("the creep hold's rate");
    // sigma_y(p) = sY (1 + E p / sY)^n (Dao), overstress K eps'^(1/m)
    let flow = s_y * (1.0 + e * 0.08 / s_y).powf(n) + k * rate.powf(1.0 / m);
    // the template prints 6 significant digits or more
    assert!(
        (flow / (op.h / 3.0) - 1.0).abs() < 1e-4,
        "{flow} vs H/3 {}",
        op.h / 3.0
    );
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("p.ron");
    let mut with_out = args.to_vec();
    let out_s = out.display().to_string();
    with_out.extend(["--out", &out_s]);
    assert_ok(&indentify(&with_out));
    assert_ok(&indentify(&["check", &out_s]));
}

/// The system shall start `init prony --data` from the hold's creep: one term whose
/// standard-linear-solid creep compliance (closed form written here) gives the hold's
/// depth ratio through Lee-Radok (`h^2 ~ J` under a Berkovich tip).
#[test]
fn init_prony_data_reproduces_the_holds_creep() {
    let file = common::examples()
        .join("data/anton-paar-unht-berkovich/anonNI.TXT")
        .display()
        .to_string();
    let o = indentify(&["init", "prony", "--data", &file]);
    assert_ok(&o);
    let text = stdout(&o);
    let tip = indentify_study::first_guess::tip_for_punch(&indentify_study::Punch::Berkovich {
        tip_radius: None,
    })
    .unwrap();
    let op =
        indentify_study::first_guess::analyse_file(std::path::Path::new(&file), None, &tip, 0.3)
            .unwrap();
    let hold = op.hold.expect("a creep hold");
    let (g, tau) = (law_value(&text, "g"), law_value(&text, "tau"));
    assert!(text.contains("Lee-Radok"), "{text}");
    assert!(g > 0.0 && g < 1.0 && tau > 0.0, "{g} {tau}");
    let j = |t: f64| (1.0 - g * (-t * (1.0 - g) / tau).exp()) / (1.0 - g);
    let ratio = (hold.h.1 / hold.h.0).powi(2);
    let got = j(hold.duration) / j(0.0);
    assert!((got / ratio - 1.0).abs() < 1e-4, "{got} vs {ratio}");
    // one term: a single (g, tau)
    assert_eq!(text.matches("tau:").count(), 1, "{text}");
}
