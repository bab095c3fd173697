//! The adjoint sweep of a material with internal variables asks its blocks a counted
//! number of times (a linear material such as `Prony`: `A`, `D`, `E` once per step and
//! the contraction `mu^T P` once per Gauss point and step, no `P` block, in the
//! Gauss-point sweep; no block per point in the all-nodal one; a nonlinear one
//! such as `Plastic`: every block once per point, in one call); `Prony`'s closed-form
//! contraction gives the gradient of the block path to 1e-12, J2's joint blocks the
//! separate blocks' bits; the sweep gives the same bits on 1 and 2 threads.

use std::sync::atomic::{AtomicUsize, Ordering};

use indentify_adjoint::Adjoint;
use indentify_contact::{
    ContactKind, DirectSolver, Kinematics, Model, Punch, Schedule, SolverOptions, Trajectory,
    trapezoid,
};
use indentify_laws::{
    Hardening, InternalInfo, LocalFailure, Material, MaterialUpdate, ParamInfo, Plastic, Prony,
    Rate, Step, Vec4,
};
use indentify_testkit::cylinder;

/// Which block a sweep asked for.
#[derive(Clone, Copy, Debug)]
enum Block {
    State,
    Previous,
    Strain,
    Params,
    ParamsTranspose,
}

/// A material that forwards to `inner` and counts the blocks asked of it; with
/// `closed_form = false` it leaves `jac_params_transpose` to the trait's default (the
/// block `P` formed and contracted), the path every law had before its closed form.
#[derive(Debug)]
struct Counting<'a> {
    inner: &'a dyn Material,
    closed_form: bool,
    counts: [AtomicUsize; 5],
}

impl<'a> Counting<'a> {
    fn new(inner: &'a dyn Material, closed_form: bool) -> Counting<'a> {
        Counting {
            inner,
            closed_form,
            counts: Default::default(),
        }
    }
    fn add(&self, b: Block) {
        self.counts[b as usize].fetch_add(1, Ordering::Relaxed);
    }
    fn take(&self) -> [usize; 5] {
        std::array::from_fn(|k| self.counts[k].swap(0, Ordering::Relaxed))
    }
}

impl Material for Counting<'_> {
    fn name(&self) -> &'static str {
        self.inner.name()
    }
    fn params(&self) -> &[ParamInfo] {
        self.inner.params()
    }
    fn internal(&self) -> &[InternalInfo] {
        self.inner.internal()
    }
    fn is_linear(&self) -> bool {
        self.inner.is_linear()
    }
    fn check_differentiable(&self, c: &[f64]) -> Result<(), indentify_laws::LawError> {
        self.inner.check_differentiable(c)
    }
    fn residual(&self, c: &[f64], step: &Step<'_>, r: &mut [f64]) {
        self.inner.residual(c, step, r)
    }
    fn jac_state(&self, c: &[f64], step: &Step<'_>, out: &mut [f64]) {
        self.add(Block::State);
        self.inner.jac_state(c, step, out)
    }
    fn jac_previous(&self, c: &[f64], step: &Step<'_>, out: &mut [f64]) {
        self.add(Block::Previous);
        self.inner.jac_previous(c, step, out)
    }
    fn jac_strain(&self, c: &[f64], step: &Step<'_>, out: &mut [f64]) {
        self.add(Block::Strain);
        self.inner.jac_strain(c, step, out)
    }
    fn jac_params(&self, c: &[f64], step: &Step<'_>, out: &mut [f64]) {
        self.add(Block::Params);
        self.inner.jac_params(c, step, out)
    }
    fn jac_params_transpose(
        &self,
        c: &[f64],
        step: &Step<'_>,
        mu: &[f64],
        weight: f64,
        scratch: &mut [f64],
        out: &mut [f64],
    ) {
        self.add(Block::ParamsTranspose);
        if self.closed_form {
            self.inner
                .jac_params_transpose(c, step, mu, weight, scratch, out)
        } else {
            // the trait's default: `P` through `jac_params`, contracted
            let nc = c.len();
            self.jac_params(c, step, scratch);
            for (k, o) in out[..nc].iter_mut().enumerate() {
                *o += weight
                    * mu.iter()
                        .enumerate()
                        .map(|(r, m)| m * scratch[r * nc + k])
                        .sum::<f64>();
            }
        }
    }
    fn update(
        &self,
        c: &[f64],
        y0: &[f64],
        deps: &Vec4,
        dt: f64,
        y1: &mut [f64],
    ) -> Result<MaterialUpdate, LocalFailure> {
        self.inner.update(c, y0, deps, dt, y1)
    }
}

fn model(kind: ContactKind, kin: Kinematics) -> Model {
    let mesh = cylinder(4.0, 8, 1.3);
    Model::with_contact(mesh, Punch::Sphere { radius: 1.0 }, kind)
        .unwrap()
        .with_kinematics(kin)
        .unwrap()
}

fn run(m: &Model, mat: &dyn Material, c: &[f64]) -> (Trajectory, Vec<f64>) {
    let s = Schedule::from_segments(&trapezoid(0.1, 1.0, 1.0, 1.0, 4)).unwrap();
    let t = DirectSolver::new(m)
        .unwrap()
        .run(mat, c, &s, &SolverOptions::default())
        .unwrap();
    let rho = (0..t.steps.len())
        .map(|i| 1.0 + 0.37 * ((i * 7) % 5) as f64)
        .collect();
    (t, rho)
}

const PRONY2: [f64; 6] = [1e5, 0.3, 0.3, 0.2, 0.2, 2.0];

/// Counts per sweep (the profile of docs/performance.md "The Prony adjoint sweep"):
/// a linear material asks `A`, `D`, `E` once per step and `mu^T P` once per Gauss point
/// and step, never the block `P`; a nonlinear material (rate-independent J2) asks every
/// block once per Gauss point and step, in one `jac_blocks` call (here the trait's
/// default, which calls the four methods), and never `mu^T P` (the sweep contracts the
/// `P` it kept).
#[test]
fn the_sweep_asks_each_block_a_counted_number_of_times() {
    let m = model(ContactKind::Vertical, Kinematics::Small);
    let nq = m.disc.n_qp();
    let prony = Prony::new(2).unwrap();
    let counted = Counting::new(&prony, true);
    let (t, rho) = run(&m, &counted, &PRONY2);
    counted.take();
    let n = t.steps.len();
    // the Gauss-point sweep (the all-nodal one off)
    let mut adj = Adjoint::new(&m).unwrap();
    adj.set_fused(false);
    adj.gradient(&counted, &PRONY2, &t, &rho).unwrap();
    let [a, d, e, p, pt] = counted.take();
    assert_eq!(
        (a, d, e, p, pt),
        (n, n, n, 0, n * nq),
        "{n} steps, {nq} points"
    );
    // the all-nodal sweep (`material/nodal.rs`): no block per point; `A`, `D`, `E` once
    // per step and once for the one step length's operators, whose parameter blocks are
    // probed with `P` (`1 + 2 m + 4` calls) and checked at one recorded point (`1`)
    adj.set_fused(true);
    adj.gradient(&counted, &PRONY2, &t, &rho).unwrap();
    assert!(adj.last_material_sweep_was_nodal());
    let [a, d, e, p, pt] = counted.take();
    let m_state = prony.state_len();
    assert_eq!(
        (a, d, e, p, pt),
        (n + 1, n + 1, n + 1, 2 * m_state + 6, 0),
        "{n} steps"
    );

    let pl = Plastic::new(Hardening::Linear, Rate::Independent);
    let c = [1e5, 0.3, 500.0, 1000.0];
    let counted = Counting::new(&pl, false);
    let (t, rho) = run(&m, &counted, &c);
    counted.take();
    let n = t.steps.len();
    Adjoint::new(&m)
        .unwrap()
        .gradient(&counted, &c, &t, &rho)
        .unwrap();
    let [a, d, e, p, pt] = counted.take();
    assert_eq!(
        (a, d, e, p, pt),
        (n * nq, n * nq, n * nq, n * nq, 0),
        "{n} steps, {nq} points"
    );
}

/// J2's `jac_blocks` (every block of a point from one evaluation of `s_eq`, the
/// hardening and the Norton rate) and its closed-form solve with `A^T` give the gradient
/// of the four separate methods and the elimination (the trait's defaults, through the
/// forwarding material) to 1e-11 relative: each hardening form, rate-independent and
/// Norton, small and finite strain.
#[test]
fn plastic_joint_blocks_and_solve_give_the_separate_blocks_gradient() {
    let (e, nu, sy, k, mm) = (1e5, 0.3, 500.0, 1500.0, 5.0);
    let forms = [
        (Hardening::Linear, vec![1000.0]),
        (Hardening::Power, vec![0.2]),
        (Hardening::Voce, vec![300.0, 20.0]),
    ];
    let mut worst = 0.0f64;
    for kin in [Kinematics::Small, Kinematics::Finite] {
        let m = model(ContactKind::Normal, kin);
        for (h, hp) in &forms {
            for rate in [Rate::Independent, Rate::Norton] {
                let pl = Plastic::new(h.clone(), rate);
                let mut c = vec![e, nu, sy];
                c.extend(hp);
                if rate == Rate::Norton {
                    c.extend([k, mm]);
                }
                let (t, rho) = run(&m, &pl, &c);
                let mut adj = Adjoint::new(&m).unwrap();
                let joint = adj.gradient(&pl, &c, &t, &rho).unwrap().dj_dc;
                let separate = Counting::new(&pl, false);
                let apart = adj.gradient(&separate, &c, &t, &rho).unwrap().dj_dc;
                assert!(separate.take()[Block::State as usize] > 0);
                // (the separate path also solves with A^T by elimination, the joint one
                // in J2's closed form: round-off apart)
                let big = joint
                    .iter()
                    .zip(&c)
                    .fold(0.0f64, |a, (g, c)| a.max((g * c).abs()));
                for k in 0..c.len() {
                    let d = (joint[k] - apart[k]).abs() * c[k] / big;
                    assert!(
                        d <= 1e-11,
                        "{h:?} {rate:?} {kin:?} {k}: {} vs {} ({d:e})",
                        joint[k],
                        apart[k]
                    );
                    worst = worst.max(d);
                }
                assert!(joint.iter().all(|g| g.is_finite() && *g != 0.0));
            }
        }
    }
    eprintln!("joint blocks and closed-form solve against the separate path: {worst:e}");
}

/// Prony's closed-form `mu^T P` gives the gradient of the block path (`P` formed per
/// point and contracted, as before the closed form) to 1e-12 relative, for one to three
/// terms, under vertical and frictionless normal contact (small strain) and normal contact
/// under finite strain.
#[test]
fn prony_closed_form_contraction_gives_the_block_paths_gradient() {
    let terms = [(0.3, 0.2), (0.2, 2.0), (0.1, 0.05)];
    for (kind, kin) in [
        (ContactKind::Vertical, Kinematics::Small),
        (ContactKind::Normal, Kinematics::Small),
        (ContactKind::Normal, Kinematics::Finite),
    ] {
        let m = model(kind, kin);
        for n in 1..=3 {
            let prony = Prony::new(n).unwrap();
            let mut c = vec![1e5, 0.3];
            for &(g, tau) in &terms[..n] {
                c.extend([g, tau]);
            }
            let (t, rho) = run(&m, &prony, &c);
            let mut adj = Adjoint::new(&m).unwrap();
            // the Gauss-point sweep's contraction (the all-nodal sweep contracts none)
            adj.set_fused(false);
            let fast = adj.gradient(&prony, &c, &t, &rho).unwrap().dj_dc;
            let block = Counting::new(&prony, false);
            let slow = adj.gradient(&block, &c, &t, &rho).unwrap().dj_dc;
            assert!(block.take()[Block::Params as usize] > 0);
            let big = fast
                .iter()
                .zip(&c)
                .fold(0.0f64, |a, (g, c)| a.max((g * c).abs()));
            for k in 0..c.len() {
                let d = (fast[k] - slow[k]).abs() * c[k] / big;
                assert!(
                    d <= 1e-12,
                    "{kind:?} {kin:?} {n} terms, {}: {} vs {} ({d:e})",
                    prony.params()[k].name,
                    fast[k],
                    slow[k]
                );
            }
        }
    }
}

/// The gradient of a Prony solid and of J2 with Norton overstress: the same bits on one
/// and on two threads (vertical contact, small strain; normal contact, finite strain).
#[test]
fn material_gradients_are_bit_identical_on_one_and_two_threads() {
    let prony = Prony::new(2).unwrap();
    let pl = Plastic::new(Hardening::Power, Rate::Norton);
    let pl_c = [1e5, 0.3, 500.0, 0.2, 1500.0, 5.0];
    let cases: [(&dyn Material, &[f64]); 2] = [(&prony, &PRONY2), (&pl, &pl_c)];
    for (kind, kin) in [
        (ContactKind::Vertical, Kinematics::Small),
        (ContactKind::Normal, Kinematics::Finite),
    ] {
        let m = model(kind, kin);
        for (mat, c) in cases {
            let grad = |threads: usize| {
                rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap()
                    .install(|| {
                        let (t, rho) = run(&m, mat, c);
                        let g = Adjoint::new(&m)
                            .unwrap()
                            .gradient(mat, c, &t, &rho)
                            .unwrap();
                        g.dj_dc.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
                    })
            };
            assert_eq!(grad(1), grad(2), "{} {kin:?}", mat.name());
        }
    }
}
