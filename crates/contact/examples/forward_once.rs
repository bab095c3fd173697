//! Profiling driver: one forward solve of R0, R1 or R2 (docs/theory.md §11) with its time split
//! and the global iterations per segment, e.g. under `valgrind --tool=callgrind`:
//! `cargo run --release -p indentify-contact --example forward_once -- r2 [REPEAT]`
//! (with REPEAT > 1 it reports the fastest of REPEAT runs; `--steps` lists every step's
//! iterations and active-set changes; `--normal` takes normal contact, `--finite` finite
//! strain with normal contact, for back-to-back ratios against `--normal`; `--sy V` sets
//! R2's yield stress sY to V MPa instead of 500; `--forces` prints every step's time and
//! force with 17 significant digits, to compare two builds' results; `--friction MU` takes
//! normal contact with Coulomb friction of coefficient MU instead of frictionless).
use indentify_contact::{
    ContactKind, DirectSolver, Kinematics, Model, Punch, Schedule, SolverOptions, trapezoid,
};
use indentify_laws::{Elastic, Law, Maxwell, NortonHoff};
use indentify_mesh::CylinderMesher;

fn main() {
    let case = std::env::args().nth(1).unwrap_or_else(|| "r1".into());
    let (law, params): (&dyn Law, Vec<f64>) = match case.as_str() {
        "r0" => (&Elastic, vec![2e4, 0.3]),
        "r1" => (&Maxwell, vec![2e4, 0.3, 3e4]),
        "r2" => (&NortonHoff, vec![1e5, 0.3, 1500.0, 5.0, yield_stress()]),
        other => {
            eprintln!("unknown case {other}: expected r0, r1 or r2");
            std::process::exit(2);
        }
    };
    let mesh = CylinderMesher::REFERENCE.build().expect("reference mesh");
    let finite = std::env::args().any(|a| a == "--finite");
    let contact = if let Some(mu) = friction() {
        ContactKind::NormalFriction { friction: mu }
    } else if finite || std::env::args().any(|a| a == "--normal") {
        ContactKind::Normal
    } else {
        ContactKind::Vertical
    };
    let kinematics = if finite {
        Kinematics::Finite
    } else {
        Kinematics::Small
    };
    let model = Model::with_contact(
        mesh,
        Punch::Cone {
            half_angle_deg: 68.0,
        },
        contact,
    )
    .and_then(|m| m.with_kinematics(kinematics))
    .expect("reference model");
    let l_nnz = indentify_fe::SparseCholesky::analyse(&model.pattern)
        .expect("analysis")
        .factor_nnz();
    println!(
        "{} equations, {} stored entries of K, {} of its Cholesky factor",
        model.dofs.n_eq,
        model.pattern.nnz(),
        l_nnz
    );
    let sched = Schedule::from_segments(&trapezoid(0.1, 1.0, 1.0, 1.0, 30)).expect("schedule");
    let mut solver = DirectSolver::new(&model).expect("solver");
    let opts = SolverOptions::default();
    let t = solver
        .run(&indentify_laws::LawMaterial(law), &params, &sched, &opts)
        .expect("forward run");
    let repeat: usize = std::env::args()
        .nth(2)
        .and_then(|r| r.parse().ok())
        .unwrap_or(1);
    let mut t = t;
    if repeat > 1 {
        for _ in 1..repeat {
            let again = solver
                .run(&indentify_laws::LawMaterial(law), &params, &sched, &opts)
                .expect("forward run");
            if again.timing.total < t.timing.total {
                t = again;
            }
        }
        println!("{case}: the fastest of {repeat} runs:");
    }
    if std::env::args().any(|a| a == "--steps") {
        for r in &t.steps {
            eprintln!(
                "t {:.4} it {} changes {} active {}",
                r.t,
                r.iterations,
                r.active_set_changes,
                r.active.len()
            );
        }
    }
    let per_segment: Vec<u32> = (0..3)
        .map(|s| {
            t.steps
                .iter()
                .filter(|r| (r.schedule_index - 1) / 30 == s)
                .map(|r| r.iterations)
                .sum()
        })
        .collect();
    if std::env::args().any(|a| a == "--forces") {
        for r in &t.steps {
            println!("{:.17e} {:.17e}", r.t, r.force);
        }
    }
    println!(
        "{case}: {} steps, {} iterations (load/hold/unload {:?}), {}; F_max {:.6} N",
        t.steps.len(),
        t.total_iterations(),
        per_segment,
        t.timing,
        t.forces().iter().cloned().fold(0.0, f64::max)
    );
}

/// R2's yield stress sY (MPa): the value after `--sy`, 500 without it.
fn yield_stress() -> f64 {
    let args: Vec<String> = std::env::args().collect();
    match args.iter().position(|a| a == "--sy") {
        None => 500.0,
        Some(i) => match args.get(i + 1).and_then(|v| v.parse::<f64>().ok()) {
            Some(v) if v >= 0.0 && v.is_finite() => v,
            _ => {
                eprintln!("--sy: expected a yield stress >= 0 in MPa after it");
                std::process::exit(2);
            }
        },
    }
}

/// The friction coefficient after `--friction`, if given.
fn friction() -> Option<f64> {
    let args: Vec<String> = std::env::args().collect();
    let i = args.iter().position(|a| a == "--friction")?;
    match args.get(i + 1).and_then(|v| v.parse::<f64>().ok()) {
        Some(v) if v > 0.0 && v.is_finite() => Some(v),
        _ => {
            eprintln!("--friction: expected a friction coefficient > 0 after it");
            std::process::exit(2);
        }
    }
}
