//! Generalized Maxwell viscoelasticity in shear with a Prony series,
//! `Prony(E, nu, terms: [(g, tau), ...])`: `G(t) = G0 (1 - sum g_i (1 - exp(-t/tau_i)))`,
//! bulk elastic; the internal variables are the viscous strains of the branches.

use crate::LawError;
use crate::elastic::{
    E_INFO, NU_INFO, isotropic_compliance, isotropic_compliance_derivative, isotropic_operator,
};
use crate::law::{LocalFailure, ParamInfo};
use crate::mandel::{Mat4, Vec4};
use crate::material::{InternalInfo, Material, MaterialUpdate, Regime, Step, stress_of};

/// The largest number of Prony terms.
pub const MAX_TERMS: usize = 8;

/// Generalized Maxwell solid: an equilibrium spring `2 G0 g_inf` (`g_inf = 1 - sum g_i`)
/// in parallel with `N` Maxwell branches of shear modulus `G_i = g_i G0` and relaxation
/// time `tau_i` (dashpot `G_i tau_i`), bulk elastic; `E`, `nu` instantaneous (`G0 =
/// E / (2 (1 + nu))`). Parameters `c = [E, nu, g1, tau1, ..., gN, tauN]` (MPa, -, -, s,
/// ...). One term is the standard linear solid.
///
/// State `y = [sigma, ev_1, ..., ev_N]` (`ev_i` the deviatoric viscous strain of branch
/// `i`, 4 Mandel components each). The total deviatoric strain is a function of the state,
/// `e = dev(sigma) / (2 G0) + sum g_j ev_j`, since `s = 2 G0 (e - sum g_j ev_j)`. Backward
/// Euler:
///
/// - `r_sigma = S (sigma_1 - sigma_0) + sum g_i (ev_i1 - ev_i0) - deps`,
/// - `r_i = tau_i (ev_i1 - ev_i0) - dt (e_1 - ev_i1)`,
///
/// solved in closed form: `e_1 = e_0 + dev deps`, `ev_i1 = (tau_i ev_i0 + dt e_1) /
/// (tau_i + dt)`, `s_1 = 2 G0 (e_1 - sum g_i ev_i1)`, `tr sigma_1 = tr sigma_0 + 3 kappa
/// tr deps`. The tangent `2 G0 (1 - sum g_i dt / (tau_i + dt)) P + 3 kappa J` depends on
/// `(c, dt)` only. Under a held strain the shear stress relaxes as
/// `1 - sum g_i (1 - (tau_i / (tau_i + dt))^n)` after `n` steps, which tends to the
/// continuous `G(t) / G0` as `dt -> 0`.
#[derive(Clone, Debug)]
pub struct Prony {
    terms: usize,
}

macro_rules! branch {
    ($i:literal) => {
        [
            InternalInfo {
                name: concat!("ev", $i, "_rr"),
                unit: "-",
                description: concat!("viscous strain of branch ", $i, ", rr"),
            },
            InternalInfo {
                name: concat!("ev", $i, "_zz"),
                unit: "-",
                description: concat!("viscous strain of branch ", $i, ", zz"),
            },
            InternalInfo {
                name: concat!("ev", $i, "_tt"),
                unit: "-",
                description: concat!("viscous strain of branch ", $i, ", tt"),
            },
            InternalInfo {
                name: concat!("ev", $i, "_rz"),
                unit: "-",
                description: concat!("viscous strain of branch ", $i, ", sqrt2 rz (Mandel)"),
            },
        ]
    };
}

macro_rules! term_params {
    ($g:literal, $tau:literal) => {
        [
            ParamInfo {
                name: $g,
                unit: "-",
                description: "Prony weight (fraction of G0 that relaxes in this term)",
                min: 0.0,
                min_inclusive: true,
                max: 1.0,
                max_inclusive: false,
            },
            ParamInfo {
                name: $tau,
                unit: "s",
                description: "Prony relaxation time",
                min: 0.0,
                min_inclusive: false,
                max: f64::INFINITY,
                max_inclusive: false,
            },
        ]
    };
}

const INTERNAL: [[InternalInfo; 4]; MAX_TERMS] = [
    branch!(1),
    branch!(2),
    branch!(3),
    branch!(4),
    branch!(5),
    branch!(6),
    branch!(7),
    branch!(8),
];

const PARAMS: [[ParamInfo; 2]; MAX_TERMS + 1] = [
    [E_INFO, NU_INFO],
    term_params!("g1", "tau1"),
    term_params!("g2", "tau2"),
    term_params!("g3", "tau3"),
    term_params!("g4", "tau4"),
    term_params!("g5", "tau5"),
    term_params!("g6", "tau6"),
    term_params!("g7", "tau7"),
    term_params!("g8", "tau8"),
];

fn view(y: &[f64], i: usize) -> Vec4 {
    let o = 4 + 4 * i;
    Vec4([y[o], y[o + 1], y[o + 2], y[o + 3]])
}

impl Prony {
    /// A Prony series of `terms` terms.
    ///
    /// # Errors
    /// [`LawError::Spec`] on `terms` outside `[1, 8]`.
    pub fn new(terms: usize) -> Result<Prony, LawError> {
        if (1..=MAX_TERMS).contains(&terms) {
            Ok(Prony { terms })
        } else {
            Err(LawError::Spec {
                law: "prony",
                field: "terms".into(),
                message: format!("{terms} terms; a Prony series takes 1 to {MAX_TERMS} terms"),
            })
        }
    }
    /// Number of terms.
    pub fn terms(&self) -> usize {
        self.terms
    }
    /// The total deviatoric strain `e = dev(sigma) / (2 G0) + sum g_j ev_j` of a state.
    fn strain(&self, c: &[f64], y: &[f64]) -> Vec4 {
        let inv_2g = (1.0 + c[1]) / c[0];
        let mut e = stress_of(y).deviator() * inv_2g;
        for j in 0..self.terms {
            e += view(y, j) * c[2 + 2 * j];
        }
        e
    }
}

impl Material for Prony {
    fn name(&self) -> &'static str {
        "prony"
    }
    fn params(&self) -> &[ParamInfo] {
        PARAMS[..=self.terms].as_flattened()
    }
    fn internal(&self) -> &[InternalInfo] {
        INTERNAL[..self.terms].as_flattened()
    }
    fn is_linear(&self) -> bool {
        true
    }
    /// The ranges, and `sum g_i < 1` (a positive equilibrium modulus).
    ///
    /// # Errors
    /// [`LawError::Parameter`] for a range, [`LawError::Spec`] naming `g1 + ... + gN`.
    fn check_params(&self, c: &[f64]) -> Result<(), LawError> {
        crate::material::check_param_ranges(self.name(), self.params(), c)?;
        let sum: f64 = (0..self.terms).map(|i| c[2 + 2 * i]).sum();
        if sum < 1.0 {
            Ok(())
        } else {
            Err(LawError::Spec {
                law: "prony",
                field: (1..=self.terms)
                    .map(|i| format!("g{i}"))
                    .collect::<Vec<_>>()
                    .join(" + "),
                message: format!(
                    "= {sum} must be in [0, 1): the equilibrium modulus G0 (1 - sum g_i) must stay positive"
                ),
            })
        }
    }
    fn residual(&self, c: &[f64], step: &Step<'_>, r: &mut [f64]) {
        let (s0, s1) = (stress_of(step.y0), stress_of(step.y1));
        let mut rs = isotropic_compliance(c[0], c[1]).mul_vec(&(s1 - s0)) - *step.deps;
        let e1 = self.strain(c, step.y1);
        for i in 0..self.terms {
            let (v0, v1) = (view(step.y0, i), view(step.y1, i));
            rs += (v1 - v0) * c[2 + 2 * i];
            let ri = (v1 - v0) * c[3 + 2 * i] - (e1 - v1) * step.dt;
            r[4 + 4 * i..8 + 4 * i].copy_from_slice(&ri.0);
        }
        r[..4].copy_from_slice(&rs.0);
    }
    fn jac_state(&self, c: &[f64], step: &Step<'_>, out: &mut [f64]) {
        let m = self.state_len();
        let dt = step.dt;
        out.fill(0.0);
        let s = isotropic_compliance(c[0], c[1]);
        let de_ds = Mat4::deviatoric_projector() * ((1.0 + c[1]) / c[0]);
        for a in 0..4 {
            out[a * m..a * m + 4].copy_from_slice(&s.0[a]);
            for j in 0..self.terms {
                out[a * m + 4 + 4 * j + a] = c[2 + 2 * j];
            }
        }
        for i in 0..self.terms {
            for a in 0..4 {
                let row = (4 + 4 * i + a) * m;
                for b in 0..4 {
                    out[row + b] = -dt * de_ds.0[a][b];
                }
                for j in 0..self.terms {
                    out[row + 4 + 4 * j + a] = -dt * c[2 + 2 * j];
                }
                out[row + 4 + 4 * i + a] += c[3 + 2 * i] + dt;
            }
        }
    }
    fn jac_previous(&self, c: &[f64], _step: &Step<'_>, out: &mut [f64]) {
        let m = self.state_len();
        out.fill(0.0);
        let s = isotropic_compliance(c[0], c[1]);
        for a in 0..4 {
            for b in 0..4 {
                out[a * m + b] = -s.0[a][b];
            }
            for j in 0..self.terms {
                out[a * m + 4 + 4 * j + a] = -c[2 + 2 * j];
                out[(4 + 4 * j + a) * m + 4 + 4 * j + a] = -c[3 + 2 * j];
            }
        }
    }
    fn jac_params(&self, c: &[f64], step: &Step<'_>, out: &mut [f64]) {
        let nc = c.len();
        out.fill(0.0);
        let (s0, s1) = (stress_of(step.y0), stress_of(step.y1));
        let dev1 = s1.deviator();
        for k in 0..2 {
            let col = isotropic_compliance_derivative(c, k).mul_vec(&(s1 - s0));
            // d e_1 / dE = -dev / (2G0 E), d e_1 / dnu = dev / E
            let de = if k == 0 {
                dev1 * (-(1.0 + c[1]) / (c[0] * c[0]))
            } else {
                dev1 * (1.0 / c[0])
            };
            for a in 0..4 {
                out[a * nc + k] = col[a];
                for i in 0..self.terms {
                    out[(4 + 4 * i + a) * nc + k] = -step.dt * de[a];
                }
            }
        }
        for j in 0..self.terms {
            let (v0, v1) = (view(step.y0, j), view(step.y1, j));
            let (kg, kt) = (2 + 2 * j, 3 + 2 * j);
            for a in 0..4 {
                out[a * nc + kg] = v1[a] - v0[a];
                for i in 0..self.terms {
                    out[(4 + 4 * i + a) * nc + kg] = -step.dt * v1[a];
                }
                out[(4 + 4 * j + a) * nc + kt] = v1[a] - v0[a];
            }
        }
    }
    /// Closed form (see [`Prony`]).
    ///
    /// # Errors
    /// [`LocalFailure`] on a negative or non-finite `dt` or non-finite input.
    fn update(
        &self,
        c: &[f64],
        y0: &[f64],
        deps: &Vec4,
        dt: f64,
        y1: &mut [f64],
    ) -> Result<MaterialUpdate, LocalFailure> {
        let m = self.state_len();
        if !dt.is_finite()
            || dt < 0.0
            || !deps.is_finite()
            || y0[..m].iter().any(|v| !v.is_finite())
        {
            return Err(LocalFailure {
                reason: format!("prony: invalid input dt = {dt}, deps = {deps:?}"),
                suggested_dt_factor: 0.5,
            });
        }
        let (e, nu) = (c[0], c[1]);
        let g2 = e / (1.0 + nu);
        let kappa3 = e / (1.0 - 2.0 * nu);
        let e1 = self.strain(c, y0) + deps.deviator();
        let mut s1 = e1;
        let mut relaxed = 0.0;
        for i in 0..self.terms {
            let (g, tau) = (c[2 + 2 * i], c[3 + 2 * i]);
            let v1 = (view(y0, i) * tau + e1 * dt) * (1.0 / (tau + dt));
            s1 -= v1 * g;
            relaxed += g * dt / (tau + dt);
            y1[4 + 4 * i..8 + 4 * i].copy_from_slice(&v1.0);
        }
        let s0 = stress_of(y0);
        let sigma = s1 * g2 + Vec4::ONE * ((s0.trace() + kappa3 * deps.trace()) / 3.0);
        y1[..4].copy_from_slice(&sigma.0);
        Ok(MaterialUpdate {
            tangent: isotropic_operator(g2 * (1.0 - relaxed), kappa3),
            iterations: 0,
            regime: Regime::Smooth,
        })
    }
}
