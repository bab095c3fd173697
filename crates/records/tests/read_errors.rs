//! Readers on small synthetic inputs: unit-bearing headers, separators, decimal commas,
//! encodings, and every error case (the message names the line and the expectation).

use indentify_records::{Format, ReadError, ReadErrorKind as K, ReadOptions, read, read_one};

fn ok(bytes: &[u8]) -> indentify_records::Record {
    read_one(bytes, "x.csv", &ReadOptions::default()).unwrap_or_else(|e| panic!("{e}"))
}

fn err(bytes: &[u8]) -> ReadError {
    read(bytes, "x.csv", &ReadOptions::default()).expect_err("should fail")
}

fn close(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len()
        && a.iter()
            .zip(b)
            .all(|(x, y)| (x - y).abs() <= 1e-12 * y.abs().max(1e-300))
}

#[test]
fn simulate_output_without_units_is_mm_n_s() {
    let r = ok(b"t,h,F,a\n0,0,0,0\n0.5,0.001,0.02,0.01\n1,0.002,0.05,0.02\n");
    assert!(
        close(&r.t, &[0.0, 0.5, 1.0])
            && close(&r.h, &[0.0, 0.001, 0.002])
            && close(&r.f, &[0.0, 0.02, 0.05])
    );
    assert_eq!(r.meta.format, Format::Csv);
}

#[test]
fn unit_bearing_headers_in_every_spelling() {
    let cases: &[&[u8]] = &[
        b"t [s],h [um],F (mN)\n0,0,0\n1,1,1\n",
        b"Time (s);Depth (nm);Load (uN)\n0;0;0\n1;1000;1000\n",
        b"time_ms\th_mm\tFn (mN)\n0\t0\t0\n1000\t1e-3\t1\n",
        b"Time (min) Pd (nm) P (N)\n0 0 0\n0.0166666666666666667 1e3 1e-3\n",
        b"zeit;Displacement [m];Force [kN]\n0;0;0\n1;1e-6;1e-6\n",
        b"# simulated\nTime (s)\tDepth (nm)\tLoad (\xB5N)\n0\t0\t0\n1\t1000\t1000\n",
        b"\xEF\xBB\xBFt [s];h [\xC2\xB5m];F [mN]\r\n0;0;0\r\n1;1;1\r\n",
        b"t,disp,force\n0,0,0\n1,1e-3,1e-3\n",
        b"Time;Depth;Load\ns;nm;mN\n0;0;0\n1;1000;1\n",
        b"Time\tDepth\tForce\n(s)\t(um)\t(uN)\n0\t0\t0\n1\t1\t1000\n",
        b"Segment,Time On Sample (s),Displacement Into Surface (nm),Load On Sample (mN)\n1,0,0,0\n1,1,1000,1\n",
    ];
    for c in cases {
        let r = ok(c);
        assert!(close(&r.t, &[0.0, 1.0]), "{r:?}");
        assert!(
            close(&r.h, &[0.0, 1e-3]),
            "{:?} for {}",
            r.h,
            String::from_utf8_lossy(c)
        );
        assert!(
            close(&r.f, &[0.0, 1e-3]),
            "{:?} for {}",
            r.f,
            String::from_utf8_lossy(c)
        );
    }
}

#[test]
fn decimal_commas_where_the_separator_is_not_a_comma() {
    let r = ok(b"Time (s)\tPd (nm)\tFn (mN)\n0,5\t1,5\t2,5\n1,5\t3,25\t4\n");
    assert!(
        close(&r.t, &[0.5, 1.5]) && close(&r.h, &[1.5e-6, 3.25e-6]) && close(&r.f, &[2.5e-3, 4e-3])
    );
    let r = ok(b"t;h;F\n0,5;1,5;2,5\n1;2;3\n");
    assert!(close(&r.t, &[0.5, 1.0]));
}

#[test]
fn segment_column_is_kept() {
    let r = ok(b"t,h,F,segment\n0,0,0,1\n1,1,1,1\n2,0.5,0,2\n");
    assert_eq!(r.segment, Some(vec![1, 1, 2]));
}

#[test]
fn empty_file() {
    for b in [&b""[..], b"  \r\n\n\t\n"] {
        let e = err(b);
        assert_eq!(e.kind, K::Empty);
        assert_eq!(
            e.to_string(),
            "x.csv: the file is empty; expected a header and at least two rows of time, depth and force"
        );
    }
}

#[test]
fn no_numeric_rows() {
    let e = err(b"time,depth,force\nnone,yet,here\n");
    assert_eq!(e.kind, K::NoRows);
    assert!(
        e.to_string()
            .starts_with("x.csv:1: no row of numbers in 2 lines"),
        "{e}"
    );
    assert!(
        e.to_string()
            .contains("expected a header line naming the columns, then rows of numbers"),
        "{e}"
    );
}

#[test]
fn missing_header() {
    let e = err(b"0,0,0\n1,1,1\n");
    assert_eq!(e.kind, K::Columns);
    assert!(e.to_string().starts_with("x.csv:1: no header line"), "{e}");
}

#[test]
fn missing_column_lists_found_and_accepted() {
    let e = err(b"t [s],h [nm],G [mN]\n0,0,0\n1,1,1\n");
    assert_eq!(e.kind, K::Columns);
    let s = e.to_string();
    assert!(s.starts_with("x.csv:1: no force column among 't [s]', 'h [nm]', 'G [mN]'; expected a column named f/force/load/fn/p"), "{s}");
    assert!(s.contains("nN, µN (uN), mN, N, kN"), "{s}");
}

#[test]
fn unrecognised_unit_lists_accepted() {
    let e = err(b"t [s],h [furlong],F [N]\n0,0,0\n1,1,1\n");
    assert_eq!(e.kind, K::Units);
    assert_eq!(
        e.to_string(),
        "x.csv:1: column 'h [furlong]' has unit 'furlong', not a unit of mm; expected one of nm, µm (um), mm, m (no unit means mm)"
    );
    // a depth in volts next to one in nm is skipped, alone it is an error
    assert!(
        read(
            b"t,Depth (V),Depth (nm),F\n0,0,0,0\n1,1,1,1\n",
            "x",
            &ReadOptions::default()
        )
        .is_ok()
    );
    assert_eq!(err(b"t,Depth (V),F\n0,0,0\n1,1,1\n").kind, K::Units);
}

#[test]
fn nan_inf_and_huge_numbers() {
    let e = err(b"t,h,F\n0,0,0\n1,NaN,1\n");
    assert_eq!(e.kind, K::NotFinite);
    assert_eq!(
        e.to_string(),
        "x.csv:3: 'NaN' in column 'h' is not finite; expected a finite number"
    );
    assert_eq!(err(b"t,h,F\n0,0,0\n1,1,-inf\n").line, Some(3));
    let e = err(b"t,h [m],F\n0,0,0\n1,1e307,1\n");
    assert_eq!(e.kind, K::NotFinite);
    assert!(e.to_string().contains("is too large"), "{e}");
}

#[test]
fn not_a_number() {
    let e = err(b"t;h;F\n0;0;0\n1;x;1\n");
    assert_eq!(e.kind, K::NotANumber);
    assert_eq!(
        e.to_string(),
        "x.csv:3: 'x' in column 'h' is not a number; expected a decimal number (point or comma)"
    );
}

#[test]
fn time_going_back_names_the_line_and_both_times() {
    let e = err(b"t,h,F\n0,0,0\n2,1,1\n1.5,2,2\n");
    assert_eq!(e.kind, K::TimeOrder);
    assert_eq!(
        e.to_string(),
        "x.csv:4: table: time goes back from 2 s (line 3) to 1.5 s; expected a time that never decreases"
    );
}

#[test]
fn row_with_too_few_fields() {
    let e = err(b"t,h,F\n0,0,0\n1,1\n");
    assert_eq!(e.kind, K::FewFields);
    assert!(
        e.to_string()
            .starts_with("x.csv:3: 2 fields; expected at least 3 fields (time 't' is field 1"),
        "{e}"
    );
}

#[test]
fn fewer_than_two_rows() {
    let e = err(b"t,h,F\n0,0,0\n");
    assert_eq!(e.kind, K::TooFewRows);
    assert_eq!(
        e.to_string(),
        "x.csv:2: table: 1 data rows; expected at least 2 rows of numbers"
    );
}

#[test]
fn declared_point_count_disagrees() {
    let txt = b"Mon Apr 29 10:41:06 2019\n\nNumber of Points = 3\nDepth (nm)\tLoad (\xB5N)\tTime (s)\n1\t2\t0\n2\t3\t1\n";
    let e = read(txt, "r.txt", &ReadOptions::default()).unwrap_err();
    assert_eq!(e.kind, K::PointCount);
    assert_eq!(
        e.to_string(),
        "r.txt:3: 'Number of Points' declares 3 points but 2 rows follow; expected 3 rows of numbers after the column header"
    );
    let hld = b"File Version: Hysitron\r\nDrift Rate: 0.1 nm/s\r\nTest Data Points: 3\r\nTime_s\tDisp_nm\tForce_\xB5N\r\n0\t0\t0\r\n1\t1\t1\r\n";
    let e = read(hld, "e.hld", &ReadOptions::default()).unwrap_err();
    assert_eq!(e.kind, K::PointCount);
    assert!(
        e.to_string()
            .starts_with("e.hld:3: 'Test Data Points' declares 3 points but 2 rows follow"),
        "{e}"
    );
    let mut ok = hld.to_vec();
    ok.extend_from_slice(b"2\t1.5\t0.5\r\n");
    let r = read_one(&ok, "e.hld", &ReadOptions::default()).unwrap();
    assert!(close(&r.h, &[0.0, 1e-6, 1.5e-6]) && close(&r.f, &[0.0, 1e-6, 0.5e-6]));
    assert_eq!(r.meta.drift_rate, Some(0.1e-6));
}

#[test]
fn test_index_out_of_range() {
    let multi = b"X_a_Time_[s]\tY_a_Fn_[mN]\tX_a_Time_[s]\tY_a_Pd_[nm]\n0\t0\t0\t0\n1\t1\t1\t1\n";
    let e = read(
        multi,
        "m.TXT",
        &ReadOptions {
            test: Some(2),
            ..ReadOptions::default()
        },
    )
    .unwrap_err();
    assert_eq!(e.kind, K::TestIndex);
    assert_eq!(
        e.to_string(),
        "m.TXT: test 2 does not exist: the file has 1 test (1 = a); expected a test index from 1 to 1"
    );
    assert!(
        read(
            multi,
            "m.TXT",
            &ReadOptions {
                test: Some(0),
                ..ReadOptions::default()
            }
        )
        .is_err()
    );
    let r = read_one(multi, "m.TXT", &ReadOptions::default()).unwrap();
    assert!(close(&r.f, &[0.0, 1e-3]) && close(&r.h, &[0.0, 1e-6]));
}

#[test]
fn multi_test_time_columns_must_agree_and_tests_may_end_early() {
    let bad = b"X_a_Time_[s]\tY_a_Fn_[mN]\tX_a_Time_[s]\tY_a_Pd_[nm]\n0\t0\t0\t0\n1\t1\t1.5\t1\n";
    let e = read(bad, "m.TXT", &ReadOptions::default()).unwrap_err();
    assert!(
        e.to_string().starts_with(
            "m.TXT:3: test 'a': the force's time 1 s differs from the depth's time 1.5 s"
        ),
        "{e}"
    );
    let short = b"X_a_Time_[s]\tY_a_Fn_[mN]\tX_a_Time_[s]\tY_a_Pd_[nm]\tX_b_Time_[s]\tY_b_Fn_[mN]\tX_b_Time_[s]\tY_b_Pd_[nm]\n0\t0\t0\t0\t0\t0\t0\t0\n1\t1\t1\t1\t1\t1\t1\t1\n\t\t\t\t2\t2\t2\t2\n";
    let rs = read(short, "m.TXT", &ReadOptions::default()).unwrap();
    assert_eq!(rs.iter().map(|r| r.len()).collect::<Vec<_>>(), [2, 3]);
}

#[test]
fn anton_paar_single_without_rows() {
    let b = b"Indentation\n   Acquisition Rate :\t10,0 [Hz]\nMeasured values\nTime (s)\tPd (nm)\tFn (mN)\n\n";
    let e = read(b, "a.TXT", &ReadOptions::default()).unwrap_err();
    assert_eq!(e.kind, K::NoRows);
    assert!(
        e.to_string()
            .starts_with("a.TXT:4: measured values: 0 data rows"),
        "{e}"
    );
}

#[test]
fn wrong_forced_format_is_an_error() {
    let opts = ReadOptions {
        format: Format::Hld,
        ..ReadOptions::default()
    };
    let e = read(b"t,h,F\n0,0,0\n1,1,1\n", "x.csv", &opts).unwrap_err();
    assert_eq!(e.kind, K::Format);
    assert!(
        e.to_string().contains("no 'Test Data Points: N' section"),
        "{e}"
    );
    let opts = ReadOptions {
        format: Format::AntonPaar,
        ..ReadOptions::default()
    };
    assert_eq!(
        read(b"t,h,F\n0,0,0\n1,1,1\n", "x.csv", &opts)
            .unwrap_err()
            .kind,
        K::Format
    );
}

/// Blank-separated tables with decimal commas, and multi-test files aligned with runs of
/// blanks, read like their tab-separated twins.
#[test]
fn blank_separated_decimal_commas_and_space_aligned_columns_read() {
    let ws = "Time (s) Depth (nm) Load (mN)\n0,0 0,0 0,0\n1,5 10,2 1,1\n3,0 20,0 2,0\n";
    let r = indentify_records::read_one(ws.as_bytes(), "ws.txt", &ReadOptions::default()).unwrap();
    assert_eq!(r.t, vec![0.0, 1.5, 3.0]);
    assert!((r.h[1] - 10.2e-6).abs() < 1e-15 && (r.f[1] - 1.1e-3).abs() < 1e-15);
    let tab = "X_A_Time_[s]\tY_A_Fn_[mN]\tX_A_Time_[s]\tY_A_Pd_[nm]\n0\t0\t0\t0\n0.1\t0.5\t0.1\t10\n0.2\t1.0\t0.2\t20\n";
    let sp = tab.replace('\t', "   ");
    let a =
        indentify_records::read_one(tab.as_bytes(), "tab.txt", &ReadOptions::default()).unwrap();
    let b = indentify_records::read_one(sp.as_bytes(), "sp.txt", &ReadOptions::default()).unwrap();
    assert_eq!((a.t, a.h, a.f), (b.t, b.h, b.f));
}
