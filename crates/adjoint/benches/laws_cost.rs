//! Forward run and adjoint gradient of every law on R2's mesh and history
//! (docs/theory.md §11: 20 x 20 Q8, cone 68 deg, trapezoid 30 steps per segment, vertical
//! contact), back to back: the stress-only laws (Elastic, Maxwell, R2's Norton-Hoff), J2
//! plasticity with each hardening form, rate-independent and Norton, and Prony series of
//! one to three terms; the gradient / forward ratio of one run is printed per law.
//! `cargo bench -p indentify-adjoint --bench laws_cost` (docs/performance.md);
//! `LAWS_COST=prony` keeps the cases whose name contains `prony`.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Duration;

use criterion::{Criterion, SamplingMode, criterion_group, criterion_main};
use indentify_adjoint::Adjoint;
use indentify_contact::{
    ContactKind, DirectSolver, Model, Punch, Schedule, SolverOptions, trapezoid,
};
use indentify_laws::{
    Elastic, Hardening, InternalInfo, Law, LawMaterial, LocalFailure, Material, MaterialUpdate,
    Maxwell, NortonHoff, ParamInfo, Plastic, Prony, Rate, Step, Vec4,
};
use indentify_mesh::CylinderMesher;

/// A material that forwards to `inner` and counts its updates and their local
/// iterations (the counts printed before each case's benchmarks).
#[derive(Debug)]
struct Counted<'a> {
    inner: &'a dyn Material,
    calls: AtomicUsize,
    iterations: AtomicUsize,
}

impl<'a> Counted<'a> {
    fn new(inner: &'a dyn Material) -> Counted<'a> {
        Counted {
            inner,
            calls: AtomicUsize::new(0),
            iterations: AtomicUsize::new(0),
        }
    }
    fn take(&self) -> (usize, usize) {
        (
            self.calls.swap(0, Ordering::Relaxed),
            self.iterations.swap(0, Ordering::Relaxed),
        )
    }
}

impl Material for Counted<'_> {
    fn name(&self) -> &'static str {
        self.inner.name()
    }
    fn params(&self) -> &[ParamInfo] {
        self.inner.params()
    }
    fn internal(&self) -> &[InternalInfo] {
        self.inner.internal()
    }
    fn is_linear(&self) -> bool {
        self.inner.is_linear()
    }
    fn as_law(&self) -> Option<&dyn Law> {
        self.inner.as_law()
    }
    fn residual(&self, c: &[f64], step: &Step<'_>, r: &mut [f64]) {
        self.inner.residual(c, step, r)
    }
    fn jac_state(&self, c: &[f64], step: &Step<'_>, out: &mut [f64]) {
        self.inner.jac_state(c, step, out)
    }
    fn jac_previous(&self, c: &[f64], step: &Step<'_>, out: &mut [f64]) {
        self.inner.jac_previous(c, step, out)
    }
    fn jac_params(&self, c: &[f64], step: &Step<'_>, out: &mut [f64]) {
        self.inner.jac_params(c, step, out)
    }
    fn update(
        &self,
        c: &[f64],
        y0: &[f64],
        deps: &Vec4,
        dt: f64,
        y1: &mut [f64],
    ) -> Result<MaterialUpdate, LocalFailure> {
        let up = self.inner.update(c, y0, deps, dt, y1)?;
        self.calls.fetch_add(1, Ordering::Relaxed);
        self.iterations
            .fetch_add(up.iterations as usize, Ordering::Relaxed);
        Ok(up)
    }
}

/// Every case: name, material, parameters.
fn cases() -> Vec<(&'static str, Box<dyn Material>, Vec<f64>)> {
    let pl = |h, r| Box::new(Plastic::new(h, r)) as Box<dyn Material>;
    let prony = |n| Box::new(Prony::new(n).expect("prony")) as Box<dyn Material>;
    let (e, nu, sy, k, m) = (1e5, 0.3, 500.0, 1500.0, 5.0);
    vec![
        ("elastic", Box::new(LawMaterial(&Elastic)), vec![e, nu]),
        (
            "maxwell",
            Box::new(LawMaterial(&Maxwell)),
            vec![20000.0, 0.3, 30000.0],
        ),
        (
            "norton_hoff",
            Box::new(LawMaterial(&NortonHoff)),
            vec![e, nu, k, m, sy],
        ),
        (
            "plastic_linear",
            pl(Hardening::Linear, Rate::Independent),
            vec![e, nu, sy, 1000.0],
        ),
        (
            "plastic_power",
            pl(Hardening::Power, Rate::Independent),
            vec![e, nu, sy, 0.2],
        ),
        (
            "plastic_voce",
            pl(Hardening::Voce, Rate::Independent),
            vec![e, nu, sy, 300.0, 20.0],
        ),
        (
            "plastic_linear_norton",
            pl(Hardening::Linear, Rate::Norton),
            vec![e, nu, sy, 1000.0, k, m],
        ),
        (
            "plastic_power_norton",
            pl(Hardening::Power, Rate::Norton),
            vec![e, nu, sy, 0.2, k, m],
        ),
        (
            "plastic_voce_norton",
            pl(Hardening::Voce, Rate::Norton),
            vec![e, nu, sy, 300.0, 20.0, k, m],
        ),
        ("prony1", prony(1), vec![e, nu, 0.3, 0.2]),
        ("prony2", prony(2), vec![e, nu, 0.3, 0.2, 0.2, 2.0]),
        (
            "prony3",
            prony(3),
            vec![e, nu, 0.3, 0.2, 0.2, 2.0, 0.1, 20.0],
        ),
    ]
}

fn bench_laws(c: &mut Criterion) {
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
    let opts = SolverOptions::default();
    let mut group = c.benchmark_group("laws_cost");
    group
        .sample_size(10)
        .sampling_mode(SamplingMode::Flat)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3));
    let mut solver = DirectSolver::new(&model).expect("solver");
    let mut adj = Adjoint::new(&model).expect("adjoint");
    // `LAWS_COST=prony` runs only the cases whose name contains `prony` (each case's
    // first run, which prints the ratio, comes before criterion's own filter)
    let only = std::env::var("LAWS_COST").unwrap_or_default();
    for (name, mat, params) in cases().into_iter().filter(|c| c.0.contains(&only)) {
        let mat = &*mat;
        // the counts first (local updates and their iterations through a counting
        // wrapper, then the run criterion times without it)
        let counted = Counted::new(mat);
        let traj = solver
            .run(&counted, &params, &schedule, &opts)
            .expect("run");
        let (calls, local) = counted.take();
        let traj_plain = solver.run(mat, &params, &schedule, &opts).expect("run");
        assert_eq!(traj.steps.len(), traj_plain.steps.len());
        let traj = traj_plain;
        // a cost with rho_i = F_i (data = 0): every step contributes
        let rho: Vec<f64> = traj.steps.iter().map(|s| s.force).collect();
        let g = adj.gradient(mat, &params, &traj, &rho).expect("gradient");
        eprintln!(
            "{name}: {} steps, {} Newton iterations, {calls} local updates, {local} local \
             iterations ({}); gradient {:.1} ms (ratio {:.2})",
            traj.steps.len(),
            traj.total_iterations(),
            traj.timing,
            1e3 * g.seconds,
            g.seconds / traj.timing.total
        );
        group.bench_function(format!("{name}_forward"), |b| {
            b.iter(|| solver.run(mat, &params, &schedule, &opts).expect("run"))
        });
        group.bench_function(format!("{name}_gradient"), |b| {
            b.iter(|| adj.gradient(mat, &params, &traj, &rho).expect("gradient"))
        });
    }
    group.finish();
}

criterion_group!(benches, bench_laws);
criterion_main!(benches);
