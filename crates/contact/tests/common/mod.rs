//! Test helpers shared by the contact crate's friction tests (small and finite strain).

use indentify_contact::{Model, Trajectory};

/// At every converged step: active nodes on the surface with `lambda >= 0` and that reaction
/// the normal component of the node's internal force; sticking off-axis nodes inside the
/// Coulomb cone (`|tau| <= mu lambda`) with their closest point where it was at the previous
/// step; slipping ones on the cone (`tau = -mu sigma lambda`) and moving along `sigma`.
/// `f_int(i)` is the internal force (all dofs) of the recorded state `i` (0 the initial
/// one), recomputed by the caller from its stresses. Returns (sticking, slipping)
/// node-steps.
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
