//! Forward runs warm started from the lowest-cost point's trajectory
//! (`Problem::set_warm_start`, on by default) against cold ones, on a small R2-like
//! problem (Norton-Hoff, cone 68 deg, 8 x 8 Q8, 8 steps per segment, 2% noise): the same
//! fit within a tenth of a standard deviation, in fewer Newton iterations.
//!
//! Reference: the same fit with every forward run started cold (the time extrapolation),
//! and its Gauss-Newton standard deviations.

use indentify_contact::{DirectSolver, Model, Punch, Schedule, SolverOptions, trapezoid};
use indentify_identify::{
    ForceRecord, IdentifyConfig, IdentifyResult, Method, ParamSpec, Problem, identify,
    multiplicative_noise,
};
use indentify_laws::{LawMaterial, NortonHoff};
use indentify_mesh::CylinderMesher;

const TRUTH: [f64; 5] = [1e5, 0.3, 1500.0, 5.0, 500.0];

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
    Model::new(
        mesh,
        Punch::Cone {
            half_angle_deg: 68.0,
        },
    )
    .unwrap()
}

fn problem() -> Problem {
    let s = Schedule::from_segments(&trapezoid(0.1, 1.0, 1.0, 1.0, 8)).unwrap();
    let f = DirectSolver::new(&model())
        .unwrap()
        .run(
            &LawMaterial(&NortonHoff),
            &TRUTH,
            &s,
            &SolverOptions::default(),
        )
        .unwrap()
        .forces();
    let f = multiplicative_noise(&f, 0.02, 3);
    let rec = ForceRecord::new(s.t.clone(), f).unwrap();
    Problem::new(
        model(),
        &NortonHoff,
        s,
        &rec,
        None,
        SolverOptions::default(),
    )
    .unwrap()
}

fn lm() -> IdentifyConfig {
    let mut cfg = IdentifyConfig::new(vec![
        ParamSpec::free("E", 7e4, 1e3, 1e7),
        ParamSpec::fixed("nu", 0.3),
        ParamSpec::free("K", 2500.0, 10.0, 1e6),
        ParamSpec::fixed("m", 5.0),
        ParamSpec::free("sY", 350.0, 1.0, 1e5),
    ]);
    cfg.method = Method::LevenbergMarquardt;
    cfg
}

fn sd(r: &IdentifyResult, name: &str) -> f64 {
    let id = r.identifiability.as_ref().expect("identifiability");
    let k = id.names.iter().position(|n| *n == name).unwrap();
    id.std_dev[k]
}

#[test]
fn warm_started_fit_lands_within_a_tenth_of_sigma_of_the_cold_one() {
    let mut p = problem();
    p.set_warm_start(false);
    let cold = identify(&p, &lm(), &mut |_| {}).unwrap();
    p.set_warm_start(true);
    let warm = identify(&p, &lm(), &mut |_| {}).unwrap();
    println!(
        "cold: {:?}, {} it, {} forward, {} Newton iterations, {} factorizations ({}); \
         warm: {:?}, {} it, {} forward, {} Newton iterations, {} factorizations ({})",
        cold.c,
        cold.iterations,
        cold.forward_solves,
        cold.newton_iterations,
        cold.factorizations,
        cold.stop_reason,
        warm.c,
        warm.iterations,
        warm.forward_solves,
        warm.newton_iterations,
        warm.factorizations,
        warm.stop_reason
    );
    assert!(cold.stop_reason.is_converged(), "{}", cold.stop_reason);
    assert!(warm.stop_reason.is_converged(), "{}", warm.stop_reason);
    for (k, name) in [(0, "E"), (2, "K"), (4, "sY")] {
        let sigma = sd(&cold, name);
        assert!(sigma.is_finite() && sigma > 0.0, "{name}: sd {sigma}");
        let shift = (warm.c[k] - cold.c[k]).abs() / sigma;
        println!("{name}: |warm - cold| / sigma = {shift:.2e}");
        assert!(shift < 0.1, "{name} moved {shift} sigma");
    }
    assert!(
        warm.newton_iterations < cold.newton_iterations,
        "warm {} against cold {} Newton iterations",
        warm.newton_iterations,
        cold.newton_iterations
    );
}
