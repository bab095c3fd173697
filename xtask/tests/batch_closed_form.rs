//! The closed-form start as the batch's (`indentify batch --start closed-form`:
//! `study::closed_form_start`, Lee and Radok's Maxwell form with one calibration run per
//! indent), on the synthetic Maxwell map (2% noise): on R1's model every row's start is near
//! its phase's truth (the map's own parameters, which the pre-fit never sees); on the coarse
//! 3 x 3 map the batch with the option gives each row within a tenth of a standard
//! deviation of the batch from the base start, in fewer Levenberg-Marquardt iterations
//! (the same bits on 1 and 2 threads: `crates/study/tests/closed_form_start.rs`).

use indentify_study::batch::{self, BatchOptions, State};
use indentify_study::synthetic::{MapOptions, PHASE_A, PHASE_B, make_map};
use xtask::batch_start::closed_form_start;

#[test]
fn the_pre_fit_of_r1_map_indents_is_near_their_phase() {
    // R1's model (20 x 20, 30 steps per segment), a 3 x 3 map: phase B at the centre
    let dir = std::env::temp_dir().join(format!("xtask-batch-lr-acc-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let map = make_map(
        &dir,
        &MapOptions {
            n: 3,
            ..Default::default()
        },
    )
    .expect("map");
    for (id, _, _, phase) in &map.indents {
        let c = closed_form_start(&map, id).expect("a row");
        let truth = if *phase == 'A' { PHASE_A } else { PHASE_B };
        eprintln!("{id} ({phase}): {} ({:.3} s)", c.summary(), c.seconds);
        let v = |n: &str| c.values.iter().find(|(m, _)| m == n).expect(n).1;
        let (e, eta) = (v("E"), v("eta"));
        assert!(
            (e / truth.0 - 1.0).abs() < 0.01,
            "{id}: E {e} against {}",
            truth.0
        );
        assert!(
            (eta / truth.1 - 1.0).abs() < 0.05,
            "{id}: eta {eta} against {}",
            truth.1
        );
        // 2% uniform noise has an rms of 1.15%: the closed form leaves no misfit beyond it
        assert!(c.rms_rel.expect("rms") < 0.015, "{id}: {c:?}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn closed_form_starts_give_the_same_fits_in_fewer_iterations() {
    let dir = std::env::temp_dir().join(format!("xtask-batch-lr-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let map = make_map(
        &dir,
        &MapOptions {
            n: 3,
            coarse: true,
            ..Default::default()
        },
    )
    .expect("map");
    let run = |closed_form: bool, name: &str, jobs: usize| {
        let out = dir.join(format!("out-{name}-{jobs}"));
        let mut o = BatchOptions::new(map.manifest.clone(), out.clone());
        o.config = Some(map.base.clone());
        o.jobs = jobs;
        o.closed_form_start = closed_form;
        // every indent its own calibration run (the seeded starts: crates/study/tests/batch_seed.rs)
        o.seeded = false;
        batch::run(&o, &()).expect("batch");
        map.indents
            .iter()
            .map(|(id, ..)| batch::read_status(&out, id).expect("status"))
            .collect::<Vec<_>>()
    };
    let base = run(false, "base", 2);
    let closed = run(true, "closed-form", 2);
    let (mut its_base, mut its_lr) = (0, 0);
    for (a, c) in closed.iter().zip(&base) {
        assert_eq!(a.state, State::Converged, "{}: {}", a.id, a.message);
        assert_eq!(c.state, State::Converged, "{}: {}", c.id, c.message);
        assert!(
            a.start
                .as_deref()
                .is_some_and(|s| s.contains("Lee and Radok")),
            "{:?}",
            a.start
        );
        assert_eq!(c.start, None);
        for k in [0usize, 2] {
            let sd = a.std_dev[k].expect("sd");
            let z = (a.values[k] - c.values[k]).abs() / sd;
            assert!(
                z <= 0.1,
                "{} {}: {} against {} (sd {sd})",
                a.id,
                a.names[k],
                a.values[k],
                c.values[k]
            );
        }
        its_base += c.iterations;
        its_lr += a.iterations;
    }
    eprintln!("LM iterations: base start {its_base}, closed-form start {its_lr}");
    assert!(its_lr < its_base, "{its_lr} against {its_base}");
    let _ = std::fs::remove_dir_all(&dir);
}
