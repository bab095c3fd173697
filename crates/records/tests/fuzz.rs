//! Fuzzing the readers and the preprocessing with proptest: random bytes, mutated real files
//! (byte flips, truncations, duplicated or deleted lines, inserted NaN/inf/huge numbers,
//! swapped columns) and random records must give a value or an error, never a panic.
//! A few thousand cases here; `cargo xtask fuzz-readers` runs 100 000+ in release.

use indentify_records::{
    Control, Correction, Format, Preprocessing, ReadOptions, Record, Resample, Segments, ZeroPoint,
    apply, read,
};
use proptest::prelude::*;
use proptest::sample::Index;

const ANON: &[u8] = include_bytes!("../../../examples/data/anton-paar-unht-berkovich/anonNI.TXT");
const MULTI: &[u8] =
    include_bytes!("../../../examples/data/anton-paar-sphere-creep/HT_V_100mN.TXT");
const ROBIN: &[u8] = include_bytes!("../../../examples/data/hysitron/RobinSteel0000LC.txt");
const HLD: &[u8] = include_bytes!("../../../examples/data/hysitron/Exp-50mN_0000.hld");
const SIM: &[u8] =
    b"t,h,F,a\n0,0,0,0\n0.5,0.001,0.02,0.01\n1,0.002,0.05,0.02\n1.5,0.0015,0.01,0.02\n";

/// The first `n` lines of a file (keeps the debug-mode suite fast on the big files).
fn head(bytes: &[u8], n: usize) -> Vec<u8> {
    let mut out = Vec::new();
    for line in bytes.split_inclusive(|&b| b == b'\n').take(n) {
        out.extend_from_slice(line);
    }
    out
}

fn seeds() -> Vec<Vec<u8>> {
    // the Hysitron text export declares its point count: 400 lines are 394 rows (2 blank)
    let mut robin = head(ROBIN, 400);
    if let Some(k) = robin.windows(4).position(|w| w == b"5304") {
        robin.splice(k..k + 4, *b"394 ");
    }
    vec![
        ANON.to_vec(),
        head(MULTI, 400),
        robin,
        HLD.to_vec(),
        SIM.to_vec(),
    ]
}

const TOKENS: &[&[u8]] = &[
    b"NaN",
    b"inf",
    b"-inf",
    b"1e308",
    b"-1e308",
    b"9e999",
    b"",
    b"\t",
    b",",
    b";",
    b"\r",
    b"\n",
    b"\xB5",
    b"\xC2\xB5",
    b"0,5",
    b"x",
    b"(nm)",
    b"[s]",
    b"Number of Points = 7",
    b"Test Data Points: 3",
    b"Measured values",
    b"X_a_Time_[s]",
];

#[derive(Debug, Clone)]
enum Mutation {
    Flip(Index, u8),
    Truncate(Index),
    DuplicateLine(Index),
    DeleteLine(Index),
    Insert(Index, usize),
    SwapColumns(Index, Index, Index),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (any::<Index>(), any::<u8>()).prop_map(|(i, b)| Mutation::Flip(i, b)),
        any::<Index>().prop_map(Mutation::Truncate),
        any::<Index>().prop_map(Mutation::DuplicateLine),
        any::<Index>().prop_map(Mutation::DeleteLine),
        (any::<Index>(), 0..TOKENS.len()).prop_map(|(i, t)| Mutation::Insert(i, t)),
        (any::<Index>(), any::<Index>(), any::<Index>())
            .prop_map(|(l, a, b)| Mutation::SwapColumns(l, a, b)),
    ]
}

fn line_spans(b: &[u8]) -> Vec<(usize, usize)> {
    let mut v = Vec::new();
    let mut s = 0;
    for (i, &c) in b.iter().enumerate() {
        if c == b'\n' {
            v.push((s, i + 1));
            s = i + 1;
        }
    }
    if s < b.len() {
        v.push((s, b.len()));
    }
    v
}

fn mutate(mut b: Vec<u8>, m: &Mutation) -> Vec<u8> {
    let lines = line_spans(&b);
    match m {
        Mutation::Flip(i, x) if !b.is_empty() => {
            let k = i.index(b.len());
            b[k] = *x;
        }
        Mutation::Truncate(i) => b.truncate(i.index(b.len() + 1)),
        Mutation::DuplicateLine(i) if !lines.is_empty() => {
            let (s, e) = lines[i.index(lines.len())];
            let l = b[s..e].to_vec();
            b.splice(e..e, l);
        }
        Mutation::DeleteLine(i) if !lines.is_empty() => {
            let (s, e) = lines[i.index(lines.len())];
            b.drain(s..e);
        }
        Mutation::Insert(i, t) => {
            let k = i.index(b.len() + 1);
            b.splice(k..k, TOKENS[*t].iter().copied());
        }
        Mutation::SwapColumns(l, x, y) if !lines.is_empty() => {
            // header lines are the interesting ones: pick among the first 80 lines
            let (s, e) = lines[l.index(lines.len().min(80))];
            let line = b[s..e].to_vec();
            let sep = [b'\t', b';', b',']
                .into_iter()
                .find(|c| line.contains(c))
                .unwrap_or(b' ');
            let mut fields: Vec<&[u8]> = line.split(|&c| c == sep).collect();
            let n = fields.len();
            fields.swap(x.index(n), y.index(n));
            let joined = fields.join(&[sep][..]);
            b.splice(s..e, joined);
        }
        _ => {}
    }
    b
}

fn options() -> impl Strategy<Value = Preprocessing> {
    let correction = prop_oneof![
        Just(Correction::Off),
        Just(Correction::Auto),
        Just(Correction::FromFile),
        any::<f64>().prop_map(Correction::Value),
        (-1e-3..1e-3f64).prop_map(Correction::Value),
    ];
    (
        correction.clone(),
        correction,
        proptest::option::of((
            -0.5..1.5f64,
            proptest::option::of(-1e-3..1e-2f64),
            -1.0..10.0f64,
            any::<bool>(),
        )),
        proptest::option::of((0..3usize, -0.1..0.6f64, -1.0..10.0f64)),
        proptest::option::of((0..600usize, 0..20usize)),
    )
        .prop_map(|(drift, compliance, z, s, r)| Preprocessing {
            drift,
            compliance,
            zero_point: z.map(|(fraction, threshold, noise_band, trim)| ZeroPoint {
                fraction,
                threshold,
                noise_band,
                trim,
            }),
            segments: s.map(|(c, tolerance, min_hold)| Segments {
                control: [Control::Auto, Control::Load, Control::Depth][c],
                tolerance,
                min_hold,
            }),
            resample: r.map(|(n, min_per_segment)| Resample { n, min_per_segment }),
        })
}

const FORMATS: [Format; 6] = [
    Format::Auto,
    Format::Csv,
    Format::AntonPaar,
    Format::AntonPaarMulti,
    Format::HysitronTxt,
    Format::Hld,
];

/// Reads with the format and, on success, preprocesses every record: never a panic, and
/// what comes out is consistent.
fn exercise(bytes: &[u8], format: Format, test: Option<usize>, p: &Preprocessing) {
    let opts = ReadOptions { format, test };
    let _ = indentify_records::read_results(bytes, "fuzz");
    if let Ok(records) = read(bytes, "fuzz", &opts) {
        for r in records {
            check_record(&r);
            if let Ok((x, _)) = apply(&r, p) {
                assert_eq!(x.t.len(), x.h.len());
                assert_eq!(x.t.len(), x.f.len());
                if let Some(rs) = &p.resample {
                    assert_eq!(x.len(), rs.n);
                }
            }
        }
    }
}

fn check_record(r: &Record) {
    assert!(r.len() >= 2);
    assert!(r.t.len() == r.h.len() && r.t.len() == r.f.len());
    assert!(r.t.windows(2).all(|w| w[1] >= w[0]));
    assert!(r.t.iter().chain(&r.h).chain(&r.f).all(|x| x.is_finite()));
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 1000, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..400), f in 0..6usize, p in options()) {
        exercise(&bytes, FORMATS[f], None, &p);
    }

    #[test]
    fn random_records_never_panic(
        rows in proptest::collection::vec((any::<f64>(), -1e-3..1e-2f64, -1e-3..1e-1f64), 0..60),
        sorted in any::<bool>(),
        seg in proptest::option::of(proptest::collection::vec(0..4u32, 60)),
        p in options(),
    ) {
        let mut t: Vec<f64> = rows.iter().map(|r| r.0).collect();
        if sorted {
            t = (0..rows.len()).map(|i| i as f64 * 0.1).collect();
        }
        let r = Record {
            name: "random".into(),
            t,
            h: rows.iter().map(|r| r.1).collect(),
            f: rows.iter().map(|r| r.2).collect(),
            segment: seg.map(|s| s.into_iter().take(rows.len()).collect()),
            meta: Default::default(),
        };
        if let Ok((x, _)) = apply(&r, &p) {
            prop_assert_eq!(x.t.len(), x.f.len());
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 3000, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn mutated_real_files_never_panic(
        which in 0..5usize,
        ms in proptest::collection::vec(mutation(), 1..5),
        f in 0..6usize,
        test in proptest::option::of(0..6usize),
        p in options(),
    ) {
        let mut b = seeds().swap_remove(which);
        for m in &ms {
            b = mutate(b, m);
        }
        exercise(&b, FORMATS[f], test, &p);
    }
}

#[test]
fn unmutated_seeds_read() {
    for (i, s) in seeds().iter().enumerate() {
        if let Err(e) = read(s, "seed", &ReadOptions::default()) {
            panic!("seed {i}: {e}");
        }
    }
}
