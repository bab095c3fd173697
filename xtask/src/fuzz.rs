//! `cargo xtask fuzz-readers [--cases N] [--seed S]`: feeds `indentify_study::records::read`,
//! `read_results` and `apply` with random bytes and mutated real files (examples/data) in release and checks
//! that nothing panics; prints the count, the time and what the inputs read as.

use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use indentify_study::records::fuzzing::{FORMATS, Mutation, mutate};
use indentify_study::records::{
    Control, Correction, Format, Preprocessing, ReadOptions, Resample, Segments, ZeroPoint, apply,
    read,
};

/// xorshift64*: small, deterministic, good enough to pick mutations.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    /// Uniform in `0..n` (0 when `n` is 0).
    fn below(&mut self, n: usize) -> usize {
        if n == 0 {
            0
        } else {
            (self.next() % n as u64) as usize
        }
    }
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    fn chance(&mut self, p: f64) -> bool {
        self.unit() < p
    }
}

/// One random mutation of the shared set (`indentify_study::records::fuzzing`).
fn mutation(rng: &mut Rng) -> Mutation {
    let (x, y, z) = (
        rng.next() as usize,
        rng.next() as usize,
        rng.next() as usize,
    );
    match rng.below(7) {
        0 => Mutation::Flip {
            at: x,
            byte: y as u8,
        },
        1 => Mutation::Truncate { at: x },
        2 => Mutation::DuplicateLine { line: x },
        3 => Mutation::DeleteLine { line: x },
        4 => Mutation::Insert { at: x, token: y },
        5 => Mutation::SwapColumns {
            line: x,
            a: y,
            b: z,
        },
        _ => Mutation::Hugify { at: x, which: y },
    }
}

fn options(rng: &mut Rng) -> Preprocessing {
    let correction = |rng: &mut Rng| match rng.below(5) {
        0 => Correction::Off,
        1 => Correction::Auto,
        2 => Correction::FromFile,
        3 => Correction::Value(f64::from_bits(rng.next())),
        _ => Correction::Value((rng.unit() - 0.5) * 2e-3),
    };
    let drift = correction(rng);
    let compliance = correction(rng);
    Preprocessing {
        drift,
        compliance,
        zero_point: rng.chance(0.8).then(|| ZeroPoint {
            fraction: rng.unit() * 1.2 - 0.1,
            threshold: rng.chance(0.2).then(|| rng.unit() * 1e-2 - 1e-3),
            noise_band: rng.unit() * 10.0 - 1.0,
            trim: rng.chance(0.8),
            // the stiffness contact, sometimes, with values outside its range too
            stiffness: rng.chance(0.2).then(|| rng.unit() * 3.0 - 0.5),
        }),
        segments: rng.chance(0.8).then(|| Segments {
            control: [Control::Auto, Control::Load, Control::Depth][rng.below(3)],
            tolerance: rng.unit() * 0.6 - 0.05,
            min_hold: rng.unit() * 10.0 - 1.0,
        }),
        resample: rng.chance(0.7).then(|| Resample {
            n: rng.below(800),
            min_per_segment: rng.below(20),
        }),
    }
}

fn head(b: &[u8], n: usize) -> Vec<u8> {
    b.split_inclusive(|&c| c == b'\n')
        .take(n)
        .flatten()
        .copied()
        .collect()
}

/// The seeds with their weights: the real files (the KLA workbook and a small hand-made one too) (the 1.3 MB multi-test file mostly
/// as its first 600 lines), and a file as `indentify simulate` writes it.
fn seeds(root: &Path) -> Result<Vec<(String, Vec<u8>, u32)>> {
    let data = root.join("examples/data");
    let load =
        |p: &str| std::fs::read(data.join(p)).with_context(|| format!("reading examples/data/{p}"));
    let multi = load("anton-paar-sphere-creep/HT_V_100mN.TXT")?;
    Ok(vec![
        ("anonNI.TXT".into(), load("anton-paar-unht-berkovich/anonNI.TXT")?, 20),
        ("HT_V_100mN.TXT (600 lines)".into(), head(&multi, 600), 20),
        ("HT_V_100mN.TXT".into(), multi, 1),
        ("HT_V_100mN_data.TXT".into(), load("anton-paar-sphere-creep/HT_V_100mN_data.TXT")?, 5),
        ("RobinSteel0000LC.txt".into(), load("hysitron/RobinSteel0000LC.txt")?, 15),
        ("Exp-50mN_0000.hld".into(), load("hysitron/Exp-50mN_0000.hld")?, 20),
        ("two-tests.xlsx".into(), std::fs::read(root.join("crates/records/tests/data/two-tests.xlsx")).context("reading crates/records/tests/data/two-tests.xlsx")?, 10),
        ("FusedSilica.xlsx".into(), load("kla-fused-silica/FusedSilica.xlsx")?, 1),
        (
            "simulate.csv".into(),
            b"t,h,F,a\n0,0,0,0\n0.5,0.001,0.02,0.01\n1,0.002,0.05,0.02\n1.5,0.0015,0.01,0.02\n2,0.001,0,0.01\n".to_vec(),
            10,
        ),
    ])
}

/// Runs the fuzzer; `args` are `--cases N` (default 100 000) and `--seed S`.
pub fn run(args: &[String]) -> Result<()> {
    let mut cases: usize = 100_000;
    let mut seed: u64 = 0x1D_E17F;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut val = || it.next().cloned().unwrap_or_default();
        match a.as_str() {
            "--cases" => cases = val().parse().context("--cases N")?,
            "--seed" => seed = val().parse().context("--seed S")?,
            other => bail!("unknown option {other} (fuzz-readers [--cases N] [--seed S])"),
        }
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_default();
    let seeds = seeds(&root)?;
    let total_weight: u32 = seeds.iter().map(|s| s.2).sum();
    let mut rng = Rng(seed | 1);
    let mut outcome: BTreeMap<String, usize> = BTreeMap::new();
    let (mut records, mut applied, mut bytes_total) = (0usize, 0usize, 0usize);
    let mut panics = Vec::new();
    let start = Instant::now();
    for case in 0..cases {
        let input: Vec<u8> = if rng.chance(0.15) {
            let n = rng.below(3000);
            (0..n).map(|_| rng.next() as u8).collect()
        } else {
            let mut w = rng.below(total_weight as usize) as u32;
            let mut b = Vec::new();
            for (_, s, weight) in &seeds {
                if w < *weight {
                    b = s.clone();
                    break;
                }
                w -= weight;
            }
            let k = rng.below(4);
            for _ in 0..k {
                let m = mutation(&mut rng);
                b = mutate(b, &m);
            }
            b
        };
        bytes_total += input.len();
        let opts = ReadOptions {
            format: if rng.chance(0.5) {
                Format::Auto
            } else {
                FORMATS[rng.below(FORMATS.len())]
            },
            test: rng.chance(0.15).then(|| rng.below(6)),
        };
        let p = options(&mut rng);
        let result = std::panic::catch_unwind(|| {
            let mut n = (0, 0);
            let _ = indentify_study::records::read_results(&input, "fuzz");
            let read = read(&input, "fuzz", &opts);
            let key = match &read {
                Ok(_) => "read ok".to_owned(),
                Err(e) => format!("read error {:?}", e.kind),
            };
            if let Ok(rs) = read {
                for r in rs {
                    n.0 += 1;
                    if apply(&r, &p).is_ok() {
                        n.1 += 1;
                    }
                }
            }
            (key, n)
        });
        match result {
            Ok((key, (r, a))) => {
                *outcome.entry(key).or_default() += 1;
                records += r;
                applied += a;
            }
            Err(_) => {
                let dir = root.join("target/fuzz-readers");
                std::fs::create_dir_all(&dir)?;
                let path = dir.join(format!("panic-{case}.bin"));
                std::fs::write(&path, &input)?;
                eprintln!(
                    "case {case}: panic with {opts:?} {p:?}; input saved to {}",
                    path.display()
                );
                panics.push(case);
            }
        }
    }
    let secs = start.elapsed().as_secs_f64();
    println!(
        "fuzz-readers: {cases} inputs ({:.1} MB) in {secs:.1} s ({:.0} inputs/s), seed {seed}",
        bytes_total as f64 / 1e6,
        cases as f64 / secs.max(1e-9)
    );
    for (k, n) in &outcome {
        println!("  {k}: {n}");
    }
    println!("  records read: {records}, preprocessed without error: {applied}");
    println!("  panics: {}", panics.len());
    if !panics.is_empty() {
        bail!(
            "{} inputs panicked (saved in target/fuzz-readers)",
            panics.len()
        );
    }
    Ok(())
}
