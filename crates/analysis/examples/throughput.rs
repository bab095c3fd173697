//! Throughput of the analysis: 10,000 synthetic indents (load 200 samples, 10 s hold at
//! 10 Hz, power-law unloading 200 samples, moduli and exponents varied), analysed on 1 and
//! 2 threads (fixed chunks, results in indent order). Run with
//! `cargo run --release -p indentify-analysis --example throughput`.

use std::time::Instant;

use indentify_analysis::{Options, Tip, analyze};
use indentify_records::{Format, Record};

fn indent(k: usize) -> Record {
    let f_max = 10e-3 * (1.0 + 0.3 * ((k * 7919) % 100) as f64 / 100.0);
    let m = 1.2 + 0.5 * ((k * 104_729) % 100) as f64 / 100.0;
    let h_load = 1e-3 * (f_max / 10e-3).sqrt();
    let (mut t, mut h, mut f) = (Vec::new(), Vec::new(), Vec::new());
    for i in 0..=200 {
        let x = h_load * i as f64 / 200.0;
        t.push(i as f64 * 0.1);
        h.push(x);
        f.push(f_max * (x / h_load).powi(2));
    }
    let mut h_max = h_load;
    for i in 1..=100 {
        t.push(20.0 + i as f64 * 0.1);
        h_max = h_load * (1.0 + 0.01 * (1.0 + i as f64).ln());
        h.push(h_max);
        f.push(f_max);
    }
    let h_f = 0.7 * h_max;
    let alpha = f_max / (h_max - h_f).powf(m);
    for i in 1..=200 {
        t.push(30.0 + i as f64 * 0.1);
        let x = h_max - (h_max - h_f) * i as f64 / 200.0;
        h.push(x);
        f.push(alpha * (x - h_f).max(0.0).powf(m));
    }
    Record {
        name: format!("indent {k}"),
        t,
        h,
        f,
        segment: None,
        meta: Default::default(),
    }
}

fn main() {
    let n = 10_000;
    let records: Vec<Record> = (0..n).map(indent).collect();
    let o = Options::new(Tip::berkovich(), Format::Csv);
    for threads in [1usize, 2] {
        let start = Instant::now();
        let chunk = n.div_ceil(threads);
        let results: Vec<f64> = std::thread::scope(|s| {
            let handles: Vec<_> = records
                .chunks(chunk)
                .map(|c| {
                    let o = &o;
                    s.spawn(move || {
                        c.iter()
                            .map(|r| {
                                analyze(r, o)
                                    .ok()
                                    .and_then(|a| a.values().map(|(_, op)| op.hardness))
                                    .unwrap_or(f64::NAN)
                            })
                            .collect::<Vec<f64>>()
                    })
                })
                .collect();
            handles
                .into_iter()
                .flat_map(|h| h.join().unwrap_or_default())
                .collect()
        });
        let ok = results.iter().filter(|v| v.is_finite()).count();
        println!(
            "{n} indents, {threads} thread(s): {:.2} s, {ok} analysed",
            start.elapsed().as_secs_f64()
        );
    }
}
