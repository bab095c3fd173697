//! A fast subset of `cargo xtask fuzz-configs`: mutated configurations and random `--set`
//! overrides through loading, set-up and simulation, with no panic and no non-finite force.

#[test]
fn mutated_configurations_never_panic() {
    let c = indentify_study::fuzzing::run(1, 300);
    assert_eq!(c.panics, 0, "{c:?}");
    assert_eq!(c.non_finite, 0, "{c:?}");
    // the mutations exercise both refusals and runs
    assert!(c.config_errors > 30 && c.simulated > 30, "{c:?}");
}
