//! Load control at a constant `Pdot/P` against closed forms
//! (docs/validation-load-control.md §12): an elastic cone under `P = P_s exp(r (t - t_s))`
//! follows Sneddon, `h ~ sqrt(P)`, so `h(t) = h_s exp(r (t - t_s) / 2)`: the loading strain
//! rate `hdot/h` is `r/2` exactly; and a Maxwell solid under the same protocol follows the
//! time-discrete Lee-Radok solution (docs/validation-viscous.md §3) inverted for the depth
//! with the forces the run carried, as docs/validation-load-control.md §3 does for a
//! linear ramp and a hold.
//!
//! ```text
//!   cone:    F = (2/pi) tan(alpha) E* h^2
//!   Maxwell: h_n^2 = h_{n-1}^2 + [pi F_n / (2 tan(alpha)) - sum_{j<n} Psi_d(n, j) d_j] / Psi_d(n, n)
//! ```

mod common;
mod viscous;

use common::*;
use indentify_contact::{DirectSolver, LoadHistory, Model, Punch, SegmentSpec, Trajectory};
use indentify_laws::{Elastic, Law, Maxwell};
use indentify_mesh::Mesh;
use viscous::Relaxation;

fn run(mesh: Mesh, law: &dyn Law, c: &[f64], h: &[SegmentSpec]) -> Trajectory {
    let cone = Punch::Cone {
        half_angle_deg: ALPHA_DEG,
    };
    let model = Model::new(mesh, cone).expect("valid model");
    let mut solver = DirectSolver::new(&model).expect("symbolic analysis");
    let history = LoadHistory::from_specs(h).expect("valid history");
    solver
        .run_history(&indentify_laws::LawMaterial(law), c, &history, &options())
        .expect("load-controlled run converges")
}

/// A trigger ramp to `p / 27` in 0.1 s (3 steps), then constant Pdot/P = `r` to `p` in
/// `n` steps (the depth grows by 27^(1/2) = 5.2 in the elastic limit), then `hold` s at
/// `p` (3 steps a second) if `hold > 0`.
fn protocol(p: f64, r: f64, n: usize, hold: f64) -> Vec<SegmentSpec> {
    let linear = |duration: f64, force: f64, steps| SegmentSpec {
        duration: Some(duration),
        depth: None,
        force: Some(force),
        pdot_over_p: None,
        steps,
    };
    let mut v = vec![
        linear(0.1, p / 27.0, 3),
        SegmentSpec {
            duration: None,
            depth: None,
            force: Some(p),
            pdot_over_p: Some(r),
            steps: n,
        },
    ];
    if hold > 0.0 {
        v.push(linear(hold, p, (3.0 * hold).ceil() as usize));
    }
    v
}

/// The least-squares slope of `ln h` against `t`.
fn log_slope(points: &[(f64, f64)]) -> f64 {
    let n = points.len() as f64;
    let (mt, ml) = points
        .iter()
        .fold((0.0, 0.0), |(a, b), &(t, h)| (a + t / n, b + h.ln() / n));
    let (num, den) = points.iter().fold((0.0, 0.0), |(a, b), &(t, h)| {
        (a + (t - mt) * (h.ln() - ml), b + (t - mt) * (t - mt))
    });
    num / den
}

/// R0's elastic solid under the cone on R1's mesh, loaded at Pdot/P = 0.5/s to Sneddon's
/// force at 0.1 mm: every depth from h_max/3 on within 1.5% of Sneddon's at the force the
/// step carried, and the loading strain rate `hdot/h` (the least-squares slope of `ln h`
/// in time over those steps) within 1% of `r/2`.
#[test]
fn elastic_cone_at_constant_pdot_over_p_loads_at_hdot_over_h_r_over_2() {
    let es = e_star(E, NU);
    let p = sneddon_cone_force(H_MAX, ALPHA_DEG, es);
    let r = 0.5;
    let t = run(
        cylinder(10.0, 20, 1.3),
        &Elastic,
        &[E, NU],
        &protocol(p, r, 24, 0.0),
    );
    let steps: Vec<_> = t.schedule_steps().collect();
    assert_eq!(steps.len(), 27);
    let mut worst: f64 = 0.0;
    let mut points = Vec::new();
    for s in &steps[3..] {
        let h_ref = H_MAX * (s.force / p).sqrt();
        if s.depth >= H_MAX / 3.0 {
            worst = worst.max(rel(s.depth, h_ref).abs());
            points.push((s.t, s.depth));
        }
    }
    let slope = log_slope(&points);
    println!(
        "elastic cone, Pdot/P = {r}/s to {p:.2} N: worst |h / h_Sneddon - 1| = {:.3}% over {} \
         steps from h_max/3; hdot/h = {slope:.5}/s vs r/2 = {} ({:+.3}%)",
        100.0 * worst,
        points.len(),
        r / 2.0,
        100.0 * rel(slope, r / 2.0)
    );
    assert!(points.len() >= 12, "{}", points.len());
    assert!(worst < 0.015, "{worst}");
    assert!(rel(slope, r / 2.0).abs() < 0.01, "{slope}");
}

/// R1's Maxwell solid (E = 20000 MPa, nu = 0.3, eta = 30000 MPa s) under the cone on R1's
/// mesh, loaded at Pdot/P = 2/s to Sneddon's elastic force at 0.1 mm (24 steps, 1.65 s)
/// and held 1 s: from h_max/3 on the depths follow the inverted discrete Lee-Radok
/// relation scaled by the elastic run's ratio `h_FE / h_Sneddon` at the step's depth
/// within 0.6% (by its final ratio alone within 1%: the elastic ratio itself varies by
/// 0.7% along the loading), and the creep over the hold within 2%.
#[test]
fn maxwell_cone_at_constant_pdot_over_p_follows_the_discrete_lee_radok_solution() {
    let es = e_star(E, NU);
    let eta = 30000.0;
    let p = sneddon_cone_force(H_MAX, ALPHA_DEG, es);
    let r = 2.0;
    let h = protocol(p, r, 24, 1.0);
    let elastic = run(cylinder(10.0, 20, 1.3), &Elastic, &[E, NU], &h[..2]);
    let s = elastic.steps.last().expect("steps").depth / H_MAX;
    // the elastic run's ratio along the loading, `h_FE / h_Sneddon` against `h_FE`: the
    // FE's elastic error at each depth (node quantization of the contact radius)
    let ratio: Vec<(f64, f64)> = elastic
        .schedule_steps()
        .map(|x| (x.depth, x.depth / (H_MAX * (x.force / p).sqrt())))
        .collect();
    let s_at = |h: f64| {
        let i = ratio.partition_point(|x| x.0 < h).clamp(1, ratio.len() - 1);
        let ((h0, s0), (h1, s1)) = (ratio[i - 1], ratio[i]);
        if h >= h1 {
            s1
        } else {
            s0 + (s1 - s0) * (h - h0) / (h1 - h0)
        }
    };
    let t = run(cylinder(10.0, 20, 1.3), &Maxwell, &[E, NU, eta], &h);
    let steps: Vec<_> = t.schedule_steps().collect();
    let times: Vec<f64> = std::iter::once(0.0)
        .chain(steps.iter().map(|x| x.t))
        .collect();
    let force: Vec<f64> = std::iter::once(0.0)
        .chain(steps.iter().map(|x| x.force))
        .collect();
    let psi = Relaxation::maxwell_indentation(E, NU, eta);
    let c = 2.0 * ALPHA_DEG.to_radians().tan() / std::f64::consts::PI;
    let mut d = vec![0.0; times.len()];
    let mut h2 = vec![0.0; times.len()];
    for n in 1..times.len() {
        let past: f64 = (1..n)
            .map(|j| psi.backward_euler(&times, j, n) * d[j])
            .sum();
        d[n] = (force[n] / c - past) / psi.backward_euler(&times, n, n);
        h2[n] = h2[n - 1] + d[n];
    }
    let mut worst: f64 = 0.0;
    let mut worst_all: f64 = 0.0;
    let mut worst_local: f64 = 0.0;
    for (n, st) in steps.iter().enumerate() {
        let h_ref = s * h2[n + 1].sqrt();
        if st.depth >= H_MAX / 3.0 {
            worst = worst.max(rel(st.depth, h_ref).abs());
            // the elastic error divided out at the step's own depth
            let local = s_at(st.depth) * h2[n + 1].sqrt();
            worst_local = worst_local.max(rel(st.depth, local).abs());
        }
        worst_all = worst_all.max(rel(st.depth, h_ref).abs());
    }
    let (a, b) = (27, steps.len());
    let (ha, hb) = (steps[a - 1].depth, steps[b - 1].depth);
    let (ra, rb) = (s * h2[a].sqrt(), s * h2[b].sqrt());
    println!(
        "Maxwell cone at Pdot/P = {r}/s to {p:.2} N: s = {s:.5}; worst |h / (s h_LR) - 1| = \
         {:.3}% from h_max/3 on ({:.3}% over all steps); creep over the hold {:.6} mm vs \
         {:.6} mm ({:+.2}%); with the elastic ratio at each depth {:.3}%",
        100.0 * worst,
        100.0 * worst_all,
        hb - ha,
        rb - ra,
        100.0 * rel(hb - ha, rb - ra),
        100.0 * worst_local
    );
    assert!(worst_local < 0.006, "{worst_local}");
    assert!(worst < 0.01, "{worst}");
    assert!(rel(hb - ha, rb - ra).abs() < 0.02);
    assert!(hb > 1.05 * ha, "creep {ha} -> {hb}");
}
