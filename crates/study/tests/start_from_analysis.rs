//! A fit that starts from the Oliver-Pharr analysis of its record (`identify(start=
//! "oliver-pharr")` in Python): on `anon-maxwell.ron` the starts are the free `E` and `eta`
//! (`nu` is held), `E` is `analyze`'s `E_IT` of the same file, and `eta` reproduces the
//! hold's strain rate through the Maxwell flow rule; a configuration without a record is a
//! clear error.

use std::path::Path;

use indentify_study::analyze::{self, AnalyzeOptions};
use indentify_study::start_from_analysis::starts;
use indentify_study::{ConfigSource, ErrorKind};

#[test]
fn anon_maxwell_starts_from_its_analysis() {
    let ex = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples");
    let s = starts(
        &ConfigSource::Path(ex.join("real/anon-maxwell.ron")),
        &[],
        None,
    )
    .unwrap();
    let names: Vec<&str> = s.starts.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["E", "eta"]);
    let a = analyze::run(&AnalyzeOptions::new(
        ex.join("data/anton-paar-unht-berkovich/anonNI.TXT"),
    ))
    .unwrap();
    let e = a.tests[0].values.e.unwrap();
    assert!(
        (s.starts[0].1 - e).abs() <= 1e-12 * e,
        "{} vs {e}",
        s.starts[0].1
    );
    // eta = 2 sigma_r / (3 eps'), sigma_r = H / 3
    let rate = s.guess.op.strain_rate.unwrap();
    let sigma = s.guess.op.h / 3.0;
    let eta = s.starts[1].1;
    assert!((2.0 * sigma / (3.0 * eta) / rate - 1.0).abs() < 1e-12);
}

#[test]
fn a_configuration_without_a_record_is_an_error() {
    let e = starts(&ConfigSource::Default, &[], None).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Config);
    assert!(e.to_string().contains("no `data` record"), "{e}");
}
