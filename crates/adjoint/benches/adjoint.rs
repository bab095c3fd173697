//! Benchmarks of the adjoint sweep against the forward solve on R1 (Maxwell) and R2
//! (Norton-Hoff) of docs/theory.md §11 under vertical contact, and R1 under normal contact
//! with Coulomb friction (mu = 0.1), and the forward sensitivities of every parameter.
//! `cargo bench -p indentify-adjoint`; the ratio adjoint / forward is printed.

use criterion::{Criterion, criterion_group, criterion_main};
use indentify_adjoint::Adjoint;
use indentify_contact::{
    ContactKind, DirectSolver, Model, Punch, Schedule, SolverOptions, trapezoid,
};
use indentify_laws::{Law, Maxwell, NortonHoff};
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
    .expect("model")
}

fn bench_adjoint(c: &mut Criterion) {
    let model = reference_model(ContactKind::Vertical);
    let friction = reference_model(ContactKind::normal_with_friction(0.1).expect("friction"));
    let schedule = Schedule::from_segments(&trapezoid(0.1, 1.0, 1.0, 1.0, 30)).expect("schedule");
    let r1 = vec![20000.0, 0.3, 30000.0];
    let cases: [(&str, &dyn Law, Vec<f64>, &Model); 3] = [
        ("r1_maxwell", &Maxwell, r1.clone(), &model),
        (
            "r2_norton_hoff",
            &NortonHoff,
            vec![1e5, 0.3, 1500.0, 5.0, 500.0],
            &model,
        ),
        ("r1_maxwell_friction", &Maxwell, r1, &friction),
    ];
    let mut group = c.benchmark_group("adjoint");
    group.sample_size(10);
    for (name, law, params, model) in cases {
        let mut solver = DirectSolver::new(model).expect("solver");
        let traj = solver
            .run(
                &indentify_laws::LawMaterial(law),
                &params,
                &schedule,
                &SolverOptions::default(),
            )
            .expect("run");
        // a cost with rho_i = F_i (data = 0): every step contributes
        let rho: Vec<f64> = traj.steps.iter().map(|s| s.force).collect();
        let mut adj = Adjoint::new(model).expect("adjoint");
        let g = adj
            .gradient(&indentify_laws::LawMaterial(law), &params, &traj, &rho)
            .expect("gradient");
        eprintln!(
            "{name}: forward {:.1} ms, adjoint {:.1} ms (ratio {:.2}), adjoint factorizations {}, trajectory {:.1} MB",
            1e3 * traj.timing.total,
            1e3 * g.seconds,
            g.seconds / traj.timing.total,
            g.factorizations,
            traj.recorded_bytes() as f64 / 1e6
        );
        group.bench_function(format!("{name}_gradient"), |b| {
            b.iter(|| {
                adj.gradient(&indentify_laws::LawMaterial(law), &params, &traj, &rho)
                    .expect("gradient")
            })
        });
        // the forward sensitivities of every parameter (what Levenberg-Marquardt asks for)
        // inside a pool, as an identification runs it (its parameters in parallel)
        let pool = rayon::ThreadPoolBuilder::new().build().expect("pool");
        group.bench_function(format!("{name}_sensitivities"), |b| {
            b.iter(|| {
                pool.install(|| {
                    adj.sensitivities(&indentify_laws::LawMaterial(law), &params, &traj)
                })
                .expect("sensitivities")
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench_adjoint);
criterion_main!(benches);
