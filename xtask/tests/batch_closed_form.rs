//! The Lee-Radok pre-fit as the batch's start (`xtask::lee_radok`, `xtask::batch_start`),
//! on the synthetic Maxwell map (2% noise): on R1's model every row's pre-fit is near its
//! phase's truth (the map's own parameters, which the pre-fit never sees); on the coarse
//! 3 x 3 map the batch started from the pre-fits gives the same rows, bit for bit, on 1 and
//! 2 threads, each within a tenth of a standard deviation of the batch from the base
//! start, in fewer Levenberg-Marquardt iterations.

use indentify_study::batch::{self, BatchOptions, State};
use indentify_study::synthetic::{MapOptions, PHASE_A, PHASE_B, make_map};
use xtask::batch_start::{calibrate, lee_radok_manifest, lee_radok_starts};

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
    let cal = calibrate(&map).expect("calibration");
    for (id, _, _, phase) in &map.indents {
        let (_, p) = lee_radok_starts(&map, id, &cal)
            .expect("a row")
            .expect("a pre-fit");
        let truth = if *phase == 'A' { PHASE_A } else { PHASE_B };
        eprintln!(
            "{id} ({phase}): E {:.1} eta {:.1} rms {:.4}",
            p.e, p.eta, p.rms_rel
        );
        // measured: E within 0.4%, eta within 1.2% (2% noise on 51 samples)
        assert!(
            (p.e / truth.0 - 1.0).abs() < 0.01,
            "{id}: E {} against {}",
            p.e,
            truth.0
        );
        assert!(
            (p.eta / truth.1 - 1.0).abs() < 0.05,
            "{id}: eta {} against {}",
            p.eta,
            truth.1
        );
        // 2% uniform noise has an rms of 1.15%: the closed form leaves no misfit beyond it
        assert!(p.rms_rel < 0.015, "{id}: rms {}", p.rms_rel);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn lee_radok_starts_give_the_same_fits_in_fewer_iterations() {
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
    let (manifest, started) =
        lee_radok_manifest(&map, &dir.join("manifest-lr.csv")).expect("manifest");
    assert_eq!(started, map.indents.len());
    let run = |manifest: &std::path::Path, name: &str, jobs: usize| {
        let out = dir.join(format!("out-{name}-{jobs}"));
        let mut o = BatchOptions::new(manifest.to_path_buf(), out.clone());
        o.config = Some(map.base.clone());
        o.jobs = jobs;
        batch::run(&o, &()).expect("batch");
        map.indents
            .iter()
            .map(|(id, ..)| batch::read_status(&out, id).expect("status"))
            .collect::<Vec<_>>()
    };
    let base = run(&map.manifest, "base", 2);
    let (one, two) = (run(&manifest, "lr", 1), run(&manifest, "lr", 2));
    let (mut its_base, mut its_lr) = (0, 0);
    for ((a, b), c) in one.iter().zip(&two).zip(&base) {
        assert_eq!(a.state, State::Converged, "{}: {}", a.id, a.message);
        assert_eq!(c.state, State::Converged, "{}: {}", c.id, c.message);
        assert_eq!(a.values, b.values, "{}", a.id);
        assert_eq!(a.std_dev, b.std_dev, "{}", a.id);
        assert_eq!(a.iterations, b.iterations, "{}", a.id);
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
    eprintln!("LM iterations: base start {its_base}, Lee-Radok {its_lr}");
    assert!(its_lr < its_base, "{its_lr} against {its_base}");
    let _ = std::fs::remove_dir_all(&dir);
}
