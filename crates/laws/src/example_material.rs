//! The worked example of docs/adding-a-law.md for a law with internal variables, compiled
//! and tested so that the guide cannot drift from the trait: a Burgers solid (a Maxwell
//! element in series with a Kelvin-Voigt element, in shear; bulk elastic). Compiled for the
//! crate's tests, and registered in [`crate::registry::REGISTRY`] behind the feature
//! `example-law` (`tests/example_law.rs` checks it from outside the crate).

use crate::LawError;
use crate::elastic::{E_INFO, NU_INFO, isotropic_compliance, isotropic_compliance_derivative};
use crate::law::{LocalFailure, ParamInfo};
use crate::mandel::{Mat4, Vec4};
use crate::material::{
    InternalInfo, Material, MaterialUpdate, Regime, Step, newton_update, stress_of,
};
use crate::registry::{Built, Fields, LawEntry, SpecFields, number, ordered_params};

/// Burgers solid, parameters `c = [E, nu, eta, Gk, etak]` (MPa, -, MPa s, MPa, MPa s);
/// state `y = [sigma, ek]`, `ek` the Kelvin element's (deviatoric) strain. Strain
/// `eps = S sigma + eps_v + ek` with the Maxwell dashpot `d eps_v/dt = P sigma / eta` and
/// the Kelvin element `P sigma = 2 Gk ek + 2 etak d ek/dt`. Backward Euler:
///
/// - `r_sigma = S (sigma_1 - sigma_0) + dt P sigma_1 / eta + (ek_1 - ek_0) - deps`,
/// - `r_k = etak (ek_1 - ek_0) - dt (P sigma_1 / 2 - Gk ek_1)`.
#[derive(Clone, Copy, Debug, Default)]
pub struct Burgers;

const ETA: usize = 2;
const GK: usize = 3;
const ETAK: usize = 4;

const fn positive(name: &'static str, unit: &'static str, description: &'static str) -> ParamInfo {
    ParamInfo {
        name,
        unit,
        description,
        min: 0.0,
        min_inclusive: false,
        max: f64::INFINITY,
        max_inclusive: false,
    }
}

const PARAMS: [ParamInfo; 5] = [
    E_INFO,
    NU_INFO,
    positive("eta", "MPa s", "viscosity of the Maxwell dashpot"),
    positive("Gk", "MPa", "shear modulus of the Kelvin spring"),
    positive("etak", "MPa s", "viscosity of the Kelvin dashpot"),
];

const INTERNAL: [InternalInfo; 4] = [
    InternalInfo {
        name: "ek_rr",
        unit: "-",
        description: "Kelvin strain, rr",
    },
    InternalInfo {
        name: "ek_zz",
        unit: "-",
        description: "Kelvin strain, zz",
    },
    InternalInfo {
        name: "ek_tt",
        unit: "-",
        description: "Kelvin strain, tt",
    },
    InternalInfo {
        name: "ek_rz",
        unit: "-",
        description: "Kelvin strain, sqrt2 rz",
    },
];

fn kelvin(y: &[f64]) -> Vec4 {
    Vec4([y[4], y[5], y[6], y[7]])
}

/// Writes the 4x4 block `b` at block row `bi`, block column `bj` of an 8x8 row-major matrix.
fn put(out: &mut [f64], bi: usize, bj: usize, b: &Mat4) {
    for i in 0..4 {
        out[(4 * bi + i) * 8 + 4 * bj..(4 * bi + i) * 8 + 4 * bj + 4].copy_from_slice(&b.0[i]);
    }
}

impl Material for Burgers {
    fn name(&self) -> &'static str {
        "burgers"
    }
    fn params(&self) -> &[ParamInfo] {
        &PARAMS
    }
    fn internal(&self) -> &[InternalInfo] {
        &INTERNAL
    }
    fn is_linear(&self) -> bool {
        true // every block depends on (c, dt) only
    }
    fn residual(&self, c: &[f64], step: &Step<'_>, r: &mut [f64]) {
        let (s0, s1) = (stress_of(step.y0), stress_of(step.y1));
        let (k0, k1) = (kelvin(step.y0), kelvin(step.y1));
        let dev = s1.deviator();
        let rs = isotropic_compliance(c[0], c[1]).mul_vec(&(s1 - s0))
            + dev * (step.dt / c[ETA])
            + (k1 - k0)
            - *step.deps;
        let rk = (k1 - k0) * c[ETAK] - (dev * 0.5 - k1 * c[GK]) * step.dt;
        r[..4].copy_from_slice(&rs.0);
        r[4..8].copy_from_slice(&rk.0);
    }
    fn jac_state(&self, c: &[f64], step: &Step<'_>, out: &mut [f64]) {
        let p = Mat4::deviatoric_projector();
        put(
            out,
            0,
            0,
            &(isotropic_compliance(c[0], c[1]) + p * (step.dt / c[ETA])),
        );
        put(out, 0, 1, &Mat4::IDENTITY);
        put(out, 1, 0, &(p * (-0.5 * step.dt)));
        put(out, 1, 1, &(Mat4::IDENTITY * (c[ETAK] + step.dt * c[GK])));
    }
    fn jac_previous(&self, c: &[f64], _step: &Step<'_>, out: &mut [f64]) {
        put(out, 0, 0, &(isotropic_compliance(c[0], c[1]) * -1.0));
        put(out, 0, 1, &(Mat4::IDENTITY * -1.0));
        put(out, 1, 0, &Mat4::ZERO);
        put(out, 1, 1, &(Mat4::IDENTITY * -c[ETAK]));
    }
    fn jac_params(&self, c: &[f64], step: &Step<'_>, out: &mut [f64]) {
        let (s0, s1) = (stress_of(step.y0), stress_of(step.y1));
        let (k0, k1) = (kelvin(step.y0), kelvin(step.y1));
        let cols = [
            (
                isotropic_compliance_derivative(c, 0).mul_vec(&(s1 - s0)),
                Vec4::ZERO,
            ),
            (
                isotropic_compliance_derivative(c, 1).mul_vec(&(s1 - s0)),
                Vec4::ZERO,
            ),
            (s1.deviator() * (-step.dt / (c[ETA] * c[ETA])), Vec4::ZERO),
            (Vec4::ZERO, k1 * step.dt),
            (Vec4::ZERO, k1 - k0),
        ];
        for (k, (top, bottom)) in cols.iter().enumerate() {
            for i in 0..4 {
                out[i * 5 + k] = top[i];
                out[(4 + i) * 5 + k] = bottom[i];
            }
        }
    }
    // The residual is linear in y: the generic Newton converges in one step.
    fn update(
        &self,
        c: &[f64],
        y0: &[f64],
        deps: &Vec4,
        dt: f64,
        y1: &mut [f64],
    ) -> Result<MaterialUpdate, LocalFailure> {
        newton_update(self, c, y0, deps, dt, Regime::Smooth, y1)
    }
}

/// Its registry entry: `Burgers(E: .., nu: .., eta: .., Gk: .., etak: ..)`; registering
/// the law is adding `example_material::ENTRY` to `REGISTRY`.
#[allow(dead_code)]
pub const ENTRY: LawEntry = LawEntry {
    name: "burgers",
    variant: "Burgers",
    summary: "Burgers viscoelasticity (Maxwell and Kelvin-Voigt in series, in shear)",
    example: "Burgers(E: 3000.0, nu: 0.35, eta: 50000.0, Gk: 800.0, etak: 2000.0)",
    fields: &[
        number("E"),
        number("nu"),
        number("eta"),
        number("Gk"),
        number("etak"),
    ],
    build: build_spec,
};

fn build_spec(fields: &SpecFields) -> Result<Built, LawError> {
    let mut f = Fields::new("burgers", "", fields);
    let names = ["E", "nu", "eta", "Gk", "etak"];
    let mut values = Vec::new();
    for n in names {
        values.push((n, f.number(n)?));
    }
    f.finish(&names)?;
    let params = ordered_params(&Burgers, &values)?;
    Ok(Built {
        material: Box::new(Burgers),
        params,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::{Point, Shear, check_material, shear_history};

    const C: [f64; 5] = [3000.0, 0.35, 5e4, 800.0, 2000.0];

    /// Every block against finite differences (the checks a law author runs with
    /// `laws::testing`, feature `testing`).
    #[test]
    fn every_block_matches_finite_differences() {
        let mut rng = crate::plastic::tests::Rng(11);
        for _ in 0..20 {
            let mut y0 = [0.0; 8];
            y0[..4].copy_from_slice(&(rng.vec4() * 20.0).0);
            y0[4..].copy_from_slice(&(rng.vec4() * 1e-3).deviator().0);
            let pt = Point {
                c: &C,
                y0: &y0,
                deps: rng.vec4() * 1e-2,
                dt: 10f64.powf(rng.next()),
            };
            check_material(&Burgers, &pt, 1e-6).unwrap();
        }
    }

    /// Creep under a held shear stress `s` (Mandel component): the Maxwell part is exact,
    /// `s t / eta`, the Kelvin part discrete `ek_n = s/(2 Gk) (1 - (etak/(etak + dt Gk))^n)`
    /// (to 1e-12) and continuous `s/(2 Gk) (1 - exp(-t Gk/etak))` (first order).
    #[test]
    fn creep_matches_the_discrete_and_continuous_solutions() {
        let (s, t_end) = (10.0, 4.0);
        let g2 = C[0] / (1.0 + C[1]);
        let discrete = |n: usize| {
            let dt = t_end / n as f64;
            let mut steps = vec![(Shear::Stress(s), 0.0)];
            steps.extend(std::iter::repeat_n((Shear::Stress(s), dt), n));
            let last = shear_history(&Burgers, &C, &[0.0; 8], &steps)
                .unwrap()
                .pop()
                .unwrap();
            let ek = s / (2.0 * C[GK]) * (1.0 - (C[ETAK] / (C[ETAK] + dt * C[GK])).powi(n as i32));
            let exact = s / g2 + s * t_end / C[ETA] + ek;
            assert!(
                (last.eps[3] - exact).abs() <= 1e-12 * exact,
                "{} vs {exact}",
                last.eps[3]
            );
            last.eps[3]
        };
        let cont = s / g2
            + s * t_end / C[ETA]
            + s / (2.0 * C[GK]) * (1.0 - (-t_end * C[GK] / C[ETAK]).exp());
        crate::testing::assert_first_order("burgers creep", 40, |n| {
            (discrete(n) - cont).abs() / cont
        });
    }

    /// The guide (docs/adding-a-law.md §4) shows this file's law, verbatim.
    #[test]
    fn the_guide_shows_this_code() {
        let me = include_str!("example_material.rs");
        let guide = include_str!("../../../docs/adding-a-law.md");
        let start = me.find("use crate::LawError;").unwrap();
        let end = me.find("#[cfg(test)]\nmod tests").unwrap();
        assert!(
            guide.contains(me[start..end].trim_end()),
            "docs/adding-a-law.md's Burgers example differs from example_material.rs"
        );
    }

    /// The entry builds the law with its parameters in order.
    #[test]
    fn entry_builds_the_law() {
        use crate::registry::SpecValue;
        let fields: Vec<(String, SpecValue)> = ["E", "nu", "eta", "Gk", "etak"]
            .iter()
            .zip(C)
            .map(|(n, v)| (n.to_string(), SpecValue::Number(v)))
            .collect();
        let b = (ENTRY.build)(&fields).unwrap();
        assert_eq!(b.params, C);
        assert_eq!(b.material.n_internal(), 4);
    }
}
