//! Coulomb friction on the normal contact ([`crate::ContactKind::NormalFriction`]): the
//! stick/slip status of an active node, its Newton equation and frame, and the checks
//! that update the stick/slip partition like the contact set (a primal-dual active set
//! in the manner of Hüeber & Wohlmuth 2005 and Popp, Gee & Wall 2009).
//!
//! Notation at an active off-axis node, in the frame `(t, m)` of its closest point
//! (docs/validation-contact.md §7): `lambda = -m . f_int` the normal reaction,
//! `tau = t . f_int` the tangential force of the punch on the body, `s` the arc
//! coordinate of the closest point (`normal::Projection::s`) and `xi` its value at the
//! last converged step (the stick point), `ds = s - xi` the slip increment.
//!
//! - **stick** (status 0): `s(x) = xi`; Newton prescribes `t . du = (xi - s)(1 + g kappa)`
//!   (the closest point moves by `t . du / (1 + g kappa)`). Admissible while
//!   `|tau| <= mu lambda`.
//! - **slip** (status `sigma = +-1`, the direction of `ds` along `t`): `tau = -mu sigma
//!   lambda`, i.e. `(t - mu sigma m) . f_int = 0`, linearized as
//!   `(t - mu sigma m) . K du + d t . du = -(t - mu sigma m) . f_int` with
//!   `d = kappa (-lambda + mu sigma tau) / (1 + g kappa)` (the rotation of `t` and `m`,
//!   `dt = kappa ds m`, `dm = -kappa ds t`). Admissible while `sigma ds >= 0`.
//!
//! A stick node with `|tau| > mu lambda` turns to slip with `sigma = -sign(tau)`; a slip
//! node whose increment runs against `sigma` turns to stick. Nodes entering contact start
//! sticking. The axis node has no tangential dof and no friction.

use crate::model::Model;
use crate::normal::Projection;
use crate::system::NodeFrame;

/// Stick/slip status of an active node: 0 sticks, `+1`/`-1` slips along `+t`/`-t`.
pub type Status = i8;

/// The frame of active candidate `k` with projection `p` (in contact), nodal internal
/// force `f = (f_r, f_z)`, status `status` and friction `mu` (> 0).
pub(crate) fn frame(
    model: &Model,
    k: usize,
    p: &Projection,
    f: [f64; 2],
    status: Status,
    mu: f64,
) -> Option<NodeFrame> {
    let node = model.candidates[k];
    let ez = model.dofs.equation(2 * node + 1)?;
    let er = model.dofs.equation(2 * node);
    let lambda = -(f[0] * p.m[0] + f[1] * p.m[1]);
    let tau = f[0] * p.t[0] + f[1] * p.t[1];
    let (stick, slip, d) = match (er, status) {
        (None, _) => (false, 0.0, 0.0),
        (Some(_), 0) => (true, 0.0, 0.0),
        (Some(_), s) => {
            let sigma = f64::from(s);
            let den = 1.0 + p.gap * p.kappa;
            let d = if p.kappa == 0.0 || !(den > 0.0) {
                0.0
            } else {
                p.kappa * (-lambda + mu * sigma * tau) / den
            };
            (false, -mu * sigma, d)
        }
    };
    Some(NodeFrame {
        er,
        ez,
        t: p.t,
        m: p.m,
        d,
        stick,
        slip,
    })
}

/// The prescribed tangential increment `t . du = (xi - s)(1 + g kappa)` of a sticking
/// node.
pub(crate) fn stick_increment(p: &Projection, xi: f64) -> f64 {
    (xi - p.s) * (1.0 + p.gap * p.kappa)
}

/// The tangential residual of an active off-axis node: `(t - mu sigma m) . f` slipping,
/// `t . f` frictionless; sticking nodes have none (their tangential dof is prescribed).
pub(crate) fn tangential_residual(p: &Projection, f: [f64; 2], status: Status, mu: f64) -> f64 {
    let c = -mu * f64::from(status);
    (p.t[0] + c * p.m[0]) * f[0] + (p.t[1] + c * p.m[1]) * f[1]
}

/// The tolerances of [`check`].
#[derive(Clone, Copy, Debug)]
pub(crate) struct CheckTolerances {
    /// On the Coulomb cone and on tension (N).
    pub cone: f64,
    /// On the slip direction (mm).
    pub slip: f64,
    /// The force that scales a cone violation (N, > 0).
    pub scale: f64,
}

/// The stick/slip check of an active off-axis node: `Some((new status, violation))` when
/// its status is inadmissible (`violation` > 0, relative to `tol.scale`), `None`
/// otherwise.
pub(crate) fn check(
    p: &Projection,
    f: [f64; 2],
    xi: f64,
    status: Status,
    mu: f64,
    tol: CheckTolerances,
) -> Option<(Status, f64)> {
    let CheckTolerances {
        cone: ltol,
        slip: stol,
        scale,
    } = tol;
    let lambda = -(f[0] * p.m[0] + f[1] * p.m[1]);
    let tau = f[0] * p.t[0] + f[1] * p.t[1];
    if status == 0 {
        // outside the cone, or under tension (released only once slipping)
        let excess = tau.abs() - mu * lambda.max(0.0);
        (excess > ltol || lambda < -ltol)
            .then(|| (if tau > 0.0 { -1 } else { 1 }, excess.max(-lambda) / scale))
    } else {
        let back = -f64::from(status) * (p.s - xi);
        (back > stol).then(|| (0, back / stol.max(1e-300) * 1e-12))
    }
}
