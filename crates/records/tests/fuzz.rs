//! Fuzzing the readers and the preprocessing with proptest: random bytes, mutated real files
//! (byte flips, truncations, duplicated or deleted lines, inserted NaN/inf/huge numbers,
//! swapped columns) and random records must give a value or an error, never a panic.
//! A few thousand cases here; `cargo xtask fuzz-readers` runs 100 000+ in release. A failing
//! case is kept by proptest's default file persistence beside this file, to be committed so
//! every later run tries it first.

use indentify_records::fuzzing::{FORMATS, Mutation, mutate};
use indentify_records::{
    Control, Correction, Format, Preprocessing, ReadOptions, Record, Resample, Segments, ZeroPoint,
    apply, read,
};
use proptest::prelude::*;

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

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (any::<usize>(), any::<u8>()).prop_map(|(at, byte)| Mutation::Flip { at, byte }),
        any::<usize>().prop_map(|at| Mutation::Truncate { at }),
        any::<usize>().prop_map(|line| Mutation::DuplicateLine { line }),
        any::<usize>().prop_map(|line| Mutation::DeleteLine { line }),
        (any::<usize>(), any::<usize>()).prop_map(|(at, token)| Mutation::Insert { at, token }),
        (0..80usize, any::<usize>(), any::<usize>())
            .prop_map(|(line, a, b)| Mutation::SwapColumns { line, a, b }),
        (any::<usize>(), any::<usize>()).prop_map(|(at, which)| Mutation::Hugify { at, which }),
    ]
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
                stiffness: None,
            }),
            segments: s.map(|(c, tolerance, min_hold)| Segments {
                control: [Control::Auto, Control::Load, Control::Depth][c],
                tolerance,
                min_hold,
            }),
            resample: r.map(|(n, min_per_segment)| Resample { n, min_per_segment }),
        })
}

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
    #![proptest_config(ProptestConfig { cases: 1000, ..ProptestConfig::default() })]

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
    #![proptest_config(ProptestConfig { cases: 3000, ..ProptestConfig::default() })]

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

/// The hand-made workbooks of tests/data (the 1.6 MB `FusedSilica.xlsx` is fuzzed by
/// `cargo xtask fuzz-readers`).
fn workbooks() -> Vec<Vec<u8>> {
    vec![
        include_bytes!("data/two-tests.xlsx").to_vec(),
        include_bytes!("data/unknown-layout.xlsx").to_vec(),
        include_bytes!("data/no-depth.xlsx").to_vec(),
        include_bytes!("data/depth-volts.xlsx").to_vec(),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

    #[test]
    fn mutated_workbooks_never_panic(
        which in 0..4usize,
        ms in proptest::collection::vec(mutation(), 1..4),
        f in 0..FORMATS.len(),
        test in proptest::option::of(0..4usize),
        p in options(),
    ) {
        let mut b = workbooks().swap_remove(which);
        for m in &ms {
            b = mutate(b, m);
        }
        exercise(&b, FORMATS[f], test, &p);
    }

    #[test]
    fn random_bytes_behind_a_zip_signature_never_panic(
        bytes in proptest::collection::vec(any::<u8>(), 0..600),
        p in options(),
    ) {
        let mut b = b"PK\x03\x04".to_vec();
        b.extend(bytes);
        exercise(&b, Format::Auto, None, &p);
    }
}
