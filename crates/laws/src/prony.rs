//! Generalized Maxwell viscoelasticity in shear with a Prony series,
//! `Prony(E, nu, terms: [(g, tau), ...])`: `G(t) = G0 (1 - sum g_i (1 - exp(-t/tau_i)))`,
//! bulk elastic; the internal variables are the viscous strains of the branches.

use crate::LawError;
use crate::elastic::{E_INFO, NU_INFO, isotropic_compliance, isotropic_operator};
use crate::law::{LocalFailure, ParamInfo};
use crate::mandel::{Mat4, Vec4};
use crate::material::{InternalInfo, Material, MaterialUpdate, Regime, Step, stress_of};
use crate::registry::{
    Built, FieldKind, FieldSchema, Fields, LawEntry, SpecValue, number, ordered_params,
};

/// The largest number of Prony terms.
pub const MAX_TERMS: usize = 8;

/// Generalized Maxwell solid: an equilibrium spring `2 G0 g_inf` (`g_inf = 1 - sum g_i`)
/// in parallel with `N` Maxwell branches of shear modulus `G_i = g_i G0` and relaxation
/// time `tau_i` (dashpot `G_i tau_i`), bulk elastic; `E`, `nu` instantaneous (`G0 =
/// E / (2 (1 + nu))`). Parameters `c = [E, nu, g1, tau1, ..., gN, tauN]` (MPa, -, -, s,
/// ...). One term is the standard linear solid.
///
/// State `y = [sigma, ev_1, ..., ev_N]` (`ev_i` the deviatoric viscous strain of branch
/// `i`, 4 Mandel components each; only their deviators `P ev` act, and a trace part, if a
/// state had one, decays with `tau_i`). The total deviatoric strain is a function of the
/// state, `e = dev(sigma) / (2 G0) + sum g_j P ev_j`, since `s = 2 G0 (e - sum g_j P ev_j)`.
/// Backward Euler:
///
/// - `r_sigma = S (sigma_1 - sigma_0) + sum g_i P (ev_i1 - ev_i0) - deps`,
/// - `r_i = tau_i (ev_i1 - ev_i0) - dt (e_1 - ev_i1)`,
///
/// solved in closed form: `e_1 = e_0 + dev deps`, `ev_i1 = (tau_i ev_i0 + dt e_1) /
/// (tau_i + dt)`, `s_1 = 2 G0 (e_1 - sum g_i P ev_i1)`, `tr sigma_1 = tr sigma_0 + 3 kappa
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

#[inline]
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
            e += view(y, j).deviator() * c[2 + 2 * j];
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
            rs += (v1 - v0).deviator() * c[2 + 2 * i];
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
        let pr = Mat4::deviatoric_projector();
        let de_ds = pr * ((1.0 + c[1]) / c[0]);
        for a in 0..4 {
            out[a * m..a * m + 4].copy_from_slice(&s.0[a]);
            for j in 0..self.terms {
                for b in 0..4 {
                    out[a * m + 4 + 4 * j + b] = c[2 + 2 * j] * pr.0[a][b];
                }
            }
        }
        for i in 0..self.terms {
            for a in 0..4 {
                let row = (4 + 4 * i + a) * m;
                for b in 0..4 {
                    out[row + b] = -dt * de_ds.0[a][b];
                    for j in 0..self.terms {
                        out[row + 4 + 4 * j + b] = -dt * c[2 + 2 * j] * pr.0[a][b];
                    }
                }
                out[row + 4 + 4 * i + a] += c[3 + 2 * i] + dt;
            }
        }
    }
    fn jac_previous(&self, c: &[f64], _step: &Step<'_>, out: &mut [f64]) {
        let m = self.state_len();
        out.fill(0.0);
        let s = isotropic_compliance(c[0], c[1]);
        let pr = Mat4::deviatoric_projector();
        for a in 0..4 {
            for b in 0..4 {
                out[a * m + b] = -s.0[a][b];
                for j in 0..self.terms {
                    out[a * m + 4 + 4 * j + b] = -c[2 + 2 * j] * pr.0[a][b];
                }
            }
            for j in 0..self.terms {
                out[(4 + 4 * j + a) * m + 4 + 4 * j + a] = -c[3 + 2 * j];
            }
        }
    }
    fn jac_params(&self, c: &[f64], step: &Step<'_>, out: &mut [f64]) {
        let nc = c.len();
        out.fill(0.0);
        let (s0, s1) = (stress_of(step.y0), stress_of(step.y1));
        let dev1 = s1.deviator();
        // dS/dc_k (s1 - s0) in closed form (no 4 x 4 matrix per point):
        // S v = ((1 + nu) v - nu tr(v) 1) / E, dS/dE v = -S v / E, dS/dnu v = (v - tr(v) 1) / E
        let (e, nu) = (c[0], c[1]);
        let ds = s1 - s0;
        let tr = ds.trace();
        for k in 0..2 {
            let col = if k == 0 {
                (ds * (1.0 + nu) - Vec4::ONE * (nu * tr)) * (-1.0 / (e * e))
            } else {
                (ds - Vec4::ONE * tr) * (1.0 / e)
            };
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
            let (dv, pv1) = ((v1 - v0).deviator(), v1.deviator());
            let (kg, kt) = (2 + 2 * j, 3 + 2 * j);
            for a in 0..4 {
                out[a * nc + kg] = dv[a];
                for i in 0..self.terms {
                    out[(4 + 4 * i + a) * nc + kg] = -step.dt * pv1[a];
                }
                out[(4 + 4 * j + a) * nc + kt] = v1[a] - v0[a];
            }
        }
    }
    /// `mu^T P` in closed form: the terms of [`Material::jac_params`] contracted with
    /// `mu = [mu_s, mu_1, ..., mu_N]` (`m_v = sum_i mu_i`, `ds = s1 - s0`,
    /// `dv_j = v1_j - v0_j`), a few 4-vector products per term and no block:
    ///
    /// - `E`: `(nu tr(mu_s) tr(ds) - (1 + nu) mu_s.ds + dt (1 + nu) m_v.dev(s1)) / E^2`,
    /// - `nu`: `(mu_s.ds - tr(mu_s) tr(ds) - dt m_v.dev(s1)) / E`,
    /// - `g_j`: `dev(mu_s).dv_j - dt dev(m_v).v1_j`,
    /// - `tau_j`: `mu_j.dv_j`.
    #[allow(clippy::needless_range_loop)] // (plain loops: no calls in the `dev` profile)
    fn jac_params_transpose(
        &self,
        c: &[f64],
        step: &Step<'_>,
        mu: &[f64],
        weight: f64,
        _scratch: &mut [f64],
        out: &mut [f64],
    ) {
        let (e, nu, dt) = (c[0], c[1], step.dt);
        let (y0, y1) = (step.y0, step.y1);
        // mu_s.ds, tr(mu_s), tr(ds), m_v
        let (mut mds, mut trm, mut trd) = (0.0, 0.0, 0.0);
        let mut mv = [0.0; 4];
        for a in 0..4 {
            let d = y1[a] - y0[a];
            mds += mu[a] * d;
            if a < 3 {
                trm += mu[a];
                trd += d;
            }
            for i in 0..self.terms {
                mv[a] += mu[4 + 4 * i + a];
            }
        }
        let trs = trm * trd;
        // dev(mu_s), dev(m_v), and m_v.dev(s1) = dev(m_v).s1
        let (pm, pv) = (trm / 3.0, (mv[0] + mv[1] + mv[2]) / 3.0);
        let dmus = [mu[0] - pm, mu[1] - pm, mu[2] - pm, mu[3]];
        let dmv = [mv[0] - pv, mv[1] - pv, mv[2] - pv, mv[3]];
        let mut mvd = 0.0;
        for a in 0..4 {
            mvd += dmv[a] * y1[a];
        }
        out[0] += weight * ((nu * trs - (1.0 + nu) * mds + dt * (1.0 + nu) * mvd) / (e * e));
        out[1] += weight * ((mds - trs - dt * mvd) / e);
        for j in 0..self.terms {
            let o = 4 + 4 * j;
            let (mut g, mut t) = (0.0, 0.0);
            for a in 0..4 {
                let dv = y1[o + a] - y0[o + a];
                g += dmus[a] * dv - dt * dmv[a] * y1[o + a];
                t += mu[o + a] * dv;
            }
            out[2 + 2 * j] += weight * g;
            out[3 + 2 * j] += weight * t;
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
            s1 -= v1.deviator() * g;
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

/// The registry entry: `Prony(E, nu, terms: [(g: .., tau: ..), ...])`, parameters
/// `E, nu, g1, tau1, g2, tau2, ...`.
pub const ENTRY: LawEntry = LawEntry {
    name: "prony",
    variant: "Prony",
    summary: "generalized Maxwell viscoelasticity in shear (Prony series), bulk elastic",
    example: "Prony(E: 3000.0, nu: 0.35, terms: [(g: 0.3, tau: 0.1), (g: 0.2, tau: 2.0)])",
    fields: &[
        number("E"),
        number("nu"),
        FieldSchema {
            name: "terms",
            kind: FieldKind::ListOf(&[number("g"), number("tau")]),
            optional: false,
        },
    ],
    build: build_spec,
};

const G_NAMES: [&str; MAX_TERMS] = ["g1", "g2", "g3", "g4", "g5", "g6", "g7", "g8"];
const TAU_NAMES: [&str; MAX_TERMS] = [
    "tau1", "tau2", "tau3", "tau4", "tau5", "tau6", "tau7", "tau8",
];

fn build_spec(fields: &[(String, SpecValue)]) -> Result<Built, LawError> {
    let mut f = Fields::new("prony", "", fields);
    let mut values = vec![("E", f.number("E")?), ("nu", f.number("nu")?)];
    let Some(SpecValue::List(terms)) = f.get("terms") else {
        return Err(f.error(
            "terms",
            "missing or not a list [(g: .., tau: ..), ...]".into(),
        ));
    };
    let material = Prony::new(terms.len())?;
    for (i, t) in terms.iter().enumerate() {
        let SpecValue::Variant { fields: tf, .. } = t else {
            return Err(f.error(&format!("terms[{i}]"), "expected (g: .., tau: ..)".into()));
        };
        let mut tf = Fields::new("prony", &format!("terms[{i}]."), tf);
        values.push((G_NAMES[i], tf.number("g")?));
        values.push((TAU_NAMES[i], tf.number("tau")?));
        tf.finish(&["g", "tau"])?;
    }
    f.finish(&["E", "nu", "terms"])?;
    let params = ordered_params(&material, &values)?;
    Ok(Built {
        material: Box::new(material),
        params,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::{Point, Shear, check_material, shear_history, uniaxial_path};

    const E: f64 = 3000.0;
    const NU: f64 = 0.35;

    fn params(terms: &[(f64, f64)]) -> Vec<f64> {
        let mut c = vec![E, NU];
        for &(g, tau) in terms {
            c.extend([g, tau]);
        }
        c
    }

    const THREE: [(f64, f64); 3] = [(0.3, 0.1), (0.2, 2.0), (0.25, 50.0)];

    /// The system shall give every block of `Prony` (1 to 3 terms) equal to central
    /// finite differences to 1e-6 and a zero residual at the update.
    #[test]
    fn every_block_matches_finite_differences() {
        let mut rng = crate::plastic::tests::Rng(99);
        for n in 1..=3 {
            let law = Prony::new(n).unwrap();
            let c = params(&THREE[..n]);
            let m = law.state_len();
            assert_eq!(m, 4 + 4 * n);
            for _ in 0..20 {
                let mut y0 = vec![0.0; m];
                let s0 = rng.vec4() * 30.0;
                y0[..4].copy_from_slice(&s0.0);
                for i in 0..n {
                    let v = (rng.vec4() * 5e-3).deviator();
                    y0[4 + 4 * i..8 + 4 * i].copy_from_slice(&v.0);
                }
                let deps = rng.vec4() * 1e-2;
                let dt = 10f64.powf(1.5 * rng.next());
                let pt = Point {
                    c: &c,
                    y0: &y0,
                    deps,
                    dt,
                };
                let rep = check_material(&law, &pt, 1e-6).unwrap();
                assert!(rep.checks[0].error.unwrap() < 1e-12, "{rep:?}");
                // the closed-form `mu^T P` is the block's contraction to rounding
                let ct = rep.checks.iter().find(|c| c.block.starts_with("mu^T P"));
                assert!(ct.unwrap().error.unwrap() < 1e-13, "{rep:?}");
                assert!(rep.checks.iter().all(|c| c.error.is_some()), "{rep:?}");
            }
        }
    }

    /// The system shall refuse `sum g_i >= 1`, `tau <= 0`, a weight outside `[0, 1)` and a
    /// number of terms outside `[1, 8]`, naming the field and the allowed range.
    #[test]
    fn bad_parameters_name_the_field_and_range() {
        let law = Prony::new(2).unwrap();
        assert!(law.check_params(&params(&[(0.3, 1.0), (0.6, 2.0)])).is_ok());
        for (c, field, range) in [
            (params(&[(0.5, 1.0), (0.5, 2.0)]), "g1 + g2", "[0, 1)"),
            (params(&[(0.3, 0.0), (0.2, 2.0)]), "`tau1`", "(0, inf)"),
            (params(&[(0.3, 1.0), (0.2, -2.0)]), "`tau2`", "(0, inf)"),
            (params(&[(-0.1, 1.0), (0.2, 2.0)]), "`g1`", "[0, 1)"),
            (params(&[(0.1, 1.0), (0.2, f64::NAN)]), "`tau2`", "(0, inf)"),
        ] {
            let text = law.check_params(&c).unwrap_err().to_string();
            assert!(
                text.contains(field) && text.contains(range) && text.contains("prony"),
                "{text}"
            );
        }
        for n in [0, 9] {
            let text = Prony::new(n).unwrap_err().to_string();
            assert!(text.contains("terms") && text.contains("1 to 8"), "{text}");
        }
        let names: Vec<&str> = Prony::new(2)
            .unwrap()
            .params()
            .iter()
            .map(|p| p.name)
            .collect();
        assert_eq!(names, ["E", "nu", "g1", "tau1", "g2", "tau2"]);
        let iv = Prony::new(2).unwrap();
        assert_eq!(iv.internal()[4].name, "ev2_rr");
        let mut y1 = vec![0.0; 8];
        let f = Prony::new(1)
            .unwrap()
            .update(
                &params(&THREE[..1]),
                &[0.0; 8],
                &Vec4([f64::NAN; 4]),
                0.1,
                &mut y1,
            )
            .unwrap_err();
        assert!(f.suggested_dt_factor < 1.0);
    }

    /// Relaxation under a held shear strain.
    ///
    /// Reference: after an instantaneous shear strain `gamma` (Mandel component
    /// `e = sqrt2 eps_rz`) held for `n` steps of `dt`, backward Euler gives each branch's
    /// elastic strain `(tau_i / (tau_i + dt))^n e`, so the exact discrete stress is
    /// `2 G0 e (1 - sum g_i (1 - (tau_i/(tau_i + dt))^n))` (agreement to 1e-12), and the
    /// continuous `2 G0 e (1 - sum g_i (1 - exp(-t/tau_i)))`, approached at first order.
    #[test]
    fn relaxation_matches_the_discrete_and_continuous_solutions() {
        let law = Prony::new(3).unwrap();
        let c = params(&THREE);
        let g2 = E / (1.0 + NU);
        let e = 2e-3;
        let t_end = 1.0;
        let discrete = |n: usize| {
            let dt = t_end / n as f64;
            let mut steps = vec![(Shear::Strain(e), 0.0)];
            steps.extend(std::iter::repeat_n((Shear::Strain(0.0), dt), n));
            let path = shear_history(&law, &c, &[0.0; 16], &steps).unwrap();
            let s = path.last().unwrap().sigma();
            assert!(s[0].abs() + s[1].abs() + s[2].abs() < 1e-12 * s[3].abs());
            let exact: f64 = 1.0
                - THREE
                    .iter()
                    .map(|&(g, tau)| g * (1.0 - (tau / (tau + dt)).powi(n as i32)))
                    .sum::<f64>();
            assert!(
                (s[3] - g2 * e * exact).abs() <= 1e-12 * g2 * e,
                "{n}: {} vs {}",
                s[3],
                g2 * e * exact
            );
            s[3]
        };
        let cont = g2
            * e
            * (1.0
                - THREE
                    .iter()
                    .map(|&(g, tau)| g * (1.0 - (-t_end / tau).exp()))
                    .sum::<f64>());
        crate::testing::assert_first_order("prony relaxation", 50, |n| {
            (discrete(n) - cont).abs() / cont
        });
        // the held strain relaxed by more than the short-time term alone
        assert!(discrete(400) < g2 * e * (1.0 - 0.3 * 0.99));
    }

    /// Creep under a held shear stress (one term, the standard linear solid).
    ///
    /// Reference: with `s` held, the branch's viscous strain `w` obeys
    /// `(tau + dt (1 - g)) (w_n - w_{n-1}) = dt (s/(2 G0) - (1 - g) w_{n-1})`, so
    /// `w_n = w_inf (1 - (tau / (tau + dt (1 - g)))^n)`, `w_inf = s / (2 G0 (1 - g))`, and
    /// the strain is `e = s/(2 G0) + g w`; continuous: `w(t) = w_inf (1 - exp(-t (1-g)/tau))`
    /// (retardation time `tau / (1 - g)`), the strain tending to `s / (2 G_inf)`.
    #[test]
    fn creep_matches_the_discrete_and_continuous_solutions() {
        let (g, tau) = (0.4, 0.5);
        let law = Prony::new(1).unwrap();
        let c = params(&[(g, tau)]);
        let g2 = E / (1.0 + NU);
        let s = 20.0;
        let t_end = 1.5;
        let w_inf = s / (g2 * (1.0 - g));
        let discrete = |n: usize| {
            let dt = t_end / n as f64;
            let mut steps = vec![(Shear::Stress(s), 0.0)];
            steps.extend(std::iter::repeat_n((Shear::Stress(s), dt), n));
            let path = shear_history(&law, &c, &[0.0; 8], &steps).unwrap();
            let last = path.last().unwrap();
            assert!((last.sigma()[3] - s).abs() < 1e-12 * s);
            let w = w_inf * (1.0 - (tau / (tau + dt * (1.0 - g))).powi(n as i32));
            let exact = s / g2 + g * w;
            assert!(
                (last.eps[3] - exact).abs() <= 1e-12 * exact,
                "{n}: {} vs {exact}",
                last.eps[3]
            );
            last.eps[3]
        };
        let cont = s / g2 + g * w_inf * (1.0 - (-t_end * (1.0 - g) / tau).exp());
        crate::testing::assert_first_order("prony creep", 50, |n| {
            (discrete(n) - cont).abs() / cont
        });
    }

    /// In uniaxial stress the instantaneous response is the elastic one with `E, nu`, and
    /// the bulk part never relaxes: under a held axial strain the mean stress tends to
    /// `kappa tr eps` with the shear relaxed (checked against the closed form of a
    /// step of uniaxial strain with free lateral contraction at `t = 0+`).
    #[test]
    fn instantaneous_uniaxial_response_is_elastic() {
        let law = Prony::new(2).unwrap();
        let c = params(&THREE[..2]);
        let path = uniaxial_path(&law, &c, &[0.0; 12], &[(Shear::Strain(1e-3), 0.0)]).unwrap();
        let p = &path[0];
        assert!((p.sigma()[1] - E * 1e-3).abs() < 1e-10 * E * 1e-3);
        assert!((p.eps[0] + NU * 1e-3).abs() < 1e-13);
    }
}
