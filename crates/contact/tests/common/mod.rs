//! Test helpers shared by the contact crate's tests: the Coulomb conditions of the friction
//! tests (small and finite strain), and the workspace's test support (`crates/testkit`)
//! compiled in as a module: `testkit` depends on `contact`, so the contact crate cannot
//! take it as a dev-dependency without a cycle; its source is read here instead.

use indentify_contact::{ContactKind, Kinematics, Model, Punch, Schedule, Segment, Trajectory};

// Each test target uses a part of it.
#[allow(dead_code)]
#[path = "../../../testkit/src/lib.rs"]
pub mod testkit;

/// A 2 x 2 mm cylinder, `n` x `n` Q8 graded 1.3 towards the axis and the top, under
/// `punch` with contact `kind`.
#[allow(dead_code)]
pub fn model_2mm(n: usize, punch: Punch, kind: ContactKind) -> Model {
    Model::with_contact(testkit::cylinder(2.0, n, 1.3), punch, kind).unwrap()
}

/// [`model_2mm`] in 10 x 10 Q8 with kinematics `kin`.
#[allow(dead_code)]
pub fn model_2mm_kin(punch: Punch, kind: ContactKind, kin: Kinematics) -> Model {
    model_2mm(10, punch, kind).with_kinematics(kin).unwrap()
}

/// One segment: the punch to `depth` (mm) in 1 s, `steps` steps.
#[allow(dead_code)]
pub fn ramp(depth: f64, steps: usize) -> Schedule {
    Schedule::from_segments(&[Segment {
        duration: 1.0,
        depth,
        steps,
    }])
    .unwrap()
}

/// Newton's quadratic rate in the residuals `r` of a step's passes (residual, sets' key):
/// each pair of consecutive passes with the same contact and stick/slip sets, after the
/// first pass (which precedes any solve), above round-off (1e-13) and from below 1e-2,
/// shall have `r_next <= 10 r^2`. Returns how many pairs were checked.
#[allow(dead_code)]
pub fn quadratic_pairs(r: &[(f64, u32)]) -> usize {
    let mut checked = 0;
    for w in r.windows(2).skip(1) {
        if w[0].1 == w[1].1 && w[1].0 > 1e-13 && w[0].0 < 1e-2 {
            assert!(
                w[1].0 <= 10.0 * w[0].0 * w[0].0,
                "{:e} -> {:e} in {r:?}",
                w[0].0,
                w[1].0
            );
            checked += 1;
        }
    }
    checked
}

/// At every converged step: active nodes on the surface with `lambda >= 0` and that reaction
/// the normal component of the node's internal force; sticking off-axis nodes inside the
/// Coulomb cone (`|tau| <= mu lambda`) with their closest point where it was at the previous
/// step; slipping ones on the cone (`tau = -mu sigma lambda`) and moving along `sigma`.
/// `f_int(i)` is the internal force (all dofs) of the recorded state `i` (0 the initial
/// one), recomputed by the caller from its stresses. Returns (sticking, slipping)
/// node-steps.
#[allow(dead_code)]
pub fn check_coulomb(
    model: &Model,
    traj: &Trajectory,
    mu: f64,
    f_int: impl Fn(usize) -> Vec<f64>,
) -> (usize, usize) {
    let (mut n_stick, mut n_slip) = (0, 0);
    for (i, s) in traj.steps.iter().enumerate() {
        let (u0, u) = (&traj.fields[i].u, &traj.fields[i + 1].u);
        let depth0 = if i == 0 { 0.0 } else { traj.steps[i - 1].depth };
        let f_int = f_int(i + 1);
        assert_eq!(s.slip.len(), s.active.len());
        for ((&k, &lam), &st) in s.active.iter().zip(&s.lambda).zip(&s.slip) {
            let k = k as usize;
            let node = model.candidates[k];
            if model.dofs.equation(2 * node).is_none() {
                continue;
            }
            let p = model.project(k, u, s.depth).in_contact();
            let p0 = model.project(k, u0, depth0);
            assert!(p.gap.abs() <= 1e-12, "step {i} node {k}: gap {}", p.gap);
            assert!(lam >= -1e-9 * s.force.abs(), "step {i} node {k}: {lam}");
            let f = [f_int[2 * node], f_int[2 * node + 1]];
            // the recorded reaction is the normal component of this force
            let lam_here = -(f[0] * p.m[0] + f[1] * p.m[1]);
            assert!((lam_here - lam).abs() <= 1e-8 * s.force.abs());
            let tau = f[0] * p.t[0] + f[1] * p.t[1];
            let tol = 1e-8 * s.force.abs();
            if st == 0 {
                n_stick += 1;
                assert!(
                    tau.abs() <= mu * lam + tol,
                    "step {i} node {k}: {tau} vs {lam}"
                );
                assert!((p.s - p0.s).abs() <= 1e-11, "step {i} node {k} slid");
            } else {
                n_slip += 1;
                let sigma = f64::from(st);
                assert!(
                    (tau + mu * sigma * lam).abs() <= tol,
                    "step {i} node {k}: tau {tau}, mu lambda {}",
                    mu * lam
                );
                assert!(
                    sigma * (p.s - p0.s) >= -1e-11,
                    "step {i} node {k} slid back"
                );
            }
        }
    }
    (n_stick, n_slip)
}
