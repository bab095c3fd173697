//! The contact direction ([`ContactKind`]) and, for normal contact, the punch surface as a
//! C1 chain of lines and circular arcs ([`Surface`]) with its closest-point projection.
//!
//! Coordinates of the projection: `(r, h)` with `h = z + U` the height above the punch
//! tip at the current depth `U` (mm); the punch surface is `h = phi(rho)`. At the closest
//! point `p` the unit tangent `t = (cos theta, sin theta)` (theta the slope angle,
//! `tan theta = phi'`) and the upward unit normal `m = (-sin theta, cos theta)` (into the
//! punch) form a rotation `[t m]`; the signed gap is `g = -(x - p) . m` (> 0: separated),
//! so that `g = phi(r) - U - z` for a horizontal surface, as the vertical gap. The
//! surface's curvature `kappa = d theta / d s` (1/mm, > 0 for a convex punch) enters the
//! consistent tangent of normal contact (docs/validation-contact.md).

use serde::{Deserialize, Serialize};

use crate::ContactError;
use crate::punch::Punch;

/// Direction of the contact constraint, and Coulomb friction.
///
/// Config: `contact: Vertical` (the default), `contact: Normal` (frictionless) or
/// `contact: Normal(friction: 0.2)` (Coulomb friction coefficient `mu >= 0`, finite;
/// `Normal(friction: 0.0)` is `Normal`). With `--set`: `--set contact=Normal`,
/// `--set "contact=Normal(friction: 0.2)"`, and `--set contact.friction=0.3` once the
/// configuration has a friction.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum ContactKind {
    /// The paper's small-strain contact (docs/theory.md §1): the gap of a top node is taken at
    /// its reference radius, `g_k = phi(r_k) - U - u_z,k`, and its reaction is vertical.
    #[default]
    Vertical,
    /// The gap of a top node is its signed distance, at its displaced position
    /// `x = X + u`, to the punch surface at the current depth, measured along the
    /// surface normal at the closest point; the reaction acts along that normal. The
    /// node's two dofs are rotated into the surface frame `(t, m)`: `m . du` is
    /// prescribed, the tangential dof stays free (frictionless), and the tangent gains the
    /// normal's rotation `-lambda kappa / (1 + g kappa)` on the tangential dof. The axis
    /// node (`u_r = 0` by symmetry) keeps the vertical gap and reaction (the tip's normal
    /// by symmetry, also at a cone apex).
    Normal,
    /// [`ContactKind::Normal`] with Coulomb friction of coefficient `friction` (> 0; 0 is
    /// [`ContactKind::Normal`]): an active node either sticks (its closest point keeps the
    /// arc coordinate it had at the last converged step: the tangential dof is prescribed)
    /// or slips with the tangential traction `friction x lambda` opposing its slip
    /// (crate::friction, docs/validation-contact.md §7).
    NormalFriction {
        /// Coulomb coefficient `mu` (finite, >= 0).
        friction: f64,
    },
}

impl ContactKind {
    /// The contact kind with normal gaps and friction `mu` (`Normal` for `mu = 0`).
    ///
    /// # Errors
    /// [`ContactError::Input`] naming `contact.friction` for a negative, NaN or infinite
    /// `mu`.
    pub fn normal_with_friction(mu: f64) -> Result<ContactKind, ContactError> {
        check_friction(mu)?;
        Ok(if mu == 0.0 {
            ContactKind::Normal
        } else {
            ContactKind::NormalFriction { friction: mu }
        })
    }

    /// The Coulomb coefficient (0 without friction).
    pub fn friction(&self) -> f64 {
        match self {
            ContactKind::NormalFriction { friction } => *friction,
            _ => 0.0,
        }
    }

    /// Whether gaps are measured along the punch's normal (`Normal`, with or without
    /// friction).
    pub fn is_normal(&self) -> bool {
        !matches!(self, ContactKind::Vertical)
    }

    /// Checks the friction coefficient.
    ///
    /// # Errors
    /// As [`ContactKind::normal_with_friction`].
    pub fn validate(&self) -> Result<(), ContactError> {
        check_friction(self.friction())
    }
}

fn check_friction(mu: f64) -> Result<(), ContactError> {
    if mu.is_finite() && mu >= 0.0 {
        Ok(())
    } else {
        Err(ContactError::Input {
            field: "contact.friction",
            value: format!("{mu}"),
            allowed: "a finite Coulomb coefficient >= 0 (e.g. Normal(friction: 0.1); \
                      0 is frictionless)"
                .into(),
        })
    }
}

/// The accepted spellings (RON and the JSON of `--set`): a name, `Vertical` or `Normal`,
/// optionally as the text `Normal(friction: mu)`, or the struct variant
/// `Normal(friction: mu)` (RON) / `{"Normal": {"friction": mu}}` (JSON). Read through
/// serde's untagged content, which keeps the variant's name in both formats.
#[derive(Deserialize)]
#[serde(untagged)]
enum ContactRepr {
    Name(String),
    Variant(std::collections::BTreeMap<String, std::collections::BTreeMap<String, f64>>),
}

const CONTACT_SPELLINGS: &str = "Vertical, Normal or Normal(friction: mu) with mu >= 0";

impl ContactKind {
    /// Parses `Vertical`, `Normal` or `Normal(friction: mu)` (spaces allowed).
    ///
    /// # Errors
    /// [`ContactError::Input`] naming `contact` (unknown spelling) or `contact.friction`
    /// (a negative, NaN or infinite coefficient).
    pub fn parse(text: &str) -> Result<ContactKind, ContactError> {
        let compact: String = text.chars().filter(|c| !c.is_whitespace()).collect();
        match compact.as_str() {
            "Vertical" => return Ok(ContactKind::Vertical),
            "Normal" => return Ok(ContactKind::Normal),
            _ => {}
        }
        let mu = compact
            .strip_prefix("Normal(friction:")
            .and_then(|r| r.strip_suffix(')'))
            .map(|v| v.trim_end_matches(','))
            .ok_or_else(|| ContactError::Input {
                field: "contact",
                value: text.to_string(),
                allowed: CONTACT_SPELLINGS.into(),
            })?;
        let mu: f64 = mu.parse().map_err(|_| ContactError::Input {
            field: "contact.friction",
            value: mu.to_string(),
            allowed: "a number >= 0 (e.g. Normal(friction: 0.1))".into(),
        })?;
        ContactKind::normal_with_friction(mu)
    }
}

impl<'de> Deserialize<'de> for ContactKind {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        let repr = ContactRepr::deserialize(d).map_err(|_| {
            D::Error::custom(format!(
                "`contact` is not allowed: expected {CONTACT_SPELLINGS}"
            ))
        })?;
        match repr {
            ContactRepr::Name(s) => ContactKind::parse(&s).map_err(D::Error::custom),
            ContactRepr::Variant(map) => {
                let mut it = map.into_iter();
                match (it.next(), it.next()) {
                    (Some((name, fields)), None) if name == "Normal" => {
                        let mut mu = None;
                        for (k, v) in fields {
                            if k != "friction" {
                                return Err(D::Error::custom(format!(
                                    "`contact.{k}` is not a field of Normal: expected `friction`"
                                )));
                            }
                            mu = Some(v);
                        }
                        let mu = mu.ok_or_else(|| {
                            D::Error::custom("`contact: Normal(...)` needs `friction: mu`")
                        })?;
                        ContactKind::normal_with_friction(mu).map_err(D::Error::custom)
                    }
                    _ => Err(D::Error::custom(format!(
                        "`contact` is not allowed: expected {CONTACT_SPELLINGS}"
                    ))),
                }
            }
        }
    }
}

impl Serialize for ContactKind {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeStructVariant;
        match self {
            ContactKind::Vertical => s.serialize_unit_variant("ContactKind", 0, "Vertical"),
            ContactKind::Normal => s.serialize_unit_variant("ContactKind", 1, "Normal"),
            ContactKind::NormalFriction { friction } => {
                let mut v = s.serialize_struct_variant("ContactKind", 1, "Normal", 1)?;
                v.serialize_field("friction", friction)?;
                v.end()
            }
        }
    }
}

/// A piece of the punch surface in `(r, h)`.
#[derive(Clone, Debug, PartialEq)]
enum Piece {
    /// `p = a + tau t`, `tau` in `[0, len]` (`len` infinite for the last piece).
    Line { a: [f64; 2], t: [f64; 2], len: f64 },
    /// Circle of center `c` and radius `radius`, slope angle in `[th0, th1]`; convex
    /// (`p = c - R m(theta)`, center on the punch side) or concave (`p = c + R m(theta)`).
    Arc {
        c: [f64; 2],
        radius: f64,
        convex: bool,
        th0: f64,
        th1: f64,
    },
}

/// The closest point of the punch surface to a displaced node.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Projection {
    /// Signed gap along the normal (mm, > 0: separated, < 0: penetrating).
    pub gap: f64,
    /// The gap of a node in contact: past a flat punch's rim, the gap to the face's plane
    /// (the rim bears a node that slides past it while in contact, as vertical contact
    /// holds every node of reference radius <= R at the face's level); `gap` elsewhere.
    pub gap_in_contact: f64,
    /// Unit tangent `(t_r, t_z)` at the closest point (pointing away from the axis).
    pub t: [f64; 2],
    /// Unit upward normal `(m_r, m_z)` (into the punch); the reaction on the body is
    /// `-lambda m`.
    pub m: [f64; 2],
    /// Curvature of the surface at the closest point (1/mm, > 0 convex, 0 on a flank).
    pub kappa: f64,
    /// Radius of the closest point (mm).
    pub rho: f64,
    /// Arc coordinate of the closest point along the surface from the tip (mm; continued
    /// along the last piece's line past its end); it moves by `t . dx / (1 + g kappa)`
    /// when the node moves by `dx`. Friction tracks it (the stick point).
    pub s: f64,
    /// The closest point lies beyond the last point of a tabulated profile: no surface is
    /// given there (a node in contact there is an error of the solver, never a force from
    /// an extrapolation).
    pub beyond_end: bool,
}

impl Projection {
    /// This projection for a node in contact (`gap` replaced by `gap_in_contact`).
    pub fn in_contact(self) -> Projection {
        Projection {
            gap: self.gap_in_contact,
            ..self
        }
    }

    /// The vertical projection of the axis node: the tip's normal by symmetry.
    pub fn vertical(gap: f64) -> Projection {
        Projection {
            gap,
            gap_in_contact: gap,
            t: [1.0, 0.0],
            m: [0.0, 1.0],
            kappa: 0.0,
            rho: 0.0,
            s: 0.0,
            beyond_end: false,
        }
    }
}

/// The punch surface as a C1 chain of lines and arcs, for normal contact.
///
/// - cone: one ray from the tip (its apex meets only the axis node, whose normal is
///   vertical by symmetry);
/// - sphere: the arc up to r = R, then the vertical wall;
/// - flat: the face up to the rim; the rim is a corner: a node not in contact whose
///   displaced radius is beyond it has a gap equal to its distance to the rim (never
///   negative: the punch is a cylinder, so it is never activated there), while a node in
///   contact that slides past the rim stays on the face's plane (`gap_in_contact`: the
///   rim bears it, with the face's vertical normal, as in vertical contact) until its
///   reaction turns tensile;
/// - sphero-cone and the instrument presets with a tip radius: the arc then the tangent
///   ray;
/// - tabulated: the segments with every interior vertex rounded by the circular arc
///   tangent to both segments at a quarter of the shorter one from the vertex (the normal
///   is otherwise undefined at a kink); beyond the last point the last segment is
///   extended (as the vertical gap's extrapolation) and flagged `beyond_end`;
/// - calibrated: its profile tabulated ([`crate::punch::AreaProfile::table`]), as a
///   tabulated profile.
#[derive(Clone, Debug, PartialEq)]
pub struct Surface {
    pieces: Vec<Piece>,
    /// Arc coordinate of each piece's start.
    starts: Vec<f64>,
    /// The chain ends at a corner (flat rim) beyond which there is no surface.
    closed_end: bool,
    /// Length of the last piece within the table (tabulated profiles).
    last_len: f64,
    /// Radial extent of each piece's closest points ([`radial_extent`]).
    lo: Vec<f64>,
    hi: Vec<f64>,
    /// The extent of each block of [`BLOCK`] pieces.
    blocks: Vec<(f64, f64)>,
}

fn line(a: [f64; 2], theta: f64, len: f64) -> Piece {
    Piece::Line {
        a,
        t: [theta.cos(), theta.sin()],
        len,
    }
}

impl Surface {
    /// The surface of a validated punch.
    ///
    /// # Errors
    /// [`ContactError::Input`] for an invalid punch.
    pub fn new(punch: &Punch) -> Result<Surface, ContactError> {
        punch.validate()?;
        punch.require_profile()?;
        let inf = f64::INFINITY;
        let half_pi = std::f64::consts::FRAC_PI_2;
        let s = match punch.equivalent() {
            Punch::Cone { half_angle_deg } => Surface {
                starts: Vec::new(),
                lo: Vec::new(),
                hi: Vec::new(),
                blocks: Vec::new(),
                pieces: vec![line([0.0, 0.0], half_pi - half_angle_deg.to_radians(), inf)],
                closed_end: false,
                last_len: inf,
            },
            Punch::Sphere { radius } => Surface {
                starts: Vec::new(),
                lo: Vec::new(),
                hi: Vec::new(),
                blocks: Vec::new(),
                pieces: vec![
                    Piece::Arc {
                        c: [0.0, radius],
                        radius,
                        convex: true,
                        th0: 0.0,
                        th1: half_pi,
                    },
                    line([radius, radius], half_pi, inf),
                ],
                closed_end: false,
                last_len: inf,
            },
            Punch::Flat { radius } => Surface {
                starts: Vec::new(),
                lo: Vec::new(),
                hi: Vec::new(),
                blocks: Vec::new(),
                pieces: vec![line([0.0, 0.0], 0.0, radius)],
                closed_end: true,
                last_len: radius,
            },
            Punch::SpheroCone {
                radius,
                half_angle_deg,
            } => {
                let a = half_angle_deg.to_radians();
                let th = half_pi - a;
                let blend = [radius * th.sin(), radius * (1.0 - th.cos())];
                Surface {
                    starts: Vec::new(),
                    lo: Vec::new(),
                    hi: Vec::new(),
                    blocks: Vec::new(),
                    pieces: vec![
                        Piece::Arc {
                            c: [0.0, radius],
                            radius,
                            convex: true,
                            th0: 0.0,
                            th1: th,
                        },
                        line(blend, th, inf),
                    ],
                    closed_end: false,
                    last_len: inf,
                }
            }
            Punch::Tabulated { r, z } => Surface::tabulated(&r, &z),
            Punch::Calibrated { area, .. } => {
                let (r, z) = area.map(|a| a.table()).unwrap_or_default();
                Surface::tabulated(&r, &z)
            }
            Punch::Berkovich { .. } | Punch::Vickers { .. } | Punch::CubeCorner { .. } => {
                unreachable!("presets are replaced by their equivalent profile")
            }
        };
        Ok(s.with_starts())
    }

    /// Fills the arc coordinate of each piece's start (the chain is C1 and connected).
    fn with_starts(mut self) -> Surface {
        let mut acc = 0.0;
        self.starts.clear();
        for p in &self.pieces {
            self.starts.push(acc);
            acc += match *p {
                Piece::Line { len, .. } => len,
                Piece::Arc {
                    radius, th0, th1, ..
                } => radius * (th1 - th0),
            };
        }
        (self.lo, self.hi) = self
            .pieces
            .iter()
            .enumerate()
            .map(|(i, p)| radial_extent(p, i))
            .unzip();
        self.blocks = self
            .lo
            .chunks(BLOCK)
            .zip(self.hi.chunks(BLOCK))
            .map(|(l, h)| {
                (
                    l.iter().copied().fold(f64::INFINITY, f64::min),
                    h.iter().copied().fold(f64::NEG_INFINITY, f64::max),
                )
            })
            .collect();
        self
    }

    /// Segments of a tabulated profile with filleted interior vertices.
    fn tabulated(r: &[f64], z: &[f64]) -> Surface {
        let n = r.len();
        let theta: Vec<f64> = (0..n - 1)
            .map(|i| (z[i + 1] - z[i]).atan2(r[i + 1] - r[i]))
            .collect();
        let len: Vec<f64> = (0..n - 1)
            .map(|i| (r[i + 1] - r[i]).hypot(z[i + 1] - z[i]))
            .collect();
        // tangent length of the fillet at each vertex (0 at the ends and where straight)
        let mut tau = vec![0.0; n];
        for i in 1..n - 1 {
            if (theta[i] - theta[i - 1]).abs() > 1e-12 {
                tau[i] = 0.25 * len[i - 1].min(len[i]);
            }
        }
        let mut pieces = Vec::new();
        for i in 0..n - 1 {
            let t = [theta[i].cos(), theta[i].sin()];
            let a = [r[i] + tau[i] * t[0], z[i] + tau[i] * t[1]];
            let l = len[i] - tau[i] - tau[i + 1];
            pieces.push(Piece::Line {
                a,
                t,
                len: if i == n - 2 { f64::INFINITY } else { l },
            });
            if i + 1 < n - 1 && tau[i + 1] > 0.0 {
                let (th0, th1) = (theta[i], theta[i + 1]);
                let half = 0.5 * (th1 - th0).abs();
                let radius = tau[i + 1] / half.tan();
                let start = [r[i + 1] - tau[i + 1] * t[0], z[i + 1] - tau[i + 1] * t[1]];
                let m0 = [-th0.sin(), th0.cos()];
                let convex = th1 > th0;
                let sgn = if convex { 1.0 } else { -1.0 };
                pieces.push(Piece::Arc {
                    c: [
                        start[0] + sgn * radius * m0[0],
                        start[1] + sgn * radius * m0[1],
                    ],
                    radius,
                    convex,
                    th0: th0.min(th1),
                    th1: th0.max(th1),
                });
            }
        }
        Surface {
            pieces,
            starts: Vec::new(),
            lo: Vec::new(),
            hi: Vec::new(),
            blocks: Vec::new(),
            closed_end: false,
            last_len: len[n - 2] - tau[n - 2],
        }
    }

    /// The closest point of the surface to `x = (r, h)` (`h` the height above the tip):
    /// the first piece (in chain order) of least squared distance, exactly as a scan of
    /// every piece finds it, but a piece (or a block of `BLOCK` (16) pieces) whose radial
    /// extent is farther from `x` than the best candidate so far is not evaluated (a
    /// calibrated tip's table has about a thousand pieces); the search starts at the piece
    /// whose radial extent reaches `x`.
    pub fn project(&self, x: [f64; 2]) -> Projection {
        let n = self.pieces.len();
        if n == 0 {
            return Projection::vertical(f64::INFINITY);
        }
        let last = n - 1;
        let seed = self.hi.partition_point(|&h| h < x[0]).min(last);
        let mut best = self.candidate(seed, x, last);
        if best.d2.is_nan() {
            return self.project_scan(x);
        }
        let below = |lo: f64, hi: f64| {
            let d = if x[0] < lo {
                lo - x[0]
            } else if x[0] > hi {
                x[0] - hi
            } else {
                0.0
            };
            d * d
        };
        for (b, &(blo, bhi)) in self.blocks.iter().enumerate() {
            if below(blo, bhi) > best.d2 {
                continue;
            }
            for i in b * BLOCK..((b + 1) * BLOCK).min(n) {
                if i == seed || below(self.lo[i], self.hi[i]) > best.d2 {
                    continue;
                }
                let c = self.candidate(i, x, last);
                // the scan keeps the first piece of least distance
                if c.d2 < best.d2 || (c.d2 == best.d2 && i < best.i) {
                    best = c;
                }
            }
        }
        self.finish(&best, x, last)
    }

    /// [`Surface::project`] by a scan of every piece (the reference the pruned search
    /// reproduces; used when a distance is not a number).
    pub fn project_scan(&self, x: [f64; 2]) -> Projection {
        let last = self.pieces.len().saturating_sub(1);
        let mut best: Option<Candidate> = None;
        for i in 0..self.pieces.len() {
            let c = self.candidate(i, x, last);
            if best.as_ref().is_none_or(|b| c.d2 < b.d2) {
                best = Some(c);
            }
        }
        best.map(|b| self.finish(&b, x, last))
            .unwrap_or_else(|| Projection::vertical(f64::INFINITY))
    }

    /// The closest point of piece `i` to `x` and its squared distance.
    fn candidate(&self, i: usize, x: [f64; 2], last: usize) -> Candidate {
        let (p, theta, kappa, clamped_end, s) = match self.pieces[i] {
            Piece::Line { a, t, len } => {
                let mut tau = (x[0] - a[0]) * t[0] + (x[1] - a[1]) * t[1];
                // the first piece starts on the axis: extended beyond it (only an
                // iterate near the axis projects there; the axis node is vertical)
                if i > 0 {
                    tau = tau.max(0.0);
                }
                // the arc coordinate continues along the last line past its end
                let s = self.starts[i] + if i == last { tau } else { tau.min(len) };
                let mut beyond = false;
                if tau > len {
                    tau = len;
                    beyond = true;
                }
                if i == last && tau > self.last_len {
                    beyond = true;
                }
                (
                    [a[0] + tau * t[0], a[1] + tau * t[1]],
                    t[1].atan2(t[0]),
                    0.0,
                    beyond,
                    s,
                )
            }
            Piece::Arc {
                c,
                radius,
                convex,
                th0,
                th1,
            } => {
                let (dr, dh) = (x[0] - c[0], x[1] - c[1]);
                let mut th = if convex {
                    dr.atan2(-dh)
                } else {
                    (-dr).atan2(dh)
                };
                if i > 0 {
                    th = th.max(th0);
                }
                th = th.min(th1);
                let m = [-th.sin(), th.cos()];
                let sgn = if convex { -1.0 } else { 1.0 };
                let p = [c[0] + sgn * radius * m[0], c[1] + sgn * radius * m[1]];
                let kappa = if convex { 1.0 / radius } else { -1.0 / radius };
                // along the chain the slope angle grows on a convex arc, falls on a
                // concave one
                let s = self.starts[i] + radius * if convex { th - th0 } else { th1 - th };
                (p, th, kappa, false, s)
            }
        };
        let d2 = (x[0] - p[0]).powi(2) + (x[1] - p[1]).powi(2);
        Candidate {
            i,
            d2,
            p,
            theta,
            kappa,
            clamped_end,
            s,
        }
    }

    /// The projection onto the chosen candidate.
    fn finish(&self, c: &Candidate, x: [f64; 2], last: usize) -> Projection {
        let (p, theta, kappa, clamped_end, s) = (c.p, c.theta, c.kappa, c.clamped_end, c.s);
        let i = c.i;
        let t = [theta.cos(), theta.sin()];
        let m = [-t[1], t[0]];
        let past_rim = clamped_end && self.closed_end;
        let beyond_end = clamped_end && !self.closed_end && i == last;
        let plane = -((x[0] - p[0]) * m[0] + (x[1] - p[1]) * m[1]);
        // past a rim: the distance to the corner (the punch is a cylinder)
        let gap = if past_rim { c.d2.sqrt() } else { plane };
        Projection {
            gap,
            gap_in_contact: plane,
            t,
            m,
            kappa,
            rho: p[0],
            s,
            beyond_end,
        }
    }
}

/// Pieces per block of [`Surface::project`]'s pruning.
const BLOCK: usize = 16;

/// One piece's closest point to a node (what [`Surface::finish`] needs).
struct Candidate {
    i: usize,
    d2: f64,
    p: [f64; 2],
    theta: f64,
    kappa: f64,
    clamped_end: bool,
    s: f64,
}

/// The radial extent `[lo, hi]` of the points [`Surface::candidate`] can return on piece
/// `i` of `n` (the first piece extends beyond the axis, the last line to infinity), widened
/// by a relative 1e-9 so that rounding never makes it exclude such a point.
fn radial_extent(piece: &Piece, i: usize) -> (f64, f64) {
    let inf = f64::INFINITY;
    let (lo, hi) = match *piece {
        Piece::Line { a, t, len } => {
            let end = if t[0] == 0.0 { a[0] } else { a[0] + len * t[0] };
            let (mut lo, mut hi) = (a[0].min(end), a[0].max(end));
            if i == 0 {
                // tau unbounded below
                if t[0] > 0.0 {
                    lo = -inf;
                } else if t[0] < 0.0 {
                    hi = inf;
                }
            }
            (lo, hi)
        }
        Piece::Arc {
            c,
            radius,
            convex,
            th0,
            th1,
        } => {
            // r = c_r + sgn' R sin(theta), theta in [th0, th1] ([-pi, th1] on the first piece)
            let a = if i == 0 { -std::f64::consts::PI } else { th0 };
            let b = th1;
            let (mut smin, mut smax) = (a.sin().min(b.sin()), a.sin().max(b.sin()));
            for k in -4i32..=4 {
                let ang = std::f64::consts::FRAC_PI_2 + f64::from(k) * std::f64::consts::PI;
                if a <= ang && ang <= b {
                    if k % 2 == 0 {
                        smax = 1.0;
                    } else {
                        smin = -1.0;
                    }
                }
            }
            if !(b - a < 4.0 * std::f64::consts::PI) {
                smin = -1.0;
                smax = 1.0;
            }
            if convex {
                (c[0] + radius * smin, c[0] + radius * smax)
            } else {
                (c[0] - radius * smax, c[0] - radius * smin)
            }
        }
    };
    let pad = |v: f64| 1e-9 * (1.0 + v.abs());
    (lo - pad(lo), hi + pad(hi))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol
    }

    /// The pruned search returns bit for bit what the scan of every piece returns, on
    /// every kind of surface (a calibrated tip's thousand pieces, a sphere's wall, a flat
    /// rim, a concave table), for points inside, outside, near the axis and far away.
    #[test]
    fn pruned_projection_is_the_scan() {
        use crate::punch::AreaProfile;
        let calibrated = Punch::calibrated(
            "TIP.ron",
            AreaProfile::new(
                vec![(24.1, 2.0), (1.2e-4, 1.0), (3.0e-7, 0.5)],
                f64::INFINITY,
            )
            .unwrap(),
        );
        let sphere_area = AreaProfile::new(
            vec![
                (2.0 * std::f64::consts::PI * 0.01, 1.0),
                (-std::f64::consts::PI, 2.0),
            ],
            0.01,
        )
        .unwrap();
        let punches = [
            calibrated,
            Punch::calibrated("S.ron", sphere_area),
            Punch::Sphere { radius: 0.5 },
            Punch::Flat { radius: 0.3 },
            Punch::Cone {
                half_angle_deg: 70.3,
            },
            Punch::SpheroCone {
                radius: 0.01,
                half_angle_deg: 60.0,
            },
            Punch::Tabulated {
                r: vec![0.0, 0.1, 0.2, 0.3, 0.5],
                z: vec![0.0, 0.02, 0.03, 0.2, 0.21],
            },
        ];
        let mut seed = 12345u64;
        let mut rand = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for punch in &punches {
            let s = Surface::new(punch).unwrap();
            let mut checked = 0;
            for scale in [1e-6, 1e-4, 1e-3, 1e-2, 0.3, 2.0] {
                for _ in 0..400 {
                    let x = [scale * (1.2 * rand() - 0.1), scale * (1.5 * rand() - 0.5)];
                    let (a, b) = (s.project(x), s.project_scan(x));
                    assert!(
                        a == b || (a.gap.is_nan() && b.gap.is_nan()),
                        "{} at {x:?}: {a:?} vs {b:?}",
                        punch.describe()
                    );
                    checked += 1;
                }
            }
            assert_eq!(checked, 2400);
        }
    }

    /// On a horizontal or straight surface the normal gap is the vertical gap times the
    /// cosine of the slope; on the sphere it is the distance to the center minus R.
    #[test]
    fn gaps_are_signed_distances() {
        let cone = Surface::new(&Punch::Cone {
            half_angle_deg: 68.0,
        })
        .unwrap();
        let a = 68f64.to_radians();
        for (r, h) in [(0.1, 0.0), (0.2, 0.05), (0.05, 0.03)] {
            let p = cone.project([r, h]);
            let vertical = r / a.tan() - h;
            assert!(close(p.gap, vertical * a.sin(), 1e-15), "{p:?}");
            assert_eq!(p.kappa, 0.0);
        }
        let sphere = Surface::new(&Punch::Sphere { radius: 2.0 }).unwrap();
        for (r, h) in [(0.3, 0.0), (0.5, 0.1), (0.2, 0.02)] {
            let p = sphere.project([r, h]);
            let d = r.hypot(h - 2.0);
            assert!(close(p.gap, d - 2.0, 1e-15), "{p:?}");
            assert!(close(p.kappa, 0.5, 0.0));
            // the normal points from the body to the center
            assert!(close(p.m[0], -r / d, 1e-15) && close(p.m[1], (2.0 - h) / d, 1e-15));
        }
        let flat = Surface::new(&Punch::Flat { radius: 0.5 }).unwrap();
        let p = flat.project([0.3, 0.01]);
        assert!(close(p.gap, -0.01, 1e-16) && !p.beyond_end);
        let p = flat.project([0.8, -0.4]);
        assert!(close(p.gap, 0.5, 1e-15) && !p.beyond_end, "{p:?}");
        assert!(close(p.in_contact().gap, 0.4, 1e-15), "{p:?}");
    }

    /// The sphero-cone's projection is continuous across the blend, with the sphere's
    /// curvature on the cap and none on the flank.
    #[test]
    fn sphero_cone_blend_is_continuous() {
        let s = Surface::new(&Punch::SpheroCone {
            radius: 0.1,
            half_angle_deg: 60.0,
        })
        .unwrap();
        let punch = Punch::SpheroCone {
            radius: 0.1,
            half_angle_deg: 60.0,
        };
        let rt = 0.1 * 60f64.to_radians().cos();
        for r in [0.5 * rt, 0.999 * rt, 1.001 * rt, 3.0 * rt] {
            // a point on the surface has gap 0 and the profile's slope
            let p = s.project([r, punch.profile(r)]);
            assert!(p.gap.abs() < 1e-15, "{r}: {p:?}");
            let slope = p.t[1] / p.t[0];
            let h = 1e-7;
            let fd = (punch.profile(r + h) - punch.profile(r - h)) / (2.0 * h);
            assert!(close(slope, fd, 1e-6), "{r}: {slope} vs {fd}");
            assert_eq!(p.kappa > 0.0, r < rt);
        }
    }

    /// A tabulated profile is filleted: gaps are continuous, the surface stays within a
    /// quarter segment of the table, and a node past the last point is flagged.
    #[test]
    fn tabulated_profiles_are_filleted() {
        let punch = Punch::Tabulated {
            r: vec![0.0, 0.1, 0.2, 0.4],
            z: vec![0.0, 0.01, 0.04, 0.2],
        };
        let s = Surface::new(&punch).unwrap();
        let mut last = s.project([0.0, -0.01]).gap;
        let mut r = 0.0;
        while r < 0.39 {
            r += 1e-4;
            let p = s.project([r, punch.profile(r)]);
            assert!(!p.beyond_end);
            // within the fillet's sag of the table
            assert!(p.gap.abs() < 0.01 && p.gap >= -1e-15, "{r}: {p:?}");
            let g = s.project([r, -0.01]).gap;
            assert!((g - last).abs() < 1e-3, "jump at {r}");
            last = g;
        }
        assert!(s.project([0.5, 0.3]).beyond_end);
        // convex vertex: positive curvature on its fillet
        let p = s.project([0.1, 0.0]);
        assert!(p.kappa > 0.0, "{p:?}");
        // a concave vertex (slope decreasing): negative curvature, the fillet below the
        // vertex by at most its sag, gaps continuous across it
        let concave = Punch::Tabulated {
            r: vec![0.0, 0.1, 0.2],
            z: vec![0.0, 0.05, 0.08],
        };
        let s = Surface::new(&concave).unwrap();
        let p = s.project([0.1, 0.05]);
        assert!(p.kappa < 0.0 && p.gap < 0.0 && p.gap > -0.01, "{p:?}");
        let mut last = s.project([0.05, 0.0]).gap;
        for i in 1..=100 {
            let g = s.project([0.05 + 1e-3 * i as f64, 0.0]).gap;
            assert!((g - last).abs() < 2e-3, "jump at {i}");
            last = g;
        }
    }
}
