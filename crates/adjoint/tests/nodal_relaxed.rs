//! The all-nodal paths' checks of a run that ends at rest read the state of largest
//! stress as well as the last one (docs/validation-load-control.md §10, "The sweep of a
//! run unloaded to rest"):
//! - a two-term Prony solid indented, unloaded to zero depth and held until relaxed
//!   (its last states are round-off of the peak's) sweeps all-nodal
//!   (`material/nodal.rs`), under plain depth control and through the frame; its
//!   gradient equals the Gauss-point sweep's (`Adjoint::set_fused(false)`) and central
//!   differences of the direct solver's own runs. With the last state alone, the check
//!   measured round-off and refused the nodal sweep;
//! - a linear law whose residual's parameter derivative differs from the isotropic form
//!   only at larger stresses (an elastic law with a small cubic term) keeps the
//!   Gauss-point sensitivity pass on a run unloaded to rest: the last step's stresses
//!   alone cannot show the difference (`nodal_sens.rs`, `residual_is_isotropic`), so the
//!   nodal pass, which reads the isotropic form, would give other columns.

use indentify_adjoint::Adjoint;
use indentify_adjoint::check::relative_difference;
use indentify_contact::{
    ContactKind, DirectSolver, Frame, Model, Punch, Schedule, Segment, Trajectory,
};
use indentify_laws::{
    Elastic, ElasticDomain, Law, LawError, LawMaterial, LocalFailure, LocalUpdate, Mat4, Material,
    ParamInfo, Prony, Vec4,
};
use indentify_mesh::CylinderMesher;
use indentify_testkit::recording;

/// The 4 x 4 mm cylinder, 8 x 8 Q8 graded 1.45, under a cone of 68 deg, vertical contact.
fn model() -> Model {
    let mesh = CylinderMesher {
        radius: 4.0,
        height: 4.0,
        nr: 8,
        nz: 8,
        grading_r: 1.45,
        grading_z: 1.45,
    }
    .build()
    .unwrap();
    Model::with_contact(
        mesh,
        Punch::Cone {
            half_angle_deg: 68.0,
        },
        ContactKind::Vertical,
    )
    .unwrap()
}

/// To 0.06 mm in 1 s, hold 1 s, back to zero in 1 s (6 steps each), then held at zero
/// for `rest` s in 20 steps.
fn to_rest(rest: f64) -> Schedule {
    let seg = |duration, depth, steps| Segment {
        duration,
        depth,
        steps,
    };
    Schedule::from_segments(&[
        seg(1.0, 0.06, 6),
        seg(1.0, 0.06, 6),
        seg(1.0, 0.0, 6),
        seg(rest, 0.0, 20),
    ])
    .unwrap()
}

/// The cost's weights on the forces (every step, all nonzero).
fn weights(n: usize) -> Vec<f64> {
    (0..n).map(|i| 1.0 + 0.37 * ((i * 7) % 5) as f64).collect()
}

fn largest_stress(t: &Trajectory, j: usize) -> f64 {
    t.fields[j]
        .sigma
        .iter()
        .fold(0.0f64, |m, s| m.max(s.max_abs()))
}

const PRONY: [f64; 6] = [1e5, 0.3, 0.3, 0.2, 0.2, 2.0];

/// `J = sum w_i F_i` of a Prony run held until relaxed: all-nodal, equal to the
/// Gauss-point sweep, and to central differences; plain depth control, then depth
/// through the frame (`Cf = 1e-5` mm/N).
#[test]
fn prony_held_until_relaxed_sweeps_all_nodal() {
    let m = model();
    let mat = Prony::new(2).unwrap();
    let schedule = to_rest(100.0);
    let frame = Frame {
        compliance: 1e-5,
        ..Frame::default()
    };
    for through_frame in [false, true] {
        let run = |c: &[f64], record: bool| {
            let mut s = DirectSolver::new(&m).unwrap();
            if through_frame {
                s.run_compliant(&mat, c, &schedule, &frame, &recording(record, 1e-12))
            } else {
                s.run(&mat, c, &schedule, &recording(record, 1e-12))
            }
            .unwrap()
        };
        let t = run(&PRONY, true);
        let n = t.steps.len();
        let peak = (0..=n).fold(0.0f64, |a, j| a.max(largest_stress(&t, j)));
        let last = largest_stress(&t, n);
        let alpha_last = t.fields[n].alpha.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        println!(
            "frame {through_frame}: last stress {last:.2e} MPa, last internal variable \
             {alpha_last:.2e}, peak stress {peak:.3e} MPa, last force {:.2e} N",
            t.steps[n - 1].force
        );
        // relaxed: the last state is far below what the last-state check could measure
        assert!(last < 1e-9 * peak, "not relaxed: {last:.2e} of {peak:.2e}");
        let w = weights(n);
        let mut adj = Adjoint::new(&m).unwrap();
        let grad = |adj: &mut Adjoint| -> Vec<f64> {
            if through_frame {
                adj.gradient_compliant(&mat, &PRONY, &t, (&schedule, &frame), &w)
                    .unwrap()
                    .dj_dc
            } else {
                adj.gradient(&mat, &PRONY, &t, &w).unwrap().dj_dc
            }
        };
        let nodal = grad(&mut adj);
        assert!(
            adj.last_material_sweep_was_nodal(),
            "frame {through_frame}: the sweep of a relaxed run left the all-nodal path"
        );
        adj.set_fused(false);
        let points = grad(&mut adj);
        assert!(!adj.last_material_sweep_was_nodal());
        let scale = nodal
            .iter()
            .zip(&PRONY)
            .fold(0.0f64, |a, (g, c)| a.max((g * c).abs()));
        let off = nodal
            .iter()
            .zip(&points)
            .zip(&PRONY)
            .fold(0.0f64, |a, ((x, y), c)| a.max((x - y).abs() * c / scale));
        println!("  all-nodal vs Gauss-point sweep: {off:.2e} of the largest |dJ/dc_k c_k|");
        assert!(off <= 1e-12, "{off:.2e}");
        for k in 0..PRONY.len() {
            let h = 1e-6 * PRONY[k];
            let j = |x: f64| {
                let mut c = PRONY;
                c[k] = x;
                let t = run(&c, false);
                t.steps
                    .iter()
                    .zip(&w)
                    .map(|(s, w)| w * s.force)
                    .sum::<f64>()
            };
            let fd = (j(PRONY[k] + h) - j(PRONY[k] - h)) / (2.0 * h);
            let d = (nodal[k] - fd).abs() * PRONY[k] / scale;
            println!(
                "  {}: adjoint {:.10e}, central differences {fd:.10e}: {d:.1e} ({:.1e} plain)",
                mat.params()[k].name,
                nodal[k],
                relative_difference(nodal[k], fd)
            );
            assert!(d <= 1e-6, "{}: {d:.2e}", mat.params()[k].name);
        }
    }
}

/// Elasticity whose residual's derivative in `E` gains `1e-22 |s1|^2 (s1 - s0)_rr`
/// (MPa^3): a linear law (its stresses, tangent and update are elasticity's) that
/// differentiates its residual otherwise than the isotropic form `dS/dE (s1 - s0)`, by
/// about 3e-3 of it at the test's peak stress and not at all where the stresses stand
/// still (the steps held at rest, the last step's).
#[derive(Debug)]
struct Skewed;

impl Law for Skewed {
    fn name(&self) -> &'static str {
        "skewed elastic"
    }
    fn params(&self) -> &'static [ParamInfo] {
        Elastic.params()
    }
    fn compliance(&self, c: &[f64]) -> Mat4 {
        Elastic.compliance(c)
    }
    fn compliance_derivative(&self, c: &[f64], k: usize) -> Mat4 {
        Elastic.compliance_derivative(c, k)
    }
    fn flow(&self, c: &[f64], sigma: &Vec4) -> Vec4 {
        Elastic.flow(c, sigma)
    }
    fn flow_hessian(&self, c: &[f64], sigma: &Vec4) -> Mat4 {
        Elastic.flow_hessian(c, sigma)
    }
    fn flow_param_derivative(&self, c: &[f64], sigma: &Vec4, k: usize) -> Vec4 {
        Elastic.flow_param_derivative(c, sigma, k)
    }
    fn is_linear(&self) -> bool {
        Elastic.is_linear()
    }
    fn affine_update(&self, c: &[f64], dt: f64) -> Option<(Mat4, Mat4)> {
        Elastic.affine_update(c, dt)
    }
    fn elastic_domain(&self, c: &[f64], dt: f64) -> Option<ElasticDomain> {
        Elastic.elastic_domain(c, dt)
    }
    fn check_params(&self, c: &[f64]) -> Result<(), LawError> {
        Elastic.check_params(c)
    }
    fn check_differentiable(&self, c: &[f64]) -> Result<(), LawError> {
        Elastic.check_differentiable(c)
    }
    fn residual_param_derivative(
        &self,
        c: &[f64],
        s0: &Vec4,
        s1: &Vec4,
        dt: f64,
        k: usize,
    ) -> Vec4 {
        let mut out = vec![Vec4::ZERO; c.len()];
        self.residual_param_derivatives(c, s0, s1, dt, &mut out);
        out[k]
    }
    fn residual_param_derivatives(
        &self,
        c: &[f64],
        s0: &Vec4,
        s1: &Vec4,
        dt: f64,
        out: &mut [Vec4],
    ) {
        Elastic.residual_param_derivatives(c, s0, s1, dt, out);
        let m = s1.max_abs();
        out[0].0[0] += 1e-22 * m * m * (s1.0[0] - s0.0[0]);
    }
    fn tangent(&self, c: &[f64], sigma: &Vec4, dt: f64) -> Result<Mat4, LocalFailure> {
        Elastic.tangent(c, sigma, dt)
    }
    fn update(
        &self,
        c: &[f64],
        s0: &Vec4,
        deps: &Vec4,
        dt: f64,
    ) -> Result<LocalUpdate, LocalFailure> {
        Elastic.update(c, s0, deps, dt)
    }
}

#[test]
fn a_residual_derivative_off_the_isotropic_form_keeps_the_gauss_point_pass_at_rest() {
    let m = model();
    let mat = LawMaterial(&Skewed);
    let c = [1e5, 0.3];
    let t = DirectSolver::new(&m)
        .unwrap()
        .run(&mat, &c, &to_rest(1.0), &recording(true, 1e-12))
        .unwrap();
    let n = t.steps.len();
    let peak = (0..=n).fold(0.0f64, |a, j| a.max(largest_stress(&t, j)));
    println!(
        "last stress {:.2e} MPa, peak {peak:.3e} MPa",
        largest_stress(&t, n)
    );
    let mut adj = Adjoint::new(&m).unwrap();
    let fused = adj.sensitivities(&mat, &c, &t).unwrap();
    assert!(
        !adj.last_pass_nodal(),
        "the nodal pass ran for a residual derivative it does not hold"
    );
    adj.set_fused(false);
    let points = adj.sensitivities(&mat, &c, &t).unwrap();
    for k in 0..c.len() {
        let scale = points.df_dc.iter().fold(0.0f64, |a, r| a.max(r[k].abs()));
        let off = (fused.df_dc.iter().zip(&points.df_dc))
            .fold(0.0f64, |a, (x, y)| a.max((x[k] - y[k]).abs() / scale));
        println!("column {k}: default pass vs the Gauss-point pass {off:.2e}");
        assert!(off <= 1e-12, "column {k}: {off:.2e}");
    }
}
