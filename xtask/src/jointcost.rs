//! `cargo xtask joint-cost`: the cost of one joint cost + gradient evaluation (forward
//! runs and adjoint sweeps of every test) of `examples/r2-multi-rate.ron` on N threads
//! (default 2) against each of its tests alone, measured back to back (rounds alternate
//! the joint problem and the single tests, each evaluation at a new parameter point so that
//! nothing comes from the cache); prints the median wall times and the ratio of the joint
//! evaluation to the slowest single test (the target once set: at most 1.2), with the cost and
//! gradient asked together and as a line search asks them (cost, then gradient, the
//! adjoints prefetched), and the lower bound of any schedule. Each single test is timed on
//! one thread and, with `--threads` above 1, also on that many (its Gauss-point passes in
//! parallel: what a one-test fit uses by default).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Result, bail};
use indentify_identify::{Evaluator, Prefetch, Problem};
use indentify_study::ConfigSource;
use indentify_study::identify::{self, IdentifyOptions};

/// `cargo xtask joint-cost [--rounds 5] [--threads 2] [--config FILE] [--set K=V]`.
pub fn run(args: &[String]) -> Result<()> {
    let mut rounds = 5usize;
    let mut threads = 2usize;
    let mut config = PathBuf::from("examples/r2-multi-rate.ron");
    let mut sets = Vec::new();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut val = || it.next().cloned().unwrap_or_default();
        match a.as_str() {
            "--rounds" => rounds = val().parse()?,
            "--threads" => threads = val().parse()?,
            "--config" => config = PathBuf::from(val()),
            "--set" => sets.push(val()),
            other => bail!("unknown option {other}"),
        }
    }
    if rounds == 0 || threads == 0 {
        bail!("--rounds and --threads take a number >= 1");
    }
    let mut opts = IdentifyOptions::new(ConfigSource::Path(config.clone()));
    opts.sets = sets.clone();
    let (mut joint, c0) = identify::problem(&opts)?;
    joint.set_threads(threads)?;
    let n = joint.tests.len();
    let cfg = ConfigSource::Path(config.clone()).load(&sets)?;
    // each test alone on one thread, then (with threads > 1) on `threads`
    let single_threads: Vec<usize> = if threads > 1 {
        vec![1, threads]
    } else {
        vec![1]
    };
    let mut singles: Vec<Problem> = Vec::with_capacity(n * single_threads.len());
    for (k, &st) in (0..n).flat_map(|k| single_threads.iter().map(move |t| (k, t))) {
        let one = cfg.test_config(k)?;
        let value = serde_json::to_value(&one)?;
        let mut o = IdentifyOptions::new(ConfigSource::Value {
            value,
            name: format!("{} [test {}]", config.display(), k + 1),
        });
        o.sets = Vec::new();
        let (mut p, _) = identify::problem(&o)?;
        p.set_threads(st)?;
        singles.push(p);
    }
    // a new point for every evaluation: every law value scaled by 1 + 1e-4 (r + 1)
    let point = |r: usize| -> Vec<f64> {
        c0.iter()
            .map(|v| v * (1.0 + 1e-4 * (r as f64 + 1.0)))
            .collect()
    };
    let mut ev_joint = Evaluator::new(&joint)?;
    // the line-search pattern of BFGS: the cost at a point, then its gradient, with the
    // adjoint sweeps prefetched on idle cores (as `identify` sets it)
    let mut ev_search = Evaluator::new(&joint)?;
    ev_search.set_prefetch(Prefetch::Gradient);
    // the same without prefetching: the forwards, then the adjoints, one phase after the
    // other (what every joint evaluation did before the task scheduler)
    let mut ev_phases = Evaluator::new(&joint)?;
    let mut ev_single: Vec<Evaluator> = singles
        .iter()
        .map(Evaluator::new)
        .collect::<Result<_, _>>()?;
    // one warm-up of each
    ev_joint.cost_and_gradient(&point(rounds))?;
    ev_search.cost(&point(rounds))?;
    ev_search.cost_and_gradient(&point(rounds))?;
    ev_phases.cost(&point(rounds))?;
    ev_phases.cost_and_gradient(&point(rounds))?;
    for e in &mut ev_single {
        e.cost_and_gradient(&point(rounds))?;
    }
    let mut t_joint = Vec::new();
    let mut t_search = Vec::new();
    let mut t_phases = Vec::new();
    let mut t_single = vec![Vec::new(); singles.len()];
    let mut t_forward = vec![Vec::new(); singles.len()];
    for r in 0..rounds {
        let c = point(r);
        let clock = Instant::now();
        ev_joint.cost_and_gradient(&c)?;
        t_joint.push(clock.elapsed().as_secs_f64());
        let clock = Instant::now();
        ev_search.cost(&c)?;
        ev_search.cost_and_gradient(&c)?;
        t_search.push(clock.elapsed().as_secs_f64());
        let clock = Instant::now();
        ev_phases.cost(&c)?;
        ev_phases.cost_and_gradient(&c)?;
        t_phases.push(clock.elapsed().as_secs_f64());
        for (k, e) in ev_single.iter_mut().enumerate() {
            let clock = Instant::now();
            e.cost(&c)?;
            t_forward[k].push(clock.elapsed().as_secs_f64());
            e.cost_and_gradient(&c)?;
            t_single[k].push(clock.elapsed().as_secs_f64());
        }
    }
    let timings = Timings {
        joint: t_joint,
        search: t_search,
        phases: t_phases,
        single: t_single,
        forward: t_forward,
    };
    report(&config, n, threads, rounds, &single_threads, &timings);
    Ok(())
}

/// The wall times of each round (s).
struct Timings {
    joint: Vec<f64>,
    search: Vec<f64>,
    phases: Vec<f64>,
    single: Vec<Vec<f64>>,
    forward: Vec<Vec<f64>>,
}

/// The table and the ratios.
fn report(
    config: &std::path::Path,
    n: usize,
    threads: usize,
    rounds: usize,
    single_threads: &[usize],
    t: &Timings,
) {
    let (t_joint, t_search, t_phases, t_single, t_forward) =
        (&t.joint, &t.search, &t.phases, &t.single, &t.forward);
    let median = |v: &[f64]| {
        let mut v = v.to_vec();
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    println!(
        "## One cost + gradient evaluation of `{}`: {n} tests on {threads} threads vs each test alone, {rounds} rounds back to back\n",
        config.display()
    );
    println!("| evaluation | median wall (s) | of which the forward run (s) | all rounds (s) |");
    println!("|---|---|---|---|");
    let show = |v: &[f64]| {
        v.iter()
            .map(|x| format!("{x:.3}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    // the slowest single test and the sum of the single tests, per thread count
    let mut slowest = vec![0.0_f64; single_threads.len()];
    let mut sum = vec![0.0; single_threads.len()];
    for (i, t) in t_single.iter().enumerate() {
        let (k, j) = (i / single_threads.len(), i % single_threads.len());
        let m = median(t);
        slowest[j] = slowest[j].max(m);
        sum[j] += m;
        println!(
            "| test {} alone on {} thread(s) (cost, then gradient) | {m:.3} | {:.3} | {} |",
            k + 1,
            single_threads[j],
            median(&t_forward[i]),
            show(t)
        );
    }
    let mj = median(t_joint);
    let ms = median(t_search);
    let mp = median(t_phases);
    println!(
        "| joint, cost and gradient asked together ({n} tests, {threads} threads) | {mj:.3} | | {} |",
        show(t_joint)
    );
    println!(
        "| joint, cost then gradient, adjoints prefetched ({n} tests, {threads} threads) | {ms:.3} | | {} |",
        show(t_search)
    );
    println!(
        "| joint, cost then gradient, no prefetching: the forwards, then the adjoints ({n} tests, {threads} threads) | {mp:.3} | | {} |",
        show(t_phases)
    );
    // the least any schedule can take: the one-thread work spread evenly, or the longest
    // test
    let bound = (sum[0] / threads as f64).max(slowest[0]);
    println!(
        "\n- joint / slowest single test on 1 thread: **{:.2}x** asked together, **{:.2}x** cost then \
         gradient ({:.2}x in two phases; target <= 1.2x; no schedule can do better than {:.2}x: the tests' \
         one-thread work spread evenly over {threads} cores); joint / sum of the single tests: {:.2}x",
        mj / slowest[0],
        ms / slowest[0],
        mp / slowest[0],
        bound / slowest[0],
        mj / sum[0],
    );
    if let (Some(&sn), Some(&st)) = (slowest.get(1), single_threads.get(1)) {
        println!(
            "- joint / slowest single test on {st} threads: **{:.2}x** asked together, **{:.2}x** cost \
             then gradient ({:.2}x in two phases); a single test on {st} threads takes {:.2}x its time on one",
            mj / sn,
            ms / sn,
            mp / sn,
            sn / slowest[0],
        );
    }
    println!(
        "- the load average after the run: {}",
        std::fs::read_to_string("/proc/loadavg")
            .unwrap_or_default()
            .trim()
    );
}
