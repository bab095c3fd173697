//! Reading the real instrument records of `examples/data` (provenance in its README): row
//! counts, first and last values in mm, N, s, metadata, and preprocessing of each.

use indentify_records::prep::{MAP_THRESHOLD, Phase, spans};
use indentify_records::{
    Correction, Format, Preprocessing, ReadErrorKind, ReadOptions, Record, Resample, apply, detect,
    read, read_one,
};

const ANON: &[u8] = include_bytes!("../../../examples/data/anton-paar-unht-berkovich/anonNI.TXT");
const MULTI: &[u8] =
    include_bytes!("../../../examples/data/anton-paar-sphere-creep/HT_V_100mN.TXT");
const ROBIN: &[u8] = include_bytes!("../../../examples/data/hysitron/RobinSteel0000LC.txt");
const HLD: &[u8] = include_bytes!("../../../examples/data/hysitron/Exp-50mN_0000.hld");

/// `a` equals `b` to 1e-12 relative.
fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * b.abs().max(1e-300)
}

fn first_last(r: &Record) -> [f64; 6] {
    let n = r.len() - 1;
    [r.t[0], r.h[0], r.f[0], r.t[n], r.h[n], r.f[n]]
}

fn assert_row(r: &Record, expected: [f64; 6]) {
    let got = first_last(r);
    for (g, e) in got.iter().zip(expected) {
        assert!(
            close(*g, e) || (e == 0.0 && *g == 0.0),
            "{}: got {got:?}, expected {expected:?}",
            r.name
        );
    }
}

fn quantity(v: &[indentify_records::Quantity], name: &str) -> (f64, String) {
    let q = v
        .iter()
        .find(|q| q.name == name)
        .unwrap_or_else(|| panic!("no {name} in {v:?}"));
    (q.value, q.unit.clone())
}

#[test]
fn anton_paar_single_test() {
    assert_eq!(detect(ANON), Format::AntonPaar);
    let r = read_one(ANON, "anonNI.TXT", &ReadOptions::default()).unwrap();
    assert_eq!(r.len(), 1000);
    assert_row(&r, [0.0, 0.0, 0.0, 97.3026, 1396.1167e-6, 0.1219e-3]);
    let seg = r.segment.as_deref().unwrap();
    let count = |id| seg.iter().filter(|&&s| s == id).count();
    assert_eq!(
        [count(0), count(1), count(2), count(3), count(4)],
        [6, 342, 309, 342, 1]
    );
    let m = &r.meta;
    assert_eq!(m.format, Format::AntonPaar);
    assert_eq!(m.instrument.as_deref(), Some("STeP - UNHT S/N: 1000065235"));
    assert_eq!(m.date.as_deref(), Some("16.02.2022 15:51:12"));
    assert_eq!(m.acquisition_rate, Some(10.0));
    assert_eq!(m.protocol.control.as_deref(), Some("Linear Loading"));
    assert!(close(m.protocol.max_depth.unwrap(), 2000e-6));
    assert!(close(
        m.protocol.loading_rate.as_ref().unwrap().value,
        20e-3 / 60.0
    ));
    assert_eq!(m.protocol.loading_rate.as_ref().unwrap().unit, "N/s");
    assert_eq!(m.protocol.hold, Some(30.0));
    assert_eq!(quantity(&m.results, "EIT"), (2.5187, "GPa".into()));
    assert_eq!(quantity(&m.results, "HIT"), (134.71, "MPa".into()));
    assert_eq!(quantity(&m.results, "Fmax"), (11.13, "mN".into()));
    assert_eq!(quantity(&m.results, "hmax"), (2110.86, "nm".into()));
    assert_eq!(quantity(&m.other, "Fn contact"), (0.05, "mN".into()));
    // the file's segment ids map to approach, load, hold (force within 1.1 %), unload
    let phases: Vec<Phase> = spans(&r, false, MAP_THRESHOLD)
        .iter()
        .map(|s| s.phase)
        .collect();
    assert_eq!(
        phases,
        [
            Phase::Hold,
            Phase::Load,
            Phase::Hold,
            Phase::Unload,
            Phase::Hold
        ]
    );
}

#[test]
fn anton_paar_multi_test() {
    assert_eq!(detect(MULTI), Format::AntonPaarMulti);
    let all = read(MULTI, "HT_V_100mN.TXT", &ReadOptions::default()).unwrap();
    // trailing rows repeating a shorter test's last row are padding and dropped
    assert_eq!(
        all.iter().map(Record::len).collect::<Vec<_>>(),
        [7005, 7009, 7006, 7006]
    );
    let names: Vec<_> = all
        .iter()
        .map(|r| r.meta.test_name.clone().unwrap())
        .collect();
    assert_eq!(
        names,
        [
            "HT_V_100mN_1",
            "HT_V_100mN_2",
            "HT_V_100mN_3",
            "HT_V_100mN_4"
        ]
    );
    assert_row(
        &all[0],
        [
            0.0,
            0.0,
            0.0,
            700.4,
            365.391622884539e-6,
            0.465975647960483e-3,
        ],
    );
    assert_row(
        &all[1],
        [
            0.0,
            0.0,
            0.0,
            700.8,
            378.129534363078e-6,
            0.332591141901579e-3,
        ],
    );
    assert!(close(all[0].t[1], 0.0999999999999943) && close(all[0].h[1], 2.48685987935751e-6));
    assert!(close(all[0].f[1], 0.00166296027807422e-3));
    let opts = ReadOptions {
        test: Some(4),
        ..ReadOptions::default()
    };
    let r4 = read_one(MULTI, "HT_V_100mN.TXT", &opts).unwrap();
    assert_eq!(r4.name, "HT_V_100mN.TXT: HT_V_100mN_4");
    assert!(close(r4.f[1], 0.00105801373266502e-3) && close(r4.h[1], 2.29500973939198e-6));
    assert_eq!(r4, all[3]);
    let e = read_one(MULTI, "HT_V_100mN.TXT", &ReadOptions::default()).unwrap_err();
    assert_eq!(e.kind, ReadErrorKind::TestIndex);
    assert!(
        e.to_string()
            .contains("4 tests (1 = HT_V_100mN_1, 2 = HT_V_100mN_2"),
        "{e}"
    );
    let e = read(
        MULTI,
        "HT_V_100mN.TXT",
        &ReadOptions {
            test: Some(5),
            ..ReadOptions::default()
        },
    )
    .unwrap_err();
    assert_eq!(
        e.to_string(),
        "HT_V_100mN.TXT: test 5 does not exist: the file has 4 tests (1 = HT_V_100mN_1, 2 = HT_V_100mN_2, 3 = HT_V_100mN_3, 4 = HT_V_100mN_4); expected a test index from 1 to 4"
    );
}

#[test]
fn hysitron_text_export() {
    assert_eq!(detect(ROBIN), Format::HysitronTxt);
    let r = read_one(ROBIN, "RobinSteel0000LC.txt", &ReadOptions::default()).unwrap();
    assert_eq!(r.len(), 5304);
    assert_row(
        &r,
        [
            0.0,
            0.814723e-6,
            1.836146e-6,
            27.059622,
            135.028188e-6,
            2.138711e-6,
        ],
    );
    // blank lines separate the segments: 1 s and 0.5 s at the start, 10 s load, 5 s hold,
    // 10 s unload at 200 Hz
    let phases: Vec<(Phase, usize)> = spans(&r, false, MAP_THRESHOLD)
        .iter()
        .map(|s| (s.phase, s.end + 1 - s.start))
        .collect();
    assert_eq!(
        phases,
        [
            (Phase::Hold, 201),
            (Phase::Hold, 104),
            (Phase::Load, 2000),
            (Phase::Hold, 1000),
            (Phase::Unload, 1999)
        ]
    );
    assert_eq!(r.meta.date.as_deref(), Some("Mon Apr 29 10:41:06 2019"));
    let e = read(
        ROBIN,
        "RobinSteel0000LC.txt",
        &ReadOptions {
            test: Some(2),
            ..ReadOptions::default()
        },
    )
    .unwrap_err();
    assert!(e.to_string().contains("the file has 1 test "), "{e}");
}

#[test]
fn hysitron_hld() {
    assert_eq!(detect(HLD), Format::Hld);
    let r = read_one(HLD, "Exp-50mN_0000.hld", &ReadOptions::default()).unwrap();
    assert_eq!(r.len(), 1068);
    assert_row(
        &r,
        [
            0.0,
            5.800346e-6,
            204.644060e-6,
            6.677978,
            181.340354e-6,
            194.563565e-6,
        ],
    );
    let m = &r.meta;
    assert!(close(m.frame_compliance.unwrap(), 0.00663947));
    assert!(close(m.drift_rate.unwrap(), 0.03648e-6));
    assert_eq!(m.protocol.control.as_deref(), Some("Load Control"));
    assert!(close(m.protocol.max_load.unwrap(), 0.05));
    assert_eq!(m.tip.as_deref(), Some("Tip"));
    assert_eq!(m.tip_area.len(), 7);
    assert_eq!(quantity(&m.tip_area, "Tip C0"), (24.5, "nm^2/nm^2".into()));
    assert_eq!(m.protocol.segments.len(), 4);
    let s2 = &m.protocol.segments[2];
    assert!(
        close(s2.t_begin, 4.67914)
            && close(s2.end, 0.05)
            && s2.unit == "N"
            && s2.points == Some(200)
    );
    assert_eq!(quantity(&m.other, "Test Data Points").0, 1068.0);
    assert_eq!(quantity(&m.other, "Sample Approach Data Points").0, 312.0);
    // samples carry the load-function segment they fall in
    let seg = r.segment.as_deref().unwrap();
    assert_eq!((seg[0], seg[seg.len() - 1]), (0, 3));
    let phases: Vec<Phase> = spans(&r, false, MAP_THRESHOLD)
        .iter()
        .map(|s| s.phase)
        .collect();
    assert_eq!(
        phases,
        [Phase::Hold, Phase::Hold, Phase::Load, Phase::Unload]
    );
}

#[test]
fn metadata_snapshots() {
    let anon = read_one(ANON, "anonNI.TXT", &ReadOptions::default()).unwrap();
    insta::assert_debug_snapshot!("anonNI_meta", anon.meta);
    let hld = read_one(HLD, "Exp-50mN_0000.hld", &ReadOptions::default()).unwrap();
    insta::assert_debug_snapshot!("hld_meta", hld.meta);
}

/// (name, rows, t_end s, h_max nm, F_max mN) after preprocessing with defaults plus
/// resampling to 200 points, for the report.
#[test]
fn preprocessing_of_each_real_record() {
    let p = Preprocessing {
        drift: Correction::Auto,
        compliance: Correction::Auto,
        resample: Some(Resample::default()),
        ..Preprocessing::default()
    };
    let mut lines = Vec::new();
    for (b, n) in [
        (ANON, "anonNI.TXT"),
        (MULTI, "HT_V_100mN.TXT"),
        (ROBIN, "RobinSteel0000LC.txt"),
        (HLD, "Exp-50mN_0000.hld"),
    ] {
        for r in read(b, n, &ReadOptions::default()).unwrap() {
            let (x, done) = apply(&r, &p).unwrap();
            assert_eq!(x.len(), 200);
            assert_eq!(x.t[0], 0.0);
            assert!(x.t.windows(2).all(|w| w[1] > w[0]), "{}", r.name);
            // zero at contact, up to the compliance times the baseline noise
            assert!(
                x.h[0].abs() < 0.1e-6,
                "{}: depth {} at contact",
                r.name,
                x.h[0]
            );
            // the resampled peak depth is the corrected record's peak
            let z = apply(
                &r,
                &Preprocessing {
                    resample: None,
                    ..p.clone()
                },
            )
            .unwrap()
            .0;
            assert_eq!(x.h_max(), z.h_max());
            lines.push(format!(
                "{}: raw {} rows, {:.3} s, h_max {:.1} nm, F_max {:.3} mN -> {} steps",
                r.name,
                r.len(),
                r.t[r.len() - 1],
                r.h_max() * 1e6,
                r.f_max() * 1e3,
                done.iter()
                    .map(|a| a.step.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ));
            for a in &done {
                lines.push(format!("  {}: {}", a.step, a.description));
            }
        }
    }
    insta::assert_snapshot!("preprocessing_accounts", lines.join("\n"));
}

#[test]
fn anton_paar_results_table() {
    const DATA: &[u8] =
        include_bytes!("../../../examples/data/anton-paar-sphere-creep/HT_V_100mN_data.TXT");
    let res = indentify_records::read_results(DATA, "HT_V_100mN_data.TXT").unwrap();
    assert_eq!(res.len(), 30);
    assert_eq!(res.iter().map(|r| r.values.len()).sum::<usize>(), 792);
    let mut all = read(MULTI, "HT_V_100mN.TXT", &ReadOptions::default()).unwrap();
    assert_eq!(indentify_records::attach_results(&mut all, &res), 4);
    let last = &all[3].meta.results;
    assert_eq!(last.len(), 27);
    assert_eq!(quantity(last, "F/S²(O&P)"), (293.762, "nm²/mN".into()));
    assert_eq!(
        quantity(&all[0].meta.results, "Poisson's ratio"),
        (0.3, String::new())
    );
    let e = indentify_records::read_results(b"a\tb\n", "x.TXT").unwrap_err();
    assert_eq!(e.kind, ReadErrorKind::Format);
    let e = indentify_records::read_results(
        b"Group\tMeasurement\tParameter\tUnit\tValue\ng\t1\tHIT\tGPa\n",
        "x.TXT",
    )
    .unwrap_err();
    assert_eq!(
        e.to_string(),
        "x.TXT:2: 4 fields; expected 5 tab-separated fields: group, measurement, parameter, unit, value"
    );
}

/// Micro Materials NanoTest exports (micromechanics' public sample): detected, read in s,
/// mm, N, each indent's deepest point within 5 % of the target depth its file is named
/// after (500 nm, 2000 nm), the force rising to a few hundred mN.
#[test]
fn micro_materials_nanotest_exports() {
    for (bytes, target_nm) in [
        (
            &include_bytes!("../../../examples/data/micromaterials-nanotest/500nm-4.txt")[..],
            500.0,
        ),
        (
            &include_bytes!("../../../examples/data/micromaterials-nanotest/2000nm-5.txt")[..],
            2000.0,
        ),
    ] {
        assert_eq!(detect(bytes), Format::MicroMaterials);
        let r = read_one(bytes, "nanotest", &ReadOptions::default()).unwrap();
        assert_eq!(r.meta.format, Format::MicroMaterials);
        assert!(r.len() > 800, "{}", r.len());
        let h_max = r.h.iter().copied().fold(f64::MIN, f64::max);
        assert!((h_max / (target_nm * 1e-6) - 1.0).abs() < 0.05, "{h_max}"); // 511.7, 1985.5 nm
        let f_max = r.f.iter().copied().fold(f64::MIN, f64::max);
        assert!(f_max > 0.01 && f_max < 1.0, "{f_max} N");
        assert!(r.t.windows(2).all(|w| w[1] >= w[0]));
    }
}
