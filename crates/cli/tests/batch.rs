//! `indentify batch` end to end through the binary: a manifest of curves, results.csv, a
//! rerun that skips, a failed indent that does not stop the batch, seeded starts,
//! `batch slurm` and `batch merge`.

mod common;

use common::*;

#[test]
fn batch_identifies_a_manifest_and_reports_failures() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    // two synthetic curves of R1 (coarse), at two viscosities
    let base = d.join("base.ron");
    std::fs::copy(example("r1-maxwell.ron"), &base).unwrap();
    for (name, eta) in [("a.csv", "30000"), ("b.csv", "60000")] {
        let out = d.join(name).display().to_string();
        let set = format!("law.eta={eta}");
        assert_ok(&indentify(&coarse(&[
            "-q",
            "simulate",
            &base.display().to_string(),
            "--set",
            &set,
            "--out",
            &out,
        ])));
    }
    std::fs::write(
        d.join("m.csv"),
        "id,data,x,y,specimen.nr,specimen.nz,history.segments.0.steps,history.segments.1.steps,history.segments.2.steps,identify.params.eta.start\n\
         a,a.csv,0,0,6,6,4,4,4,20000\n\
         b,b.csv,1,0,6,6,4,4,4,20000\n\
         broken,missing.csv,2,0,6,6,4,4,4,20000\n",
    )
    .unwrap();
    let m = d.join("m.csv").display().to_string();
    let out = d.join("out").display().to_string();
    let b = base.display().to_string();
    let run = indentify(&[
        "-q", "batch", &m, "--config", &b, "--out", &out, "--jobs", "2",
    ]);
    // one indent failed: non-zero exit naming it, the others done
    assert_rejected(&run, &["1 of 3 indents failed", "results.csv"], "batch");
    assert!(stdout(&run).contains("2 converged"), "{}", stdout(&run));
    let results = std::fs::read_to_string(d.join("out/results.csv")).unwrap();
    let lines: Vec<&str> = results.lines().collect();
    assert!(lines[0].starts_with("id,x,y,E,E_std,nu,nu_std,eta,eta_std,R2,rms_rel,status"));
    assert_eq!(lines.len(), 4, "{results}");
    let eta_of = |id: &str| -> f64 {
        let row: Vec<&str> = lines
            .iter()
            .find(|l| l.starts_with(id))
            .unwrap()
            .split(',')
            .collect();
        row[7].parse().unwrap()
    };
    assert!((eta_of("a,") - 30000.0).abs() < 30.0, "{results}");
    assert!((eta_of("b,") - 60000.0).abs() < 60.0, "{results}");
    assert!(
        results.contains("failed") && results.contains("missing.csv"),
        "{results}"
    );
    for f in ["eta_map.svg", "eta_hist.png", "R2_map.svg"] {
        assert!(d.join("out/maps").join(f).is_file(), "{f}");
    }
    // a rerun skips what is finished
    let again = indentify(&["batch", &m, "--config", &b, "--out", &out]);
    assert!(
        stdout(&again).contains("0 run now, 3 already finished"),
        "{}",
        stdout(&again)
    );

    // shards into another folder, then merge: same results but the wall times
    let out2 = d.join("out2").display().to_string();
    for k in ["1/2", "2/2"] {
        indentify(&[
            "-q", "batch", &m, "--config", &b, "--out", &out2, "--shard", k,
        ]);
    }
    let merged = indentify(&["batch", "merge", &out2]);
    assert_ok(&merged);
    let strip = |t: &str| -> Vec<String> {
        t.lines()
            .map(|l| {
                let mut f: Vec<&str> = l.split(',').collect();
                f.remove(13); // seconds
                f.join(",")
            })
            .collect()
    };
    let results2 = std::fs::read_to_string(d.join("out2/results.csv")).unwrap();
    assert_eq!(strip(&results2), strip(&results));

    // seeded closed-form starts: a (first in the manifest) seeds b; the same fitted values
    let out3 = d.join("out3").display().to_string();
    let seeded = indentify(&[
        "-q", "batch", &m, "--config", &b, "--out", &out3, "--start", "seeded", "--jobs", "2",
    ]);
    assert_rejected(&seeded, &["1 of 3 indents failed"], "batch --start seeded");
    let status_b = std::fs::read_to_string(d.join("out3/indents/b/status.json")).unwrap();
    assert!(status_b.contains("seeded by a"), "{status_b}");
    let results3 = std::fs::read_to_string(d.join("out3/results.csv")).unwrap();
    let eta3 = |id: &str| -> f64 {
        let row = results3.lines().find(|l| l.starts_with(id)).unwrap();
        row.split(',').nth(7).unwrap().parse().unwrap()
    };
    assert!((eta3("a,") - 30000.0).abs() < 30.0, "{results3}");
    assert!((eta3("b,") - 60000.0).abs() < 60.0, "{results3}");

    // a Slurm job array over the shards
    let slurm = indentify(&[
        "batch", "slurm", &m, "--config", &b, "--out", &out2, "--array", "3", "--time", "00:10:00",
    ]);
    assert_ok(&slurm);
    assert!(stdout(&slurm).contains("sbatch "), "{}", stdout(&slurm));
    let script = std::fs::read_to_string(d.join("out2/batch.sbatch")).unwrap();
    assert!(script.contains("#SBATCH --array=1-3"), "{script}");
    assert!(
        script.contains("--shard \"${SLURM_ARRAY_TASK_ID}/3\""),
        "{script}"
    );
}

#[test]
fn bad_batch_input_is_refused_clearly() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let m = d.join("m.csv");
    let out = d.join("out").display().to_string();
    let r1 = example("r1-maxwell.ron");
    let ms = m.display().to_string();
    let cases: [(&str, &[&str]); 3] = [
        ("id,data\na,x.csv\na,y.csv\n", &["m.csv:3", "used twice"]),
        (
            "id,data,colour\na,x.csv,red\n",
            &["unknown column `colour`"],
        ),
        ("data\nx.csv\n", &["no `id` column"]),
    ];
    for (text, needles) in cases {
        std::fs::write(&m, text).unwrap();
        let o = indentify(&["batch", &ms, "--config", &r1, "--out", &out]);
        assert_rejected(&o, needles, text);
    }
    std::fs::write(&m, "id,data\na,x.csv\n").unwrap();
    for (shard, what) in [("0/2", "1 <= K <= N"), ("3/2", "1 <= K <= N")] {
        let o = indentify(&[
            "batch", &ms, "--config", &r1, "--out", &out, "--shard", shard,
        ]);
        assert_rejected(&o, &[what], shard);
    }
    let o = indentify(&["batch", "merge", &d.join("nothing").display().to_string()]);
    assert_rejected(&o, &["holds no batch"], "merge of nothing");
}
