//! The material point with internal variables: the [`Material`] trait (local residual in
//! `y = (sigma, alpha)`, its Jacobian blocks, the consistent tangent, parameter
//! derivatives) and [`LawMaterial`], which makes every stress-only [`Law`] a material
//! with no internal variables and the same bits.
//!
//! The adjoint recursion these blocks serve is docs/theory.md §12.

use crate::LawError;
use crate::law::{Law, LocalFailure, ParamInfo};
use crate::mandel::{Mat4, Vec4};

/// Metadata of one internal variable: name, unit and what it is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InternalInfo {
    /// Short name, e.g. `p` or `ev1_zz`.
    pub name: &'static str,
    /// Unit in the internal system (`-` for strains, MPa for stresses).
    pub unit: &'static str,
    /// One-line description.
    pub description: &'static str,
}

/// Which branch of a piecewise local residual the converged update took.
///
/// Rate-independent plasticity has two residuals, an elastic one (`Delta p = 0`) and a
/// plastic one (the consistency condition `s_eq = sigma_y(p)`). The adjoint and the
/// sensitivities hold the converged partition as the contact active set is held
/// (docs/theory.md §12): where a parameter change flips a point from one branch to the
/// other the cost is continuous but its derivative jumps.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Regime {
    /// One smooth residual everywhere (elasticity, viscous laws, overstress plasticity).
    #[default]
    Smooth,
    /// Rate-independent law, elastic branch of the residual.
    Elastic,
    /// Rate-independent law, plastic branch of the residual.
    Plastic,
}

/// Converged result of a [`Material::update`]; the end-of-step state is written into
/// the caller's slice.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MaterialUpdate {
    /// Consistent tangent `d sigma_1 / d deps` (MPa), `-(A^-1 E)` restricted to the stress
    /// rows and columns.
    pub tangent: Mat4,
    /// Local iterations used (0 for closed forms).
    pub iterations: u32,
    /// The branch of the residual the converged state satisfies.
    pub regime: Regime,
}

/// Everything a block needs about one converged step at one material point: the
/// previous and end states `y = [sigma (4 Mandel components), alpha (n)]`, the strain
/// increment, the step and the branch of the residual.
#[derive(Clone, Copy, Debug)]
pub struct Step<'a> {
    /// State at the start of the step, length `4 + n_internal`.
    pub y0: &'a [f64],
    /// State at the end of the step, length `4 + n_internal`.
    pub y1: &'a [f64],
    /// Strain increment (Mandel).
    pub deps: &'a Vec4,
    /// Time step (s).
    pub dt: f64,
    /// Branch of the residual (held).
    pub regime: Regime,
}

/// The stress part of a state `y` (its first four entries).
#[inline]
pub fn stress_of(y: &[f64]) -> Vec4 {
    Vec4([y[0], y[1], y[2], y[3]])
}

/// A material point with internal variables `alpha` (paper §2.1 generalized): the state
/// is `y = [sigma, alpha]` (`m = 4 + n_internal` numbers), one implicit step solves the
/// local residual
///
/// `R(y_1; y_0, deps, c, dt) = 0`,   `R` in `R^m`,
///
/// whose first four rows carry the strain increment as `... - deps` (strain units) and
/// whose remaining rows are the evolution of `alpha`. The blocks are dense, row-major:
///
/// | block | shape | meaning |
/// |---|---|---|
/// | [`Material::jac_state`] `A` | `m x m` | `dR/dy_1` |
/// | [`Material::jac_previous`] `D` | `m x m` | `dR/dy_0` |
/// | [`Material::jac_strain`] `E` | `m x 4` | `dR/d deps` (`-[I; 0]` for every law here) |
/// | [`Material::jac_params`] `P` | `m x n_c` | `dR/dc` |
///
/// The consistent tangent is `C = -[A^-1 E]` restricted to the stress rows; the update
/// returns it (in closed form where the law has one; `testing` checks it against the
/// blocks and against finite differences of the update). Parameters are an input of
/// every method, never state; structure that is not identified (the hardening form, the
/// number of Prony terms, a fixed table) lives in the value.
pub trait Material: Send + Sync + std::fmt::Debug {
    /// Name used in configurations (`plastic`, `prony`, `norton-hoff`, ...).
    fn name(&self) -> &'static str;

    /// Parameter metadata, in the order of the slice `c`.
    fn params(&self) -> &[ParamInfo];

    /// Internal variables, in the order of `alpha = y[4..]`.
    fn internal(&self) -> &[InternalInfo];

    /// `n_internal`, the length of `alpha`.
    fn n_internal(&self) -> usize {
        self.internal().len()
    }

    /// `m = 4 + n_internal`, the length of the state `y`.
    fn state_len(&self) -> usize {
        4 + self.n_internal()
    }

    /// Checks every parameter against its admissible range.
    ///
    /// # Errors
    /// [`LawError::Parameter`] naming the first offending parameter, its value and range.
    fn check_params(&self, c: &[f64]) -> Result<(), LawError> {
        check_param_ranges(self.name(), self.params(), c)
    }

    /// Whether the discrete cost is differentiable in every parameter at `c` (with the
    /// regime held).
    ///
    /// # Errors
    /// [`LawError::NotDifferentiable`] naming the parameter and why.
    fn check_differentiable(&self, _c: &[f64]) -> Result<(), LawError> {
        Ok(())
    }

    /// `true` when the tangent and the blocks depend on `(c, dt)` only.
    fn is_linear(&self) -> bool {
        false
    }

    /// The stress-only [`Law`] this material adapts ([`LawMaterial`]), `None` for a law with
    /// internal variables: a solver keeps the `Law` fast paths (`affine_update`,
    /// `elastic_domain`, the adjoint of docs/theory.md §3) and their bits for these.
    fn as_law(&self) -> Option<&dyn Law> {
        None
    }

    /// The local residual `R` of the branch `step.regime`, into `r` (length `m`).
    fn residual(&self, c: &[f64], step: &Step<'_>, r: &mut [f64]);

    /// `A = dR/dy_1` (`m x m`, row-major) into `out`.
    fn jac_state(&self, c: &[f64], step: &Step<'_>, out: &mut [f64]);

    /// `D = dR/dy_0` (`m x m`, row-major) into `out`.
    fn jac_previous(&self, c: &[f64], step: &Step<'_>, out: &mut [f64]);

    /// `E = dR/d deps` (`m x 4`, row-major) into `out`; the default is `-[I; 0]`, the
    /// form of every law whose first rows are `... - deps`.
    fn jac_strain(&self, _c: &[f64], _step: &Step<'_>, out: &mut [f64]) {
        out.fill(0.0);
        for i in 0..4 {
            out[i * 4 + i] = -1.0;
        }
    }

    /// `P = dR/dc` (`m x n_c`, row-major) into `out`.
    fn jac_params(&self, c: &[f64], step: &Step<'_>, out: &mut [f64]);

    /// Every block of one step at once: `A` into `a` (`m x m`), `D` into `d` (`m x m`),
    /// `E` into `e` (`m x 4`) and `P` into `p` (`m x n_c`), what an adjoint sweep (and a
    /// sensitivity step) asks of a nonlinear material at every Gauss point and step. The
    /// default calls [`Material::jac_state`], [`Material::jac_previous`],
    /// [`Material::jac_strain`] and [`Material::jac_params`]; a law whose blocks share
    /// work (J2's `s_eq` and normal, the hardening curve, the Norton rate) overrides it and
    /// does that work once per point (`Plastic`). `testing::check_material` checks it
    /// against the four.
    fn jac_blocks(
        &self,
        c: &[f64],
        step: &Step<'_>,
        a: &mut [f64],
        d: &mut [f64],
        e: &mut [f64],
        p: &mut [f64],
    ) {
        self.jac_state(c, step, a);
        self.jac_previous(c, step, d);
        self.jac_strain(c, step, e);
        self.jac_params(c, step, p);
    }

    /// Solves `A^T X = B` in place for `nrhs` right-hand sides (`b` is `m x nrhs`,
    /// row-major, and becomes `X`), `a` the step's `A` as [`Material::jac_state`] (or
    /// [`Material::jac_blocks`]) wrote it: what an adjoint sweep does at every Gauss point
    /// and step. The default transposes `a` into `work` (length `m x m`) and eliminates
    /// ([`dense_solve_many`]); a law whose `A` has a structure solves in closed form
    /// (`Plastic`: an isotropic operator plus `n (x) n` and a bordered row, so one Schur
    /// complement). `false` when `A` is singular. `testing::check_material` checks it
    /// against the elimination.
    fn solve_state_transpose(
        &self,
        _c: &[f64],
        _step: &Step<'_>,
        a: &[f64],
        b: &mut [f64],
        nrhs: usize,
        work: &mut [f64],
    ) -> bool {
        let m = self.state_len();
        for r in 0..m {
            for k in 0..m {
                work[k * m + r] = a[r * m + k];
            }
        }
        dense_solve_many(work, m, b, nrhs)
    }

    /// `out[k] += weight * sum_r mu[r] P[r][k]`: the parameter block transposed applied
    /// to a cotangent `mu` (length `m`), what an adjoint sweep asks of `P` at every Gauss
    /// point and step (`dJ/dc -= w mu^T P`). The default forms `P` with
    /// [`Material::jac_params`] in `scratch` (length `m x n_c`) and contracts it; a law
    /// with a closed form overrides it and forms no block (`Prony`).
    /// `testing::check_material` checks it against `P`.
    fn jac_params_transpose(
        &self,
        c: &[f64],
        step: &Step<'_>,
        mu: &[f64],
        weight: f64,
        scratch: &mut [f64],
        out: &mut [f64],
    ) {
        let nc = c.len();
        self.jac_params(c, step, scratch);
        for (k, o) in out[..nc].iter_mut().enumerate() {
            *o += weight
                * mu.iter()
                    .enumerate()
                    .map(|(r, m)| m * scratch[r * nc + k])
                    .sum::<f64>();
        }
    }

    /// The implicit update from `y0` under `deps` over `dt`: writes `y1` (length `m`) and
    /// returns the consistent tangent and the branch taken.
    ///
    /// # Errors
    /// [`LocalFailure`] with a suggested step factor when the local problem cannot be
    /// solved (never a NaN in `y1` on success).
    fn update(
        &self,
        c: &[f64],
        y0: &[f64],
        deps: &Vec4,
        dt: f64,
        y1: &mut [f64],
    ) -> Result<MaterialUpdate, LocalFailure>;
}

/// The range check shared by [`Law::check_params`] and [`Material::check_params`].
///
/// # Errors
/// [`LawError::ParameterCount`] or [`LawError::Parameter`].
pub fn check_param_ranges(
    law: &'static str,
    infos: &[ParamInfo],
    c: &[f64],
) -> Result<(), LawError> {
    if c.len() != infos.len() {
        return Err(LawError::ParameterCount {
            law,
            expected: infos.len(),
            got: c.len(),
        });
    }
    for (info, &v) in infos.iter().zip(c) {
        if !info.admits(v) {
            return Err(LawError::Parameter {
                law,
                name: info.name,
                value: v,
                range: info.range_text(),
            });
        }
    }
    Ok(())
}

/// A stress-only [`Law`] as a [`Material`] with no internal variables: `y = sigma`,
/// `R = S (sigma_1 - sigma_0) + dt g(sigma_1) - deps`, `A = S + dt H`, `D = -S`,
/// `E = -I`, `P = dr/dc` ([`Law::residual_param_derivative`]); the update is the law's,
/// so the stress and tangent are the same bits.
#[derive(Clone, Copy, Debug)]
pub struct LawMaterial<'a>(pub &'a dyn Law);

impl Material for LawMaterial<'_> {
    fn name(&self) -> &'static str {
        self.0.name()
    }
    fn as_law(&self) -> Option<&dyn Law> {
        Some(self.0)
    }
    fn params(&self) -> &[ParamInfo] {
        self.0.params()
    }
    fn internal(&self) -> &[InternalInfo] {
        &[]
    }
    fn check_params(&self, c: &[f64]) -> Result<(), LawError> {
        self.0.check_params(c)
    }
    fn check_differentiable(&self, c: &[f64]) -> Result<(), LawError> {
        self.0.check_differentiable(c)
    }
    fn is_linear(&self) -> bool {
        self.0.is_linear()
    }
    fn residual(&self, c: &[f64], step: &Step<'_>, r: &mut [f64]) {
        let (s0, s1) = (stress_of(step.y0), stress_of(step.y1));
        let v =
            self.0.compliance(c).mul_vec(&(s1 - s0)) + self.0.flow(c, &s1) * step.dt - *step.deps;
        r[..4].copy_from_slice(&v.0);
    }
    fn jac_state(&self, c: &[f64], step: &Step<'_>, out: &mut [f64]) {
        let s1 = stress_of(step.y1);
        let a = self.0.compliance(c) + self.0.flow_hessian(c, &s1) * step.dt;
        out[..16].copy_from_slice(a.0.as_flattened());
    }
    fn jac_previous(&self, c: &[f64], _step: &Step<'_>, out: &mut [f64]) {
        let d = self.0.compliance(c) * -1.0;
        out[..16].copy_from_slice(d.0.as_flattened());
    }
    fn jac_params(&self, c: &[f64], step: &Step<'_>, out: &mut [f64]) {
        let (s0, s1) = (stress_of(step.y0), stress_of(step.y1));
        let n = c.len();
        for k in 0..n {
            let col = self.0.residual_param_derivative(c, &s0, &s1, step.dt, k);
            for i in 0..4 {
                out[i * n + k] = col[i];
            }
        }
    }
    fn update(
        &self,
        c: &[f64],
        y0: &[f64],
        deps: &Vec4,
        dt: f64,
        y1: &mut [f64],
    ) -> Result<MaterialUpdate, LocalFailure> {
        let up = self.0.update(c, &stress_of(y0), deps, dt)?;
        y1[..4].copy_from_slice(&up.sigma.0);
        Ok(MaterialUpdate {
            tangent: up.tangent,
            iterations: up.iterations,
            regime: Regime::Smooth,
        })
    }
}

/// A generic update for a law that writes only its residual and blocks: Newton on
/// `R(y_1) = 0` from `y_1 = y_0` with `A = dR/dy_1`, converged when every row of the
/// residual is below 1e-12 of the size of its terms (`sum_j |A_ij y_1j|` plus the
/// strain increment), the tangent `-[A^-1 E]` from the blocks; `regime` is the branch the
/// residual is evaluated in (`Smooth` for one smooth residual). Allocates (a few vectors
/// of `m` and `m^2`): meant for prototypes and for laws whose residual is smooth, not for
/// the production laws of this crate, which write closed forms or scalar return maps.
///
/// # Errors
/// [`LocalFailure`] on a singular `A`, a non-finite iterate, or after 50 iterations.
pub fn newton_update(
    mat: &dyn Material,
    c: &[f64],
    y0: &[f64],
    deps: &Vec4,
    dt: f64,
    regime: Regime,
    y1: &mut [f64],
) -> Result<MaterialUpdate, LocalFailure> {
    let m = mat.state_len();
    let fail = |reason: String| LocalFailure {
        reason: format!("{}: {reason}", mat.name()),
        suggested_dt_factor: 0.5,
    };
    if !dt.is_finite() || dt < 0.0 || !deps.is_finite() || y0[..m].iter().any(|v| !v.is_finite()) {
        return Err(fail(format!("invalid input dt = {dt}, deps = {deps:?}")));
    }
    y1[..m].copy_from_slice(&y0[..m]);
    let (mut r, mut a) = (vec![0.0; m], vec![0.0; m * m]);
    for it in 0..50u32 {
        let step = Step {
            y0,
            y1,
            deps,
            dt,
            regime,
        };
        mat.residual(c, &step, &mut r);
        mat.jac_state(c, &step, &mut a);
        let converged = (0..m).all(|i| {
            let terms: f64 = (0..m).map(|j| (a[i * m + j] * y1[j]).abs()).sum::<f64>()
                + if i < 4 { deps.max_abs() } else { 0.0 };
            r[i].abs() <= 1e-12 * terms.max(1e-300)
        });
        if converged {
            let tangent = tangent_from_blocks(mat, c, &step)?;
            return Ok(MaterialUpdate {
                tangent,
                iterations: it,
                regime,
            });
        }
        if !dense_solve(&mut a, m, &mut r) {
            return Err(fail(format!("singular local Jacobian at iteration {it}")));
        }
        for (y, d) in y1.iter_mut().zip(&r) {
            *y -= d;
        }
        if y1[..m].iter().any(|v| !v.is_finite()) {
            return Err(fail(format!("non-finite state at iteration {it}")));
        }
    }
    Err(fail(
        "local Newton did not converge in 50 iterations".into(),
    ))
}

/// Solves the dense `m x m` system `a x = b` in place (`b` becomes `x`) by Gaussian
/// elimination with partial pivoting; `a` is overwritten. `false` when a pivot is below
/// `1e-14` of the largest entry or not finite. No allocation.
pub fn dense_solve(a: &mut [f64], m: usize, b: &mut [f64]) -> bool {
    dense_solve_many(a, m, b, 1)
}

/// [`dense_solve`] for `nrhs` right-hand sides at once: `b` is `m x nrhs`, row-major, and
/// becomes `X` with `a X = b`. One elimination serves every column (each column gets the
/// same operations, so the same bits, as [`dense_solve`] of that column alone). No
/// allocation.
pub fn dense_solve_many(a: &mut [f64], m: usize, b: &mut [f64], nrhs: usize) -> bool {
    let big = a[..m * m].iter().fold(0.0f64, |s, v| s.max(v.abs()));
    let tiny = 1e-14 * big;
    for col in 0..m {
        let mut piv = col;
        for row in col + 1..m {
            if a[row * m + col].abs() > a[piv * m + col].abs() {
                piv = row;
            }
        }
        let p = a[piv * m + col];
        if !p.is_finite() || p.abs() <= tiny {
            return false;
        }
        if piv != col {
            for k in 0..m {
                a.swap(col * m + k, piv * m + k);
            }
            for k in 0..nrhs {
                b.swap(col * nrhs + k, piv * nrhs + k);
            }
        }
        for row in col + 1..m {
            let f = a[row * m + col] / a[col * m + col];
            if f != 0.0 {
                for k in col..m {
                    a[row * m + k] -= f * a[col * m + k];
                }
                for k in 0..nrhs {
                    b[row * nrhs + k] -= f * b[col * nrhs + k];
                }
            }
        }
    }
    for row in (0..m).rev() {
        for r in 0..nrhs {
            let mut s = b[row * nrhs + r];
            for k in row + 1..m {
                s -= a[row * m + k] * b[k * nrhs + r];
            }
            b[row * nrhs + r] = s / a[row * m + row];
        }
    }
    true
}

/// The consistent tangent from the blocks, `C = -[A^-1 E]` on the stress rows
/// (allocates: a checking tool, not for hot loops).
///
/// # Errors
/// [`LocalFailure`] when `A` is singular.
pub fn tangent_from_blocks(
    mat: &dyn Material,
    c: &[f64],
    step: &Step<'_>,
) -> Result<Mat4, LocalFailure> {
    let m = mat.state_len();
    let mut a = vec![0.0; m * m];
    let mut e = vec![0.0; m * 4];
    mat.jac_state(c, step, &mut a);
    mat.jac_strain(c, step, &mut e);
    let mut t = Mat4::ZERO;
    let mut work = vec![0.0; m * m];
    for j in 0..4 {
        work.copy_from_slice(&a);
        let mut col: Vec<f64> = (0..m).map(|i| -e[i * 4 + j]).collect();
        if !dense_solve(&mut work, m, &mut col) {
            return Err(LocalFailure {
                reason: format!("{}: singular local Jacobian dR/dy", mat.name()),
                suggested_dt_factor: 0.5,
            });
        }
        for i in 0..4 {
            t.0[i][j] = col[i];
        }
    }
    Ok(t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Elastic, Maxwell, NortonHoff};

    fn cases() -> Vec<(&'static dyn Law, Vec<f64>)> {
        vec![
            (&Elastic, vec![2e5, 0.3]),
            (&Maxwell, vec![3e3, 0.35, 2e4]),
            (&NortonHoff, vec![1e5, 0.3, 1500.0, 5.0, 500.0]),
            (&NortonHoff, vec![1e5, 0.3, 1500.0, 1.0, 0.0]),
        ]
    }

    /// The system shall make every existing law a material with no internal variables
    /// whose update gives the same bits as the law's own (stress and tangent), over a
    /// path through elastic, yielding and unloading steps.
    #[test]
    fn law_material_updates_are_bit_identical_to_the_law() {
        for (law, c) in cases() {
            let mat = LawMaterial(law);
            assert_eq!(mat.n_internal(), 0);
            assert_eq!(mat.state_len(), 4);
            assert_eq!(mat.name(), law.name());
            assert!(mat.as_law().is_some());
            let mut s = Vec4::ZERO;
            let mut y = [0.0; 4];
            for i in 0..40 {
                let a = if i < 25 { 1.0 } else { -1.5 };
                let deps = Vec4([-0.3e-3, 1e-3, -0.3e-3, 0.2e-3]) * a;
                let dt = 0.01 * (1 + i % 3) as f64;
                let up = law.update(&c, &s, &deps, dt).unwrap();
                let mut y1 = [0.0; 4];
                let mu = mat.update(&c, &y, &deps, dt, &mut y1).unwrap();
                for k in 0..4 {
                    assert_eq!(y1[k].to_bits(), up.sigma[k].to_bits(), "{}", law.name());
                }
                assert_eq!(mu.tangent, up.tangent);
                assert_eq!(mu.iterations, up.iterations);
                assert_eq!(mu.regime, Regime::Smooth);
                s = up.sigma;
                y = y1;
            }
        }
    }

    /// The blocks of the adapter are the law's own: `A = S + dt H`, `D = -S`, `E = -I`,
    /// `P` the residual's parameter derivatives, and `-A^-1 E` its tangent.
    #[test]
    fn law_material_blocks_are_the_laws_derivatives() {
        for (law, c) in cases() {
            let mat = LawMaterial(law);
            let s0 = Vec4([10.0, 800.0, -20.0, 100.0]);
            let deps = Vec4([-1e-3, 4e-3, -1e-3, 1e-3]);
            let dt = 0.1;
            let up = law.update(&c, &s0, &deps, dt).unwrap();
            let step = Step {
                y0: &s0.0,
                y1: &up.sigma.0,
                deps: &deps,
                dt,
                regime: Regime::Smooth,
            };
            let mut r = [0.0; 4];
            mat.residual(&c, &step, &mut r);
            let scale = law.compliance(&c).mul_vec(&up.sigma).max_abs() + deps.max_abs();
            assert!(Vec4(r).max_abs() <= 1e-10 * scale, "{}: {r:?}", law.name());
            let t = tangent_from_blocks(&mat, &c, &step).unwrap();
            assert!(
                (t - up.tangent).max_abs() <= 1e-9 * up.tangent.max_abs(),
                "{}",
                law.name()
            );
            let mut d = [0.0; 16];
            mat.jac_previous(&c, &step, &mut d);
            assert_eq!(d, (law.compliance(&c) * -1.0).0.as_flattened());
            let n = c.len();
            let mut p = vec![0.0; 4 * n];
            mat.jac_params(&c, &step, &mut p);
            for k in 0..n {
                let col = law.residual_param_derivative(&c, &s0, &up.sigma, dt, k);
                for i in 0..4 {
                    assert_eq!(p[i * n + k], col[i]);
                }
            }
        }
    }

    /// The system shall give every block of the adapted laws (Elastic, Maxwell,
    /// Norton-Hoff) equal to finite differences to 1e-6 through the shared checks.
    #[test]
    fn law_material_blocks_match_finite_differences() {
        let mut rng = crate::plastic::tests::Rng(5);
        for (law, c) in cases() {
            let mat = LawMaterial(law);
            for _ in 0..30 {
                let s0 = rng.vec4() * 600.0;
                let deps = rng.vec4() * 10f64.powf(-4.0 + 1.5 * (rng.next() + 1.0));
                let dt = 10f64.powf(-2.0 + 2.0 * rng.next());
                let pt = crate::testing::Point {
                    c: &c,
                    y0: &s0.0,
                    deps,
                    dt,
                };
                crate::testing::check_material(&mat, &pt, 1e-6).unwrap();
            }
        }
    }

    #[test]
    fn dense_solve_many_equals_one_column_at_a_time() {
        let a0 = [4.0, 1.0, -2.0, 3.0, -5.0, 1.0, 0.5, 2.0, 6.0];
        let b0 = [1.0, 0.0, 2.0, -1.0, 3.0, 0.25];
        let (mut a, mut b) = (a0, b0);
        assert!(dense_solve_many(&mut a, 3, &mut b, 2));
        for k in 0..2 {
            let (mut a1, mut b1) = (a0, [b0[k], b0[2 + k], b0[4 + k]]);
            assert!(dense_solve(&mut a1, 3, &mut b1));
            for r in 0..3 {
                assert_eq!(b[r * 2 + k].to_bits(), b1[r].to_bits());
                let ax: f64 = (0..3).map(|j| a0[r * 3 + j] * b[j * 2 + k]).sum();
                assert!((ax - b0[r * 2 + k]).abs() < 1e-14);
            }
        }
    }

    #[test]
    fn dense_solve_solves_and_refuses_singular() {
        let mut a = vec![4.0, 1.0, 0.0, 1.0, 3.0, 1.0, 0.0, 1.0, 2.0];
        let mut b = vec![1.0, 2.0, 3.0];
        assert!(dense_solve(&mut a, 3, &mut b));
        let x = b;
        let a0 = [4.0, 1.0, 0.0, 1.0, 3.0, 1.0, 0.0, 1.0, 2.0];
        for i in 0..3 {
            let ax: f64 = (0..3).map(|k| a0[i * 3 + k] * x[k]).sum();
            assert!((ax - [1.0, 2.0, 3.0][i]).abs() < 1e-14);
        }
        let mut s = vec![1.0, 2.0, 2.0, 4.0];
        let mut b = vec![1.0, 1.0];
        assert!(!dense_solve(&mut s, 2, &mut b));
    }
}
