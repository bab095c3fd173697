//! Depth control through the instrument's frame unloaded to rest (the machine depth back
//! to zero, docs/validation-load-control.md §10, "The sweep of a run unloaded to rest"):
//! an elastic run ends with stresses of round-off, and its sweep must still take the
//! all-nodal path (`Adjoint::last_sweep_was_nodal`), equal to the Gauss-point pass to
//! round-off; a plastic run leaves its impression and ends out of contact, and its sweep
//! skips the steps after the last contact (no factorization for them) while its gradient
//! stays the forward sensitivities' and central differences'.

mod common;

use common::{small_model, weighted_forces};
use indentify_adjoint::{Adjoint, FrameGradient, FrameIndex};
use indentify_contact::{
    ContactKind, DirectSolver, Frame, Model, Schedule, SolverOptions, Trajectory,
};
use indentify_laws::{Elastic, Hardening, LawMaterial, Material, Plastic, Rate};
use indentify_testkit::{cone68 as cone, depth_lhu, recording, weights};

fn opts(record: bool) -> SolverOptions {
    recording(record, 1e-12)
}

/// Machine depth: ramp to `h` mm, hold, unload to zero, `steps` steps per segment (1 s
/// each).
fn to_rest(h: f64, steps: usize) -> Schedule {
    depth_lhu(h, 0.0, steps)
}

const FRAME: Frame = Frame {
    compliance: 1e-4,
    drift: 0.0,
    offset: 0.0,
};

fn run(m: &Model, mat: &dyn Material, c: &[f64], schedule: &Schedule) -> Trajectory {
    DirectSolver::new(m)
        .unwrap()
        .run_compliant(mat, c, schedule, &FRAME, &opts(true))
        .unwrap()
}

/// Every entry of the gradient (the law's, the frame's, each `dJ/dH_i`) scaled by its
/// parameter (`dJ/dH_i` by the peak depth), as one vector.
fn scaled(g: &FrameGradient, c: &[f64], h_max: f64) -> Vec<f64> {
    let mut v: Vec<f64> = g.dj_dc.iter().zip(c).map(|(g, c)| g * c).collect();
    v.push(g.dj_dframe[0] * FRAME.compliance);
    v.extend(g.dj_dframe[1..].iter().map(|d| d * h_max));
    v.extend(g.dj_dh.iter().map(|d| d * h_max));
    v
}

/// The largest entry difference relative to the largest entry.
fn rel(a: &[f64], b: &[f64]) -> f64 {
    let big = a.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    assert!(big > 0.0);
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs() / big))
}

/// `J` of a compliant run at the law's parameters `p`.
fn cost(m: &Model, mat: &dyn Material, p: &[f64], schedule: &Schedule, n: usize) -> f64 {
    let t = DirectSolver::new(m)
        .unwrap()
        .run_compliant(mat, p, schedule, &FRAME, &opts(false))
        .unwrap();
    weighted_forces(&t, n)
}

/// The law's gradient against central differences (relative step `h_rel`), the worst
/// relative to the largest `|dJ/dc_k c_k|`.
fn against_differences(
    m: &Model,
    mat: &dyn Material,
    c: &[f64],
    schedule: &Schedule,
    g: &[f64],
    h_rel: f64,
    n: usize,
) -> f64 {
    let big = g
        .iter()
        .zip(c)
        .fold(0.0f64, |a, (g, c)| a.max((g * c).abs()));
    let mut worst = 0.0f64;
    for k in 0..c.len() {
        let h = h_rel * c[k].abs();
        let mut q = c.to_vec();
        q[k] = c[k] + h;
        let fp = cost(m, mat, &q, schedule, n);
        q[k] = c[k] - h;
        let fm = cost(m, mat, &q, schedule, n);
        let fd = (fp - fm) / (2.0 * h);
        let r = (fd - g[k]).abs() * c[k].abs() / big;
        println!(
            "{} c[{k}]: adjoint {:.10e}, fd {fd:.10e}, rel {r:.2e}",
            mat.name(),
            g[k]
        );
        worst = worst.max(r);
    }
    worst
}

/// An elastic solid unloaded to rest through the frame: the last recorded stresses are
/// round-off, so checking the nodal form against them alone measured nothing and refused
/// the all-nodal sweep (the Gauss-point pass swept every step). The sweep now checks the
/// state of largest stress too and runs all-nodal, to the Gauss-point pass's gradient to
/// round-off and central differences.
#[test]
fn elastic_unloaded_to_rest_sweeps_all_nodal() {
    let m = small_model(cone(), ContactKind::Vertical);
    let mat = LawMaterial(&Elastic);
    let c = [1e5, 0.3];
    let schedule = to_rest(0.06, 8);
    let traj = run(&m, &mat, &c, &schedule);
    let n = traj.steps.len();
    let peak = traj.fields.iter().fold(0.0f64, |a, f| {
        f.sigma.iter().fold(a, |a, s| a.max(s.max_abs()))
    });
    let last = traj.fields[n]
        .sigma
        .iter()
        .fold(0.0f64, |a, s| a.max(s.max_abs()));
    println!("largest stress {peak:.3e} MPa, last {last:.3e} MPa");
    assert!(last < 1e-9 * peak, "the run does not end at rest: {last:e}");
    let h_max = traj.steps.iter().fold(0.0f64, |a, s| a.max(s.depth));
    let w = weights(n);
    let mut adj = Adjoint::new(&m).unwrap();
    let nodal = adj
        .gradient_compliant(&mat, &c, &traj, (&schedule, &FRAME), &w)
        .unwrap();
    assert!(
        adj.last_sweep_was_nodal(),
        "the sweep left the all-nodal path"
    );
    adj.set_fused(false);
    let points = adj
        .gradient_compliant(&mat, &c, &traj, (&schedule, &FRAME), &w)
        .unwrap();
    assert!(!adj.last_sweep_was_nodal());
    let off = rel(&scaled(&points, &c, h_max), &scaled(&nodal, &c, h_max));
    println!("all-nodal vs Gauss-point sweep: {off:.2e}");
    assert!(off < 1e-12, "{off:.2e}");
    let fd = against_differences(&m, &mat, &c, &schedule, &nodal.dj_dc, 1e-5, n);
    assert!(fd < 1e-7, "{fd:.2e}");
}

/// J2 with power hardening and Norton overstress unloaded to zero machine depth: the
/// punch leaves the impression and the last steps carry no force. The sweep skips them
/// (as the depth-controlled sweep does): one factorization per step up to the last
/// contact, none after; the gradient is the forward sensitivities' `J^T w` to
/// round-off and the central differences'.
#[test]
fn plastic_unloaded_off_its_impression_skips_the_steps_after_contact() {
    let m = small_model(cone(), ContactKind::Vertical);
    let mat = Plastic::new(Hardening::Power, Rate::Norton);
    let c = [1e5, 0.3, 500.0, 0.2, 1500.0, 5.0];
    let schedule = to_rest(0.06, 8);
    let traj = run(&m, &mat, &c, &schedule);
    let n = traj.steps.len();
    let last_contact = (0..n)
        .rev()
        .find(|&i| !traj.steps[i].active.is_empty())
        .unwrap();
    println!("{n} steps, the last in contact {last_contact}");
    assert!(last_contact + 3 <= n, "too few steps out of contact");
    let w = weights(n);
    let mut adj = Adjoint::new(&m).unwrap();
    let g = adj
        .gradient_compliant(&mat, &c, &traj, (&schedule, &FRAME), &w)
        .unwrap();
    println!("factorizations {}", g.factorizations);
    assert_eq!(g.factorizations, last_contact + 1);
    assert!(g.dj_dh[last_contact + 1..].iter().all(|d| *d == 0.0));
    // the forward sensitivities sweep every step forward
    let s = adj
        .sensitivities_compliant(&mat, &c, &traj, (&schedule, &FRAME), FrameIndex::default())
        .unwrap();
    let jtw: Vec<f64> = (0..c.len())
        .map(|k| (0..n).map(|i| s.df_dc[i][k] * w[i]).sum())
        .collect();
    let a: Vec<f64> = g.dj_dc.iter().zip(&c).map(|(g, c)| g * c).collect();
    let b: Vec<f64> = jtw.iter().zip(&c).map(|(g, c)| g * c).collect();
    let off = rel(&a, &b);
    println!("adjoint vs J^T w of the sensitivities: {off:.2e}");
    assert!(off < 1e-12, "{off:.2e}");
    let fd = against_differences(&m, &mat, &c, &schedule, &g.dj_dc, 1e-5, n);
    assert!(fd < 1e-6, "{fd:.2e}");
}

/// The same check under plain depth control, which shares it: the elastic run unloaded to
/// rest now sweeps all-nodal (`Adjoint::gradient`) and its forward sensitivities
/// (`Adjoint::sensitivities`, which start from the same check) equal the Gauss-point
/// pass's to round-off, whichever path they take.
#[test]
fn depth_controlled_elastic_run_unloaded_to_rest() {
    let m = small_model(cone(), ContactKind::Vertical);
    let mat = LawMaterial(&Elastic);
    let c = [1e5, 0.3];
    let schedule = to_rest(0.06, 8);
    let traj = DirectSolver::new(&m)
        .unwrap()
        .run(&mat, &c, &schedule, &opts(true))
        .unwrap();
    let n = traj.steps.len();
    let w = weights(n);
    let mut adj = Adjoint::new(&m).unwrap();
    let nodal = adj.gradient(&mat, &c, &traj, &w).unwrap();
    assert!(
        adj.last_sweep_was_nodal(),
        "the sweep left the all-nodal path"
    );
    let s_fused = adj.sensitivities(&mat, &c, &traj).unwrap();
    let s_nodal = adj.last_pass_nodal();
    adj.set_fused(false);
    let points = adj.gradient(&mat, &c, &traj, &w).unwrap();
    let s_points = adj.sensitivities(&mat, &c, &traj).unwrap();
    let a: Vec<f64> = nodal.dj_dc.iter().zip(&c).map(|(g, c)| g * c).collect();
    let b: Vec<f64> = points.dj_dc.iter().zip(&c).map(|(g, c)| g * c).collect();
    let off = rel(&a, &b);
    println!("depth control, all-nodal vs Gauss-point sweep: {off:.2e}");
    assert!(off < 1e-12, "{off:.2e}");
    let flat = |s: &indentify_adjoint::Sensitivities| -> Vec<f64> {
        s.df_dc
            .iter()
            .flat_map(|r| r.iter().zip(&c).map(|(d, c)| d * c))
            .collect()
    };
    let off = rel(&flat(&s_points), &flat(&s_fused));
    println!("sensitivities (all-nodal: {s_nodal}) vs the Gauss-point pass: {off:.2e}");
    assert!(off < 1e-12, "{off:.2e}");
}
