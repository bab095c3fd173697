//! The kinematics of the direct problem ([`Kinematics`]): the paper's small strain, or
//! finite strain (total-Lagrangian, laws in logarithmic strain space), and the Gauss-point
//! evaluation of the finite-strain internal force and element tangents.
//!
//! Under [`Kinematics::Finite`] the state stored at each Gauss point is the stress `T`
//! conjugate to the Hencky strain `E = ln(C)/2` (Miehe, Apel & Lambrecht 2002); the law
//! updates `T` from the increment of `E` with its small-strain code, and the element
//! receives `S = P : T` and `dS/dE_GL = P : A : P + T : L` (`indentify_laws::LogStrain`,
//! `indentify_fe::finite`). For the isotropic laws of this crate the Kirchhoff stress is
//! `tau = R T R^T`, so `T` has the principal values of `J sigma`.

use indentify_fe::{Deformation, Discretization, QP_PER_ELEMENT};
use indentify_laws::{ElasticDomain, Law, LogStrain, Mat4, Material, Regime, Vec4};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::{ContactError, ContactKind};

/// Kinematics of the direct problem.
///
/// Config: `kinematics: Small` (the default) or `kinematics: Finite` (requires
/// `contact: Normal` or `contact: Normal(friction: mu)`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Kinematics {
    /// The paper's small strain: `eps = B u` on the reference configuration.
    #[default]
    Small,
    /// Finite strain: total-Lagrangian axisymmetric Q8 with the hoop stretch
    /// `1 + u_r/R`, the laws applied to the Hencky strain `ln(C)/2` (their small-strain
    /// update and tangent unchanged), the consistent tangent with its material and
    /// geometric parts. Needs normal contact (the gap at the displaced position),
    /// frictionless or with Coulomb friction.
    Finite,
}

impl Kinematics {
    /// Checks that `contact` supports these kinematics: finite strain needs `Normal`
    /// contact (the gap of the displaced node along the punch's normal), frictionless or
    /// with Coulomb friction (`Normal(friction: mu)`: the stick/slip law on the displaced
    /// node's closest point, as in small strain).
    ///
    /// # Errors
    /// [`ContactError::Input`] naming `kinematics`, with what is allowed.
    pub fn check_contact(self, contact: ContactKind) -> Result<(), ContactError> {
        if self == Kinematics::Finite && !contact.is_normal() {
            return Err(ContactError::Input {
                field: "kinematics",
                value: "Finite".into(),
                allowed: "`kinematics: Finite` with `contact: Normal` or `Normal(friction: \
                      mu)` only: vertical contact \
                      takes the gap at the node's reference radius and a vertical \
                      reaction, which finite strain's displaced and rotated surface \
                      contradicts; set `contact: Normal` (or keep `kinematics: Small`)"
                    .into(),
            });
        }
        Ok(())
    }
}

/// Why a finite-strain Gauss-point evaluation failed.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum FiniteFailure {
    /// `det F <= 0` (or `C` not positive definite) at Gauss point `qp`.
    Inverted { qp: usize, det: f64 },
    /// The law's local update failed at `qp`.
    Local {
        qp: usize,
        reason: String,
        factor: f64,
    },
}

impl FiniteFailure {
    /// The Gauss point where it failed (the first in element order is the one reported).
    fn qp(&self) -> usize {
        match self {
            FiniteFailure::Inverted { qp, .. } | FiniteFailure::Local { qp, .. } => *qp,
        }
    }
}

/// Elements per parallel task of the Gauss-point passes ([`evaluate`],
/// [`element_tangents`], and the small-strain pass of `DirectSolver`): fixed, so the work
/// split, and with the assembly in element order the results, do not depend on the number
/// of threads.
pub(crate) const ELEMENT_CHUNK: usize = 8;

/// Inputs of [`evaluate`]: the law, its parameters and the step length, the initial
/// state's stresses `t0` and Hencky strains `e0` (every Gauss point), and the law's
/// elastic domain when it has one.
#[derive(Clone, Copy)]
pub(crate) struct FiniteIn<'a> {
    /// The stress-only law, or `None` for a material with internal variables.
    pub law: Option<&'a dyn Law>,
    /// The material with internal variables (when `law` is `None`) and the internal
    /// variables of the initial state (point-major).
    pub material: Option<(&'a dyn Material, &'a [f64])>,
    /// Its parameters.
    pub c: &'a [f64],
    /// Step length (s).
    pub dt: f64,
    /// Stresses `T` of the initial state.
    pub t0: &'a [Vec4],
    /// Hencky strains of the initial state.
    pub e0: &'a [Vec4],
    /// Where the law's update is the elastic one ([`Law::elastic_domain`]).
    pub domain: Option<&'a ElasticDomain>,
}

/// Output buffers of [`evaluate`].
pub(crate) struct FiniteOut<'a> {
    /// The stresses `T` (every Gauss point).
    pub sigma: &'a mut [Vec4],
    /// The internal force (all dofs).
    pub f_int: &'a mut [f64],
    /// The laws' consistent tangents `A = dT/dE` (every Gauss point), from which
    /// [`element_tangents`] forms the element matrices if a Newton pass needs them.
    pub tangents: &'a mut [Mat4],
    /// The deformation and its Hencky strain (with `P` and the second derivatives) at every
    /// Gauss point, kept for [`element_tangents`] at the same displacement.
    pub points: &'a mut [Point],
    /// A material's internal variables and regimes (empty for a stress-only law).
    pub alpha: &'a mut [f64],
    /// See `alpha`.
    pub regime: &'a mut [Regime],
}

/// A Gauss point's deformation and Hencky strain, as [`evaluate`] formed them.
pub(crate) type Point = (Deformation, LogStrain);

/// A placeholder [`Point`] (the undeformed state) for sizing buffers.
pub(crate) fn undeformed_point(disc: &Discretization) -> Point {
    let def = Deformation::new(&disc.qp[0], &[0.0; 16]);
    let ls = LogStrain::from_difference(&Vec4::ZERO)
        .unwrap_or_else(|| unreachable!("the Hencky strain of C = 1 exists"));
    (def, ls)
}

/// The Hencky strain of every Gauss point at displacement `u` (all dofs).
///
/// # Errors
/// [`FiniteFailure::Inverted`] at the first inverted point.
pub(crate) fn log_strains(
    disc: &Discretization,
    u: &[f64],
    out: &mut [Vec4],
) -> Result<(), FiniteFailure> {
    for e in 0..disc.elements.len() {
        let ue = disc.gather(e, u);
        for g in 0..QP_PER_ELEMENT {
            let q = QP_PER_ELEMENT * e + g;
            let def = Deformation::new(&disc.qp[q], &ue);
            let det = def.det();
            let ls = (det > 0.0)
                .then(|| LogStrain::from_difference(&def.c_minus_one()))
                .flatten()
                .ok_or(FiniteFailure::Inverted { qp: q, det })?;
            out[q] = ls.e;
        }
    }
    Ok(())
}

/// The Gauss point of smallest `det F` at displacement `u`, and that determinant.
pub(crate) fn smallest_det(disc: &Discretization, u: &[f64]) -> (usize, f64) {
    let mut worst = (0, f64::INFINITY);
    for e in 0..disc.elements.len() {
        let ue = disc.gather(e, u);
        for g in 0..QP_PER_ELEMENT {
            let q = QP_PER_ELEMENT * e + g;
            let det = Deformation::new(&disc.qp[q], &ue).det();
            if det.is_nan() || det < worst.1 {
                worst = (q, det);
            }
        }
    }
    worst
}

/// Local updates from the state (`t0`, Hencky strains `e0`) to displacement `u`: the
/// stresses `T` into `out.sigma`, the laws' tangents into `out.tangents`, each point's
/// deformation and Hencky strain into `out.points` and the internal force into `out.f_int`
/// (overwritten). The element tangents are left to [`element_tangents`], from those kept
/// points: a Newton pass whose residual has converged never needs them.
///
/// # Errors
/// The first inverted Gauss point or failed local update.
pub(crate) fn evaluate(
    disc: &Discretization,
    input: &FiniteIn<'_>,
    u: &[f64],
    out: FiniteOut<'_>,
) -> Result<(), FiniteFailure> {
    let FiniteIn {
        law,
        material,
        c,
        dt,
        t0,
        e0,
        domain,
    } = *input;
    let ne = disc.elements.len();
    let nq = QP_PER_ELEMENT * ne;
    let n_int = material.map_or(0, |(mat, _)| mat.n_internal());
    let m = 4 + n_int;
    let chunks = ne.div_ceil(ELEMENT_CHUNK);
    let (alpha_out, regime_out) = (out.alpha, out.regime);
    let mut alpha_chunks: Vec<&mut [f64]> = if n_int > 0 {
        alpha_out[..nq * n_int]
            .chunks_mut(QP_PER_ELEMENT * ELEMENT_CHUNK * n_int)
            .collect()
    } else {
        (0..chunks).map(|_| &mut [][..]).collect()
    };
    let mut regime_chunks: Vec<&mut [Regime]> = if material.is_some() {
        regime_out[..nq]
            .chunks_mut(QP_PER_ELEMENT * ELEMENT_CHUNK)
            .collect()
    } else {
        (0..chunks).map(|_| &mut [][..]).collect()
    };
    // element forces in parallel over fixed chunks of elements, each element's arithmetic
    // the serial one; then assembled serially in element order: bit for bit the same for
    // any number of threads
    let mut fe_all = vec![[0.0; 16]; ne];
    let chunk_qp = QP_PER_ELEMENT * ELEMENT_CHUNK;
    let first_failure = fe_all
        .par_chunks_mut(ELEMENT_CHUNK)
        .zip(out.sigma[..nq].par_chunks_mut(chunk_qp))
        .zip(out.tangents[..nq].par_chunks_mut(chunk_qp))
        .zip(out.points[..nq].par_chunks_mut(chunk_qp))
        .zip(alpha_chunks.par_iter_mut().map(|a| &mut **a))
        .zip(regime_chunks.par_iter_mut().map(|r| &mut **r))
        .enumerate()
        .filter_map(|(chunk, (((((fes, sigma), tangents), points), al), reg))| {
            // the states y0, y1 of a material's update (one scratch per chunk)
            let mut buf = vec![0.0; if material.is_some() { 2 * m } else { 0 }];
            for (i, fe) in fes.iter_mut().enumerate() {
                let e = chunk * ELEMENT_CHUNK + i;
                let ue = disc.gather(e, u);
                for g in 0..QP_PER_ELEMENT {
                    let q = QP_PER_ELEMENT * e + g;
                    let local = QP_PER_ELEMENT * i + g;
                    let qp = &disc.qp[q];
                    let def = Deformation::new(qp, &ue);
                    let ls = match log_strain(&def, q) {
                        Ok(ls) => ls,
                        Err(f) => return Some(f),
                    };
                    let de = ls.e - e0[q];
                    let (t, a) = match domain
                        .and_then(|d| d.update(&t0[q], &de).map(|t| (t, d.stiffness)))
                    {
                        Some(x) => x,
                        None => {
                            let up = match (law, material) {
                                (Some(law), _) => law
                                    .update(c, &t0[q], &de, dt)
                                    .map(|up| (up.sigma, up.tangent)),
                                (None, Some((mat, alpha0))) => {
                                    let (y0, y1) = buf.split_at_mut(m);
                                    y0[..4].copy_from_slice(&t0[q].0);
                                    y0[4..].copy_from_slice(&alpha0[q * n_int..(q + 1) * n_int]);
                                    mat.update(c, y0, &de, dt, y1).and_then(|up| {
                                        if y1.iter().any(|v| !v.is_finite()) {
                                            return Err(indentify_laws::LocalFailure {
                                                reason: format!(
                                                    "{}: non-finite state after the update",
                                                    mat.name()
                                                ),
                                                suggested_dt_factor: 0.5,
                                            });
                                        }
                                        al[local * n_int..(local + 1) * n_int]
                                            .copy_from_slice(&y1[4..]);
                                        reg[local] = up.regime;
                                        Ok((Vec4([y1[0], y1[1], y1[2], y1[3]]), up.tangent))
                                    })
                                }
                                (None, None) => Err(indentify_laws::LocalFailure {
                                    reason: "neither a law nor a material".into(),
                                    suggested_dt_factor: 0.5,
                                }),
                            };
                            match up {
                                Ok(x) => x,
                                Err(f) => {
                                    return Some(FiniteFailure::Local {
                                        qp: q,
                                        reason: f.reason,
                                        factor: f.suggested_dt_factor,
                                    });
                                }
                            }
                        }
                    };
                    let s = ls.pk2(&t);
                    Deformation::add_bt(&def.b_l(qp), &s, qp.w, fe);
                    sigma[local] = t;
                    tangents[local] = a;
                    points[local] = (def, ls);
                }
            }
            None
        })
        // the failure of the first element in order, as the serial loop would report it
        .min_by_key(FiniteFailure::qp);
    if let Some(f) = first_failure {
        return Err(f);
    }
    out.f_int.fill(0.0);
    for (e, fe) in fe_all.iter().enumerate() {
        for (d, v) in disc.element_dofs(e).iter().zip(fe) {
            out.f_int[*d] += v;
        }
    }
    Ok(())
}

/// The element tangents (lower triangles) from the deformations and Hencky strains
/// `points`, stresses `t` and laws' tangents `a` that [`evaluate`] left at one
/// displacement: per point `w0 (B_L^T (P A P + T:L) B_L + G(S))`, `S = P T`. Each element
/// writes its own matrix: in parallel over fixed chunks, bit for bit the serial result for
/// any number of threads.
pub(crate) fn element_tangents(
    disc: &Discretization,
    points: &[Point],
    t: &[Vec4],
    a: &[Mat4],
    ke: &mut [[[f64; 16]; 16]],
) {
    ke.par_chunks_mut(ELEMENT_CHUNK)
        .enumerate()
        .for_each(|(chunk, kes)| {
            for (i, ke) in kes.iter_mut().enumerate() {
                let e = chunk * ELEMENT_CHUNK + i;
                *ke = [[0.0; 16]; 16];
                for g in 0..QP_PER_ELEMENT {
                    let q = QP_PER_ELEMENT * e + g;
                    let qp = &disc.qp[q];
                    let (def, ls) = &points[q];
                    let dm = ls.material_tangent(&a[q], &t[q]);
                    def.add_tangent(qp, &dm, &ls.pk2(&t[q]), qp.w, ke);
                }
            }
        });
}

/// The Hencky strain of deformation `def` at Gauss point `q`.
///
/// # Errors
/// [`FiniteFailure::Inverted`] if `det F <= 0` (or `C` is not positive definite).
#[inline]
fn log_strain(def: &Deformation, q: usize) -> Result<LogStrain, FiniteFailure> {
    let det = def.det();
    (det > 0.0)
        .then(|| LogStrain::from_difference(&def.c_minus_one()))
        .flatten()
        .ok_or(FiniteFailure::Inverted { qp: q, det })
}

#[cfg(test)]
mod tests {
    use super::*;
    use indentify_laws::{Elastic, NortonHoff};
    use indentify_mesh::CylinderMesher;

    /// The assembled element tangents are the derivative of the internal force through the
    /// laws' local updates (Norton-Hoff from a stressed state, elasticity), at small and
    /// large deformations: central differences along a random direction.
    #[test]
    fn element_tangents_are_the_derivative_of_the_internal_force() {
        let mesh = CylinderMesher {
            radius: 1.0,
            height: 1.0,
            nr: 2,
            nz: 2,
            grading_r: 1.2,
            grading_z: 1.2,
        }
        .build()
        .unwrap();
        let disc = Discretization::new(&mesh);
        let (nq, ne, nd) = (disc.n_qp(), disc.elements.len(), disc.n_dofs());
        let cases: [(&dyn Law, Vec<f64>); 2] = [
            (&NortonHoff, vec![1e5, 0.3, 1500.0, 5.0, 0.0]),
            (&Elastic, vec![1e5, 0.3]),
        ];
        for amp in [1e-4, 0.2] {
            for (law, c) in &cases {
                let u0: Vec<f64> = (0..nd)
                    .map(|k| amp * 0.5 * (((k * 7 + 3) % 11) as f64 / 11.0 - 0.5))
                    .collect();
                let u1: Vec<f64> = u0
                    .iter()
                    .enumerate()
                    .map(|(k, v)| v + amp * 0.3 * (((k * 5 + 1) % 13) as f64 / 13.0 - 0.5))
                    .collect();
                let dir: Vec<f64> = (0..nd)
                    .map(|k| ((k * 3 + 2) % 7) as f64 / 7.0 - 0.5)
                    .collect();
                let mut e0 = vec![Vec4::ZERO; nq];
                log_strains(&disc, &u0, &mut e0).unwrap();
                // a stressed initial state
                let t0: Vec<Vec4> = e0.iter().map(|e| *e * 5e4).collect();
                let run = |u: &[f64]| {
                    let mut sigma = vec![Vec4::ZERO; nq];
                    let mut f = vec![0.0; nd];
                    let mut ke = vec![[[0.0; 16]; 16]; ne];
                    let mut a = vec![Mat4::ZERO; nq];
                    let mut points = vec![undeformed_point(&disc); nq];
                    let out = FiniteOut {
                        sigma: &mut sigma,
                        f_int: &mut f,
                        tangents: &mut a,
                        points: &mut points,
                        alpha: &mut [],
                        regime: &mut [],
                    };
                    let input = FiniteIn {
                        law: Some(*law),
                        material: None,
                        c,
                        dt: 0.1,
                        t0: &t0,
                        e0: &e0,
                        domain: None,
                    };
                    evaluate(&disc, &input, u, out).unwrap();
                    element_tangents(&disc, &points, &sigma, &a, &mut ke);
                    (f, ke)
                };
                let (_, ke) = run(&u1);
                let h = 1e-7 * amp.max(1e-2);
                let up: Vec<f64> = u1.iter().zip(&dir).map(|(a, d)| a + h * d).collect();
                let um: Vec<f64> = u1.iter().zip(&dir).map(|(a, d)| a - h * d).collect();
                let (fp, fm) = (run(&up).0, run(&um).0);
                let mut kd = vec![0.0; nd];
                for (e, k) in ke.iter().enumerate() {
                    let dofs = disc.element_dofs(e);
                    for p in 0..16 {
                        for q in 0..16 {
                            let v = if p >= q { k[p][q] } else { k[q][p] };
                            kd[dofs[p]] += v * dir[dofs[q]];
                        }
                    }
                }
                let scale = kd.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                for i in 0..nd {
                    let fd = (fp[i] - fm[i]) / (2.0 * h);
                    assert!(
                        (fd - kd[i]).abs() < 1e-6 * scale,
                        "{} amp {amp}: dof {i}: {fd} vs {}",
                        law.name(),
                        kd[i]
                    );
                }
            }
        }
    }
}
