//! `batch --analyze` against closed forms: a map of synthetic elastic indents (Sneddon's cone,
//! `F = (2/pi) E_r tan(theta) h^2` on loading and unloading, a known `E` that varies over the
//! map) gives back each indent's `E` and `H = F_max / (pi (h_c tan theta)^2)` with
//! `h_c = 2 h_max / pi`; the CSV and the H and E maps (units, positions in mm) are written;
//! an indent without unloading and one with a missing file carry their reasons and the
//! others are analysed; the results do not depend on the thread count.

use std::f64::consts::PI;
use std::path::Path;

use indentify_analysis::calibrate::reduced_modulus;
use indentify_analysis::{AreaFunction, Tip};
use indentify_study::batch_analysis::{self, BatchAnalysisOptions};

const HALF_ANGLE: f64 = 70.3;

fn tip() -> Tip {
    Tip::diamond(AreaFunction::Cone {
        half_angle_deg: HALF_ANGLE,
    })
}

/// Sneddon's cone to `h_max` (mm) and back, `E` in MPa; internal units (s, mm, N).
fn sneddon_csv(e: f64, nu: f64, h_max: f64, unload: bool) -> String {
    let er = reduced_modulus(e, nu, &tip());
    let tan = HALF_ANGLE.to_radians().tan();
    let mut s = String::from("t,h,F\n");
    let n = if unload { 200 } else { 100 };
    for i in 0..=n {
        let h = h_max * (1.0 - (i as f64 - 100.0).abs() / 100.0);
        let f = 2.0 / PI * er * tan * h * h;
        s.push_str(&format!("{},{h:e},{f:e}\n", i as f64));
    }
    s
}

fn modulus_at(i: usize, j: usize) -> f64 {
    // 50 to 120 GPa over the map
    50e3 + 10e3 * i as f64 + 3e3 * j as f64
}

fn write_map(dir: &Path) -> std::path::PathBuf {
    let mut manifest = String::from("id,data,x,y\n");
    for i in 0..5 {
        for j in 0..4 {
            let id = format!("i{i}-{j}");
            std::fs::write(
                dir.join(format!("{id}.csv")),
                sneddon_csv(modulus_at(i, j), 0.25, 1e-3 * (1.0 + 0.1 * j as f64), true),
            )
            .unwrap();
            manifest.push_str(&format!(
                "{id},{id}.csv,{},{}\n",
                0.01 * i as f64,
                0.01 * j as f64
            ));
        }
    }
    std::fs::write(
        dir.join("loading.csv"),
        sneddon_csv(70e3, 0.25, 1e-3, false),
    )
    .unwrap();
    manifest.push_str("loading,loading.csv,0.05,0\nmissing,nowhere.csv,0.05,0.01\n");
    let p = dir.join("manifest.csv");
    std::fs::write(&p, manifest).unwrap();
    p
}

#[test]
fn a_map_of_sneddon_cones_gives_back_e_and_h() {
    let tmp = tempfile::tempdir().unwrap();
    let manifest = write_map(tmp.path());
    let out = tmp.path().join("out");
    let mut o = BatchAnalysisOptions::new(&manifest, &out);
    o.tip = tip();
    o.nu = 0.25;
    o.jobs = 2;
    let r = batch_analysis::run(&o).unwrap();
    assert_eq!(r.indents.len(), 22);
    assert_eq!((r.analysed, r.failed), (20, 2));
    let tan = HALF_ANGLE.to_radians().tan();
    for a in &r.indents[..20] {
        let (i, j) = (
            a.id[1..2].parse::<usize>().unwrap(),
            a.id[3..4].parse::<usize>().unwrap(),
        );
        let e = modulus_at(i, j);
        let got = a.values.e.unwrap();
        assert!((got / e - 1.0).abs() < 1e-4, "{}: E {got} vs {e}", a.id);
        let h_max = 1e-3 * (1.0 + 0.1 * j as f64);
        let hc = 2.0 * h_max / PI;
        let f_max = 2.0 / PI * reduced_modulus(e, 0.25, &tip()) * tan * h_max * h_max;
        let h = f_max / (PI * (hc * tan).powi(2));
        assert!(
            (a.values.h.unwrap() / h - 1.0).abs() < 1e-4,
            "{}: H {:?} vs {h}",
            a.id,
            a.values.h
        );
        assert!((a.m.unwrap() - 2.0).abs() < 1e-4);
    }
    let loading = &r.indents[20];
    assert!(
        loading.values.e.is_none() && loading.error.is_some(),
        "{loading:?}"
    );
    let missing = r.indents[21].error.as_deref().unwrap();
    assert!(missing.contains("nowhere.csv"), "{missing}");
    // the files
    let csv = std::fs::read_to_string(out.join("analysis.csv")).unwrap();
    assert_eq!(csv.lines().count(), 23);
    assert!(csv.starts_with("id,x_mm,y_mm,"));
    assert!(csv.lines().nth(1).unwrap().starts_with("i0-0,0,0,"));
    for stem in ["H_IT_map", "E_IT_map", "H_IT_hist", "E_IT_hist"] {
        let svg = std::fs::read_to_string(out.join(format!("maps/{stem}.svg"))).unwrap();
        assert!(svg.contains("(GPa)"), "{stem}");
        if stem.ends_with("map") {
            assert!(svg.contains("x [mm]") && svg.contains("y [mm]"), "{stem}");
        }
    }
    // one thread gives the same rows
    let out1 = tmp.path().join("out1");
    let mut o1 = o.clone();
    o1.out = out1.clone();
    o1.jobs = 1;
    let r1 = batch_analysis::run(&o1).unwrap();
    assert_eq!(r1.indents, r.indents);
    assert_eq!(
        std::fs::read_to_string(out1.join("analysis.csv")).unwrap(),
        csv
    );
}

#[test]
fn a_bad_manifest_names_the_line() {
    let tmp = tempfile::tempdir().unwrap();
    let p = tmp.path().join("m.csv");
    std::fs::write(&p, "id,data\na,a.csv\na,b.csv\n").unwrap();
    let e = batch_analysis::run(&BatchAnalysisOptions::new(&p, tmp.path().join("o")))
        .unwrap_err()
        .to_string();
    assert!(e.contains("m.csv") && e.contains("used twice"), "{e}");
}
