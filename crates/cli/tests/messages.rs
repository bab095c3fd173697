//! What a user sees on the edges: `batch slurm` validates every indent of its manifest
//! before writing a job array.

mod common;

use common::*;

#[test]
fn batch_slurm_validates_every_indent_before_writing_a_job_array() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(d.join("c.csv"), "t,F\n0,0\n1,1\n2,0\n").unwrap();
    let r1 = example("r1-maxwell.ron");
    for (manifest, needles) in [
        (
            "id,data,law.foo\na,c.csv,1\n",
            vec!["m.csv:2", "`a`", "foo"],
        ),
        (
            "id,data,law.E\na,c.csv,1000\nb,c.csv,-5\n",
            vec!["m.csv:3", "`b`", "law.E"],
        ),
        (
            "id,test\na,2\n",
            vec!["m.csv:2", "`test` column (2)", "no `data` section"],
        ),
        ("id,data\na,missing.csv\n", vec!["m.csv:2", "missing.csv"]),
    ] {
        std::fs::write(d.join("m.csv"), manifest).unwrap();
        let out = d.join("run");
        let o = indentify(&[
            "batch",
            "slurm",
            &d.join("m.csv").display().to_string(),
            "--config",
            &r1,
            "--out",
            &out.display().to_string(),
            "--array",
            "2",
        ]);
        assert_rejected(&o, &needles, manifest);
        assert!(!out.join("batch.sbatch").exists(), "{manifest}");
    }
}
