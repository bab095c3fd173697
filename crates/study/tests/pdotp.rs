//! Constant-`Pdot/P` segments in configurations (`(force, pdot_over_p, steps)`;
//! docs/cli.md, docs/validation-load-control.md §12): `simulate` carries the exponential
//! force; `gradient-check` passes on the depth cost for Maxwell and a Plastic law with a
//! Norton rate (the adjoint and the forward sensitivities of the bordered system against
//! central differences of the command's own cost); bad segments are refused naming the
//! field and the allowed range; `design` ranks candidates that load at constant Pdot/P.

use indentify_study::check::{self, CheckOptions};
use indentify_study::design::{self, DesignOptions};
use indentify_study::simulate::{self, SimulateOptions};
use indentify_study::source::ConfigSource;

const MAXWELL: &str = "Maxwell(E: 20000.0, nu: 0.3, eta: 30000.0)";
const PLASTIC: &str = "Plastic(E: 20000.0, nu: 0.3, sY: 150.0, hardening: Power(n: 0.2), \
                       rate: Norton(K: 400.0, m: 4.0))";

fn source(law: &str, segments: &str) -> ConfigSource {
    ConfigSource::Text {
        text: format!(
            "(specimen: Cylinder(radius: 10.0, height: 10.0, nr: 8, nz: 8, grading_r: 1.3, \
             grading_z: 1.3), punch: Cone(half_angle_deg: 68.0), law: {law}, \
             history: (segments: [{segments}]))"
        ),
        name: "pdotp".into(),
    }
}

/// A trigger ramp to 5 N, constant Pdot/P = 0.5/s to 60 N, a hold, in depth control first
/// to 0.005 mm (an approach), as an instrument runs it.
const PROTOCOL: &str = "(duration: 0.1, depth: 0.005, steps: 2), \
                        (duration: 0.1, force: 5.0, steps: 2), \
                        (force: 60.0, pdot_over_p: 0.5, steps: 6), \
                        (duration: 1.0, force: 60.0, steps: 4)";

#[test]
fn simulate_carries_the_exponential_force() {
    let out = simulate::run(&SimulateOptions::new(source(MAXWELL, PROTOCOL))).unwrap();
    assert!(out.failure.is_none(), "{:?}", out.failure);
    let rows = &out.rows;
    assert_eq!(rows.len(), 15);
    let t_end = 0.2 + 12f64.ln() / 0.5;
    assert!((rows[10].t - t_end).abs() < 1e-12, "{}", rows[10].t);
    for r in &rows[4..=10] {
        let p = 5.0 * (0.5 * (r.t - 0.2)).exp();
        assert!((r.f - p).abs() < 1e-7 * p, "t = {}: {} vs {p}", r.t, r.f);
    }
    // Maxwell creeps under the held load
    assert!(
        rows[14].h > rows[10].h * 1.02,
        "{} {}",
        rows[10].h,
        rows[14].h
    );
}

/// `gradient-check` on the depth cost passes every parameter of Maxwell and of the
/// Plastic law with a Norton rate, over the approach, the trigger, the Pdot/P loading and
/// the hold.
#[test]
fn gradient_check_passes_with_a_pdotp_segment() {
    for law in [MAXWELL, PLASTIC] {
        let r = check::run(&CheckOptions::new(source(law, PROTOCOL))).unwrap();
        assert!(r.j > 0.0);
        for c in &r.checks {
            println!(
                "{law} {}: adjoint {:.10e} fd {:.10e} ({:.1e}) sens ({:.1e})",
                c.name, c.adjoint, c.fd, c.rel_diff_fd, c.rel_diff_sensitivity
            );
            assert!(c.passed, "{law} {}: {:?}", c.name, c.rel_diff_fd);
        }
    }
}

/// Bad constant-Pdot/P segments: the message names the field, the segment and the
/// allowed range; nothing runs.
#[test]
fn bad_pdotp_segments_are_refused_naming_the_field() {
    let trigger = "(duration: 0.1, force: 5.0, steps: 2)";
    for (segments, words) in [
        (
            "(force: 60.0, pdot_over_p: 0.5, steps: 6)".to_string(),
            vec!["history.segments[].pdot_over_p", "segment 0", "P = 0"],
        ),
        (
            "(duration: 0.1, depth: 0.005, steps: 2), (force: 60.0, pdot_over_p: 0.5, steps: 6)"
                .to_string(),
            vec!["history.segments[].pdot_over_p", "segment 1", "trigger"],
        ),
        (
            format!("{trigger}, (force: 60.0, pdot_over_p: 0.0, steps: 6)"),
            vec!["history.segments[].pdot_over_p", "segment 1", "> 0"],
        ),
        (
            format!("{trigger}, (force: 60.0, pdot_over_p: -0.5, steps: 6)"),
            vec!["history.segments[].pdot_over_p", "-0.5"],
        ),
        (
            format!("{trigger}, (force: 4.0, pdot_over_p: 0.5, steps: 6)"),
            vec!["history.segments[].force", "segment 1", "start force 5"],
        ),
        (
            format!("{trigger}, (duration: 2.0, force: 60.0, pdot_over_p: 0.5, steps: 6)"),
            vec!["history.segments[].duration", "follows from the rate"],
        ),
        (
            format!("{trigger}, (depth: 0.1, pdot_over_p: 0.5, steps: 6)"),
            vec!["history.segments[].pdot_over_p", "force"],
        ),
        (
            format!("{trigger}, (force: 60.0, steps: 6)"),
            vec!["history.segments[].duration", "missing"],
        ),
    ] {
        let e = simulate::run(&SimulateOptions::new(source(MAXWELL, &segments))).unwrap_err();
        let text = e.messages().join(": ");
        println!("{text}");
        for w in words {
            assert!(text.contains(w), "{segments}: `{w}` not in {text}");
        }
    }
    // a misspelt field is refused by the parser, naming it
    let e = source(
        MAXWELL,
        &format!("{trigger}, (force: 60.0, pdot_p: 0.5, steps: 6)"),
    )
    .load(&[])
    .unwrap_err();
    let text = e.messages().join(": ");
    println!("{text}");
    assert!(
        text.contains("pdot_p") && text.contains("history.segments"),
        "{text}"
    );
}

/// Norton-Hoff under the cone: a candidate of two constant-Pdot/P rates (0.05/s and
/// 0.5/s, each to 400 N and held 10 s) determines the rate exponent m better than either
/// rate alone and better than one rate with twice the points.
#[test]
fn two_pdotp_rates_pin_m_better_than_one() {
    let test = |r: f64, n: usize| {
        format!(
            "(history: (segments: [(duration: 0.1, force: 10.0, steps: 2), \
             (force: 400.0, pdot_over_p: {r}, steps: {n}), \
             (duration: 10.0, force: 400.0, steps: {n})]))"
        )
    };
    let text = format!(
        "(specimen: Cylinder(radius: 10.0, height: 10.0, nr: 8, nz: 8, grading_r: 1.3, \
         grading_z: 1.3), punch: Cone(half_angle_deg: 68.0), \
         law: NortonHoff(E: 100000.0, nu: 0.3, K: 1500.0, m: 5.0, sY: 500.0), \
         history: (segments: [(duration: 1.0, force: 400.0, steps: 4)]), \
         identify: (params: {{\"E\": Free(lower: 10000.0, upper: 1e6), \
         \"nu\": Fixed(value: 0.3), \"K\": Free(lower: 10.0, upper: 1e5), \
         \"m\": Free(lower: 1.1, upper: 30.0), \"sY\": Free(lower: 1.0, upper: 5000.0)}}, \
         method: Lm), \
         design: (noise: Relative(0.01), depth_noise: Absolute(1e-4), candidates: [\
         (name: \"0.05/s\", tests: [{}]), \
         (name: \"0.5/s\", tests: [{}]), \
         (name: \"0.05/s, twice the points\", tests: [{}]), \
         (name: \"0.05/s and 0.5/s\", tests: [{}, {}])]))",
        test(0.05, 8),
        test(0.5, 8),
        test(0.05, 16),
        test(0.05, 8),
        test(0.5, 8),
    );
    let dsg = design::run(&DesignOptions::new(ConfigSource::Text {
        text,
        name: "design-pdotp".into(),
    }))
    .unwrap();
    println!("{}", dsg.summary());
    let m = |k: usize| {
        dsg.candidates[k]
            .params
            .iter()
            .find(|p| p.name == "m")
            .unwrap()
            .rel_std_dev
    };
    println!("sigma(m)/m: {} / {} / {} / {}", m(0), m(1), m(2), m(3));
    assert!(m(3) < m(0) && m(3) < m(1) && m(3) < m(2), "{dsg:?}");
    assert_eq!(dsg.rank_d[0], 3, "{:?}", dsg.rank_d);
}
