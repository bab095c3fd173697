//! The body's piece of a Newton pass under the model's kinematics: the Gauss-point pass
//! (local updates, stresses, the internal force, the laws' tangents) and the tangent
//! matrix of a Newton solve, small strain or finite strain ([`Kinematics`]). The Newton
//! driver (`newton.rs`) calls [`Body::begin_step`] once per step, [`Body::evaluate`] once
//! per pass and [`Body::set_tangent`] before each solve; it never looks at the
//! kinematics itself.
//!
//! Small strain: affine laws (`sigma_1 = A sigma_0 + C deps`, [`Law::affine_update`]) are
//! updated in one product per point and assembled once per parameters and step length;
//! other laws update every point (those whose elastic trial stays below yield with one
//! 4x4 product, [`Law::elastic_domain`]) and re-assemble the elements whose tangents
//! changed. Finite strain (`kinematics.rs`): the laws on the Hencky strain, the element
//! tangents formed only for passes that solve.
//!
//! A [`Material`] with internal variables (no [`Material::as_law`]) is updated point by
//! point from `y_0 = [sigma_0, alpha_0]` (small strain); its internal variables live in
//! one flat vector beside the stresses ([`Internal`]).

use indentify_fe::QP_PER_ELEMENT;
use indentify_laws::{Law, Mat4, Material, Regime, Vec4};
use rayon::prelude::*;

use crate::kinematics::{self, ELEMENT_CHUNK, FiniteIn, FiniteOut, Kinematics};
use crate::model::Model;
use crate::newton::{State, StepFailure, finite_failure};
use crate::system::ConstrainedSystem;

/// A step's data for the Gauss-point passes: the law and its parameters, the step's
/// initial state, its length, and the affine form of the law's update when it has one
/// (small strain only).
pub(crate) struct StepLaw<'a> {
    /// The material.
    pub mat: &'a dyn Material,
    /// The stress-only law it adapts, if any (today's paths and bits).
    pub law: Option<&'a dyn Law>,
    /// Its parameters.
    pub c: &'a [f64],
    /// The converged state the step starts from.
    pub state: &'a State,
    /// Step length (s).
    pub dt: f64,
    /// `(A, C)` of `sigma_1 = A sigma_0 + C deps` (affine laws under small strain).
    pub affine: Option<(Mat4, Mat4)>,
}

/// One chunk of the small-strain Gauss-point pass: its index, and its elements' forces,
/// stresses and tangents.
type PassChunk<'a> = (
    usize,
    ((&'a mut [[f64; 16]], &'a mut [Vec4]), &'a mut [Mat4]),
);

/// The internal variables of every Gauss point of a state or an iterate: `alpha` flat,
/// point-major (`alpha[q * n .. (q + 1) * n]` at Gauss point `q`, `n` the material's
/// `n_internal`), and the branch of the residual each point's last update took. Both are
/// empty for a stress-only law.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Internal {
    /// Internal variables, point-major.
    pub(crate) alpha: Vec<f64>,
    /// Branch of the local residual at each Gauss point.
    pub(crate) regime: Vec<Regime>,
}

impl Internal {
    /// The initial internal state of `nq` points of `mat` (zero internal variables, the
    /// smooth branch), empty for a stress-only law.
    pub(crate) fn initial(mat: &dyn Material, nq: usize) -> Internal {
        if mat.as_law().is_some() {
            return Internal::default();
        }
        Internal {
            alpha: vec![0.0; nq * mat.n_internal()],
            regime: vec![Regime::default(); nq],
        }
    }
}

/// One chunk of the small-strain pass of a material with internal variables: its index,
/// its elements' forces, stresses, tangents, internal variables and branches.
type MaterialChunk<'a> = (
    usize,
    (
        (
            ((&'a mut [[f64; 16]], &'a mut [Vec4]), &'a mut [Mat4]),
            &'a mut [f64],
        ),
        &'a mut [Regime],
    ),
);

/// The buffers of the body's Gauss-point passes (allocated once per solver).
#[derive(Debug)]
pub(crate) struct Body {
    /// The laws' consistent tangents of the last evaluation (every Gauss point; under
    /// finite strain `dT/dE`, from which the element tangents are formed).
    pub(crate) tangents: Vec<Mat4>,
    /// The internal force of the last evaluation (all dofs, N).
    pub(crate) f_int: Vec<f64>,
    /// Finite strain: the element tangents of the last Newton solve, and the Hencky strains
    /// of the step's initial state (empty under small strain).
    finite_ke: Vec<[[f64; 16]; 16]>,
    finite_e0: Vec<Vec4>,
    /// Finite strain: each Gauss point's deformation and Hencky strain of the last
    /// evaluation, from which its element tangents are formed.
    finite_points: Vec<kinematics::Point>,
    /// Small strain: each element's internal force of the last evaluation (summed into
    /// `f_int` in element order).
    element_forces: Vec<[f64; 16]>,
}

/// What a Gauss-point pass leaves in the [`Body`] besides the iterate's stresses and
/// internal variables: the internal force, the laws' tangents and (finite strain) each
/// point's deformation. The line search keeps an evaluated iterate's aside by swapping
/// buffers ([`Body::swap_pass`]) and returns to it without evaluating it again
/// (`newton.rs`, `Newton::backtrack`).
#[derive(Debug, Default)]
pub(crate) struct PassOutputs {
    f_int: Vec<f64>,
    tangents: Vec<Mat4>,
    finite_points: Vec<kinematics::Point>,
}

impl Body {
    /// Exchanges the last pass's outputs with `kept` (no copy once `kept` has the
    /// body's sizes: the first call sizes it). A pass overwrites every entry it leaves
    /// (the internal force, the tangent of every point of a non-affine law, every
    /// finite-strain point), so the buffers swapped in need no clearing.
    pub(crate) fn swap_pass(&mut self, kept: &mut PassOutputs) {
        if kept.f_int.len() != self.f_int.len() {
            kept.f_int.clone_from(&self.f_int);
        }
        if kept.tangents.len() != self.tangents.len() {
            kept.tangents.clone_from(&self.tangents);
        }
        if kept.finite_points.len() != self.finite_points.len() {
            kept.finite_points.clone_from(&self.finite_points);
        }
        std::mem::swap(&mut self.f_int, &mut kept.f_int);
        std::mem::swap(&mut self.tangents, &mut kept.tangents);
        std::mem::swap(&mut self.finite_points, &mut kept.finite_points);
    }

    /// Buffers for `model`.
    pub(crate) fn new(model: &Model) -> Body {
        Body {
            tangents: vec![Mat4::ZERO; model.disc.n_qp()],
            f_int: vec![0.0; model.disc.n_dofs()],
            finite_ke: Vec::new(),
            finite_e0: Vec::new(),
            finite_points: Vec::new(),
            element_forces: Vec::new(),
        }
    }

    /// The start of a step from `state`: under finite strain the Hencky strains of the
    /// initial state, from which the laws' increments run. Returns the affine form of the
    /// law's update for the step (small strain only: under finite strain the tangent
    /// depends on the displacement).
    ///
    /// # Errors
    /// [`StepFailure::Inverted`] if the initial state has an inverted element.
    pub(crate) fn begin_step(
        &mut self,
        model: &Model,
        law: Option<&dyn Law>,
        c: &[f64],
        state: &State,
        dt: f64,
    ) -> Result<Option<(Mat4, Mat4)>, StepFailure> {
        if model.kinematics != Kinematics::Finite {
            return Ok(law.and_then(|l| l.affine_update(c, dt)));
        }
        let (nq, ne) = (model.disc.n_qp(), model.disc.elements.len());
        self.finite_e0.resize(nq, Vec4::ZERO);
        self.finite_ke.resize(ne, [[0.0; 16]; 16]);
        if self.finite_points.len() != nq {
            self.finite_points = vec![kinematics::undeformed_point(&model.disc); nq];
        }
        kinematics::log_strains(&model.disc, &state.u, &mut self.finite_e0)
            .map_err(|f| finite_failure(f, state.depth))?;
        Ok(None)
    }

    /// Local updates at every Gauss point for displacement `u` from the step's initial
    /// state; fills `sigma_out` and `self.f_int`, and `self.tangents` unless the law is
    /// affine (`sigma_1 = A sigma_0 + C deps` everywhere: its one tangent is `C`). With an
    /// affine law and `u` the state's own displacement (a step's first pass) the strain
    /// increments vanish and `sigma_1 = A sigma_0`; with `A = I` besides (elasticity) the
    /// internal force is the state's own and nothing is computed.
    ///
    /// # Errors
    /// The first failed local update ([`StepFailure::Local`]) or, under finite strain,
    /// inverted element.
    pub(crate) fn evaluate(
        &mut self,
        model: &Model,
        step: &StepLaw<'_>,
        u: &[f64],
        sigma_out: &mut [Vec4],
        internal_out: &mut Internal,
    ) -> Result<(), StepFailure> {
        let (c, state, dt) = (step.c, step.state, step.dt);
        let disc = &model.disc;
        if model.kinematics == Kinematics::Finite {
            let domain = step.law.and_then(|law| law.elastic_domain(c, dt));
            let input = FiniteIn {
                law: step.law,
                material: step
                    .law
                    .is_none()
                    .then_some((step.mat, state.internal.alpha.as_slice())),
                c,
                dt,
                t0: &state.sigma,
                e0: &self.finite_e0,
                domain: domain.as_ref(),
            };
            let out = FiniteOut {
                sigma: sigma_out,
                f_int: &mut self.f_int,
                tangents: &mut self.tangents,
                points: &mut self.finite_points,
                alpha: &mut internal_out.alpha,
                regime: &mut internal_out.regime,
            };
            return kinematics::evaluate(disc, &input, u, out)
                .map_err(|f| finite_failure(f, state.depth));
        }
        let Some(law) = step.law else {
            return self.evaluate_material(model, step, u, sigma_out, internal_out);
        };
        let affine = step.affine.as_ref();
        // (only affine laws use it: a nonlinear law's iterate is never compared)
        let at_start = affine.is_some() && u == state.u.as_slice();
        if at_start && affine.is_some_and(|(a, _)| *a == Mat4::IDENTITY) {
            self.f_int.copy_from_slice(&state.f_int);
            sigma_out.copy_from_slice(&state.sigma);
            return Ok(());
        }
        // one pass: strains, local updates and each element's internal force while the
        // stresses are hot, on rayon over fixed chunks of elements (each point's update is
        // independent); points whose elastic trial stays below yield skip the law's update.
        // The element forces are then summed serially in element order, as a serial pass
        // would: the result is the same bits for any number of threads.
        let domain = law.elastic_domain(c, dt);
        let ne = disc.elements.len();
        let nq = QP_PER_ELEMENT * ne;
        self.element_forces.resize(ne, [0.0; 16]);
        let chunk_qp = QP_PER_ELEMENT * ELEMENT_CHUNK;
        let tangents = &mut self.tangents[..nq];
        let work = |(chunk, ((fes, sig), tan)): PassChunk<'_>| {
            for (i, fe) in fes.iter_mut().enumerate() {
                let e = chunk * ELEMENT_CHUNK + i;
                let dofs = disc.element_dofs(e);
                let due: [f64; 16] = std::array::from_fn(|k| u[dofs[k]] - state.u[dofs[k]]);
                *fe = [0.0; 16];
                for g in 0..QP_PER_ELEMENT {
                    let q = QP_PER_ELEMENT * e + g;
                    let l = QP_PER_ELEMENT * i + g;
                    let qp = &disc.qp[q];
                    if let Some((a, cm)) = affine {
                        let mut s = a.mul_vec(&state.sigma[q]);
                        if !at_start {
                            s += cm.mul_vec(&Vec4(qp.strain(&due)));
                        }
                        qp.add_bt(&s.0, qp.w, fe);
                        sig[l] = s;
                        continue;
                    }
                    let deps = Vec4(qp.strain(&due));
                    if let Some(dom) = &domain {
                        if let Some(s1) = dom.update(&state.sigma[q], &deps) {
                            qp.add_bt(&s1.0, qp.w, fe);
                            sig[l] = s1;
                            tan[l] = dom.stiffness;
                            continue;
                        }
                    }
                    match law.update(c, &state.sigma[q], &deps, dt) {
                        Ok(up) => {
                            qp.add_bt(&up.sigma.0, qp.w, fe);
                            sig[l] = up.sigma;
                            tan[l] = up.tangent;
                        }
                        Err(f) => {
                            return Some(StepFailure::Local {
                                qp: q,
                                reason: f.reason,
                                factor: f.suggested_dt_factor,
                            });
                        }
                    }
                }
            }
            None
        };
        // on one thread, in place (handing a pass to a pool of one costs more than it does)
        let failure = if rayon::current_num_threads() > 1 {
            self.element_forces
                .par_chunks_mut(ELEMENT_CHUNK)
                .zip(sigma_out[..nq].par_chunks_mut(chunk_qp))
                .zip(tangents.par_chunks_mut(chunk_qp))
                .enumerate()
                .find_map_first(work)
        } else {
            self.element_forces
                .chunks_mut(ELEMENT_CHUNK)
                .zip(sigma_out[..nq].chunks_mut(chunk_qp))
                .zip(tangents.chunks_mut(chunk_qp))
                .enumerate()
                .find_map(work)
        };
        if let Some(f) = failure {
            return Err(f);
        }
        self.f_int.fill(0.0);
        for (e, fe) in self.element_forces.iter().enumerate() {
            for (d, v) in disc.element_dofs(e).iter().zip(fe) {
                self.f_int[*d] += v;
            }
        }
        Ok(())
    }

    /// [`Body::evaluate`] for a material with internal variables (small strain): at every
    /// Gauss point the update from `y_0 = [sigma_0, alpha_0]` of the step's state under
    /// the point's strain increment writes `sigma_1`, `alpha_1`, the consistent tangent
    /// and the branch taken; the same fixed chunks of elements as the law's pass, the
    /// element forces summed in element order (the same bits for any thread count). The
    /// state vectors `y_0, y_1` are one scratch per chunk (on the stack up to 32 entries
    /// each): nothing is allocated per Gauss point.
    ///
    /// # Errors
    /// The first failed local update, or an update whose state is not finite
    /// ([`StepFailure::Local`], naming the Gauss point).
    fn evaluate_material(
        &mut self,
        model: &Model,
        step: &StepLaw<'_>,
        u: &[f64],
        sigma_out: &mut [Vec4],
        internal_out: &mut Internal,
    ) -> Result<(), StepFailure> {
        let (mat, c, state, dt) = (step.mat, step.c, step.state, step.dt);
        let disc = &model.disc;
        let n = mat.n_internal();
        let m = 4 + n;
        let ne = disc.elements.len();
        let nq = QP_PER_ELEMENT * ne;
        self.element_forces.resize(ne, [0.0; 16]);
        let chunk_qp = QP_PER_ELEMENT * ELEMENT_CHUNK;
        let n_chunks = ne.div_ceil(ELEMENT_CHUNK);
        let alpha0 = &state.internal.alpha;
        let Internal { alpha, regime } = internal_out;
        let mut alpha_chunks: Vec<&mut [f64]> = if n > 0 {
            alpha[..nq * n].chunks_mut(chunk_qp * n).collect()
        } else {
            (0..n_chunks).map(|_| &mut [][..]).collect()
        };
        let tangents = &mut self.tangents[..nq];
        let work = |(chunk, ((((fes, sig), tan), al), reg)): MaterialChunk<'_>| {
            let mut stack = [0.0f64; 64];
            let mut heap = Vec::new();
            let buf: &mut [f64] = if 2 * m <= stack.len() {
                &mut stack[..2 * m]
            } else {
                heap.resize(2 * m, 0.0);
                &mut heap
            };
            let (y0, y1) = buf.split_at_mut(m);
            for (i, fe) in fes.iter_mut().enumerate() {
                let e = chunk * ELEMENT_CHUNK + i;
                let dofs = disc.element_dofs(e);
                let due: [f64; 16] = std::array::from_fn(|k| u[dofs[k]] - state.u[dofs[k]]);
                *fe = [0.0; 16];
                for g in 0..QP_PER_ELEMENT {
                    let q = QP_PER_ELEMENT * e + g;
                    let l = QP_PER_ELEMENT * i + g;
                    let qp = &disc.qp[q];
                    let deps = Vec4(qp.strain(&due));
                    y0[..4].copy_from_slice(&state.sigma[q].0);
                    y0[4..].copy_from_slice(&alpha0[q * n..(q + 1) * n]);
                    let failure = |reason: String, factor: f64| StepFailure::Local {
                        qp: q,
                        reason,
                        factor,
                    };
                    match mat.update(c, y0, &deps, dt, y1) {
                        Ok(up) => {
                            if y1.iter().any(|v| !v.is_finite()) {
                                return Some(failure(
                                    format!("{}: non-finite state after the update", mat.name()),
                                    0.5,
                                ));
                            }
                            let s1 = Vec4([y1[0], y1[1], y1[2], y1[3]]);
                            qp.add_bt(&s1.0, qp.w, fe);
                            sig[l] = s1;
                            tan[l] = up.tangent;
                            al[l * n..(l + 1) * n].copy_from_slice(&y1[4..]);
                            reg[l] = up.regime;
                        }
                        Err(f) => return Some(failure(f.reason, f.suggested_dt_factor)),
                    }
                }
            }
            None
        };
        let failure = if rayon::current_num_threads() > 1 {
            self.element_forces
                .par_chunks_mut(ELEMENT_CHUNK)
                .zip(sigma_out[..nq].par_chunks_mut(chunk_qp))
                .zip(tangents.par_chunks_mut(chunk_qp))
                .zip(alpha_chunks.par_iter_mut().map(|a| &mut **a))
                .zip(regime[..nq].par_chunks_mut(chunk_qp))
                .enumerate()
                .find_map_first(work)
        } else {
            self.element_forces
                .chunks_mut(ELEMENT_CHUNK)
                .zip(sigma_out[..nq].chunks_mut(chunk_qp))
                .zip(tangents.chunks_mut(chunk_qp))
                .zip(alpha_chunks.iter_mut().map(|a| &mut **a))
                .zip(regime[..nq].chunks_mut(chunk_qp))
                .enumerate()
                .find_map(work)
        };
        if let Some(f) = failure {
            return Err(f);
        }
        self.f_int.fill(0.0);
        for (e, fe) in self.element_forces.iter().enumerate() {
            for (d, v) in disc.element_dofs(e).iter().zip(fe) {
                self.f_int[*d] += v;
            }
        }
        Ok(())
    }

    /// Sets the tangent of the last evaluation (at the stresses `sigma` it gave) in
    /// `system` for a Newton solve: an affine law's one tangent (reused while the
    /// parameters and the step length are), the element tangents under finite strain
    /// (formed only now that a solve needs them), or the laws' Gauss-point tangents
    /// (reused by a linear law). Returns the seconds spent forming element tangents (a
    /// part of the local work).
    pub(crate) fn set_tangent(
        &mut self,
        model: &Model,
        step: &StepLaw<'_>,
        sigma: &[Vec4],
        system: &mut ConstrainedSystem,
    ) -> f64 {
        let (c, dt) = (step.c, step.dt);
        match &step.affine {
            Some((_, cm)) => {
                system.set_tangent_uniform(model, cm, (c, dt));
                0.0
            }
            None if model.kinematics == Kinematics::Finite => {
                let tl = std::time::Instant::now();
                // (from the deformations and Hencky strains the evaluation of this
                // iterate kept: the same `u`)
                kinematics::element_tangents(
                    &model.disc,
                    &self.finite_points,
                    sigma,
                    &self.tangents,
                    &mut self.finite_ke,
                );
                let seconds = tl.elapsed().as_secs_f64();
                system.set_tangent_elements(model, &self.finite_ke);
                seconds
            }
            None => {
                let reuse = step.mat.is_linear().then_some((c, dt));
                system.set_tangent(model, &self.tangents, reuse);
                0.0
            }
        }
    }
}
