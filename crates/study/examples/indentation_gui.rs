//! A comparison with indentationGUI (micromechanics, MIT), printed, not asserted: its example
//! 1 is the same `FusedSilica.xlsx` as examples/data/kla-fused-silica (byte for byte; git blob
//! 93da809), and its repository published the tab "H and E" output for it
//! (`FusedSilica_tabHE_output.xlsx`, commit eedc217): per test the largest `h_c` and the mean
//! H and E over the unloadings with `h_c` in 0.1 to 2 µm, with the ideal Berkovich (`C0`
//! 24.5), no frame compliance, `nu` 0.179, a diamond tip (1141 GPa, 0.07) and the stiffness
//! fitted from 98 % to 50 % of `P_max`. This runs the same settings with both of our zero
//! points (the contact detected on the force, the default for KLA files, and the file's own
//! `Surface Index`) and prints the three side by side; docs/analysis.md ("Against
//! indentationGUI") says why they differ. Run with
//! `cargo run -p indentify-study --example indentation_gui`.

use std::path::PathBuf;

use indentify_analysis::{FitRange, Tip};
use indentify_study::analyze::{self, AnalyzeOptions};

/// indentationGUI's (test name, largest h_c µm, mean H GPa, mean E GPa), 6 digits.
const GUI: [(&str, f64, f64, f64); 12] = [
    ("Test 1", 0.433853, 10.0992, 76.5624),
    ("Test 2", 0.444809, 9.69056, 73.1789),
    ("Test 3", 0.457342, 8.68517, 69.3710),
    ("Test 4", 0.459804, 8.52388, 68.7050),
    ("Test 5", 0.455741, 8.79134, 70.2998),
    ("Test 6", 0.459005, 8.73342, 68.8819),
    ("Test 7", 0.456414, 8.77946, 70.5188),
    ("Test 8", 0.458778, 8.68894, 69.6886),
    ("Test 9", 0.452162, 9.28683, 71.4151),
    ("Test 10", 0.457007, 8.82195, 70.4258),
    ("Test 11", 0.455109, 8.97793, 70.4912),
    ("Test 12", 0.455179, 8.99613, 70.6676),
];

/// Per test: (largest h_c µm, mean H GPa, mean E GPa, unloadings averaged, H and E GPa of
/// the deepest unloading).
type Row = (String, f64, f64, f64, usize, f64, f64);

fn ours(zero_point: bool) -> Vec<Row> {
    let file = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples/data/kla-fused-silica/FusedSilica.xlsx");
    let mut tip = Tip::berkovich();
    tip.frame_compliance = Some(0.0);
    let o = AnalyzeOptions {
        tip,
        nu: 0.179,
        fit_range: Some(FitRange {
            lower: 0.5,
            upper: 0.98,
        }),
        zero_point: Some(zero_point),
        ..AnalyzeOptions::new(file)
    };
    let out = analyze::run(&o).expect("the workbook analyses");
    out.tests
        .iter()
        .map(|t| {
            let (mut hc, mut h, mut e, mut n) = (0.0f64, 0.0, 0.0, 0);
            let (mut h_deep, mut e_deep) = (f64::NAN, f64::NAN);
            for u in t.analysis.iter().flat_map(|a| &a.unloadings) {
                let Some(op) = &u.op else { continue };
                if op.hc * 1e3 > hc {
                    hc = op.hc * 1e3;
                    h_deep = op.hardness * 1e-3;
                    e_deep = op.e.unwrap_or(f64::NAN) * 1e-3;
                }
                if (1e-4..=2e-3).contains(&op.hc) {
                    h += op.hardness * 1e-3;
                    e += op.e.unwrap_or(f64::NAN) * 1e-3;
                    n += 1;
                }
            }
            (
                t.test.clone(),
                hc,
                h / n as f64,
                e / n as f64,
                n,
                h_deep,
                e_deep,
            )
        })
        .collect()
}

fn main() {
    let detected = ours(true);
    let file_zero = ours(false);
    println!(
        "test      | indentationGUI: hc_max um, mean H, E GPa | ours, contact on the force: hc_max, mean H, E (n); deepest H, E | ours, file's Surface Index: the same"
    );
    for (name, hc, h, e) in GUI {
        let a = detected.iter().find(|t| t.0 == name);
        let b = file_zero.iter().find(|t| t.0 == name);
        let show = |t: Option<&Row>| {
            t.map_or("-".to_string(), |t| {
                format!(
                    "{:.3}, {:.2}, {:.1} ({}); deepest {:.2}, {:.1}",
                    t.1, t.2, t.3, t.4, t.5, t.6
                )
            })
        };
        println!(
            "{name:9} | {hc:.3}, {h:.2}, {e:.1} | {} | {}",
            show(a),
            show(b)
        );
    }
}
