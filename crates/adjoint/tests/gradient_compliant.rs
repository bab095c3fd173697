//! Depth control through the instrument's frame (docs/theory.md §13.7): the adjoint
//! gradient of a cost on the forces (`Adjoint::gradient_compliant`) with respect to the
//! law's parameters and the frame's compliance `Cf`, drift `vd` and offset `h0`, against
//! central differences of the direct solver's own compliant runs
//! (`DirectSolver::run_compliant`) over a load-hold-unload of the machine depth: Maxwell
//! under a cone with vertical contact, Maxwell and J2 with power-law hardening and Norton
//! overstress (internal variables) under a sphere with frictionless normal contact, small
//! and finite strain; at `Cf = 0` (plain depth control) the frame's derivatives are the
//! force's sensitivity to the prescribed depth history. Coulomb friction, and the forward
//! sensitivities of laws with internal variables: `compliant_frame.rs`.

mod common;

use common::{finite_model, small_model, weighted_forces};
use indentify_adjoint::Adjoint;
use indentify_contact::{ContactKind, DirectSolver, Frame, Model, Schedule, SolverOptions};
use indentify_laws::{Hardening, LawMaterial, Material, Maxwell, Plastic, Rate};
use indentify_testkit::{cone68 as cone, depth_lhu, recording, sphere1 as sphere, weights};

fn opts(record: bool) -> SolverOptions {
    recording(record, 1e-12)
}

/// Machine depth: ramp to `h` mm, hold, unload to `0.6 h`, `steps` steps per segment
/// (1 s each).
fn lhu(h: f64, steps: usize) -> Schedule {
    depth_lhu(h, 0.6 * h, steps)
}

/// `J(c, frame)` of a compliant run without fields (the same steps as the recorded run).
fn cost(
    solver: &mut DirectSolver,
    mat: &dyn Material,
    p: &[f64],
    schedule: &Schedule,
    n: usize,
) -> f64 {
    let nl = p.len() - 3;
    let frame = Frame {
        compliance: p[nl],
        drift: p[nl + 1],
        offset: p[nl + 2],
    };
    let t = solver
        .run_compliant(mat, &p[..nl], schedule, &frame, &opts(false))
        .unwrap();
    weighted_forces(&t, n)
}

/// Adjoint vs differences of `J = sum w_i F_i` for the law's parameters `c` and the
/// frame's, central with the relative step `h_rel` (the frame's at `Cf = 0`: a one-sided
/// second-order difference for `Cf`, which cannot be negative, with the step that makes `Cf F_max` 1e-5 of the peak depth: below the first change of a
/// contact set on these grids).
/// Returns the worst difference relative to the largest `|dJ/dp_k p_k|` (`p_k` = 1e-4
/// mm/N for a zero `Cf`).
fn check(
    m: &Model,
    mat: &dyn Material,
    c: &[f64],
    frame: &Frame,
    schedule: &Schedule,
    h_rel: f64,
) -> f64 {
    let mut solver = DirectSolver::new(m).unwrap();
    let traj = solver
        .run_compliant(mat, c, schedule, frame, &opts(true))
        .unwrap();
    let n = traj.steps.len();
    let mut adj = Adjoint::new(m).unwrap();
    let g = adj
        .gradient_compliant(mat, c, &traj, (schedule, frame), &weights(n))
        .unwrap();
    let mut p = c.to_vec();
    p.extend([frame.compliance, frame.drift, frame.offset]);
    let mut grad = g.dj_dc.clone();
    grad.extend(g.dj_dframe);
    let names: Vec<&str> = mat
        .params()
        .iter()
        .map(|i| i.name)
        .chain(["Cf", "vd", "h0"])
        .collect();
    let nl = c.len();
    let scale = |k: usize| {
        if k == nl && p[k] == 0.0 {
            1e-4
        } else {
            p[k].abs()
        }
    };
    let big = (0..p.len()).fold(0.0f64, |a, k| a.max((grad[k] * scale(k)).abs()));
    assert!(
        big > 0.0,
        "{}: a zero gradient cannot be checked",
        mat.name()
    );
    let mut worst: f64 = 0.0;
    for k in 0..p.len() {
        let fd = if k == nl && p[k] == 0.0 {
            // the frame's share `h F_max` a 1e-5 part of the peak depth
            let f_max = traj.steps.iter().map(|s| s.force).fold(0.0, f64::max);
            let h_max = traj.steps.iter().map(|s| s.depth).fold(0.0, f64::max);
            let h = 1e-5 * h_max / f_max;
            let mut q = p.clone();
            let f0 = cost(&mut solver, mat, &q, schedule, n);
            q[k] = h;
            let f1 = cost(&mut solver, mat, &q, schedule, n);
            q[k] = 2.0 * h;
            let f2 = cost(&mut solver, mat, &q, schedule, n);
            (-3.0 * f0 + 4.0 * f1 - f2) / (2.0 * h)
        } else {
            let h = h_rel * p[k].abs();
            let mut q = p.clone();
            q[k] = p[k] + h;
            let fp = cost(&mut solver, mat, &q, schedule, n);
            q[k] = p[k] - h;
            let fm = cost(&mut solver, mat, &q, schedule, n);
            (fp - fm) / (2.0 * h)
        };
        let rel = (fd - grad[k]).abs() * scale(k) / big;
        println!(
            "{} {}: adjoint {:.10e}, fd {fd:.10e}, rel {rel:.2e}",
            mat.name(),
            names[k],
            grad[k]
        );
        worst = worst.max(rel);
    }
    worst
}

const R1: [f64; 3] = [20000.0, 0.3, 30000.0];
const MAXWELL_SPHERE: [f64; 3] = [1e5, 0.3, 2e5];
const POWER_NORTON: [f64; 6] = [1e5, 0.3, 500.0, 0.2, 1500.0, 5.0];

/// Maxwell under the cone, vertical contact: the frame takes ~15% of the machine depth.
#[test]
fn maxwell_cone_vertical() {
    let m = small_model(cone(), ContactKind::Vertical);
    let frame = Frame {
        compliance: 1e-4,
        drift: 2e-3,
        offset: -2e-3,
    };
    let w = check(&m, &LawMaterial(&Maxwell), &R1, &frame, &lhu(0.06, 6), 1e-4);
    assert!(w < 1e-7, "{w:.2e}");
}

/// Maxwell under the sphere, frictionless normal contact, small and finite strain.
#[test]
fn maxwell_sphere_normal_small_and_finite_strain() {
    let frame = Frame {
        compliance: 1.5e-5,
        drift: 1e-3,
        offset: 1e-3,
    };
    let mx = LawMaterial(&Maxwell);
    let m = small_model(sphere(), ContactKind::Normal);
    let w = check(&m, &mx, &MAXWELL_SPHERE, &frame, &lhu(0.04, 6), 1e-4);
    assert!(w < 1e-7, "small strain {w:.2e}");
    let m = finite_model(sphere());
    let w = check(&m, &mx, &MAXWELL_SPHERE, &frame, &lhu(0.04, 6), 1e-4);
    assert!(w < 1e-7, "finite strain {w:.2e}");
}

/// J2 with power-law hardening and Norton overstress (internal variables, the material's
/// blocks), sphere, normal contact, small strain.
#[test]
fn plastic_power_norton_sphere_normal() {
    let pl = Plastic::new(Hardening::Power, Rate::Norton);
    let frame = Frame {
        compliance: 1.5e-5,
        drift: 1e-3,
        offset: 1e-3,
    };
    let m = small_model(sphere(), ContactKind::Normal);
    let w = check(&m, &pl, &POWER_NORTON, &frame, &lhu(0.04, 6), 1e-4);
    assert!(w < 1e-7, "{w:.2e}");
}

/// `Cf = 0`: plain depth control, where the frame's derivatives are the force's
/// sensitivity to the prescribed depth history (`dJ/dCf = -sum F_i dJ/dH_i`), vertical
/// and normal contact.
#[test]
fn zero_compliance_frame_derivatives() {
    let frame = Frame {
        compliance: 0.0,
        drift: 2e-3,
        offset: -2e-3,
    };
    let m = small_model(cone(), ContactKind::Vertical);
    let w = check(&m, &LawMaterial(&Maxwell), &R1, &frame, &lhu(0.06, 6), 1e-4);
    assert!(w < 1e-7, "vertical {w:.2e}");
    let m = small_model(sphere(), ContactKind::Normal);
    let w = check(
        &m,
        &LawMaterial(&Maxwell),
        &MAXWELL_SPHERE,
        &frame,
        &lhu(0.04, 6),
        1e-4,
    );
    assert!(w < 1e-7, "normal {w:.2e}");
}

/// Back-to-back cost (printed, not asserted: no timed assertions): on the cone's model,
/// the depth-controlled forward, the compliant forward of the same machine depths
/// (`Cf = 1e-4` mm/N) and its adjoint, for Maxwell and Norton-Hoff, alternated over five
/// rounds (best of each).
#[test]
fn compliant_cost_back_to_back() {
    use indentify_laws::NortonHoff;
    let m = small_model(cone(), ContactKind::Vertical);
    let schedule = lhu(0.06, 20);
    let frame = Frame {
        compliance: 1e-4,
        ..Frame::default()
    };
    let r2 = [1e5, 0.3, 1500.0, 5.0, 500.0];
    for (name, mat, c) in [
        ("maxwell", LawMaterial(&Maxwell), &R1[..]),
        ("norton-hoff", LawMaterial(&NortonHoff), &r2[..]),
    ] {
        let mut solver = DirectSolver::new(&m).unwrap();
        let mut adj = Adjoint::new(&m).unwrap();
        let mut best = [f64::INFINITY; 3];
        let mut iters = (0, 0);
        for _ in 0..5 {
            let t = std::time::Instant::now();
            let d = solver.run(&mat, c, &schedule, &opts(true)).unwrap();
            best[0] = best[0].min(t.elapsed().as_secs_f64());
            let t = std::time::Instant::now();
            let traj = solver
                .run_compliant(&mat, c, &schedule, &frame, &opts(true))
                .unwrap();
            best[1] = best[1].min(t.elapsed().as_secs_f64());
            let t = std::time::Instant::now();
            let w = weights(traj.steps.len());
            adj.gradient_compliant(&mat, c, &traj, (&schedule, &frame), &w)
                .unwrap();
            best[2] = best[2].min(t.elapsed().as_secs_f64());
            iters = (d.total_iterations(), traj.total_iterations());
        }
        println!(
            "{name}: depth forward {:.1} ms, compliant forward {:.1} ms ({:.2}x), its adjoint \
             {:.1} ms ({:.2}x the compliant forward); Newton iterations {} / {}",
            1e3 * best[0],
            1e3 * best[1],
            best[1] / best[0],
            1e3 * best[2],
            best[2] / best[1],
            iters.0,
            iters.1
        );
    }
}
