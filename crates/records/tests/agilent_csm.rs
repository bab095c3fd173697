//! The CSM stiffness of micromechanics' `FS_Calibration.xls` (examples/data, MIT), read
//! straight from the workbook with `calamine`: the KLA reader does not read the
//! `Harmonic Contact Stiffness` column, and this test measures how far the CSM stiffness at
//! the deepest sample and micromechanics' pinned area function (25.99, 305.70, 2050.70,
//! nm-based, E 72 GPa, nu 0.18) lie from each other without a frame compliance
//! (docs/analysis.md, "Against micromechanics' Agilent calibration").

use std::io::Cursor;

use calamine::{Data, Reader, open_workbook_auto_from_rs};

const XLS: &[u8] =
    include_bytes!("../../../examples/data/agilent-fs-calibration/FS_Calibration.xls");

/// micromechanics' area function, `A` nm² at `hc` nm.
fn micromechanics_area(hc: f64) -> f64 {
    25.99088100777346 * hc * hc + 305.6978416681741 * hc + 2050.70109154738 * hc.sqrt()
}

fn number(c: &Data) -> f64 {
    match c {
        Data::Float(x) => *x,
        Data::Int(x) => *x as f64,
        _ => f64::NAN,
    }
}

#[test]
fn the_csm_stiffness_at_the_deepest_sample_against_micromechanics_area() {
    let mut wb = open_workbook_auto_from_rs(Cursor::new(XLS)).unwrap();
    // reduced modulus of fused silica (72 GPa, 0.18) under diamond (1141 GPa, 0.07), GPa
    let er = 1.0 / ((1.0 - 0.18f64 * 0.18) / 72.0 + (1.0 - 0.07f64 * 0.07) / 1141.0);
    let mut ratios = Vec::new();
    for k in 1..=16 {
        let r = wb.worksheet_range(&format!("Test {k:03}")).unwrap();
        let rows: Vec<_> = r.rows().collect();
        let names: Vec<String> = rows[0].iter().map(|c| c.to_string()).collect();
        let units: Vec<String> = rows[1].iter().map(|c| c.to_string()).collect();
        let col = |s: &str| names.iter().position(|n| n == s).unwrap();
        let (cs, ch, cp) = (
            col("Harmonic Contact Stiffness"),
            col("Displacement Into Surface"),
            col("Load On Sample"),
        );
        assert_eq!((&*units[cs], &*units[ch], &*units[cp]), ("N/m", "nm", "mN"));
        // the deepest sample with a stiffness (the hold's samples carry a sentinel)
        let (mut s, mut h, mut p) = (0.0, 0.0, 0.0);
        for row in &rows[2..] {
            let (si, hi, pi) = (number(&row[cs]), number(&row[ch]), number(&row[cp]));
            if si > 0.0 && si < 1e9 && hi > h {
                (s, h, p) = (si * 1e-3, hi, pi); // mN/µm, nm, mN
            }
        }
        let hc = h - 0.75 * p / s * 1e3; // nm
        let a = std::f64::consts::PI / 4.0 * (s / er).powi(2); // µm²
        ratios.push(a / (micromechanics_area(hc) * 1e-6));
        assert!((500.0..600.0).contains(&s), "test {k}: S {s} mN/µm");
    }
    let mean = ratios.iter().sum::<f64>() / ratios.len() as f64;
    let (lo, hi) = ratios
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), &r| (a.min(r), b.max(r)));
    println!(
        "CSM area / micromechanics' area at the deepest sample: mean {mean:.4}, {lo:.4} to {hi:.4}"
    );
    // measured 0.973 (0.942 to 1.039 per test)
    assert!((0.95..0.99).contains(&mean), "mean ratio {mean}");
}
