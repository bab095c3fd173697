//! Benchmarks of the laws with internal variables on R2's mesh and history
//! (docs/theory.md §11: 20 x 20 Q8, cone 68 deg, trapezoid 30 steps per segment, vertical
//! contact), back to back with R2's Norton-Hoff: the forward of J2 plasticity
//! (rate-independent, linear hardening), of `Plastic(Linear(H: 0), Norton)` (R2's physics
//! through the material path) and of a two-term Prony solid; the adjoint gradient and the
//! forward sensitivities of the new laws (the sweep / forward ratio is printed).
//! `cargo bench -p indentify-adjoint --bench materials`.

use criterion::{Criterion, criterion_group, criterion_main};
use indentify_adjoint::Adjoint;
use indentify_contact::{
    ContactKind, DirectSolver, Model, Punch, Schedule, SolverOptions, trapezoid,
};
use indentify_laws::{Hardening, LawMaterial, Material, NortonHoff, Plastic, Prony, Rate};
use indentify_mesh::CylinderMesher;

fn bench_materials(c: &mut Criterion) {
    let mesh = CylinderMesher::REFERENCE.build().expect("reference mesh");
    let model = Model::with_contact(
        mesh,
        Punch::Cone {
            half_angle_deg: 68.0,
        },
        ContactKind::Vertical,
    )
    .expect("model");
    let schedule = Schedule::from_segments(&trapezoid(0.1, 1.0, 1.0, 1.0, 30)).expect("schedule");
    let nh = LawMaterial(&NortonHoff);
    let j2 = Plastic::new(Hardening::Linear, Rate::Independent);
    let j2_norton = Plastic::new(Hardening::Linear, Rate::Norton);
    let prony = Prony::new(2).expect("prony");
    let cases: [(&str, &dyn Material, Vec<f64>, bool); 4] = [
        (
            "r2_norton_hoff",
            &nh,
            vec![1e5, 0.3, 1500.0, 5.0, 500.0],
            false,
        ),
        ("j2_linear", &j2, vec![1e5, 0.3, 500.0, 1000.0], true),
        (
            "j2_norton_h0",
            &j2_norton,
            vec![1e5, 0.3, 500.0, 0.0, 1500.0, 5.0],
            true,
        ),
        ("prony2", &prony, vec![1e5, 0.3, 0.3, 0.2, 0.2, 2.0], true),
    ];
    let mut group = c.benchmark_group("materials");
    group.sample_size(10);
    for (name, mat, params, adjoint) in cases {
        let mut solver = DirectSolver::new(&model).expect("solver");
        let opts = SolverOptions::default();
        let traj = solver.run(mat, &params, &schedule, &opts).expect("run");
        eprintln!(
            "{name}: {} steps, {} iterations, {}",
            traj.steps.len(),
            traj.total_iterations(),
            traj.timing
        );
        group.bench_function(format!("{name}_forward"), |b| {
            b.iter(|| solver.run(mat, &params, &schedule, &opts).expect("run"))
        });
        if !adjoint {
            continue;
        }
        let rho: Vec<f64> = traj.steps.iter().map(|s| s.force).collect();
        let mut adj = Adjoint::new(&model).expect("adjoint");
        let g = adj.gradient(mat, &params, &traj, &rho).expect("gradient");
        eprintln!(
            "{name}: forward {:.1} ms, adjoint {:.1} ms (ratio {:.2})",
            1e3 * traj.timing.total,
            1e3 * g.seconds,
            g.seconds / traj.timing.total
        );
        group.bench_function(format!("{name}_gradient"), |b| {
            b.iter(|| adj.gradient(mat, &params, &traj, &rho).expect("gradient"))
        });
        group.bench_function(format!("{name}_sensitivities"), |b| {
            b.iter(|| {
                adj.sensitivities(mat, &params, &traj)
                    .expect("sensitivities")
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench_materials);
criterion_main!(benches);
