//! Finite-difference checks of every block of a [`Material`] at one material point: the
//! residual's Jacobians `A, D, E, P` (regime held), the update's residual, its consistent
//! tangent (against the blocks and against finite differences of the update) and the
//! update's derivatives in the previous state and the parameters (`-A^-1 D`, `-A^-1 P`,
//! what the adjoint and the sensitivities use), and the adjoint's contraction `mu^T P`
//! ([`Material::jac_params_transpose`]) against `P`.

use crate::mandel::Vec4;
use crate::material::{Material, Regime, Step, dense_solve, tangent_from_blocks};

/// One material-point case: parameters, previous state, strain increment, time step.
#[derive(Clone, Debug)]
pub struct Point<'a> {
    /// Parameters in the material's order.
    pub c: &'a [f64],
    /// Previous state `y0 = [sigma, alpha]`.
    pub y0: &'a [f64],
    /// Strain increment.
    pub deps: Vec4,
    /// Time step (s).
    pub dt: f64,
}

/// The agreement of one block with its finite-difference estimate.
#[derive(Clone, Debug, PartialEq)]
pub struct BlockCheck {
    /// Which block (`A = dR/dy1`, `tangent vs fd(update)`, ...).
    pub block: &'static str,
    /// Largest row-wise relative error (rows scaled by their largest entry; columns by
    /// the typical size of their variable), `None` when skipped.
    pub error: Option<f64>,
    /// Why the check was skipped, if it was.
    pub skipped: Option<&'static str>,
}

/// Every check at one point, with the regime the update took.
#[derive(Clone, Debug)]
pub struct FdReport {
    /// The regime of the converged update.
    pub regime: Regime,
    /// One entry per block.
    pub checks: Vec<BlockCheck>,
}

impl FdReport {
    /// The largest error of the checks that ran.
    pub fn worst(&self) -> f64 {
        self.checks
            .iter()
            .filter_map(|c| c.error)
            .fold(0.0, f64::max)
    }
}

/// Relative step of the fourth-order central stencil (truncation ~1e-20 relative,
/// round-off ~1e-11).
const DELTA: f64 = 1e-5;

/// `(-f(2h) + 8 f(h) - 8 f(-h) + f(-2h)) / (12 h)` for a vector function.
fn stencil(f: &mut dyn FnMut(f64) -> Vec<f64>, h: f64) -> Vec<f64> {
    let (p2, p1, m1, m2) = (f(2.0 * h), f(h), f(-h), f(-2.0 * h));
    (0..p1.len())
        .map(|i| (m2[i] - p2[i] + 8.0 * (p1[i] - m1[i])) / (12.0 * h))
        .collect()
}

/// Row-wise relative error of `a` vs `b` (`rows x cols`, row-major), each column scaled
/// by `t[j]` (the typical size of its variable): rows that are zero in both pass.
fn row_error(a: &[f64], b: &[f64], rows: usize, t: &[f64]) -> f64 {
    let cols = t.len();
    let mut worst = 0.0f64;
    for i in 0..rows {
        let (mut scale, mut diff) = (0.0f64, 0.0f64);
        for j in 0..cols {
            let (x, y) = (a[i * cols + j] * t[j], b[i * cols + j] * t[j]);
            scale = scale.max(x.abs()).max(y.abs());
            diff = diff.max((x - y).abs());
        }
        if scale > 0.0 {
            worst = worst.max(diff / scale);
        }
    }
    worst
}

/// Finite-difference matrix (`rows x t.len()`, row-major) of `f` around 0 in each
/// coordinate direction `j`, with step `DELTA t[j]`.
fn fd_matrix(rows: usize, t: &[f64], mut f: impl FnMut(usize, f64) -> Vec<f64>) -> Vec<f64> {
    let cols = t.len();
    let mut out = vec![0.0; rows * cols];
    for j in 0..cols {
        let col = stencil(&mut |h| f(j, h), DELTA * t[j]);
        for i in 0..rows {
            out[i * cols + j] = col[i];
        }
    }
    out
}

/// Typical sizes of the state's entries: the largest stress component for the four
/// stress entries (at least 1 MPa), each internal variable's own size (at least 1e-6).
fn state_scales(y0: &[f64], y1: &[f64]) -> Vec<f64> {
    let smax = y0[..4]
        .iter()
        .chain(&y1[..4])
        .fold(1.0f64, |m, v| m.max(v.abs()));
    let mut t = vec![smax; 4];
    t.extend((4..y0.len()).map(|j| y0[j].abs().max(y1[j].abs()).max(1e-6)));
    t
}

fn push(checks: &mut Vec<BlockCheck>, block: &'static str, error: f64) {
    checks.push(BlockCheck {
        block,
        error: Some(error),
        skipped: None,
    });
}

/// The checks of what an adjoint sweep calls instead of the single blocks: `jac_blocks`
/// against the four methods' `blocks = [A, D, E, P]`, and `solve_state_transpose` by its
/// backward error (`scales` = the state's, the strain's and the parameters' sizes).
fn sweep_checks(
    mat: &dyn Material,
    pt: &Point<'_>,
    y1: &[f64],
    regime: Regime,
    [a, d, e, p]: [&[f64]; 4],
    [ty, te, tc]: [&[f64]; 3],
    checks: &mut Vec<BlockCheck>,
) {
    let (c, m) = (pt.c, mat.state_len());
    let st = Step {
        y0: pt.y0,
        y1,
        deps: &pt.deps,
        dt: pt.dt,
        regime,
    };
    // every block at once (what a sweep calls) against the four methods
    let (mut a2, mut d2, mut e2, mut p2) = (vec![0.0; m * m], d.to_vec(), e.to_vec(), p.to_vec());
    for v in [&mut d2, &mut e2, &mut p2] {
        v.fill(f64::NAN);
    }
    a2.fill(f64::NAN);
    mat.jac_blocks(c, &st, &mut a2, &mut d2, &mut e2, &mut p2);
    let together = row_error(&a2, a, m, ty)
        .max(row_error(&d2, d, m, ty))
        .max(row_error(&e2, e, m, te))
        .max(row_error(&p2, p, m, tc));
    push(
        checks,
        "jac_blocks vs the four blocks",
        if together.is_nan() {
            f64::INFINITY
        } else {
            together
        },
    );

    // the sweep's solve with `A^T` (a law's closed form, or the default elimination)
    // against the elimination, for the four unit vectors and a cotangent of mixed signs
    {
        let nrhs = 5;
        let mut rhs = vec![0.0; m * nrhs];
        for r in 0..m {
            if r < 4 {
                rhs[r * nrhs + r] = 1.0;
            }
            rhs[r * nrhs + 4] = (1.1 + 0.9 * r as f64).cos() * ty[r];
        }
        let mut want = rhs.clone();
        let mut at = vec![0.0; m * m];
        for r in 0..m {
            for k in 0..m {
                at[k * m + r] = a[r * m + k];
            }
        }
        let solved = crate::material::dense_solve_many(&mut at, m, &mut want, nrhs);
        let mut got = rhs.clone();
        let mut work = vec![0.0; m * m];
        let ok = mat.solve_state_transpose(c, &st, a, &mut got, nrhs, &mut work);
        let err = if solved && ok {
            // the backward error of each equation `(A^T x)_i = b_i`, relative to the
            // size of its terms (scale free; the elimination's own is ~1e-16)
            let mut worst = 0.0f64;
            for k in 0..nrhs {
                for i in 0..m {
                    let (mut ax, mut size) = (0.0, rhs[i * nrhs + k].abs());
                    for r in 0..m {
                        let t = a[r * m + i] * got[r * nrhs + k];
                        ax += t;
                        size += t.abs();
                    }
                    let d = (ax - rhs[i * nrhs + k]).abs();
                    worst = worst.max(if size > 0.0 { d / size } else { d });
                }
            }
            let _ = &want;
            worst
        } else if solved == ok {
            0.0
        } else {
            f64::INFINITY
        };
        push(checks, "A^T solve (backward error)", err);
    }
}

/// Runs every check at `pt` and fails when one exceeds `tol` (1e-6 is the level this
/// crate's laws meet).
///
/// Blocks of the residual are compared with central finite differences of
/// [`Material::residual`] with the update's regime held; the update's derivatives with
/// finite differences of [`Material::update`], skipped when the regime changes within the
/// stencil (the point sits on a switch of a rate-independent law).
///
/// # Errors
/// A message naming the material, the block and its error, or the update's failure.
pub fn check_material(mat: &dyn Material, pt: &Point<'_>, tol: f64) -> Result<FdReport, String> {
    let (c, m, nc) = (pt.c, mat.state_len(), pt.c.len());
    let name = mat.name();
    let mut y1 = vec![0.0; m];
    let up = mat
        .update(c, pt.y0, &pt.deps, pt.dt, &mut y1)
        .map_err(|f| format!("{name}: update failed: {f}"))?;
    if y1.iter().any(|v| !v.is_finite()) {
        return Err(format!("{name}: update returned a non-finite state {y1:?}"));
    }
    let regime = up.regime;
    let step = |y0: &[f64], y1: &[f64], deps: &Vec4, f: &mut dyn FnMut(&Step<'_>)| {
        f(&Step {
            y0,
            y1,
            deps,
            dt: pt.dt,
            regime,
        });
    };
    let resid = |c: &[f64], y0: &[f64], y1: &[f64], deps: &Vec4| {
        let mut r = vec![0.0; m];
        step(y0, y1, deps, &mut |s| mat.residual(c, s, &mut r));
        r
    };
    let ty = state_scales(pt.y0, &y1);
    let te = vec![pt.deps.max_abs().max(1e-9); 4];
    let tc: Vec<f64> = c.iter().map(|v| v.abs().max(1e-3)).collect();
    let mut checks = Vec::new();

    // the residual at the converged state, relative to the size of its terms
    let r = resid(c, pt.y0, &y1, &pt.deps);
    let mut a = vec![0.0; m * m];
    step(pt.y0, &y1, &pt.deps, &mut |s| mat.jac_state(c, s, &mut a));
    let term = (0..m)
        .map(|i| {
            (0..m)
                .map(|j| (a[i * m + j] * ty[j]).abs())
                .fold(0.0, f64::max)
        })
        .collect::<Vec<_>>();
    let res_err = (0..m)
        .map(|i| {
            if term[i] > 0.0 {
                r[i].abs() / term[i]
            } else {
                r[i].abs()
            }
        })
        .fold(0.0, f64::max);
    push(&mut checks, "residual at the update", res_err);

    let fd_a = fd_matrix(m, &ty, |j, h| {
        let mut y = y1.clone();
        y[j] += h;
        resid(c, pt.y0, &y, &pt.deps)
    });
    push(&mut checks, "A = dR/dy1", row_error(&a, &fd_a, m, &ty));

    let mut d = vec![0.0; m * m];
    step(pt.y0, &y1, &pt.deps, &mut |s| {
        mat.jac_previous(c, s, &mut d)
    });
    let fd_d = fd_matrix(m, &ty, |j, h| {
        let mut y = pt.y0.to_vec();
        y[j] += h;
        resid(c, &y, &y1, &pt.deps)
    });
    push(&mut checks, "D = dR/dy0", row_error(&d, &fd_d, m, &ty));

    let mut e = vec![0.0; m * 4];
    step(pt.y0, &y1, &pt.deps, &mut |s| mat.jac_strain(c, s, &mut e));
    let fd_e = fd_matrix(m, &te, |j, h| {
        let mut de = pt.deps;
        de[j] += h;
        resid(c, pt.y0, &y1, &de)
    });
    push(&mut checks, "E = dR/ddeps", row_error(&e, &fd_e, m, &te));

    let mut p = vec![0.0; m * nc];
    step(pt.y0, &y1, &pt.deps, &mut |s| mat.jac_params(c, s, &mut p));
    let fd_p = fd_matrix(m, &tc, |k, h| {
        let mut cc = c.to_vec();
        cc[k] += h;
        resid(&cc, pt.y0, &y1, &pt.deps)
    });
    push(&mut checks, "P = dR/dc", row_error(&p, &fd_p, m, &tc));

    sweep_checks(
        mat,
        pt,
        &y1,
        regime,
        [&a, &d, &e, &p],
        [&ty, &te, &tc],
        &mut checks,
    );

    // the adjoint's contraction `mu^T P` (a law's closed form, or the default) against
    // the block, with a cotangent of mixed signs scaled by the state's sizes, added to
    // a nonzero `out`
    let mu: Vec<f64> = (0..m)
        .map(|r| (0.7 + 1.3 * r as f64).sin() / ty[r])
        .collect();
    let weight = -1.75;
    // (each entry's offset on the scale of its terms: it is added to, not overwritten)
    let size: Vec<f64> = (0..nc)
        .map(|k| (0..m).map(|r| (mu[r] * p[r * nc + k]).abs()).sum())
        .collect();
    let mut got: Vec<f64> = size.iter().map(|s| 0.5 * s).collect();
    let mut scratch = vec![0.0; m * nc];
    step(pt.y0, &y1, &pt.deps, &mut |s| {
        mat.jac_params_transpose(c, s, &mu, weight, &mut scratch, &mut got)
    });
    let (mut diff, mut scale) = (0.0f64, 0.0f64);
    for k in 0..nc {
        let want: f64 = (0..m).map(|r| mu[r] * p[r * nc + k]).sum();
        diff = diff.max((got[k] - 0.5 * size[k] - weight * want).abs() * tc[k]);
        scale = scale.max(weight.abs() * size[k] * tc[k]);
    }
    push(
        &mut checks,
        "mu^T P (jac_params_transpose)",
        if scale > 0.0 { diff / scale } else { diff },
    );

    // the update's tangent against the blocks
    let mut tb = None;
    step(pt.y0, &y1, &pt.deps, &mut |s| {
        tb = Some(tangent_from_blocks(mat, c, s))
    });
    let tb = tb.expect("set").map_err(|f| format!("{name}: {f}"))?;
    let flat = |t: &crate::Mat4| t.0.as_flattened().to_vec();
    push(
        &mut checks,
        "tangent vs -A^-1 E",
        row_error(&flat(&up.tangent), &flat(&tb), 4, &[1.0; 4]),
    );

    // derivatives of the update itself: tangent, -A^-1 D, -A^-1 P
    let updated = |c: &[f64], y0: &[f64], deps: &Vec4| -> Option<(Vec<f64>, Regime)> {
        let mut y = vec![0.0; m];
        let u = mat.update(c, y0, deps, pt.dt, &mut y).ok()?;
        Some((y, u.regime))
    };
    let mut switched = false;
    let mut track = |r: Option<(Vec<f64>, Regime)>| match r {
        Some((y, reg)) => {
            switched |= reg != regime;
            y
        }
        None => {
            switched = true;
            vec![f64::NAN; m]
        }
    };
    let fd_t = fd_matrix(m, &te, |j, h| {
        let mut de = pt.deps;
        de[j] += h;
        track(updated(c, pt.y0, &de))
    });
    let fd_y0 = fd_matrix(m, &ty, |j, h| {
        let mut y = pt.y0.to_vec();
        y[j] += h;
        track(updated(c, &y, &pt.deps))
    });
    let fd_c = fd_matrix(m, &tc, |k, h| {
        let mut cc = c.to_vec();
        cc[k] += h;
        track(updated(&cc, pt.y0, &pt.deps))
    });
    if switched {
        for block in [
            "tangent vs fd(update)",
            "dy1/dy0 = -A^-1 D",
            "dy1/dc = -A^-1 P",
        ] {
            checks.push(BlockCheck {
                block,
                error: None,
                skipped: Some("the regime changes within the stencil"),
            });
        }
    } else {
        let mut t_rows = vec![0.0; 16];
        for i in 0..4 {
            t_rows[i * 4..i * 4 + 4].copy_from_slice(&fd_t[i * 4..i * 4 + 4]);
        }
        push(
            &mut checks,
            "tangent vs fd(update)",
            row_error(&flat(&up.tangent), &t_rows, 4, &te),
        );
        let sens = |b: &[f64], cols: usize| -> Vec<f64> {
            let mut out = vec![0.0; m * cols];
            for j in 0..cols {
                let mut col: Vec<f64> = (0..m).map(|i| -b[i * cols + j]).collect();
                let mut work = a.clone();
                if dense_solve(&mut work, m, &mut col) {
                    for i in 0..m {
                        out[i * cols + j] = col[i];
                    }
                } else {
                    out.fill(f64::NAN);
                }
            }
            out
        };
        push(
            &mut checks,
            "dy1/dy0 = -A^-1 D",
            row_error(&sens(&d, m), &fd_y0, m, &ty),
        );
        push(
            &mut checks,
            "dy1/dc = -A^-1 P",
            row_error(&sens(&p, nc), &fd_c, m, &tc),
        );
    }
    let report = FdReport { regime, checks };
    for ch in &report.checks {
        if let Some(err) = ch.error
            && !(err <= tol)
        {
            return Err(format!(
                "{name} ({regime:?}): {} disagrees with finite differences: {err:e} > {tol:e} \
                 at c = {c:?}, y0 = {:?}, deps = {:?}, dt = {}",
                ch.block, pt.y0, pt.deps, pt.dt
            ));
        }
    }
    Ok(report)
}
