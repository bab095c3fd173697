//! KLA/Agilent/Keysight workbooks: the real `FusedSilica.xlsx` of examples/data (16 tests,
//! their samples in mm, N, s, the vendor's results and method settings) and small
//! hand-made workbooks for the layouts it does not show and for bad input.

use indentify_records::{Format, ReadErrorKind, ReadOptions, detect, read, read_one};

const FS: &[u8] = include_bytes!("../../../examples/data/kla-fused-silica/FusedSilica.xlsx");
const UNKNOWN: &[u8] = include_bytes!("data/unknown-layout.xlsx");
const NO_DEPTH: &[u8] = include_bytes!("data/no-depth.xlsx");
const VOLTS: &[u8] = include_bytes!("data/depth-volts.xlsx");
const TWO: &[u8] = include_bytes!("data/two-tests.xlsx");

fn q<'a>(v: &'a [indentify_records::Quantity], name: &str) -> &'a indentify_records::Quantity {
    v.iter()
        .find(|q| q.name == name)
        .unwrap_or_else(|| panic!("no {name} in {v:?}"))
}

#[test]
fn fused_silica_reads_sixteen_tests() {
    assert_eq!(detect(FS), Format::Kla);
    let rs = read(FS, "FusedSilica.xlsx", &ReadOptions::default()).unwrap();
    assert_eq!(rs.len(), 16);
    for (k, r) in rs.iter().enumerate() {
        assert_eq!(r.meta.format, Format::Kla);
        assert_eq!(
            r.meta.test_name.as_deref(),
            Some(format!("Test {}", k + 1).as_str())
        );
        assert!(r.len() > 2500, "{}: {} samples", r.name, r.len());
        // 10 load cycles to 48 mN
        assert!((r.f_max() - 48.0e-3).abs() < 0.1e-3, "{}", r.f_max());
        // about 800 nm deep; Test 3 (1605 nm) and Test 11 (906 nm) sank in at first contact
        let deep = match k + 1 {
            3 => 1.606e-3,
            11 => 0.906e-3,
            _ => 0.81e-3,
        };
        assert!(
            r.h_max() > 0.79e-3 && r.h_max() < deep,
            "{}: {}",
            r.name,
            r.h_max()
        );
    }
    let r = &rs[0];
    // the sheet's rows 3 to 2869: the first and last samples as written (s, mN, nm)
    assert_eq!(r.len(), 2867);
    assert_eq!(r.t[0], 54.4330636);
    assert_eq!(r.f[0], 0.0);
    assert_eq!(r.h[0], 0.0);
    assert!((r.t[1] - 54.5337669).abs() < 1e-12);
    assert!((r.f[1] - -0.000441536046155608e-3).abs() < 1e-18);
    assert!((r.h[1] - 11.8740047876901e-6).abs() < 1e-18);
    assert!((r.t[2866] - 346.4650744).abs() < 1e-9);
    assert!((r.h[2866] - -206.190352999828e-6).abs() < 1e-15);
    // the method and the vendor's values
    let m = &r.meta;
    assert_eq!(m.protocol.max_load, Some(48.0e-3));
    assert_eq!(m.protocol.hold, Some(5.0));
    assert_eq!(m.acquisition_rate, Some(10.0));
    assert_eq!(q(&m.other, "Poisson's Ratio of Sample").value, 0.188);
    assert_eq!(q(&m.other, "Number of Loading Cycles").value, 10.0);
    let pmax = q(&m.results, "Pmax");
    assert_eq!((pmax.value, pmax.unit.as_str()), (47.635, "mN"));
    let su = q(&m.results, "Cycle Su [cycle 10]");
    assert_eq!((su.value, su.unit.as_str()), (151000.0, "N/m"));
    assert_eq!(q(&m.results, "Cycle Eu [cycle 1]").value, 13.41);
    assert_eq!(q(&m.results, "X_Position").unit, "µm");
    // markers: the sample's time
    assert_eq!(q(&m.other, "marker: Surface Index").value, 54.4330636);
    assert!((q(&m.other, "marker: End Of Loading Index").value - 231.3024067).abs() < 1e-9);
    // one test by index
    let one = read_one(
        FS,
        "FusedSilica.xlsx",
        &ReadOptions {
            test: Some(16),
            ..ReadOptions::default()
        },
    )
    .unwrap();
    assert_eq!(one.meta.test_name.as_deref(), Some("Test 16"));
    assert_eq!(q(&one.meta.results, "Pmax").value, 47.628);
}

#[test]
fn other_column_names_and_units_are_understood() {
    let rs = read(TWO, "two.xlsx", &ReadOptions::default()).unwrap();
    assert_eq!(rs.len(), 2);
    let r = &rs[0];
    assert_eq!(r.len(), 21);
    // 1000 uN = 1 mN = 1e-3 N at 0.1 um = 1e-4 mm
    assert!((r.f_max() - 1e-3).abs() < 1e-15);
    assert!((r.h_max() - 1e-4).abs() < 1e-15);
    assert_eq!(q(&r.meta.results, "Modulus").value, 70.5);
    assert_eq!(q(&rs[1].meta.results, "Hardness").value, 9.2);
}

#[test]
fn bad_workbooks_say_what_is_wrong() {
    let e = read(UNKNOWN, "u.xlsx", &ReadOptions::default()).unwrap_err();
    assert_eq!(e.kind, ReadErrorKind::Format);
    assert!(e.to_string().contains("unknown layout"), "{e}");
    assert!(e.to_string().contains("Data"), "{e}");
    let e = read(NO_DEPTH, "n.xlsx", &ReadOptions::default()).unwrap_err();
    assert_eq!(e.kind, ReadErrorKind::Columns);
    assert!(e.to_string().contains("Test 1"), "{e}");
    assert!(e.to_string().contains("Depth"), "{e}");
    let e = read(VOLTS, "v.xlsx", &ReadOptions::default()).unwrap_err();
    assert_eq!(e.kind, ReadErrorKind::Units);
    assert!(e.to_string().contains("'V'"), "{e}");
    let e = read(
        FS,
        "FusedSilica.xlsx",
        &ReadOptions {
            test: Some(17),
            ..ReadOptions::default()
        },
    )
    .unwrap_err();
    assert_eq!(e.kind, ReadErrorKind::TestIndex);
    // truncated: not a readable workbook
    let e = read(&FS[..FS.len() / 2], "cut.xlsx", &ReadOptions::default()).unwrap_err();
    assert_eq!(e.kind, ReadErrorKind::Format);
    // text asked to be read as a workbook
    let e = read(
        b"t,h,F\n0,0,0\n1,1,1\n",
        "x.csv",
        &ReadOptions {
            format: Format::Kla,
            ..ReadOptions::default()
        },
    )
    .unwrap_err();
    assert_eq!(e.kind, ReadErrorKind::Format);
}

/// Two workbooks whose first data cell has an impossible reference (`A` then 23 letters:
/// a column past any integer; a 24-digit row): the parser may fail or panic on them (an
/// overflow in its cell references, as the fuzz test once found), and either way the reader
/// returns a format error naming the file.
#[test]
fn impossible_cell_references_are_a_format_error_not_a_panic() {
    for (bytes, name) in [
        (&include_bytes!("data/overflow-column.xlsx")[..], "col.xlsx"),
        (&include_bytes!("data/overflow-row.xlsx")[..], "row.xlsx"),
    ] {
        let e = read(bytes, name, &ReadOptions::default()).unwrap_err();
        eprintln!("{name}: {e}");
        assert_eq!(e.kind, ReadErrorKind::Format, "{e}");
        assert!(e.to_string().contains(name), "{e}");
    }
}
