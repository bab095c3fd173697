//! `init --data` starts the fit from the record's Oliver-Pharr analysis: the template's E is
//! `indentify analyze`'s E_IT of the same test (docs/analysis.md, First guesses).

mod common;

use common::{assert_ok, examples, indentify, stdout};

/// The number after `key` (`E: 97210.5,`) in the template's `law` section.
fn law_value(text: &str, key: &str) -> f64 {
    let law = &text[text.find("law: ").expect("law")..];
    let at = law.find(&format!("{key}: ")).expect(key) + key.len() + 2;
    let end = law[at..].find([',', ')', '\n']).unwrap() + at;
    law[at..end].trim().parse().unwrap()
}

#[test]
fn init_data_starts_from_the_oliver_pharr_analysis() {
    let file = examples()
        .join("data/anton-paar-sphere-creep/HT_V_100mN.TXT")
        .display()
        .to_string();
    let o = indentify(&[
        "analyze",
        &file,
        "--tip",
        "sphere:10",
        "--test",
        "3",
        "--json",
    ]);
    assert_ok(&o);
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let e_op = v["tests"][0]["E"].as_f64().unwrap();
    for law in ["maxwell", "norton-hoff"] {
        let args = [
            "init",
            law,
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
        assert!(
            text.contains("Start values from the record's Oliver-Pharr"),
            "{text}"
        );
        let e = law_value(&text, "E");
        assert!((e / e_op - 1.0).abs() < 1e-6, "{law}: E {e} vs O&P {e_op}");
        // the hold of this creep test gives the viscous start
        let viscous = if law == "maxwell" { "eta" } else { "K" };
        assert!(text.contains(&format!(" {viscous} = ")), "{text}");
        let mut no = args.to_vec();
        no.push("--no-guess");
        let o = indentify(&no);
        assert_ok(&o);
        assert!(!stdout(&o).contains("Start values from the record's"));
    }
}
