//! Reading the real instrument records of `examples/data` (see its README for provenance).

use indentify_records::{Format, ReadOptions, Record, read, read_one};

const ANON: &[u8] = include_bytes!("../../../examples/data/anton-paar-unht-berkovich/anonNI.TXT");
const MULTI: &[u8] = include_bytes!("../../../examples/data/anton-paar-sphere-creep/HT_V_100mN.TXT");
const ROBIN: &[u8] = include_bytes!("../../../examples/data/hysitron/RobinSteel0000LC.txt");
const HLD: &[u8] = include_bytes!("../../../examples/data/hysitron/Exp-50mN_0000.hld");

fn summary(r: &Record) -> String {
    format!(
        "{}: {} rows, t {}..{} s, h_max {:.3} nm, F_max {:.4} mN",
        r.name,
        r.len(),
        r.t[0],
        r.t[r.len() - 1],
        r.h_max() * 1e6,
        r.f_max() * 1e3
    )
}

#[test]
fn print_all() {
    for (b, n) in [(ANON, "anonNI.TXT"), (MULTI, "HT_V_100mN.TXT"), (ROBIN, "RobinSteel0000LC.txt"), (HLD, "Exp-50mN_0000.hld")] {
        let rs = read(b, n, &ReadOptions::default()).unwrap();
        for r in &rs {
            println!("{}", summary(r));
            println!("{:?}", r.meta);
        }
    }
    let _ = (Format::Auto, read_one);
}

#[test]
fn print_prep() {
    use indentify_records::{Preprocessing, Resample, apply};
    let p = Preprocessing { resample: Some(Resample::default()), drift: indentify_records::Correction::Auto, compliance: indentify_records::Correction::Auto, ..Preprocessing::default() };
    for (b, n) in [(ANON, "anonNI.TXT"), (MULTI, "HT_V_100mN.TXT"), (ROBIN, "RobinSteel0000LC.txt"), (HLD, "Exp-50mN_0000.hld")] {
        for r in read(b, n, &ReadOptions::default()).unwrap() {
            let (x, done) = apply(&r, &p).unwrap();
            println!("{}", summary(&x));
            for a in done { println!("  {}: {}", a.step, a.description); }
        }
    }
}
