//! Benchmarks of the direct problem on the reference problems R0 (elastic), R1 (Maxwell)
//! and R2 (Norton-Hoff) of docs/theory.md §11: 20 x 20 Q8, cone 68 deg, trapezoid 30 steps per
//! segment, with the paper's vertical contact; R1 and R2 also with normal contact
//! (`*_normal`, [`ContactKind::Normal`]), run right after their vertical twins so that the
//! ratio is measured back to back; and with Coulomb friction mu = 0.1 (`*_friction`,
//! [`ContactKind::NormalFriction`]) right after the frictionless normal twin. Finite strain
//! (`*_finite`, [`Kinematics::Finite`], normal contact) runs right after its small-strain
//! normal twin, for R0, R1 and R2 with sY = 500 and sY = 0 (`r2_sy0_*`): the ratio of
//! finite-strain cost study (docs/validation-finite-strain.md §4). Finite strain's Gauss-point passes run
//! on rayon's threads, small strain's do not: `RAYON_NUM_THREADS=1 cargo bench -p
//! indentify-contact` gives the serial ratio.
//! `cargo bench -p indentify-contact`.

use criterion::{Criterion, criterion_group, criterion_main};
use indentify_contact::{
    ContactKind, DirectSolver, Kinematics, Model, Punch, Schedule, SolverOptions, trapezoid,
};
use indentify_laws::{Elastic, Law, Maxwell, NortonHoff};
use indentify_mesh::CylinderMesher;

fn reference_model(contact: ContactKind) -> Model {
    let mesh = CylinderMesher::REFERENCE.build().expect("reference mesh");
    Model::with_contact(
        mesh,
        Punch::Cone {
            half_angle_deg: 68.0,
        },
        contact,
    )
    .expect("reference model")
}

fn bench_forward(c: &mut Criterion) {
    let vertical = reference_model(ContactKind::Vertical);
    let normal = reference_model(ContactKind::Normal);
    let friction = reference_model(ContactKind::normal_with_friction(0.1).expect("friction"));
    let finite = reference_model(ContactKind::Normal)
        .with_kinematics(Kinematics::Finite)
        .expect("finite strain");
    let schedule = Schedule::from_segments(&trapezoid(0.1, 1.0, 1.0, 1.0, 30)).expect("schedule");
    let r1 = vec![20000.0, 0.3, 30000.0];
    let r2 = vec![1e5, 0.3, 1500.0, 5.0, 500.0];
    let r2_sy0 = vec![1e5, 0.3, 1500.0, 5.0, 0.0];
    let r0 = vec![20000.0, 0.3];
    let cases: [(&str, &dyn Law, Vec<f64>, &Model); 13] = [
        ("r0_elastic", &Elastic, r0.clone(), &vertical),
        ("r0_elastic_normal", &Elastic, r0.clone(), &normal),
        ("r0_elastic_finite", &Elastic, r0, &finite),
        ("r1_maxwell", &Maxwell, r1.clone(), &vertical),
        ("r1_maxwell_normal", &Maxwell, r1.clone(), &normal),
        ("r1_maxwell_finite", &Maxwell, r1.clone(), &finite),
        ("r1_maxwell_friction", &Maxwell, r1, &friction),
        ("r2_norton_hoff", &NortonHoff, r2.clone(), &vertical),
        ("r2_norton_hoff_normal", &NortonHoff, r2.clone(), &normal),
        ("r2_norton_hoff_finite", &NortonHoff, r2.clone(), &finite),
        ("r2_norton_hoff_friction", &NortonHoff, r2, &friction),
        ("r2_sy0_normal", &NortonHoff, r2_sy0.clone(), &normal),
        ("r2_sy0_finite", &NortonHoff, r2_sy0, &finite),
    ];
    let mut group = c.benchmark_group("forward");
    group.sample_size(10);
    for (name, law, params, model) in cases {
        let mut solver = DirectSolver::new(model).expect("solver");
        let opts = SolverOptions::default();
        // one run to report the split, then the timed runs
        let t = solver
            .run(&indentify_laws::LawMaterial(law), &params, &schedule, &opts)
            .expect("run");
        eprintln!(
            "{name}: {} steps, {} iterations, {}",
            t.steps.len(),
            t.total_iterations(),
            t.timing
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

criterion_group!(benches, bench_forward);
criterion_main!(benches);
