//! The README's library example: simulate R1 (Maxwell) and take the adjoint gradient of a
//! least-squares misfit. `cargo run --release -p indentify-adjoint --example quickstart`.

use indentify_adjoint::Adjoint;
use indentify_contact::{DirectSolver, Model, Punch, Schedule, SolverOptions, trapezoid};
use indentify_laws::{Law, Maxwell};
use indentify_mesh::CylinderMesher;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mesh = CylinderMesher::REFERENCE.build()?;
    let model = Model::new(
        mesh,
        Punch::Cone {
            half_angle_deg: 68.0,
        },
    )?;
    let schedule = Schedule::from_segments(&trapezoid(0.1, 1.0, 1.0, 1.0, 30))?;
    let c = [20000.0, 0.3, 30000.0];
    let traj = DirectSolver::new(&model)?.run(
        &indentify_laws::LawMaterial(&Maxwell),
        &c,
        &schedule,
        &SolverOptions::default(),
    )?;
    let rho: Vec<f64> = traj.steps.iter().map(|s| s.force - 100.0).collect(); // dJ/dF_i
    let grad =
        Adjoint::new(&model)?.gradient(&indentify_laws::LawMaterial(&Maxwell), &c, &traj, &rho)?;
    let fmax = traj.steps.iter().map(|s| s.force).fold(0.0, f64::max);
    println!(
        "F_max = {fmax:.3} N over {} steps ({:.1} ms)",
        traj.steps.len(),
        1e3 * traj.timing.total
    );
    for (info, g) in Maxwell.params().iter().zip(&grad.dj_dc) {
        println!("dJ/d{} = {g:.6e} N^2/{}", info.name, info.unit);
    }
    println!("adjoint sweep {:.1} ms", 1e3 * grad.seconds);
    Ok(())
}
