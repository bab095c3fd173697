//! `cargo xtask make-map [DIR] [--n N] [--noise A] [--seed S] [--coarse] [--run]`: writes a
//! synthetic two-phase Maxwell map (records, manifest.csv, base.ron, phases.csv) and, with
//! `--run`, identifies it with the batch runner and reports how well each phase is
//! recovered.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Result, bail};
use indentify_study::batch::{self, BatchOptions, State};
use indentify_study::synthetic::{MapOptions, PHASE_A, PHASE_B, make_map};

pub fn run(args: &[String]) -> Result<()> {
    let mut dir = PathBuf::from("out/map");
    let mut o = MapOptions::default();
    let mut run = false;
    let mut jobs = 0usize;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut val = || it.next().cloned().unwrap_or_default();
        match a.as_str() {
            "--n" => o.n = val().parse()?,
            "--noise" => o.noise = val().parse()?,
            "--seed" => o.seed = val().parse()?,
            "--coarse" => o.coarse = true,
            "--run" => run = true,
            "--jobs" => jobs = val().parse()?,
            s if !s.starts_with("--") => dir = PathBuf::from(s),
            other => bail!("unknown option {other}"),
        }
    }
    let t0 = Instant::now();
    let map = make_map(&dir, &o)?;
    println!(
        "wrote a {n}x{n} two-phase Maxwell map ({} indents, noise +-{}%) into {} in {:.1} s:\n  \
         indentify batch {} --config {} --out {}/out",
        map.indents.len(),
        100.0 * o.noise,
        dir.display(),
        t0.elapsed().as_secs_f64(),
        map.manifest.display(),
        map.base.display(),
        dir.display(),
        n = o.n
    );
    if !run {
        return Ok(());
    }
    let out = dir.join("out");
    let mut opts = BatchOptions::new(map.manifest.clone(), out.clone());
    opts.config = Some(map.base.clone());
    opts.jobs = jobs;
    let s = batch::run(&opts, &())?;
    println!(
        "batch: {} indents, {} run, {:?}, {:.1} s",
        s.total, s.ran, s.counts, s.seconds
    );
    let mut worst: [(f64, f64); 2] = [(0.0, 0.0); 2];
    let mut means = [[0.0f64; 2]; 2];
    let mut n = [0usize; 2];
    for (id, _, _, phase) in &map.indents {
        let st = batch::read_status(&out, id).expect("every indent has a status");
        if st.state == State::Failed {
            println!("  {id} failed: {}", st.message);
            continue;
        }
        let p = usize::from(*phase == 'B');
        let (e, eta) = if p == 0 { PHASE_A } else { PHASE_B };
        let (re, reta) = (
            (st.values[0] - e).abs() / e,
            (st.values[2] - eta).abs() / eta,
        );
        worst[p] = (worst[p].0.max(re), worst[p].1.max(reta));
        means[p][0] += st.values[0];
        means[p][1] += st.values[2];
        n[p] += 1;
    }
    for (p, name, (e, eta)) in [(0, "A", PHASE_A), (1, "B", PHASE_B)] {
        if n[p] == 0 {
            continue;
        }
        println!(
            "  phase {name} ({} indents): mean E {:.0} MPa (truth {e}), mean eta {:.0} MPa s \
             (truth {eta}); worst relative error E {:.2}%, eta {:.2}%",
            n[p],
            means[p][0] / n[p] as f64,
            means[p][1] / n[p] as f64,
            100.0 * worst[p].0,
            100.0 * worst[p].1
        );
    }
    Ok(())
}
