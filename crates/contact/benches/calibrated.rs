//! The calibrated tip's normal contact against the cone it equals: `punch: Calibrated` with
//! the area function `A = 24.5 h^2` (the 70.3 deg cone's, as a table of about a thousand
//! surface pieces, `punch/calibrated.rs`) and the 70.3 deg cone, R0 (elastic) and R2
//! (Norton-Hoff) on the reference mesh with normal contact, run back to back; and the
//! projection of a node onto the calibrated surface by the pruned search
//! (`Surface::project`) and by the scan of every piece (`Surface::project_scan`, what the
//! search replaced). `cargo bench -p indentify-contact --bench calibrated`.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use indentify_contact::normal::Surface;
use indentify_contact::punch::AreaProfile;
use indentify_contact::{
    ContactKind, DirectSolver, Model, Punch, Schedule, SolverOptions, trapezoid,
};
use indentify_laws::{Elastic, Law, NortonHoff};
use indentify_mesh::CylinderMesher;

fn calibrated() -> Punch {
    Punch::calibrated(
        "TIP.ron",
        AreaProfile::new(vec![(24.5, 2.0)], f64::INFINITY).expect("area"),
    )
}

fn model(punch: Punch) -> Model {
    let mesh = CylinderMesher::REFERENCE.build().expect("reference mesh");
    Model::with_contact(mesh, punch, ContactKind::Normal).expect("model")
}

fn bench_projection(c: &mut Criterion) {
    let s = Surface::new(&calibrated()).expect("surface");
    // nodes of a surface 0.1 mm deep under the tip: radii to 0.5 mm, near the profile
    let points: Vec<[f64; 2]> = (0..200)
        .map(|i| {
            let r = 0.5 * f64::from(i) / 200.0;
            [
                r,
                r / 70.3f64.to_radians().tan() + 1e-4 * f64::from(i % 7) - 3e-4,
            ]
        })
        .collect();
    let mut group = c.benchmark_group("calibrated_projection");
    group.bench_function("pruned", |b| {
        b.iter(|| {
            points
                .iter()
                .map(|&x| s.project(black_box(x)).gap)
                .sum::<f64>()
        })
    });
    group.bench_function("scan", |b| {
        b.iter(|| {
            points
                .iter()
                .map(|&x| s.project_scan(black_box(x)).gap)
                .sum::<f64>()
        })
    });
    group.finish();
}

fn bench_forward(c: &mut Criterion) {
    let cone = model(Punch::Cone {
        half_angle_deg: 70.3,
    });
    let tip = model(calibrated());
    let schedule = Schedule::from_segments(&trapezoid(0.1, 1.0, 1.0, 1.0, 30)).expect("schedule");
    let r0 = vec![20000.0, 0.3];
    let r2 = vec![1e5, 0.3, 1500.0, 5.0, 500.0];
    let cases: [(&str, &dyn Law, Vec<f64>, &Model); 4] = [
        ("r0_cone_normal", &Elastic, r0.clone(), &cone),
        ("r0_calibrated_normal", &Elastic, r0, &tip),
        ("r2_cone_normal", &NortonHoff, r2.clone(), &cone),
        ("r2_calibrated_normal", &NortonHoff, r2, &tip),
    ];
    let mut group = c.benchmark_group("calibrated_forward");
    group.sample_size(10);
    for (name, law, params, model) in cases {
        let mut solver = DirectSolver::new(model).expect("solver");
        let opts = SolverOptions::default();
        let t = solver
            .run(&indentify_laws::LawMaterial(law), &params, &schedule, &opts)
            .expect("run");
        eprintln!(
            "{name}: {} steps, {} iterations",
            t.steps.len(),
            t.total_iterations()
        );
        group.bench_function(name, |b| {
            b.iter(|| {
                solver
                    .run(&indentify_laws::LawMaterial(law), &params, &schedule, &opts)
                    .expect("run")
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench_projection, bench_forward);
criterion_main!(benches);
