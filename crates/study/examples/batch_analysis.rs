//! Throughput of `indentify batch --analyze`: writes 10,000 synthetic elastic indents
//! (Sneddon's cone, `F = (2/pi) E_r tan(theta) h^2` loaded and unloaded over 201 samples, a
//! known `E` from 50 to 150 GPa over a 100 x 100 map) as CSV files with a manifest into a
//! temporary folder, then runs the whole pipeline (read, preprocess, analyse, analysis.csv,
//! H and E maps) on 1 and 2 threads and checks every `E` against the known one. Run with
//! `cargo run --release -p indentify-study --example batch_analysis [N]`.

use std::f64::consts::PI;
use std::time::Instant;

use indentify_analysis::calibrate::reduced_modulus;
use indentify_analysis::{AreaFunction, Tip};
use indentify_study::batch_analysis::{self, BatchAnalysisOptions};

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(10_000);
    let side = (n as f64).sqrt().ceil() as usize;
    let tip = Tip::diamond(AreaFunction::Cone {
        half_angle_deg: 70.3,
    });
    let tan = 70.3f64.to_radians().tan();
    let tmp = tempfile::tempdir().expect("a temporary folder");
    let dir = tmp.path();
    let modulus = |k: usize| 50e3 + 100e3 * (k as f64) / (n as f64);
    let start = Instant::now();
    let mut manifest = String::from("id,data,x,y\n");
    for k in 0..n {
        let er = reduced_modulus(modulus(k), 0.3, &tip);
        let h_max = 1e-3 * (1.0 + 0.5 * ((k * 7919) % 100) as f64 / 100.0);
        let mut s = String::from("t,h,F\n");
        for i in 0..=200 {
            let h = h_max * (1.0 - (i as f64 - 100.0).abs() / 100.0);
            s.push_str(&format!(
                "{i},{h:.9e},{:.9e}\n",
                2.0 / PI * er * tan * h * h
            ));
        }
        std::fs::write(dir.join(format!("{k}.csv")), s).expect("writing an indent");
        manifest.push_str(&format!(
            "i{k},{k}.csv,{},{}\n",
            0.01 * (k % side) as f64,
            0.01 * (k / side) as f64
        ));
    }
    let path = dir.join("manifest.csv");
    std::fs::write(&path, manifest).expect("writing the manifest");
    println!(
        "{n} indents written in {:.2} s",
        start.elapsed().as_secs_f64()
    );
    for jobs in [1usize, 2] {
        let mut o = BatchAnalysisOptions::new(&path, dir.join(format!("out{jobs}")));
        o.tip = tip.clone();
        o.jobs = jobs;
        let t = Instant::now();
        let r = batch_analysis::run(&o).expect("the batch analysis");
        let wall = t.elapsed().as_secs_f64();
        let worst = r
            .indents
            .iter()
            .enumerate()
            .map(|(k, a)| {
                a.values
                    .e
                    .map_or(f64::INFINITY, |e| (e / modulus(k) - 1.0).abs())
            })
            .fold(0.0, f64::max);
        println!(
            "{jobs} thread(s): {wall:.2} s wall ({:.2} ms per indent), {} analysed, {} failed, \
             largest relative error of E {worst:.2e}, {} files written",
            1e3 * wall / n as f64,
            r.analysed,
            r.failed,
            r.written.len()
        );
    }
}
