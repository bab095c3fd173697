//! The simulation pipeline from a configuration value: the curve, and the constrained
//! tangent of a step written as Matrix Market through sprs and read back.

use indentify_study::ConfigSource;
use indentify_study::simulate::{self, SimulateOptions};

fn coarse_r0() -> ConfigSource {
    ConfigSource::Text {
        text: indentify_study::templates::template(indentify_study::config::Reference::R0Elastic),
        name: "r0".into(),
    }
}

#[test]
fn the_tangent_of_a_step_is_written_as_matrix_market() {
    let tmp = tempfile::tempdir().unwrap();
    let mut opts = SimulateOptions::new(coarse_r0());
    opts.sets = vec!["specimen.nr=6".into(), "specimen.nz=6".into()];
    opts.matrix_market = Some((tmp.path().to_path_buf(), 20));
    let o = simulate::run(&opts).unwrap();
    assert!(o.failure.is_none());
    let (path, n, nnz) = o.matrix.clone().unwrap();
    let k: sprs::TriMat<f64> = sprs::io::read_matrix_market(&path).unwrap();
    let k = k.to_csc::<usize>();
    assert_eq!((k.rows(), k.cols(), k.nnz()), (n, n, nnz));
    // symmetric
    let kt = k.transpose_view().to_csc();
    for (v, (i, j)) in k.iter() {
        let w = kt.get(i, j).copied().unwrap_or(0.0);
        assert!((v - w).abs() <= 1e-12 * v.abs().max(1.0), "({i}, {j})");
    }
    // the constrained equations (active contact at step 20 of the loading) keep only their
    // diagonal, and they are the z-dofs of top nodes
    let eqs = std::fs::read_to_string(tmp.path().join("equations.csv")).unwrap();
    let constrained: Vec<(usize, String)> = eqs
        .lines()
        .skip(1)
        .filter(|l| l.ends_with(",1"))
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (f[0].parse().unwrap(), f[2].to_string())
        })
        .collect();
    assert!(!constrained.is_empty(), "contact is active at step 20");
    for (e, comp) in &constrained {
        assert_eq!(comp, "z");
        let col = k.outer_view(*e).unwrap();
        assert_eq!(col.nnz(), 1, "equation {e}");
        assert!(col.get(*e).copied().unwrap() > 0.0);
    }
    assert_eq!(eqs.lines().count() - 1, n);
}

#[test]
fn a_step_outside_the_schedule_is_refused_before_solving() {
    let tmp = tempfile::tempdir().unwrap();
    let mut opts = SimulateOptions::new(coarse_r0());
    opts.matrix_market = Some((tmp.path().to_path_buf(), 1000));
    let e = simulate::run(&opts).unwrap_err();
    assert_eq!(e.kind(), indentify_study::ErrorKind::Config);
    assert!(e.to_string().contains("expected 1 to 90"), "{e}");
}
