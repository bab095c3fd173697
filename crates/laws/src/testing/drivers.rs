//! Material-point drivers for closed-form checks of a [`Material`]: uniaxial stress
//! (`sigma_rr = sigma_tt = sigma_rz = 0`, the axial strain or stress controlled) and
//! shear (`rz` strain or stress controlled, the other strains held at zero).

use crate::law::LocalFailure;
use crate::mandel::{Mat4, Vec4};
use crate::material::{Material, Regime, stress_of};

/// Control of the driven component over one step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shear {
    /// Prescribed strain increment of the driven component (Mandel).
    Strain(f64),
    /// Prescribed end-of-step stress of the driven component (MPa, Mandel).
    Stress(f64),
}

/// The state after one driven step.
#[derive(Clone, Debug, PartialEq)]
pub struct UniaxialPoint {
    /// Accumulated strain (Mandel).
    pub eps: Vec4,
    /// State `y = [sigma, alpha]` at the end of the step.
    pub y: Vec<f64>,
    /// Regime of the step's update.
    pub regime: Regime,
    /// Time at the end of the step (s).
    pub t: f64,
}

impl UniaxialPoint {
    /// The stress part of the state.
    pub fn sigma(&self) -> Vec4 {
        stress_of(&self.y)
    }
}

/// One step: strains of the components `strain_ctl` prescribed (`deps[i] = e`), the
/// stresses of the others equal to `target` (zero except the driven one under stress
/// control); Newton on the free strain increments with the consistent tangent, to 1e-13
/// of the stress.
fn drive_step(
    mat: &dyn Material,
    c: &[f64],
    y0: &[f64],
    dt: f64,
    (prescribed, target): ([Option<f64>; 4], Vec4),
    guess: Vec4,
    y1: &mut [f64],
) -> Result<(Vec4, Regime), LocalFailure> {
    let mut deps = guess;
    let free: Vec<usize> = (0..4).filter(|&i| prescribed[i].is_none()).collect();
    for (i, p) in prescribed.iter().enumerate() {
        if let Some(e) = p {
            deps[i] = *e;
        }
    }
    for _ in 0..60 {
        let up = mat.update(c, y0, &deps, dt, y1)?;
        let sigma = stress_of(y1);
        let mut res = Vec4::ZERO;
        let mut jac = Mat4::IDENTITY;
        for &i in &free {
            res[i] = sigma[i] - target[i];
            for &j in &free {
                jac.0[i][j] = up.tangent.0[i][j];
            }
        }
        let tol = 1e-13 * (sigma.max_abs() + target.max_abs()).max(1e-300);
        if res.max_abs() <= tol {
            return Ok((deps, up.regime));
        }
        let inv = jac.inverse().ok_or_else(|| LocalFailure {
            reason: "driver: singular tangent on the free components".into(),
            suggested_dt_factor: 0.5,
        })?;
        deps -= inv.mul_vec(&res);
    }
    Err(LocalFailure {
        reason: "driver: the free components did not converge in 60 iterations".into(),
        suggested_dt_factor: 0.5,
    })
}

fn history(
    mat: &dyn Material,
    c: &[f64],
    y0: &[f64],
    steps: &[(Shear, f64)],
    axis: usize,
    lateral_free: &[usize],
) -> Result<Vec<UniaxialPoint>, LocalFailure> {
    let m = mat.state_len();
    let mut y = y0.to_vec();
    let mut y1 = vec![0.0; m];
    let mut eps = Vec4::ZERO;
    let mut t = 0.0;
    let mut guess = Vec4::ZERO;
    let mut out = Vec::with_capacity(steps.len());
    for &(ctl, dt) in steps {
        let mut prescribed = [Some(0.0); 4];
        for &i in lateral_free {
            prescribed[i] = None;
        }
        let mut target = Vec4::ZERO;
        match ctl {
            Shear::Strain(e) => prescribed[axis] = Some(e),
            Shear::Stress(s) => {
                prescribed[axis] = None;
                target[axis] = s;
            }
        }
        let (deps, regime) = drive_step(mat, c, &y, dt, (prescribed, target), guess, &mut y1)?;
        eps += deps;
        t += dt;
        guess = deps;
        y.copy_from_slice(&y1);
        out.push(UniaxialPoint {
            eps,
            y: y.clone(),
            regime,
            t,
        });
    }
    Ok(out)
}

/// A uniaxial-stress history along `zz` from the state `y0`: each step `(control, dt)`
/// prescribes the axial strain increment or the end axial stress; `sigma_rr = sigma_tt =
/// 0` by Newton on the lateral strains, `eps_rz = 0`.
///
/// # Errors
/// The update's [`LocalFailure`], or a driver that does not converge.
pub fn uniaxial_path(
    mat: &dyn Material,
    c: &[f64],
    y0: &[f64],
    steps: &[(Shear, f64)],
) -> Result<Vec<UniaxialPoint>, LocalFailure> {
    history(mat, c, y0, steps, 1, &[0, 2])
}

/// A shear history in the Mandel component `rz` (`sqrt2 eps_rz`, `sqrt2 sigma_rz`) with
/// the other strain components held at zero.
///
/// # Errors
/// The update's [`LocalFailure`], or a driver that does not converge.
pub fn shear_history(
    mat: &dyn Material,
    c: &[f64],
    y0: &[f64],
    steps: &[(Shear, f64)],
) -> Result<Vec<UniaxialPoint>, LocalFailure> {
    history(mat, c, y0, steps, 3, &[])
}
