//! Profiling driver: one R1 forward solve (`valgrind --tool=callgrind`).
use indentify_contact::*;
use indentify_laws::Maxwell;
use indentify_mesh::CylinderMesher;
fn main() {
    let mesh = CylinderMesher {
        radius: 10.0,
        height: 10.0,
        nr: 20,
        nz: 20,
        grading_r: 1.3,
        grading_z: 1.3,
    }
    .build()
    .unwrap();
    let model = Model::new(
        mesh,
        Punch::Cone {
            half_angle_deg: 68.0,
        },
    )
    .unwrap();
    let sched = Schedule::from_segments(&trapezoid(0.1, 1.0, 1.0, 1.0, 30)).unwrap();
    let mut s = DirectSolver::new(&model).unwrap();
    let t = s
        .run(
            &model,
            &Maxwell,
            &[2e4, 0.3, 3e4],
            &sched,
            &SolverOptions::default(),
        )
        .unwrap();
    eprintln!(
        "its {} fact {} {:?}",
        t.total_iterations(),
        t.timing.factorizations,
        t.timing
    );
}
