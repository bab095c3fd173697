//! Dev-only test support shared by the test targets of several crates (a dev-dependency
//! only, never a library's dependency): the graded test cylinders and the 68-degree cone
//! model their set-ups built again and again, history segments, and the bit-for-bit and
//! relative comparisons of their checks. Each helper builds exactly what the tests wrote
//! out before, so that a test's subject, tolerances and assertions stay where they were.
//!
//! It depends on `mesh` and `contact` only, so that every crate above them (`adjoint`,
//! `identify`, `study`, `xtask`) may take it as a dev-dependency without a cycle; the
//! `contact` crate's own tests keep their `tests/common/mod.rs`.

use indentify_contact::{
    ContactKind, HistorySegment, LoadHistory, Model, Punch, Schedule, Segment, SolverOptions,
};
use indentify_mesh::{CylinderMesher, Mesh};

/// A `size` x `size` mm cylinder in `n` x `n` Q8 graded `grading` towards the axis and the
/// top (the same ratio along r and z).
///
/// # Panics
/// On a size, count or grading the mesher refuses (a test's own mistake).
pub fn cylinder(size: f64, n: usize, grading: f64) -> Mesh {
    cylinder_rz(size, n, n, grading)
}

/// A `size` x `size` mm cylinder in `nr` x `nz` Q8 graded `grading` towards the axis and
/// the top (the same ratio along r and z).
///
/// # Panics
/// On a size, count or grading the mesher refuses (a test's own mistake).
pub fn cylinder_rz(size: f64, nr: usize, nz: usize, grading: f64) -> Mesh {
    CylinderMesher {
        radius: size,
        height: size,
        nr,
        nz,
        grading_r: grading,
        grading_z: grading,
    }
    .build()
    .unwrap()
}

/// The small test cylinder most adjoint and identification tests run on: 4 x 4 mm, 8 x 8
/// Q8 graded 1.45 towards the axis and the top.
pub fn small_cylinder() -> Mesh {
    cylinder(4.0, 8, 1.45)
}

/// The cone of half-angle 68 degrees (the Vickers and Berkovich equivalent).
pub fn cone68() -> Punch {
    Punch::Cone {
        half_angle_deg: 68.0,
    }
}

/// The sphere of radius 1 mm.
pub fn sphere1() -> Punch {
    Punch::Sphere { radius: 1.0 }
}

/// The small R2-like model: [`small_cylinder`] under [`cone68`], frictionless normal
/// contact, small strain.
///
/// # Panics
/// Never for these fixed inputs (the model is always valid).
pub fn cone_model() -> Model {
    Model::new(small_cylinder(), cone68()).unwrap()
}

/// A load-controlled segment: to `force` (N) in `duration` (s), `steps` steps.
pub fn force(duration: f64, force: f64, steps: usize) -> HistorySegment {
    HistorySegment {
        duration,
        depth: None,
        force: Some(force),
        steps,
    }
}

/// A depth-controlled segment: to `depth` (mm) in `duration` (s), `steps` steps.
pub fn depth(duration: f64, depth: f64, steps: usize) -> HistorySegment {
    HistorySegment {
        duration,
        depth: Some(depth),
        force: None,
        steps,
    }
}

/// Coulomb friction of coefficient `mu` on normal contact.
///
/// # Panics
/// On a coefficient the contact refuses (a test's own mistake).
pub fn coulomb(mu: f64) -> ContactKind {
    ContactKind::normal_with_friction(mu).unwrap()
}

/// Force ramp to `p` (N), hold, unload to `0.4 p`, `steps` steps per segment (1 s each).
///
/// # Panics
/// On a history the contact refuses (a test's own mistake).
pub fn force_lhu(p: f64, steps: usize) -> LoadHistory {
    LoadHistory::from_segments(&[
        force(1.0, p, steps),
        force(1.0, p, steps),
        force(1.0, 0.4 * p, steps),
    ])
    .unwrap()
}

/// Machine depth: ramp to `h` (mm), hold, unload to `end` (mm), `steps` steps per segment
/// (1 s each).
///
/// # Panics
/// On a schedule the contact refuses (a test's own mistake).
pub fn depth_lhu(h: f64, end: f64, steps: usize) -> Schedule {
    let seg = |depth, steps| Segment {
        duration: 1.0,
        depth,
        steps,
    };
    Schedule::from_segments(&[seg(h, steps), seg(h, steps), seg(end, steps)]).unwrap()
}

/// Solver options recording every field or not (`record`), Newton to the residual `tol`,
/// the others at their defaults.
pub fn recording(record: bool, tol: f64) -> SolverOptions {
    SolverOptions {
        record_fields: record,
        residual_tol: tol,
        ..SolverOptions::default()
    }
}

/// The gradient checks' cost weights, `w_i = 1 + 0.37 ((7 i) mod 5)`, `i < n`: unequal,
/// so that no entry of a gradient hides behind a symmetric sum.
pub fn weights(n: usize) -> Vec<f64> {
    (0..n).map(|i| 1.0 + 0.37 * ((i * 7) % 5) as f64).collect()
}

/// The workspace's root folder (absolute: the parent of `crates`).
///
/// # Panics
/// Never: this crate's folder is `crates/testkit` below the root.
pub fn workspace_root() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .and_then(|p| p.parent())
        .unwrap()
        .to_path_buf()
}

/// The bits of every value, for comparisons that must hold bit for bit (with NaN equal to
/// itself and -0 apart from +0).
pub fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

/// The largest `|a_k - b_k|` relative to the largest `|a_k|`.
pub fn rel_to_largest(a: &[f64], b: &[f64]) -> f64 {
    let scale = a.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs() / scale))
}
