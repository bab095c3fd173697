//! A batch manifest's `law.*` columns take every parameter of every law by its registry
//! name (`law.n`, `law.K`, `law.Q`, `law.g2`, ...) and are checked for every row before
//! anything runs: an unknown parameter or a value outside its range is refused naming the
//! manifest, the line, the indent and the column, and nothing is written.

use std::path::Path;

use indentify_study::batch::{self, BatchOptions};

/// A small configuration around the law text `law`.
fn with_law(law: &str) -> String {
    format!(
        "(\n    specimen: Cylinder(radius: 10.0, height: 10.0, nr: 4, nz: 4, grading_r: 1.0, \
         grading_z: 1.0),\n    punch: Cone(half_angle_deg: 68.0),\n    law: {law},\n    \
         history: (segments: [(duration: 1.0, depth: 0.05, steps: 2)]),\n)"
    )
}

fn write(dir: &Path, name: &str, text: &str) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// The system shall accept the new laws' parameters as manifest columns and refuse an
/// unknown one or a value out of range before running, naming line and column.
#[test]
fn law_columns_of_the_new_laws_are_checked_before_anything_runs() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    write(
        d,
        "plastic.ron",
        &with_law(
            "Plastic(E: 70000.0, nu: 0.3, sY: 300.0, hardening: Power(n: 0.2), rate: \
             Norton(K: 200.0, m: 3.0))",
        ),
    );
    write(
        d,
        "prony.ron",
        &with_law("Prony(E: 3000.0, nu: 0.35, terms: [(g: 0.3, tau: 0.1), (g: 0.2, tau: 1.0)])"),
    );
    let check = |csv: &str| {
        let m = write(d, "m.csv", csv);
        let manifest = batch::read_manifest(&m, None).unwrap();
        batch::check_law_columns(&manifest, None).map_err(|e| e.messages().join(": "))
    };
    // every parameter of the new laws by its registry name
    check(
        "id,config,law.E,law.sY,law.n,law.K,law.m\na,plastic.ron,71000,310,0.25,150,4\n\
         b,plastic.ron,,,,,\n",
    )
    .unwrap();
    check("id,config,law.g1,law.tau1,law.g2,law.tau2\np,prony.ron,0.2,0.5,0.1,5\n").unwrap();
    // out of range: n in [0, 1]
    let e =
        check("id,config,law.K,law.n\na,plastic.ron,150,0.3\nb,plastic.ron,150,1.5\n").unwrap_err();
    assert!(
        e.contains("m.csv:3") && e.contains("indent `b`") && e.contains("column `law.n`"),
        "{e}"
    );
    assert!(e.contains("[0, 1]"), "{e}");
    // Q is not a parameter of a Power hardening
    let e = check("id,config,law.Q\na,plastic.ron,100\n").unwrap_err();
    assert!(e.contains("m.csv:2") && e.contains("column `law.Q`"), "{e}");
    // sum of g >= 1, tau <= 0
    let e = check("id,config,law.g1\np,prony.ron,0.9\n").unwrap_err();
    assert!(e.contains("column `law.g1`"), "{e}");
    let e = check("id,config,law.tau2\np,prony.ron,0\n").unwrap_err();
    assert!(e.contains("column `law.tau2`") && e.contains("tau2"), "{e}");
    // a batch run refuses before writing anything
    let m = write(
        d,
        "bad.csv",
        "id,config,law.n\nok,plastic.ron,0.3\nbad,plastic.ron,-1\n",
    );
    let out = d.join("out");
    let err = batch::run(&BatchOptions::new(m, out.clone()), &()).unwrap_err();
    let text = err.messages().join(": ");
    assert!(
        text.contains("bad.csv:3") && text.contains("column `law.n`"),
        "{text}"
    );
    assert!(!out.join("batch.json").exists());
    assert!(!out.join("indents").exists());
}
