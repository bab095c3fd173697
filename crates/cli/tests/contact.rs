//! `contact: Normal` from the command line: the configuration field and its `--set`, a
//! different force than the paper's vertical contact, an exact gradient (frictionless and
//! with Coulomb friction), and a clear error for an unknown kind.

mod common;

use common::*;

#[test]
fn normal_contact_is_selected_by_set_and_its_gradient_is_exact() {
    let r1 = example("r1-maxwell.ron");
    // the reference mesh (a coarse one puts the whole contact on the axis node, where both
    // kinds agree), few steps
    let short = |args: &[&str]| -> Vec<String> {
        let mut v: Vec<String> = args.iter().map(|s| s.to_string()).collect();
        for k in 0..3 {
            v.push("--set".into());
            v.push(format!("history.segments.{k}.steps=5"));
        }
        v
    };
    let peak = |extra: &[&str]| -> f64 {
        let mut args = short(&["-q", "simulate", &r1]);
        args.extend(extra.iter().map(|s| s.to_string()));
        let o = indentify(&args);
        assert_ok(&o);
        parse_curve(&stdout(&o))
            .iter()
            .map(|r| r[2])
            .fold(0.0, f64::max)
    };
    let vertical = peak(&[]);
    let normal = peak(&["--set", "contact=Normal"]);
    let change = normal / vertical - 1.0;
    // the flank pushes the surface outward: a few percent on Maxwell (+2..4% on R1)
    assert!(change > 0.005 && change < 0.08, "{vertical} -> {normal}");

    let args = short(&[
        "-q",
        "gradient-check",
        &r1,
        "--set",
        "contact=Normal",
        "--json",
    ]);
    let o = indentify(&args);
    assert_ok(&o);
    assert_eq!(json(&o)["passed"], true, "{}", stdout(&o));

    let bad = indentify(&coarse(&["check", &r1, "--set", "contact=Sideways"]));
    assert_rejected(&bad, &["Sideways"], "unknown contact kind");
}

/// `gradient-check` with Coulomb friction (`contact=Normal(friction: 0.1)`) on R1's
/// reference mesh, few steps: the adjoint (sticking and slipping nodes, the transposed
/// unsymmetric system) agrees with central differences and with the sensitivities.
#[test]
fn gradient_check_passes_with_friction() {
    let r1 = example("r1-maxwell.ron");
    let mut args: Vec<String> = [
        "-q",
        "gradient-check",
        &r1,
        "--set",
        "contact=Normal(friction: 0.1)",
        "--json",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    for k in 0..3 {
        args.push("--set".into());
        args.push(format!("history.segments.{k}.steps=5"));
    }
    let o = indentify(&args);
    assert_ok(&o);
    let j = json(&o);
    assert_eq!(j["passed"], true, "{}", stdout(&o));
    for c in j["checks"].as_array().unwrap() {
        let rd = c["rel_diff_fd"].as_f64().unwrap();
        assert!(rd < 1e-6, "{c}");
    }
}
