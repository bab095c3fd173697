//! Seeded closed-form starts of a batch (`study::batch_seed`, `BatchOptions::seeded`): on the coarse 3 x 3 synthetic Maxwell
//! map (two phases, 2% noise) every indent's result is the same bits on 1 and 2 threads and
//! as two shards into one folder; the first indent is the seed, the others say they were
//! seeded by it; and every parameter lies within a tenth of its standard deviation of the
//! base-start batch's fit (the reference: the same indents fitted from the configuration's
//! start, no closed form, no seed). With `identify.stop.proposed_step` (a manifest column)
//! the same holds, in no more iterations.

use std::path::{Path, PathBuf};

use indentify_study::batch::{self, BatchOptions, IndentStatus, Shard, State};
use indentify_study::synthetic::{MapFiles, MapOptions, make_map};

fn run(
    map: &MapFiles,
    manifest: &Path,
    out: &Path,
    jobs: usize,
    closed: bool,
) -> Vec<IndentStatus> {
    run_shard(map, manifest, out, jobs, closed, None);
    statuses(map, out)
}

fn run_shard(
    map: &MapFiles,
    manifest: &Path,
    out: &Path,
    jobs: usize,
    closed: bool,
    shard: Option<Shard>,
) {
    let mut o = BatchOptions::new(manifest.to_path_buf(), out.to_path_buf());
    o.config = Some(map.base.clone());
    o.jobs = jobs;
    o.closed_form_start = closed;
    o.seeded = true;
    o.shard = shard;
    batch::run(&o, &()).expect("batch");
}

fn statuses(map: &MapFiles, out: &Path) -> Vec<IndentStatus> {
    map.indents
        .iter()
        .map(|(id, ..)| batch::read_status(out, id).expect("status"))
        .collect()
}

fn same_bits(a: &[IndentStatus], b: &[IndentStatus], what: &str) {
    for (a, b) in a.iter().zip(b) {
        assert_eq!(a.values, b.values, "{what}: {}", a.id);
        assert_eq!(a.std_dev, b.std_dev, "{what}: {}", a.id);
        assert_eq!(a.iterations, b.iterations, "{what}: {}", a.id);
        assert_eq!(a.start, b.start, "{what}: {}", a.id);
    }
}

/// Every free parameter within `0.1` of its deviation of the base fit's; the iterations.
fn near_base(base: &[IndentStatus], st: &[IndentStatus], what: &str) -> usize {
    for (a, b) in st.iter().zip(base) {
        assert_eq!(a.state, State::Converged, "{what}: {}: {}", a.id, a.message);
        for k in [0usize, 2] {
            let sd = a.std_dev[k].expect("sd");
            let z = (a.values[k] - b.values[k]).abs() / sd;
            assert!(
                z <= 0.1,
                "{what}: {} {}: {} against {} (sd {sd}, {z:.3} sd)",
                a.id,
                a.names[k],
                a.values[k],
                b.values[k]
            );
        }
    }
    st.iter().map(|s| s.iterations).sum()
}

/// The map's manifest with the column `identify.stop.proposed_step` = `on` on every row.
fn with_column(map: &MapFiles, out: &Path, on: bool) -> PathBuf {
    let text = std::fs::read_to_string(&map.manifest).expect("manifest");
    let mut s = String::new();
    for (k, line) in text.lines().enumerate() {
        s.push_str(line);
        s.push_str(if k == 0 {
            ",identify.stop.proposed_step\n"
        } else {
            if on { ",true\n" } else { ",false\n" }
        });
    }
    std::fs::write(out, s).expect("write");
    out.to_path_buf()
}

#[test]
fn seeded_starts_do_not_depend_on_threads_or_shards_and_keep_the_fits() {
    let dir = std::env::temp_dir().join(format!("study-batch-seed-{}", std::process::id()));
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
    // without the stop on the proposed step (on by default in configurations), then with it
    let off = with_column(&map, &dir.join("manifest-off.csv"), false);
    let base = run(&map, &off, &dir.join("base"), 2, false);
    let one = run(&map, &off, &dir.join("one"), 1, true);
    let two = run(&map, &off, &dir.join("two"), 2, true);
    same_bits(&one, &two, "1 and 2 threads");
    let sharded = dir.join("shards");
    // the second shard first: its seed (row 1) is the first shard's and runs here unwritten
    for k in [2, 1] {
        run_shard(
            &map,
            &off,
            &sharded,
            1,
            true,
            Some(Shard { index: k, count: 2 }),
        );
    }
    same_bits(&one, &statuses(&map, &sharded), "two shards");
    let seed = &map.indents[0].0;
    for s in &one {
        let start = s.start.as_deref().unwrap_or("");
        if s.id == *seed {
            assert!(start.contains("the seed of its configuration"), "{start}");
            assert!(start.contains("Lee and Radok"), "{start}");
        } else {
            assert!(
                start.contains(&format!("seeded by {seed}")),
                "{}: {start}",
                s.id
            );
        }
    }
    let its_base = near_base(&base, &base, "base");
    let its_seeded = near_base(&base, &one, "seeded");
    let proposed = with_column(&map, &dir.join("manifest-proposed.csv"), true);
    let fast = run(&map, &proposed, &dir.join("proposed"), 2, true);
    let its_fast = near_base(&base, &fast, "seeded + proposed_step");
    eprintln!("LM iterations: base {its_base}, seeded {its_seeded}, + proposed_step {its_fast}");
    assert!(its_fast <= its_seeded, "{its_fast} against {its_seeded}");
    let _ = std::fs::remove_dir_all(&dir);
}
