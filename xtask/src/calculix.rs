//! CalculiX referee for normal contact, friction and finite strain:
//! input decks of the reference problems R0, R1 and R2 on our own mesh (CAX8, node for
//! node), a rigid cone in node-to-surface penalty contact (surface-to-surface optional),
//! the reaction-force parser of the `.dat` file, and the comparison with our `Normal`
//! contact, `Normal(friction: mu)` and `kinematics: Finite`. `cargo xtask calculix` runs
//! them (not part of CI: it needs `ccx`).
//!
//! The contact (docs/validation-contact.md §9): node-to-surface penalty contact
//! (`*CONTACT PAIR, TYPE=NODE TO SURFACE`): each slave node (the specimen's top nodes) is
//! paired with the nearest face of the punch's flank, a spring along that face's normal
//! with `p = K x overclosure` (`PRESSURE-OVERCLOSURE=LINEAR`, ccx's default small tension
//! at large clearances), friction by a stick slope and Coulomb's `mu p`. Two changes keep
//! it off the axis, where CalculiX's expansion of axisymmetric elements into 3D collapses
//! faces: the punch's flank starts at `r = punch_r_min` (1e-4 mm, the CalculiX manual:
//! no master face may touch the axis), and the specimen's top face on the axis is left out
//! of the slave surface (with it, ccx stops on "matrix found to be singular" in the first
//! increment), so its two nodes at `r < h_1` (`h_1` = the first element's width, 0.0159
//! mm on the reference mesh) are not held by the punch.
//!
//! The material models (CalculiX 2.20, read in its source):
//! - elastic: `*ELASTIC` (isotropic, linear); with `NLGEOM` a compressible neo-Hooke
//!   solid of the same small-strain moduli (`*ELASTIC` would be St. Venant-Kirchhoff there),
//!   or with `--elastic mooney-rivlin` the Mooney-Rivlin solid `C10 = C01 = mu/4`,
//!   `D1 = 2/kappa`, whose isochoric part equals our Hencky-linear law's
//!   `mu |dev E|^2` to third order in the logarithmic strains ([`FiniteElastic`]);
//! - Maxwell and Norton-Hoff, small strain: the additive infinitesimal-strain
//!   viscoplastic model "elastic anisotropy with isotropic viscoplasticity"
//!   (`umat_aniso_plas.f`, material name `ANISO_PLAS...`, `*USER MATERIAL` with 15
//!   constants) given isotropic elastic constants. Its return map solves
//!   `|s| = sqrt(2/3) (r0 + (sqrt(2/3) dg / (A dt))^(1/n))` with `dg` the increment of
//!   the plastic multiplier along `s/|s|`, i.e. backward Euler of
//!   `eps_dot_eq = A <sigma_eq - r0>^n`, `eps_dot_p = (3/2) eps_dot_eq s / sigma_eq`:
//!   our Norton-Hoff (`eps_dot_vp = (3/2) <(sigma_eq - sY)/K>^m s/sigma_eq`) with
//!   `A = K^-m`, `n = m`, `r0 = sY`, and our Maxwell (`eps_dot_v = s/eta`) with
//!   `n = 1`, `A = 2/(3 eta)`, `r0 = 0`;
//! - the same with `NLGEOM` (finite strain): `*ELASTIC`, `*PLASTIC` (a constant yield
//!   stress sY) and `*CREEP, LAW=NORTON` (`A`, `n`, 0), CalculiX's multiplicative
//!   (Simo 1988) viscoplasticity of `incplas.f`: the overstress `q = sigma_eq - sY` of the
//!   Kirchhoff stress drives `eps_dot_eq = A q^n`; elasticity is hyperelastic (neo-Hooke
//!   deviatoric part, `K (J^2 - 1)/2` volumetric).
//! - rate-independent J2 plasticity (the cases `r2-j2-linear`, `r2-j2-power`, [`J2_CASES`]):
//!   `*ELASTIC` and `*PLASTIC` with the flow curve as points, the same points as our
//!   `Table(points)` (or our `Linear(H)`), `*STATIC`; docs/validation-laws.md §10;
//! - `--elastic hencky-umat` under `NLGEOM`: our own finite-strain law for every law
//!   (Hencky-linear elasticity, Maxwell, Norton-Hoff in the Hencky strain, backward
//!   Euler), the user material `USERHENCKY` of `validation/calculix/umat/umat_user.f`,
//!   run by a `ccx` built with it (`--ccx PATH`; [`FiniteElastic::HenckyUmat`]).

use std::fmt::Write as _;

use anyhow::{Result, bail};
use indentify_contact::{Punch, Schedule};
use indentify_mesh::Mesh;

pub mod force;

/// The specimen's material as CalculiX is told it.
#[derive(Clone, Debug, PartialEq)]
pub enum Material {
    /// Linear isotropic elasticity.
    Elastic {
        /// Young's modulus (MPa).
        e: f64,
        /// Poisson's ratio.
        nu: f64,
    },
    /// Elasticity in series with `eps_dot_eq = a <sigma_eq - sy>^n` (deviatoric flow).
    Viscoplastic {
        /// Young's modulus (MPa).
        e: f64,
        /// Poisson's ratio.
        nu: f64,
        /// Norton coefficient `A` (MPa^-n / s).
        a: f64,
        /// Norton exponent.
        n: f64,
        /// Yield stress (MPa), 0 for none.
        sy: f64,
    },
    /// Rate-independent J2 plasticity with isotropic hardening: `*ELASTIC` and `*PLASTIC`
    /// with the flow curve as points (CalculiX interpolates linearly between them and keeps
    /// the last stress beyond the last one).
    Plastic {
        /// Young's modulus (MPa).
        e: f64,
        /// Poisson's ratio.
        nu: f64,
        /// The flow curve `(eps_p, sigma)` (-, MPa), from `eps_p = 0`.
        curve: Vec<(f64, f64)>,
    },
}

impl Material {
    /// Our Maxwell law `[E, nu, eta]` as CalculiX's Norton creep with `n = 1`.
    pub fn maxwell(e: f64, nu: f64, eta: f64) -> Material {
        Material::Viscoplastic {
            e,
            nu,
            a: 2.0 / (3.0 * eta),
            n: 1.0,
            sy: 0.0,
        }
    }

    /// Our Norton-Hoff law `[E, nu, K, m, sY]`: `A = K^-m`, `n = m`.
    pub fn norton_hoff(e: f64, nu: f64, k: f64, m: f64, sy: f64) -> Material {
        Material::Viscoplastic {
            e,
            nu,
            a: k.powf(-m),
            n: m,
            sy,
        }
    }

    /// The material of a law named as in `indentify_laws` with its parameters.
    ///
    /// # Errors
    /// A law CalculiX cannot express here.
    pub fn from_law(name: &str, c: &[f64]) -> Result<Material> {
        Ok(match (name, c) {
            ("elastic", [e, nu]) => Material::Elastic { e: *e, nu: *nu },
            ("maxwell", [e, nu, eta]) => Material::maxwell(*e, *nu, *eta),
            ("norton-hoff", [e, nu, k, m, sy]) => Material::norton_hoff(*e, *nu, *k, *m, *sy),
            _ => bail!(
                "law `{name}` with {} parameters has no CalculiX deck",
                c.len()
            ),
        })
    }
}

/// CalculiX's contact formulation of a deck.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ContactType {
    /// `TYPE=NODE TO SURFACE`: a penalty spring per slave node (the default).
    NodeToSurface,
    /// `TYPE=SURFACE TO SURFACE`: face-to-face penalty contact, integrated over the slave
    /// faces (R0's earlier runs; its viscoplastic runs cycle, docs/validation-contact.md §9).
    SurfaceToSurface,
}

impl ContactType {
    /// The value of `TYPE=` on `*CONTACT PAIR`.
    pub fn keyword(self) -> &'static str {
        match self {
            ContactType::NodeToSurface => "NODE TO SURFACE",
            ContactType::SurfaceToSurface => "SURFACE TO SURFACE",
        }
    }

    /// Parses `node-to-surface` or `surface-to-surface`.
    ///
    /// # Errors
    /// Any other spelling, named.
    pub fn from_name(name: &str) -> Result<ContactType> {
        match name {
            "node-to-surface" => Ok(ContactType::NodeToSurface),
            "surface-to-surface" => Ok(ContactType::SurfaceToSurface),
            _ => bail!("--contact: `{name}` is not node-to-surface or surface-to-surface"),
        }
    }
}

/// CalculiX's hyperelastic solid for our elastic law under `NLGEOM` (CalculiX cannot
/// express Hencky's energy `mu |dev E|^2 + kappa (ln J)^2 / 2` exactly).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FiniteElastic {
    /// `*HYPERELASTIC, NEO HOOKE`: `C10 = mu/2`, `D1 = 2/kappa` (the default). Its
    /// isochoric energy differs from Hencky's at second order in the strains (in
    /// compression about 1% per 1% strain softer).
    NeoHooke,
    /// `*HYPERELASTIC, MOONEY-RIVLIN`: `C10 = C01 = mu/4`, `D1 = 2/kappa`. In the
    /// isochoric principal stretches it is Ogden's `sum_p 2 mu_p/alpha_p^2 (sum_i
    /// lambda_i^alpha_p - 3)` with `alpha = (2, -2)`, `mu_p = mu/2`: the cubic term of its
    /// expansion in the log strains cancels (`sum_p mu_p alpha_p = 0`), so it equals
    /// Hencky's `mu |dev E|^2` up to a relative stress error of about `(2/3) eps^2`. The
    /// volumetric parts still differ (`kappa (J - 1)` against `kappa ln(J)/J` for the
    /// pressure), which vanishes as `nu -> 1/2`.
    MooneyRivlin,
    /// Our own law, exactly: the user material of `validation/calculix/umat/umat_user.f`
    /// (`*MATERIAL, NAME=USERHENCKY`, `*USER MATERIAL` with `E, nu` (elastic),
    /// `E, nu, eta` (Maxwell) or `E, nu, K, m, sY` (Norton-Hoff), `*DEPVAR 6`: the
    /// viscous strain): `T = C : (E - E_v)` in the Hencky strain `E = ln(C)/2`, the
    /// small-strain update of `crates/laws` by backward Euler, `S = P : T`. Unlike the
    /// others it also replaces the viscoplastic materials under `NLGEOM` (CalculiX's
    /// creep material fixes Simo's neo-Hookean elasticity). It needs a `ccx` linked with
    /// that user material (`validation/calculix/umat/build.sh`, `--ccx PATH`): the
    /// stock `ccx` stops on it. Such a run checks the kinematics, element, contact and
    /// time integration, not the law (the same formulation on both sides).
    HenckyUmat,
}

impl FiniteElastic {
    /// Parses `neo-hooke`, `mooney-rivlin` or `hencky-umat`.
    ///
    /// # Errors
    /// Any other spelling, named.
    pub fn from_name(name: &str) -> Result<FiniteElastic> {
        match name {
            "neo-hooke" => Ok(FiniteElastic::NeoHooke),
            "mooney-rivlin" => Ok(FiniteElastic::MooneyRivlin),
            "hencky-umat" => Ok(FiniteElastic::HenckyUmat),
            _ => bail!("--elastic: `{name}` is not neo-hooke, mooney-rivlin or hencky-umat"),
        }
    }

    /// The suffix of a run's file stem (`-mr` for Mooney-Rivlin, `-hencky` for the user
    /// material, none for the default).
    pub fn suffix(self) -> &'static str {
        match self {
            FiniteElastic::NeoHooke => "",
            FiniteElastic::MooneyRivlin => "-mr",
            FiniteElastic::HenckyUmat => "-hencky",
        }
    }

    /// Whether it changes the `NLGEOM` deck of `material` (the hyperelastic solids
    /// replace only the elastic law; the user material replaces every law).
    pub fn applies_to(self, material: &Material) -> bool {
        match self {
            FiniteElastic::HenckyUmat => true,
            FiniteElastic::NeoHooke | FiniteElastic::MooneyRivlin => {
                matches!(material, Material::Elastic { .. })
            }
        }
    }
}

/// Thickness of the rigid punch's strip of CAX4 elements above its flank (mm).
pub const PUNCH_THICKNESS: f64 = 0.05;

/// Options of a deck.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DeckOptions {
    /// The contact formulation.
    pub contact: ContactType,
    /// Radius at which the punch's flank starts (mm): a master face touching the axis
    /// has no normal in CalculiX's 3D expansion.
    pub punch_r_min: f64,
    /// Geometrically nonlinear (finite strain) analysis.
    pub nlgeom: bool,
    /// The hyperelastic solid of an elastic law under `NLGEOM`.
    pub finite_elastic: FiniteElastic,
    /// The loading segment as its own `*STEP`, the rest of the history as a second one
    /// (amplitude and time points in total time).
    pub split_load: bool,
    /// Increments per schedule step in the first `*STEP` (the loading with `split_load`,
    /// the whole history otherwise): its initial and largest increment is
    /// `dt / load_substeps` (1: `dt`; the `NLGEOM` friction run of R2 sY = 0 with
    /// mu = 0.2 needs 3, docs/validation-finite-strain.md §7).
    pub load_substeps: usize,
    /// Coulomb friction coefficient (0: frictionless, no `*FRICTION` card).
    pub friction: f64,
    /// Slope of the linear pressure-overclosure law (MPa/mm).
    pub penalty: f64,
    /// Stick slope of the friction law (MPa/mm), used when `friction > 0`.
    pub stick_slope: f64,
    /// Radius up to which the rigid cone is meshed (mm).
    pub punch_radius: f64,
    /// Faces of the rigid cone's flank.
    pub punch_segments: usize,
}

impl Default for DeckOptions {
    fn default() -> DeckOptions {
        DeckOptions {
            contact: ContactType::NodeToSurface,
            punch_r_min: 1e-4,
            nlgeom: false,
            finite_elastic: FiniteElastic::NeoHooke,
            split_load: false,
            load_substeps: 1,
            friction: 0.0,
            penalty: 1e9,
            stick_slope: 1e8,
            punch_radius: 0.6,
            punch_segments: 60,
        }
    }
}

/// The top faces of the specimen: `(element, local edge 0..4)` whose two corners lie on
/// `z = 0` (the edge `k` joins corners `k` and `k + 1 mod 4`; CalculiX face `S(k+1)`).
pub fn top_faces(mesh: &Mesh) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    for (e, el) in mesh.elements.iter().enumerate() {
        for k in 0..4 {
            let (a, b) = (el[k], el[(k + 1) % 4]);
            if mesh.nodes[a][1] == 0.0 && mesh.nodes[b][1] == 0.0 {
                out.push((e, k));
            }
        }
    }
    out
}

/// The slave faces of a deck: [`top_faces`], without the face touching the axis for
/// node-to-surface contact (its axis node makes ccx's matrix singular).
pub fn slave_faces(mesh: &Mesh, contact: ContactType) -> Vec<(usize, usize)> {
    top_faces(mesh)
        .into_iter()
        .filter(|&(e, k)| {
            let el = mesh.elements[e];
            contact == ContactType::SurfaceToSurface
                || (mesh.nodes[el[k]][0] > 0.0 && mesh.nodes[el[(k + 1) % 4]][0] > 0.0)
        })
        .collect()
}

/// The uniform time step of `schedule`, or an error if its steps are not uniform.
///
/// # Errors
/// Steps differing by more than 1e-9 relative.
pub fn uniform_step(schedule: &Schedule) -> Result<f64> {
    let t = &schedule.t;
    if t.len() < 2 {
        bail!("the schedule has no step");
    }
    let dt = t[1] - t[0];
    for w in t.windows(2) {
        if ((w[1] - w[0]) - dt).abs() > 1e-9 * dt {
            bail!(
                "the CalculiX decks use fixed increments: the schedule's steps differ ({} s and {} s)",
                dt,
                w[1] - w[0]
            );
        }
    }
    Ok(dt)
}

/// The depth history's corners: `(t, depth)` where the rate changes, with the first and
/// last points (the amplitude table of the deck).
pub fn corners(schedule: &Schedule) -> Vec<(f64, f64)> {
    let (t, h) = (&schedule.t, &schedule.depth);
    let mut out = vec![(t[0], h[0])];
    for i in 1..t.len() - 1 {
        let r0 = (h[i] - h[i - 1]) / (t[i] - t[i - 1]);
        let r1 = (h[i + 1] - h[i]) / (t[i + 1] - t[i]);
        if (r1 - r0).abs() > 1e-9 * (r0.abs() + r1.abs() + 1e-300) {
            out.push((t[i], h[i]));
        }
    }
    out.push((t[t.len() - 1], h[h.len() - 1]));
    out
}

/// The CalculiX input deck of `mesh` under the rigid cone of `punch` driven by
/// `schedule` (depth into the body, the tip starting on the surface at the axis).
///
/// Node `i` and element `e` of `mesh` are CalculiX's `i + 1` and `e + 1` (CAX8, the same
/// node order); the cone is a strip of CAX4 elements whose lower faces are the flank,
/// every node of it prescribed (a rigid body by kinematics, its reaction the punch force).
///
/// # Errors
/// A punch other than a cone, a non-uniform schedule, a J2 material under the user
/// material.
pub fn deck(
    title: &str,
    mesh: &Mesh,
    punch: &Punch,
    material: &Material,
    schedule: &Schedule,
    o: &DeckOptions,
) -> Result<String> {
    let Punch::Cone { half_angle_deg } = punch else {
        bail!(
            "the CalculiX decks model a cone; {} is not one",
            punch.describe()
        )
    };
    let cot = 1.0 / half_angle_deg.to_radians().tan();
    let dt = uniform_step(schedule)?;
    let t_end = schedule.t[schedule.t.len() - 1];
    let h_ref = schedule.depth.iter().copied().fold(0.0, f64::max);
    if h_ref <= 0.0 {
        bail!("the schedule never presses the punch in");
    }
    let mut s = String::new();
    let w = &mut s;
    head_cards(w, title, mesh, cot, material, o)?;
    // amplitude and time points in total time when the history spans several steps
    let total = if o.split_load {
        ", TIME=TOTAL TIME"
    } else {
        ""
    };
    writeln!(w, "*AMPLITUDE, NAME=DEPTH{total}")?;
    for (t, h) in corners(schedule) {
        writeln!(w, "{t:.12e}, {:.12e}", h / h_ref)?;
    }
    writeln!(w, "*BOUNDARY")?;
    writeln!(w, "AXIS, 1, 1")?;
    writeln!(w, "BOTTOM, 2, 2")?;
    writeln!(w, "PUNCH, 1, 1")?;
    writeln!(w, "*TIME POINTS, NAME=TP{total}")?;
    for t in &schedule.t[1..] {
        writeln!(w, "{t:.12e}")?;
    }
    let n_inc = 20 * schedule.t.len();
    let procedure = match material {
        Material::Elastic { .. } | Material::Plastic { .. } => "*STATIC",
        Material::Viscoplastic { .. } => "*VISCO",
    };
    // One step, or (split_load) the loading segment and the rest as two steps: a step
    // starts without extrapolating the previous increment's velocity, which at the
    // corner of the trapezoid drove the NLGEOM runs' tip nodes off (§3.1 of
    // docs/validation-finite-strain.md).
    let steps: Vec<f64> = match corners(schedule).get(1) {
        Some(&(t1, _)) if o.split_load && t1 < t_end => vec![t1, t_end - t1],
        _ => vec![t_end],
    };
    if o.load_substeps == 0 {
        bail!("load_substeps = 0: expected at least 1 increment per schedule step");
    }
    for (k, duration) in steps.into_iter().enumerate() {
        // the first step's increments: dt / load_substeps (the minimum stays dt 1e-4)
        let inc = if k == 0 {
            dt / o.load_substeps as f64
        } else {
            dt
        };
        if o.nlgeom {
            writeln!(w, "*STEP, NLGEOM, INC={n_inc}")?;
        } else {
            writeln!(w, "*STEP, INC={n_inc}")?;
        }
        // Automatic incrementation capped at the schedule's step (fixed increments,
        // DIRECT, stop the viscoplastic runs when CalculiX's divergence check fires); the
        // time points make every schedule time an increment's end, so the curves share
        // our time grid (CalculiX cuts an increment where its Newton iteration needs it,
        // nowhere else). CETOL is required by *VISCO but only used by isotropic creep
        // with automatic incrementation's creep-strain control: 1.0 switches that
        // control off. More Newton iterations before CalculiX declares divergence and
        // cuts the increment (I_0 = 20, I_R = 30, I_A = 200 iterations, 20 cutbacks).
        writeln!(w, "*CONTROLS, PARAMETERS=TIME INCREMENTATION")?;
        writeln!(w, "20, 30, 9, 200, 10, 4, , 20")?;
        if procedure == "*VISCO" {
            writeln!(w, "{procedure}, CETOL=1.0")?;
        } else {
            writeln!(w, "{procedure}")?;
        }
        writeln!(
            w,
            "{inc:.12e}, {duration:.12e}, {:.12e}, {inc:.12e}",
            dt * 1e-4
        )?;
        writeln!(w, "*BOUNDARY, AMPLITUDE=DEPTH")?;
        writeln!(w, "PUNCH, 2, 2, {:.12e}", -h_ref)?;
        writeln!(w, "*NODE PRINT, NSET=PUNCH, TOTALS=ONLY, TIME POINTS=TP")?;
        writeln!(w, "RF")?;
        writeln!(w, "*END STEP")?;
    }
    Ok(s)
}

/// The cards every deck opens with: the title, the geometry ([`geometry_cards`]), the
/// specimen's and the rigid punch's materials and the contact pair.
pub(crate) fn head_cards(
    w: &mut String,
    title: &str,
    mesh: &Mesh,
    cot: f64,
    material: &Material,
    o: &DeckOptions,
) -> Result<()> {
    writeln!(w, "** {title}")?;
    writeln!(
        w,
        "** generated by `cargo xtask calculix` (xtask/src/calculix.rs); units N, mm, s, MPa"
    )?;
    writeln!(
        w,
        "** axisymmetric: x = r, y = z; CalculiX's CAX elements model a 2-degree wedge: full force = 180 x RF"
    )?;
    // nodes, elements, sets and surfaces
    geometry_cards(w, mesh, cot, o)?;
    // materials
    material_cards(w, material, o)?;
    writeln!(w, "*MATERIAL, NAME=RIGID")?;
    writeln!(w, "*ELASTIC")?;
    writeln!(w, "1e7, 0.3")?;
    writeln!(w, "*SOLID SECTION, ELSET=EPUNCH, MATERIAL=RIGID")?;
    // contact
    writeln!(w, "*SURFACE INTERACTION, NAME=SI")?;
    writeln!(w, "*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR")?;
    writeln!(w, "{:e}", o.penalty)?;
    if o.friction > 0.0 {
        writeln!(w, "*FRICTION")?;
        writeln!(w, "{}, {:e}", o.friction, o.stick_slope)?;
    }
    writeln!(
        w,
        "*CONTACT PAIR, INTERACTION=SI, TYPE={}",
        o.contact.keyword()
    )?;
    writeln!(w, "STOP, SPUNCH")?;
    Ok(())
}

/// The nodes and elements of the specimen (CAX8) and of the cone's strip (CAX4), the node
/// sets and the contact surfaces; `cot` is the cone's `cot(half-angle)`.
fn geometry_cards(w: &mut String, mesh: &Mesh, cot: f64, o: &DeckOptions) -> Result<()> {
    writeln!(w, "*NODE, NSET=NSPEC")?;
    for (i, p) in mesh.nodes.iter().enumerate() {
        writeln!(w, "{}, {:.12e}, {:.12e}, 0.0", i + 1, p[0], p[1])?;
    }
    let n0 = mesh.nodes.len();
    let np = o.punch_segments;
    let thickness = PUNCH_THICKNESS;
    writeln!(w, "*NODE, NSET=PUNCH")?;
    if !(o.punch_r_min >= 0.0 && o.punch_r_min < o.punch_radius / np as f64) {
        bail!(
            "the punch's flank starts at r = {} mm: expected 0 <= r < {} mm (its first face)",
            o.punch_r_min,
            o.punch_radius / np as f64
        );
    }
    for j in 0..=np {
        let r = if j == 0 {
            o.punch_r_min
        } else {
            o.punch_radius * j as f64 / np as f64
        };
        writeln!(w, "{}, {:.12e}, {:.12e}, 0.0", n0 + 1 + j, r, r * cot)?;
        writeln!(
            w,
            "{}, {:.12e}, {:.12e}, 0.0",
            n0 + np + 2 + j,
            r,
            r * cot + thickness
        )?;
    }
    writeln!(w, "*ELEMENT, TYPE=CAX8, ELSET=ESPEC")?;
    for (e, el) in mesh.elements.iter().enumerate() {
        write!(w, "{}", e + 1)?;
        for n in el {
            write!(w, ", {}", n + 1)?;
        }
        writeln!(w)?;
    }
    let e0 = mesh.elements.len();
    writeln!(w, "*ELEMENT, TYPE=CAX4, ELSET=EPUNCH")?;
    for j in 0..np {
        let (b0, b1) = (n0 + 1 + j, n0 + 2 + j);
        let (t0, t1) = (n0 + np + 2 + j, n0 + np + 3 + j);
        writeln!(w, "{}, {b0}, {b1}, {t1}, {t0}", e0 + 1 + j)?;
    }
    writeln!(w, "*NSET, NSET=AXIS")?;
    write_ids(w, mesh.node_set("axis").iter().map(|n| n + 1))?;
    writeln!(w, "*NSET, NSET=BOTTOM")?;
    write_ids(w, mesh.node_set("bottom").iter().map(|n| n + 1))?;
    writeln!(w, "*SURFACE, NAME=STOP, TYPE=ELEMENT")?;
    for (e, k) in slave_faces(mesh, o.contact) {
        writeln!(w, "{}, S{}", e + 1, k + 1)?;
    }
    writeln!(w, "*SURFACE, NAME=SPUNCH, TYPE=ELEMENT")?;
    for j in 0..np {
        writeln!(w, "{}, S1", e0 + 1 + j)?;
    }
    Ok(())
}

/// The specimen's material cards (`*MATERIAL`, its model, `*SOLID SECTION`): small or
/// finite strain, CalculiX's own models or the user materials.
///
/// # Errors
/// A J2 material under the user material (it has no hardening).
fn material_cards(w: &mut String, material: &Material, o: &DeckOptions) -> Result<()> {
    if o.nlgeom
        && o.finite_elastic == FiniteElastic::HenckyUmat
        && matches!(material, Material::Plastic { .. })
    {
        bail!(
            "the user material USERHENCKY has no hardening: run the J2 cases with CalculiX's own *PLASTIC (no --elastic hencky-umat)"
        );
    }
    match *material {
        _ if o.nlgeom && o.finite_elastic == FiniteElastic::HenckyUmat => {
            let constants = hencky_umat_constants(material);
            writeln!(
                w,
                "** finite strain: our own law as the user material of validation/calculix/umat/umat_user.f"
            )?;
            writeln!(
                w,
                "** (Hencky strain, the small-strain update of crates/laws, S = P : T; needs ccx built by its build.sh)"
            )?;
            writeln!(w, "*MATERIAL, NAME=USERHENCKY")?;
            writeln!(w, "*USER MATERIAL, CONSTANTS={}", constants.len())?;
            let line: Vec<String> = constants.iter().map(|c| format!("{c:.15e}")).collect();
            writeln!(w, "{}", line.join(", "))?;
            writeln!(w, "*DEPVAR")?;
            writeln!(w, "6")?;
            writeln!(w, "*SOLID SECTION, ELSET=ESPEC, MATERIAL=USERHENCKY")?;
        }
        Material::Elastic { e, nu } if o.nlgeom => {
            // CalculiX's *ELASTIC with NLGEOM is St. Venant-Kirchhoff (PK2 linear in the
            // Green strain), which softens under the compression at the cone's tip (its
            // stress vanishes at a stretch of 1/sqrt(3)): the elastic force at 0.05 mm came
            // out at half the small-strain one. A compressible neo-Hooke solid with the
            // same small-strain moduli is used instead: W = C10 (I1b - 3) + (J - 1)^2 / D1,
            // C10 = mu/2, D1 = 2/kappa.
            // With `finite_elastic: MooneyRivlin`, C10 = C01 = mu/4 (see [`FiniteElastic`]).
            let mu = e / (2.0 * (1.0 + nu));
            let kappa = e / (3.0 * (1.0 - 2.0 * nu));
            writeln!(w, "*MATERIAL, NAME=SPEC")?;
            match o.finite_elastic {
                // (the user material is written by the first arm above)
                FiniteElastic::NeoHooke | FiniteElastic::HenckyUmat => {
                    writeln!(w, "*HYPERELASTIC, NEO HOOKE")?;
                    writeln!(w, "{:.12e}, {:.12e}", mu / 2.0, 2.0 / kappa)?;
                }
                FiniteElastic::MooneyRivlin => {
                    writeln!(w, "*HYPERELASTIC, MOONEY-RIVLIN")?;
                    writeln!(
                        w,
                        "{:.12e}, {:.12e}, {:.12e}",
                        mu / 4.0,
                        mu / 4.0,
                        2.0 / kappa
                    )?;
                }
            }
            writeln!(w, "*SOLID SECTION, ELSET=ESPEC, MATERIAL=SPEC")?;
        }
        Material::Elastic { e, nu } => {
            writeln!(w, "*MATERIAL, NAME=SPEC")?;
            writeln!(w, "*ELASTIC")?;
            writeln!(w, "{e:e}, {nu}")?;
            writeln!(w, "*SOLID SECTION, ELSET=ESPEC, MATERIAL=SPEC")?;
        }
        Material::Viscoplastic { e, nu, a, n, sy } if o.nlgeom => {
            writeln!(
                w,
                "** finite strain: CalculiX's multiplicative viscoplasticity (incplas.f)"
            )?;
            writeln!(w, "*MATERIAL, NAME=SPEC")?;
            writeln!(w, "*ELASTIC")?;
            writeln!(w, "{e:e}, {nu}")?;
            if sy > 0.0 {
                writeln!(w, "*PLASTIC")?;
                writeln!(w, "{sy:e}, 0.0")?;
            }
            writeln!(w, "*CREEP, LAW=NORTON")?;
            writeln!(w, "{a:.12e}, {n}, 0.0")?;
            writeln!(w, "*SOLID SECTION, ELSET=ESPEC, MATERIAL=SPEC")?;
        }
        Material::Plastic { e, nu, ref curve } => {
            // small strain and NLGEOM alike: CalculiX's incremental J2 plasticity of
            // incplas.f (under NLGEOM Simo's multiplicative model with its neo-Hookean
            // elasticity, docs/validation-finite-strain.md §3.1)
            writeln!(
                w,
                "** rate-independent J2 plasticity, isotropic hardening: *PLASTIC (sigma, eps_p)"
            )?;
            writeln!(w, "*MATERIAL, NAME=SPEC")?;
            writeln!(w, "*ELASTIC")?;
            writeln!(w, "{e:e}, {nu}")?;
            writeln!(w, "*PLASTIC, HARDENING=ISOTROPIC")?;
            for (eps, sigma) in curve {
                writeln!(w, "{sigma:.12e}, {eps:.12e}")?;
            }
            writeln!(w, "*SOLID SECTION, ELSET=ESPEC, MATERIAL=SPEC")?;
        }
        Material::Viscoplastic { e, nu, a, n, sy } => {
            let lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
            let mu = e / (2.0 * (1.0 + nu));
            let d11 = lambda + 2.0 * mu;
            writeln!(
                w,
                "** small strain: the additive viscoplastic model of umat_aniso_plas.f with isotropic constants"
            )?;
            writeln!(
                w,
                "** D1111 D1122 D2222 D1133 D2233 D3333 D1212 D1313 / D2323 r0 H_iso H_kin A n m T"
            )?;
            writeln!(w, "*MATERIAL, NAME=ANISO_PLAS_SPEC")?;
            writeln!(w, "*USER MATERIAL, CONSTANTS=15")?;
            writeln!(
                w,
                "{d11:.12e}, {lambda:.12e}, {d11:.12e}, {lambda:.12e}, {lambda:.12e}, {d11:.12e}, {mu:.12e}, {mu:.12e}"
            )?;
            writeln!(w, "{mu:.12e}, {sy:e}, 0.0, 0.0, {a:.12e}, {n}, 0.0, 0.0")?;
            writeln!(w, "*DEPVAR")?;
            writeln!(w, "14")?;
            writeln!(w, "*SOLID SECTION, ELSET=ESPEC, MATERIAL=ANISO_PLAS_SPEC")?;
        }
    }
    Ok(())
}

/// The constants of the user material `USERHENCKY` (`validation/calculix/umat/umat_user.f`)
/// for `material`: `[E, nu]` (elastic), `[E, nu, eta]` (Maxwell: `n = 1`, no yield stress,
/// `eta = 2/(3 A)`) or `[E, nu, K, m, sY]` (Norton-Hoff: `K = A^(-1/n)`, `m = n`), the
/// parameters of our laws back from CalculiX's creep constants ([`Material::maxwell`],
/// [`Material::norton_hoff`]).
pub fn hencky_umat_constants(material: &Material) -> Vec<f64> {
    match *material {
        Material::Elastic { e, nu } | Material::Plastic { e, nu, .. } => vec![e, nu],
        Material::Viscoplastic { e, nu, a, n, sy } if n == 1.0 && sy == 0.0 => {
            vec![e, nu, 2.0 / (3.0 * a)]
        }
        Material::Viscoplastic { e, nu, a, n, sy } => vec![e, nu, a.powf(-1.0 / n), n, sy],
    }
}

fn write_ids(w: &mut String, ids: impl Iterator<Item = usize>) -> std::fmt::Result {
    let ids: Vec<usize> = ids.collect();
    for chunk in ids.chunks(16) {
        let line: Vec<String> = chunk.iter().map(usize::to_string).collect();
        writeln!(w, "{},", line.join(", "))?;
    }
    Ok(())
}

/// The punch force history of a `.dat` file: `(t, F)` with `F = -180 RF_y` of the set
/// PUNCH (CalculiX's axisymmetric reactions are those of a 2-degree wedge; the reaction
/// on the punch is upward when it presses down, so `F > 0` in compression).
///
/// # Errors
/// A total-force block without its values.
pub fn parse_dat(text: &str) -> Result<Vec<(f64, f64)>> {
    dat_blocks(text, |l| {
        l.starts_with("total force") && l.contains("PUNCH")
    })?
    .into_iter()
    .map(|b| {
        if b.values.len() < 2 {
            bail!(
                "cannot read the total force `{}` after `{}`",
                b.raw,
                b.header
            );
        }
        Ok((b.t, -180.0 * b.values[1]))
    })
    .collect()
}

/// One block of a `.dat` file: its header line, the time the header ends with, and the
/// first non-empty line after it (as written and as numbers).
pub struct DatBlock<'a> {
    /// The header line, trimmed.
    pub header: &'a str,
    /// The time at its end (s).
    pub t: f64,
    /// The first non-empty line after it, trimmed.
    pub raw: &'a str,
    /// The numbers of that line.
    pub values: Vec<f64>,
}

/// The blocks of a `.dat` file whose (trimmed) header line `wanted` accepts, in order.
///
/// # Errors
/// A header without its time or its values.
pub fn dat_blocks<'a>(text: &'a str, wanted: impl Fn(&str) -> bool) -> Result<Vec<DatBlock<'a>>> {
    let mut out = Vec::new();
    let mut lines = text.lines();
    while let Some(line) = lines.next() {
        let header = line.trim();
        if !wanted(header) {
            continue;
        }
        let t: f64 = header
            .rsplit("time")
            .next()
            .map(str::trim)
            .and_then(|s| s.parse().ok())
            .ok_or_else(|| anyhow::anyhow!("no time in `{header}`"))?;
        let raw = lines
            .by_ref()
            .map(str::trim)
            .find(|s| !s.is_empty())
            .ok_or_else(|| anyhow::anyhow!("no values after `{header}`"))?;
        let values = raw
            .split_whitespace()
            .filter_map(|x| x.parse().ok())
            .collect();
        out.push(DatBlock {
            header,
            t,
            raw,
            values,
        });
    }
    Ok(out)
}

/// Linear interpolation of a curve `(t, F)` at `t` (`None` outside it).
pub fn at(curve: &[(f64, f64)], t: f64) -> Option<f64> {
    let i = curve.iter().position(|p| p.0 >= t - 1e-9)?;
    if (curve[i].0 - t).abs() <= 1e-9 {
        return Some(curve[i].1);
    }
    if i == 0 {
        return None;
    }
    let (a, b) = (curve[i - 1], curve[i]);
    Some(a.1 + (b.1 - a.1) * (t - a.0) / (b.0 - a.0))
}

/// One reference problem of the comparison.
#[derive(Clone, Debug, PartialEq)]
pub struct Case {
    /// Short name (`r0`, `r1`, `r2`, `r2-sy0`).
    pub name: &'static str,
    /// The example configuration (relative to the workspace root).
    pub example: &'static str,
    /// `--set` overrides on top of `contact=Normal`.
    pub sets: &'static [&'static str],
}

/// R0 (elastic), R1 (Maxwell), R2 (Norton-Hoff, sY = 500) and R2 with sY = 0; R0 with
/// `nu = 0.49` isolates the kinematics from the volumetric elastic law (`r0-nu049`, not run
/// by default); R2's problem with rate-independent J2 plasticity, linear and power-law
/// hardening (`r2-j2-linear`, `r2-j2-power`, [`J2_CASES`], not run by default).
pub const CASES: [Case; 7] = [
    Case {
        name: "r0",
        example: "examples/r0-elastic.ron",
        sets: &[],
    },
    Case {
        name: "r0-nu049",
        example: "examples/r0-elastic.ron",
        sets: &["law.nu=0.49"],
    },
    Case {
        name: "r1",
        example: "examples/r1-maxwell.ron",
        sets: &[],
    },
    Case {
        name: "r2",
        example: "examples/r2-norton-hoff.ron",
        sets: &[],
    },
    Case {
        name: "r2-sy0",
        example: "examples/r2-norton-hoff.ron",
        sets: &["law.sY=0"],
    },
    Case {
        name: "r2-j2-linear",
        example: "examples/r2-norton-hoff.ron",
        sets: &[],
    },
    Case {
        name: "r2-j2-power",
        example: "examples/r2-norton-hoff.ron",
        sets: &[],
    },
];

/// The hardening of a J2 case.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum J2Hardening {
    /// `sigma = sY + H eps_p`: ours `Linear(H)`, CalculiX's `*PLASTIC` two points (the last
    /// at [`J2_EPS_LAST`]).
    Linear {
        /// Hardening modulus (MPa).
        h: f64,
    },
    /// Dao's `sigma = sY (1 + E eps_p / sY)^n` as a table of [`J2_POINTS`] points
    /// (`eps_p` = 0, then geometric from 1e-5 to [`J2_EPS_LAST`]): the same table is our
    /// `Table(points)` and CalculiX's `*PLASTIC`, so both codes run one law.
    PowerTable {
        /// Hardening exponent.
        n: f64,
    },
}

/// The last plastic strain of a J2 case's table (CalculiX keeps the stress constant beyond
/// it, ours extends the last slope; no point of R2 comes near it).
pub const J2_EPS_LAST: f64 = 5.0;
/// Points of the power-law table.
pub const J2_POINTS: usize = 41;

/// A J2 case: R2's mesh, cone and trapezoid (`examples/r2-norton-hoff.ron`) with a
/// rate-independent `Plastic` law, its flow curve given to both codes point for point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct J2Case {
    /// The case's name in [`CASES`].
    pub name: &'static str,
    /// Young's modulus (MPa).
    pub e: f64,
    /// Poisson's ratio.
    pub nu: f64,
    /// Initial yield stress (MPa).
    pub sy: f64,
    /// The hardening.
    pub hardening: J2Hardening,
}

/// The J2 cases: R2's `E`, `nu`, `sY` with linear hardening `H = E/10` and Dao's power
/// law with `n = 0.2`.
pub const J2_CASES: [J2Case; 2] = [
    J2Case {
        name: "r2-j2-linear",
        e: 1e5,
        nu: 0.3,
        sy: 500.0,
        hardening: J2Hardening::Linear { h: 10000.0 },
    },
    J2Case {
        name: "r2-j2-power",
        e: 1e5,
        nu: 0.3,
        sy: 500.0,
        hardening: J2Hardening::PowerTable { n: 0.2 },
    },
];

/// The J2 case named `name`, if it is one.
pub fn j2_case(name: &str) -> Option<J2Case> {
    J2_CASES.iter().copied().find(|c| c.name == name)
}

impl J2Case {
    /// The flow curve `(eps_p, sigma)` both codes are given.
    pub fn curve(&self) -> Vec<(f64, f64)> {
        match self.hardening {
            J2Hardening::Linear { h } => {
                vec![(0.0, self.sy), (J2_EPS_LAST, self.sy + h * J2_EPS_LAST)]
            }
            J2Hardening::PowerTable { n } => {
                let first: f64 = 1e-5;
                let ratio = (J2_EPS_LAST / first).powf(1.0 / (J2_POINTS - 2) as f64);
                std::iter::once(0.0)
                    .chain((0..J2_POINTS - 1).map(|i| first * ratio.powi(i as i32)))
                    .map(|p| (p, self.sy * (1.0 + self.e * p / self.sy).powf(n)))
                    .collect()
            }
        }
    }

    /// Our law: `Plastic(E, nu, sY, hardening: Linear(H))` or `Table(points)` of
    /// [`J2Case::curve`], rate-independent.
    pub fn law(&self) -> String {
        let hardening = match self.hardening {
            J2Hardening::Linear { h } => format!("Linear(H: {h:?})"),
            J2Hardening::PowerTable { .. } => {
                let points: Vec<String> = self
                    .curve()
                    .iter()
                    .map(|(p, s)| format!("({p:?}, {s:?})"))
                    .collect();
                format!("Table(points: [{}])", points.join(", "))
            }
        };
        format!(
            "Plastic(E: {:?}, nu: {:?}, sY: {:?}, hardening: {hardening})",
            self.e, self.nu, self.sy
        )
    }

    /// The configuration: R2's (`examples/r2-norton-hoff.ron`: 20 x 20 graded cylinder of
    /// 10 mm, cone 68 deg, 0.1 mm in 1 s, held 1 s, unloaded in 1 s, 30 steps each) with
    /// [`J2Case::law`].
    pub fn config(&self) -> String {
        format!(
            "(specimen: Cylinder(radius: 10.0, height: 10.0, nr: 20, nz: 20, grading_r: 1.3, grading_z: 1.3), \
             punch: Cone(half_angle_deg: 68.0), contact: Vertical, kinematics: Small, law: {}, \
             history: (segments: [(duration: 1.0, depth: 0.1, steps: 30), \
             (duration: 1.0, depth: 0.1, steps: 30), (duration: 1.0, depth: 0.0, steps: 30)]))",
            self.law()
        )
    }

    /// CalculiX's material: `*ELASTIC` and `*PLASTIC` with [`J2Case::curve`].
    pub fn material(&self) -> Material {
        Material::Plastic {
            e: self.e,
            nu: self.nu,
            curve: self.curve(),
        }
    }
}

/// The times (s) at which the forces are compared.
pub const TIMES: [f64; 4] = [0.5, 1.0, 1.5, 2.0];

/// The file stem of a run: `r2-mu0.1-nlgeom`.
pub fn stem(case: &str, friction: f64, nlgeom: bool) -> String {
    let mut s = case.to_string();
    if friction > 0.0 {
        s.push_str(&format!("-mu{friction}"));
    }
    if nlgeom {
        s.push_str("-nlgeom");
    }
    s
}

/// A curve as CSV text (`t_s,F_N`).
pub fn curve_csv(curve: &[(f64, f64)]) -> String {
    let mut s = String::from("t_s,F_N\n");
    for (t, f) in curve {
        let _ = writeln!(s, "{t:.6},{f:.9e}");
    }
    s
}

/// Reads a curve written by [`curve_csv`].
///
/// # Errors
/// A malformed line.
pub fn read_curve_csv(text: &str) -> Result<Vec<(f64, f64)>> {
    text.lines()
        .skip(1)
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let mut it = l.split(',').map(|x| x.trim().parse::<f64>());
            match (it.next(), it.next()) {
                (Some(Ok(t)), Some(Ok(f))) => Ok((t, f)),
                _ => bail!("malformed curve line `{l}`"),
            }
        })
        .collect()
}

/// What `cargo xtask calculix` does.
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// The workspace root (examples are read from it).
    pub root: std::path::PathBuf,
    /// Where decks and curves go.
    pub out: std::path::PathBuf,
    /// The cases (names of [`CASES`]).
    pub cases: Vec<String>,
    /// Friction coefficients (0 = frictionless).
    pub frictions: Vec<f64>,
    /// Small strain, finite strain or both.
    pub kinematics: Vec<bool>,
    /// Deck options (friction and nlgeom are set per run).
    pub deck: DeckOptions,
    /// Write the decks without running `ccx` or our solver.
    pub decks_only: bool,
    /// Read the curves already in `out` (`STEM.csv`, `STEM-ours.csv`) instead of running
    /// `ccx` or our solver again; missing ones are run.
    pub reuse: bool,
    /// Never run `ccx`: compare with the CalculiX curves already in `out` (runs without
    /// one are listed as not run); our curves are computed (or reused).
    pub no_ccx: bool,
    /// The CalculiX executable (`ccx` on the path by default; the one linked with our
    /// user material for `--elastic hencky-umat`).
    pub ccx: std::path::PathBuf,
}

/// A case loaded: the configuration resolved to our mesh, punch, law and schedule.
pub struct Loaded {
    /// The prepared model (mesh and punch) and schedule.
    pub prepared: indentify_study::config::Prepared,
    /// The material for CalculiX.
    pub material: Material,
    /// The configuration source of the case.
    pub source: indentify_study::source::ConfigSource,
}

/// Our `--set` overrides of a run, on top of the case's own: `contact=Normal` or
/// `contact=Normal(friction: mu)`, and `kinematics=Finite` for a finite-strain run.
pub fn our_sets(case: &Case, friction: f64, nlgeom: bool) -> Vec<String> {
    let mut sets = vec![if friction > 0.0 {
        format!("contact=Normal(friction: {friction})")
    } else {
        "contact=Normal".to_string()
    }];
    if nlgeom {
        sets.push("kinematics=Finite".to_string());
    }
    sets.extend(case.sets.iter().map(|s| (*s).to_string()));
    sets
}

/// Loads `case` from the workspace `root` (frictionless `Normal` contact, small strain:
/// the mesh, punch, law and schedule of every run of the case).
///
/// # Errors
/// A configuration that cannot be read or prepared, a law without a CalculiX material.
pub fn load(root: &std::path::Path, case: &Case) -> Result<Loaded> {
    let j2 = j2_case(case.name);
    let source = match j2 {
        Some(j) => indentify_study::source::ConfigSource::Text {
            text: j.config(),
            name: case.name.to_string(),
        },
        None => indentify_study::source::ConfigSource::Path(root.join(case.example)),
    };
    let cfg = source.load(&our_sets(case, 0.0, false))?;
    let material = match j2 {
        Some(j) => j.material(),
        None => {
            let (law, params) = cfg.law.build()?;
            Material::from_law(law.name(), &params)?
        }
    };
    let prepared = cfg.prepare(case.name)?;
    Ok(Loaded {
        prepared,
        material,
        source,
    })
}

/// A force history `(t, F)` (s, N).
pub type Curve = Vec<(f64, f64)>;

/// Runs `ccx` on `deck` in a scratch folder under `out`: the force curve and, if `ccx`
/// stopped before the end, why (its last error line); a run that stops keeps the
/// increments it converged.
///
/// # Errors
/// `ccx` missing, a `.dat` file without forces.
pub fn run_ccx(
    ccx: &std::path::Path,
    out: &std::path::Path,
    stem: &str,
    deck: &str,
) -> Result<(Curve, Option<String>)> {
    run_ccx_reading(ccx, (out, stem), deck, "force", parse_dat)
}

/// Runs `ccx` on `deck` in the scratch folder `out/.work-STEM`, reads its `.dat` with
/// `parse` (`what`: the quantity named when it holds none) and says why `ccx` stopped
/// early, if it did (its last error line); the folder is removed after a complete run.
///
/// # Errors
/// `ccx` missing, a `.dat` file without the quantity.
pub fn run_ccx_reading<T>(
    ccx: &std::path::Path,
    (out, stem): (&std::path::Path, &str),
    deck: &str,
    what: &str,
    parse: impl Fn(&str) -> Result<Vec<T>>,
) -> Result<(Vec<T>, Option<String>)> {
    let work = out.join(format!(".work-{stem}"));
    std::fs::create_dir_all(&work)?;
    std::fs::write(work.join(format!("{stem}.inp")), deck)?;
    let status = std::process::Command::new(ccx)
        .arg("-i")
        .arg(stem)
        .current_dir(&work)
        .env("OMP_NUM_THREADS", "1")
        .env("CCX_NPROC_EQUATION_SOLVER", "1")
        .stdout(std::fs::File::create(work.join("ccx.log"))?)
        .status()
        .map_err(|e| {
            anyhow::anyhow!(
                "cannot start `{}` ({e}): install ccx with `apt-get install calculix-ccx`, or build the one with our user material by validation/calculix/umat/build.sh (--ccx PATH)",
                ccx.display()
            )
        })?;
    let dat = std::fs::read_to_string(work.join(format!("{stem}.dat"))).unwrap_or_default();
    let points = parse(&dat)?;
    let log = std::fs::read_to_string(work.join("ccx.log")).unwrap_or_default();
    let error = log
        .lines()
        .chain(
            std::fs::read_to_string(work.join("spooles.out"))
                .unwrap_or_default()
                .lines(),
        )
        .map(str::trim)
        .rfind(|l| l.contains("ERROR") || l.contains("singular"))
        .map(str::to_string);
    if points.is_empty() {
        bail!(
            "ccx wrote no {what} on {stem} ({status}{}); see {}",
            error.map(|e| format!(": {e}")).unwrap_or_default(),
            work.join("ccx.log").display()
        );
    }
    let stopped = if status.success() && error.is_none() {
        None
    } else {
        Some(error.unwrap_or_else(|| format!("ccx exited with {status}")))
    };
    if stopped.is_none() {
        std::fs::remove_dir_all(&work)?;
    }
    Ok((points, stopped))
}

/// Our force curve of `case` for a run (friction coefficient, finite strain or not).
///
/// # Errors
/// The simulation's errors, among them our refusal of finite strain with friction; a run
/// that stops early.
pub fn ours(loaded: &Loaded, case: &Case, friction: f64, nlgeom: bool) -> Result<Vec<(f64, f64)>> {
    let mut o = indentify_study::simulate::SimulateOptions::new(loaded.source.clone());
    o.sets = our_sets(case, friction, nlgeom);
    // the whole chain in one message (the refusal's reason is the source of "cannot build
    // the model")
    let outcome = indentify_study::simulate::run(&o)
        .map_err(|e| anyhow::anyhow!("{:#}", anyhow::Error::from(e)))?;
    if let Some(f) = outcome.failure {
        bail!("our run stopped early: {f}");
    }
    Ok(outcome.rows.iter().map(|r| (r.t, r.f)).collect())
}

/// One row of the comparison table: at each of [`TIMES`], `ours / ccx N: ours/ccx - 1`
/// where our curve exists; CalculiX's force and its ratio to `reference` (the
/// frictionless CalculiX run of the same kinematics) where it does not (`why_not_ours`
/// says why in the last column).
pub fn table_row(
    stem: &str,
    ccx: &[(f64, f64)],
    ours: Option<&[(f64, f64)]>,
    reference: Option<&[(f64, f64)]>,
    t_end: f64,
    note: &str,
) -> String {
    let mut row = format!("| {stem} |");
    for t in TIMES {
        let f = at(ccx, t);
        let cell = match (
            f,
            ours.and_then(|o| at(o, t)),
            reference.and_then(|r| at(r, t)),
        ) {
            (Some(f), Some(o), _) => {
                format!(" {o:.2} / {f:.2} N: **{:+.2}%** |", 100.0 * (o / f - 1.0))
            }
            (Some(f), None, Some(r)) => {
                format!(" ccx {f:.2} N ({:+.2}% vs mu = 0) |", 100.0 * (f / r - 1.0))
            }
            (Some(f), None, None) => format!(" ccx {f:.2} N |"),
            (None, ..) => " - |".to_string(),
        };
        row.push_str(&cell);
    }
    let last = ccx.last().map_or(0.0, |p| p.0);
    let reached = if last >= t_end - 1e-9 {
        "end".to_string()
    } else {
        format!("t = {last:.3} s")
    };
    let _ = write!(row, " {reached} | {note} |");
    row
}

/// Writes the decks, runs `ccx` and our solver (or reuses their curves in `out`), writes
/// the curves (`STEM.csv`: CalculiX; `STEM-ours.csv`: ours, e.g. `r2-mu0.1-nlgeom.csv`)
/// and returns the comparison as a Markdown table ([`table_row`]).
///
/// # Errors
/// An unknown case, a deck that cannot be written, a case that cannot be loaded.
pub fn run(o: &RunOptions) -> Result<String> {
    std::fs::create_dir_all(&o.out)?;
    let mut table = String::new();
    let _ = writeln!(
        table,
        "| run | t = 0.5 s | t = 1 s | t = 1.5 s | t = 2 s | ccx reached | notes |\n|---|---|---|---|---|---|---|"
    );
    for name in &o.cases {
        let case = CASES.iter().find(|c| c.name == name).ok_or_else(|| {
            anyhow::anyhow!(
                "unknown case `{name}`: expected r0, r0-nu049, r1, r2, r2-sy0, r2-j2-linear or r2-j2-power"
            )
        })?;
        let loaded = load(&o.root, case)?;
        let mesh = &loaded.prepared.model.mesh;
        let punch = &loaded.prepared.model.punch;
        let t_end = loaded.prepared.schedule.t.last().copied().unwrap_or(0.0);
        for &nlgeom in &o.kinematics {
            let mut frictionless: Option<Vec<(f64, f64)>> = None;
            for &mu in &o.frictions {
                let mut stem = stem(case.name, mu, nlgeom);
                if nlgeom && o.deck.finite_elastic.applies_to(&loaded.material) {
                    stem.push_str(o.deck.finite_elastic.suffix());
                }
                let opts = DeckOptions {
                    nlgeom,
                    friction: mu,
                    ..o.deck
                };
                let text = deck(
                    &format!("{} ({}), {stem}", case.name, case.example),
                    mesh,
                    punch,
                    &loaded.material,
                    &loaded.prepared.schedule,
                    &opts,
                )?;
                std::fs::write(o.out.join(format!("{stem}.inp")), &text)?;
                if o.decks_only {
                    continue;
                }
                let mut notes = Vec::new();
                // ours
                let ours_path = o.out.join(format!("{stem}-ours.csv"));
                let ours_curve = if o.reuse && ours_path.exists() {
                    Some(read_curve_csv(&std::fs::read_to_string(&ours_path)?)?)
                } else {
                    let t0 = std::time::Instant::now();
                    match ours(&loaded, case, mu, nlgeom) {
                        Ok(c) => {
                            eprintln!("{stem}: ours in {:.1} s", t0.elapsed().as_secs_f64());
                            std::fs::write(&ours_path, curve_csv(&c))?;
                            Some(c)
                        }
                        Err(e) => {
                            eprintln!("{stem}: ours: {e:#}");
                            let root = format!("{}/", o.root.display());
                            notes.push(format!("ours: {}", e.to_string().replace(&root, "")));
                            None
                        }
                    }
                };
                // CalculiX
                let ccx_path = o.out.join(format!("{stem}.csv"));
                let curve = if (o.reuse || o.no_ccx) && ccx_path.exists() {
                    read_curve_csv(&std::fs::read_to_string(&ccx_path)?)?
                } else if o.no_ccx {
                    let _ = writeln!(
                        table,
                        "| {stem} | - | - | - | - | - | ccx not run{} |",
                        notes.iter().map(|n| format!("; {n}")).collect::<String>()
                    );
                    continue;
                } else {
                    let t0 = std::time::Instant::now();
                    match run_ccx(&o.ccx, &o.out, &stem, &text) {
                        Ok((c, stopped)) => {
                            eprintln!(
                                "{stem}: ccx in {:.1} s, {} increments{}",
                                t0.elapsed().as_secs_f64(),
                                c.len(),
                                stopped
                                    .as_ref()
                                    .map(|s| format!(", stopped: {s}"))
                                    .unwrap_or_default()
                            );
                            if let Some(s) = stopped {
                                notes.push(format!("ccx stopped: {s}"));
                            }
                            std::fs::write(&ccx_path, curve_csv(&c))?;
                            c
                        }
                        Err(e) => {
                            eprintln!("{stem}: {e:#}");
                            let _ =
                                writeln!(table, "| {stem} | - | - | - | - | - | ccx failed: {e} |");
                            continue;
                        }
                    }
                };
                if mu == 0.0 {
                    frictionless = Some(curve.clone());
                }
                let reference = if mu > 0.0 {
                    frictionless.as_deref()
                } else {
                    None
                };
                let _ = writeln!(
                    table,
                    "{}",
                    table_row(
                        &stem,
                        &curve,
                        ours_curve.as_deref(),
                        reference,
                        t_end,
                        &notes.join("; ")
                    )
                );
            }
        }
    }
    Ok(table)
}
