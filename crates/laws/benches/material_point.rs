//! Benchmarks of one material-point update: `Plastic` (rate-independent, Norton, with
//! power hardening), `Prony` with 3 terms, against `NortonHoff` (directly and through the
//! `LawMaterial` adapter). Each iteration updates the same 1024 points, from states around
//! the yield surface with strain increments of the order of the yield strain (most points
//! flow). `cargo bench -p indentify-laws`; numbers in docs/validation-laws.md.

use criterion::{Criterion, criterion_group, criterion_main};
use indentify_laws::{
    Hardening, Law, LawMaterial, Material, NortonHoff, Plastic, Prony, Rate, Vec4,
};
use std::hint::black_box;

const N: usize = 1024;

/// Deterministic numbers in [-1, 1) (xorshift).
fn stream(seed: u64) -> impl FnMut() -> f64 {
    let mut s = seed;
    move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }
}

/// `N` previous stresses of von Mises size 0.5 to 1.5 times 500 MPa and strain increments
/// up to 1e-2.
fn points() -> Vec<(Vec4, Vec4)> {
    let mut r = stream(0x2545f4914f6cdd1d);
    (0..N)
        .map(|_| {
            let s = Vec4([r(), r(), r(), r()]);
            let s = s * (500.0 * (1.0 + 0.5 * r()) / s.von_mises().max(1e-9));
            let d = Vec4([r(), r(), r(), r()]) * 1e-2;
            (s, d)
        })
        .collect()
}

fn run_material(mat: &dyn Material, c: &[f64], pts: &[(Vec4, Vec4)], internal: &[f64]) -> f64 {
    let m = mat.state_len();
    let mut y0 = vec![0.0; m];
    let mut y1 = vec![0.0; m];
    y0[4..].copy_from_slice(internal);
    let mut acc = 0.0;
    for (s, d) in pts {
        y0[..4].copy_from_slice(&s.0);
        let up = mat.update(c, &y0, d, 0.01, &mut y1).expect("update");
        acc += y1[1] + up.tangent.0[1][1];
    }
    acc
}

fn bench(c: &mut Criterion) {
    let pts = points();
    let mut g = c.benchmark_group("material_point_1024");
    let nh = [1e5, 0.3, 1500.0, 5.0, 500.0];
    g.bench_function("norton_hoff_law", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for (s, d) in &pts {
                let up = NortonHoff.update(&nh, s, d, 0.01).expect("update");
                acc += up.sigma[1] + up.tangent.0[1][1];
            }
            black_box(acc)
        })
    });
    let adapted = LawMaterial(&NortonHoff);
    g.bench_function("norton_hoff_material", |b| {
        b.iter(|| black_box(run_material(&adapted, &nh, &pts, &[])))
    });
    let nt_linear = Plastic::new(Hardening::Linear, Rate::Norton);
    let c_lin = [1e5, 0.3, 500.0, 0.0, 1500.0, 5.0];
    g.bench_function("plastic_norton_linear_h0", |b| {
        b.iter(|| black_box(run_material(&nt_linear, &c_lin, &pts, &[0.01])))
    });
    let ri = Plastic::new(Hardening::Power, Rate::Independent);
    let c_ri = [1e5, 0.3, 500.0, 0.2];
    g.bench_function("plastic_power_rate_independent", |b| {
        b.iter(|| black_box(run_material(&ri, &c_ri, &pts, &[0.01])))
    });
    let nt = Plastic::new(Hardening::Power, Rate::Norton);
    let c_nt = [1e5, 0.3, 500.0, 0.2, 1500.0, 5.0];
    g.bench_function("plastic_power_norton", |b| {
        b.iter(|| black_box(run_material(&nt, &c_nt, &pts, &[0.01])))
    });
    let prony = Prony::new(3).expect("3 terms");
    let c_pr = [1e5, 0.3, 0.3, 0.1, 0.2, 2.0, 0.25, 50.0];
    let iv = [0.0; 12];
    g.bench_function("prony_3_terms", |b| {
        b.iter(|| black_box(run_material(&prony, &c_pr, &pts, &iv)))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
