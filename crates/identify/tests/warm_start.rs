//! Forward runs warm started from the lowest-cost point's trajectory
//! (`Problem::set_warm_start`, on by default) against cold ones, on a small R2-like
//! problem (Norton-Hoff, cone 68 deg, 8 x 8 Q8, 8 steps per segment, 2% noise): the same
//! fit within a tenth of a standard deviation, in fewer Newton iterations.
//!
//! Reference: the same fit with every forward run started cold (the time extrapolation),
//! and its Gauss-Newton standard deviations.

mod common;

use common::{nh_data, nh_lm as lm};
use indentify_contact::SolverOptions;
use indentify_identify::{IdentifyResult, Problem, identify};
use indentify_laws::NortonHoff;
use indentify_testkit::cone_model as model;

fn problem() -> Problem {
    let (s, rec) = nh_data(1.0, 3);
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
