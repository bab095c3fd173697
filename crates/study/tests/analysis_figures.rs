//! The figures of `indentify analyze --out DIR`: on the Anton Paar sphere file (4 tests, one
//! unloading each) every test's unloading figure exists and carries the fitted numbers (its
//! `E` it shows within 0.2 % of the vendor's own `EIT (O&P)`), the H and E against depth
//! figures exist; on a multi-cycle KLA test every analysed unloading is a point.

use std::path::PathBuf;

use indentify_analysis::{AreaFunction, Epsilon, Tip};
use indentify_study::analyze::{self, AnalyzeOptions};
use indentify_study::format::sig;

fn data(p: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples/data")
        .join(p)
}

#[test]
fn unloading_figures_carry_the_fitted_numbers() {
    let tmp = tempfile::tempdir().unwrap();
    let o = AnalyzeOptions {
        tip: Tip::diamond(AreaFunction::Sphere { radius: 1e-2 }),
        epsilon: Epsilon::FromM,
        out: Some(tmp.path().to_path_buf()),
        ..AnalyzeOptions::new(data("anton-paar-sphere-creep/HT_V_100mN.TXT"))
    };
    let out = analyze::run(&o).unwrap();
    assert_eq!(out.tests.len(), 4);
    let fig = tmp.path().join("figures");
    for t in &out.tests {
        let p = fig.join(format!("unloading-{}.svg", t.index));
        let svg = std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        assert!(out.written.contains(&p.display().to_string()));
        let (u, op) = t.analysis.as_ref().unwrap().values().unwrap();
        let f = u.fit.as_ref().unwrap();
        for number in [
            format!("m = {}", sig(f.m, 4)),
            format!("h_f = {} nm", sig(f.h_f * 1e6, 5)),
            format!("S = {} mN/nm", sig(op.s * 1e-3, 4)),
            format!("E = {} GPa", sig(op.e.unwrap() * 1e-3, 4)),
        ] {
            assert!(svg.contains(&number), "{}: no `{number}`", p.display());
        }
        // the vendor's own E_IT (GPa), as printed with 4 digits
        let vendor = t
            .vendor
            .iter()
            .find(|q| q.name == "EIT (O&P)")
            .unwrap()
            .value;
        let shown: f64 = svg
            .split(", E = ")
            .nth(1)
            .and_then(|r| r.split(" GPa").next())
            .and_then(|v| v.trim().parse().ok())
            .unwrap_or_else(|| panic!("{}: no E shown", p.display()));
        assert!(
            (shown / vendor - 1.0).abs() < 2e-3,
            "{}: shown E {shown} GPa, vendor {vendor}",
            p.display()
        );
        assert!(svg.contains("power-law fit (fitted range)"));
    }
    for stem in ["hardness_depth", "modulus_depth"] {
        let svg = std::fs::read_to_string(fig.join(format!("{stem}.svg"))).unwrap();
        assert!(svg.contains("4 unloadings of 4 tests"), "{stem}");
        assert!(svg.contains("contact depth h_c [nm]"));
    }
    // no temporary files left behind
    for e in std::fs::read_dir(&fig).unwrap() {
        let name = e.unwrap().file_name().to_string_lossy().into_owned();
        assert!(name.ends_with(".svg"), "{name}");
    }
}

#[test]
fn a_multi_cycle_test_gives_a_point_per_unloading() {
    let tmp = tempfile::tempdir().unwrap();
    let o = AnalyzeOptions {
        test: Some(2),
        nu: 0.179,
        out: Some(tmp.path().to_path_buf()),
        ..AnalyzeOptions::new(data("kla-fused-silica/FusedSilica.xlsx"))
    };
    let out = analyze::run(&o).unwrap();
    let a = out.tests[0].analysis.as_ref().unwrap();
    let n = a.unloadings.iter().filter(|u| u.op.is_some()).count();
    assert!(n >= 5, "{n} analysed unloadings");
    let svg = std::fs::read_to_string(tmp.path().join("figures/modulus_depth.svg")).unwrap();
    assert!(svg.contains(&format!("{n} unloadings of 1 tests")), "{n}");
    assert!(tmp.path().join("figures/unloading-2.svg").is_file());
}
