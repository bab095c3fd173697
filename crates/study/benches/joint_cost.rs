//! One joint cost + gradient evaluation (every test's forward run and adjoint sweep) of
//! `examples/r2-multi-rate.ron` on 2 threads against each of its three tests alone (issue
//! 14: at most 1.2x the slowest single test). `cargo bench -p indentify-study --bench
//! joint_cost`. Before criterion's own measurements the bench times a few rounds back to
//! back (joint, then each test alone, at the same new point) and prints the median ratio
//! joint / slowest single test; every evaluation is at a new parameter point so that
//! nothing comes from the evaluator's cache. docs/joint-fits.md (Performance) explains
//! the bound that whole-test parallelism puts on that ratio.

use std::path::PathBuf;
use std::time::Instant;

use criterion::{Criterion, criterion_group, criterion_main};
use indentify_identify::{Evaluator, Problem};
use indentify_study::ConfigSource;
use indentify_study::identify::{self, IdentifyOptions};

/// Threads of the joint evaluation (the machine: 2 cores).
const THREADS: usize = 2;

/// Back-to-back rounds before criterion's measurements.
const ROUNDS: usize = 3;

fn config() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples/r2-multi-rate.ron")
}

/// The joint problem on [`THREADS`] threads, each test alone on one, and the law values.
fn problems() -> (Problem, Vec<Problem>, Vec<f64>) {
    let path = config();
    let (mut joint, c0) =
        identify::problem(&IdentifyOptions::new(ConfigSource::Path(path.clone())))
            .expect("the joint problem");
    joint.set_threads(THREADS).expect("a pool");
    let cfg = ConfigSource::Path(path.clone())
        .load(&[])
        .expect("the configuration");
    let singles = (0..joint.tests.len())
        .map(|k| {
            let one = cfg.test_config(k).expect("a test");
            let value = serde_json::to_value(&one).expect("the test as a value");
            let o = IdentifyOptions::new(ConfigSource::Value {
                value,
                name: format!("{} [test {}]", path.display(), k + 1),
            });
            let (mut p, _) = identify::problem(&o).expect("a one-test problem");
            p.set_threads(1).expect("a pool");
            p
        })
        .collect();
    (joint, singles, c0)
}

/// The law values scaled by `1 + 1e-6 r`: a new point for every evaluation.
fn point(c0: &[f64], r: usize) -> Vec<f64> {
    c0.iter().map(|v| v * (1.0 + 1e-6 * r as f64)).collect()
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn bench_joint_cost(c: &mut Criterion) {
    let (joint, singles, c0) = problems();
    let mut ev_joint = Evaluator::new(&joint).expect("an evaluator");
    let mut ev_single: Vec<Evaluator> = singles
        .iter()
        .map(|p| Evaluator::new(p).expect("an evaluator"))
        .collect();
    let mut r = 1usize;
    // back to back: the ratio under the same machine load
    let mut t_joint = Vec::new();
    let mut t_single = vec![Vec::new(); singles.len()];
    for _ in 0..ROUNDS {
        let p = point(&c0, r);
        r += 1;
        let clock = Instant::now();
        ev_joint.cost_and_gradient(&p).expect("joint evaluation");
        t_joint.push(clock.elapsed().as_secs_f64());
        for (k, e) in ev_single.iter_mut().enumerate() {
            let clock = Instant::now();
            e.cost_and_gradient(&p).expect("single evaluation");
            t_single[k].push(clock.elapsed().as_secs_f64());
        }
    }
    let singles_median: Vec<f64> = t_single.into_iter().map(median).collect();
    let slowest = singles_median.iter().copied().fold(0.0, f64::max);
    let joint_median = median(t_joint);
    eprintln!(
        "joint cost + gradient, back to back ({ROUNDS} rounds, medians): tests alone {} s; \
         joint on {THREADS} threads {joint_median:.3} s; joint / slowest single test {:.2}, \
         joint / sum of the tests {:.2}",
        singles_median
            .iter()
            .map(|t| format!("{t:.3}"))
            .collect::<Vec<_>>()
            .join(", "),
        joint_median / slowest,
        joint_median / singles_median.iter().sum::<f64>()
    );

    let mut group = c.benchmark_group("joint_cost");
    group.sample_size(10);
    for (k, e) in ev_single.iter_mut().enumerate() {
        group.bench_function(format!("test_{}_alone", k + 1), |b| {
            b.iter(|| {
                r += 1;
                e.cost_and_gradient(&point(&c0, r))
                    .expect("single evaluation")
            })
        });
    }
    group.bench_function(format!("joint_{THREADS}_threads"), |b| {
        b.iter(|| {
            r += 1;
            ev_joint
                .cost_and_gradient(&point(&c0, r))
                .expect("joint evaluation")
        })
    });
    group.finish();
}

criterion_group!(benches, bench_joint_cost);
criterion_main!(benches);
