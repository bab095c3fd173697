//! Finite-difference references for gradient checks: central differences of any scalar
//! function of the parameters, and a scan over step sizes that shows the
//! truncation / round-off "V".

/// Central difference `(f(c + h e_k) - f(c - h e_k)) / 2h` with `h = h_rel * |c_k|`
/// (or `h_rel` when `c_k = 0`).
///
/// # Errors
/// Whatever `f` returns.
pub fn central_difference<E>(
    mut f: impl FnMut(&[f64]) -> Result<f64, E>,
    c: &[f64],
    k: usize,
    h_rel: f64,
) -> Result<f64, E> {
    let h = if c[k] == 0.0 {
        h_rel
    } else {
        h_rel * c[k].abs()
    };
    let mut p = c.to_vec();
    p[k] = c[k] + h;
    let fp = f(&p)?;
    p[k] = c[k] - h;
    let fm = f(&p)?;
    Ok((fp - fm) / (2.0 * h))
}

/// One row of a step-size scan: relative step, FD value and its relative difference to
/// the reference.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScanRow {
    /// Relative step `h / |c_k|`.
    pub h_rel: f64,
    /// Central-difference value.
    pub fd: f64,
    /// `|fd - reference| / |reference|` (absolute difference when the reference is 0).
    pub rel_diff: f64,
}

/// Central differences of parameter `k` over `steps` relative step sizes, compared with
/// `reference` (the adjoint value): the rows trace the truncation (large h) / round-off
/// (small h) V; its bottom is the agreement.
///
/// # Errors
/// Whatever `f` returns.
pub fn scan<E>(
    mut f: impl FnMut(&[f64]) -> Result<f64, E>,
    c: &[f64],
    k: usize,
    reference: f64,
    steps: &[f64],
) -> Result<Vec<ScanRow>, E> {
    steps
        .iter()
        .map(|&h_rel| {
            let fd = central_difference(&mut f, c, k, h_rel)?;
            Ok(ScanRow {
                h_rel,
                fd,
                rel_diff: relative_difference(fd, reference),
            })
        })
        .collect()
}

/// `|a - b| / max(|a|, |b|)`, or 0 when both vanish.
pub fn relative_difference(a: f64, b: f64) -> f64 {
    let m = a.abs().max(b.abs());
    if m == 0.0 { 0.0 } else { (a - b).abs() / m }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn central_difference_of_a_cubic_is_second_order() {
        let f = |c: &[f64]| Ok::<f64, ()>(c[0].powi(3));
        let d = central_difference(f, &[2.0], 0, 1e-3).unwrap();
        // exact 12; error h^2 = (2e-3)^2 = 4e-6
        assert!((d - 12.0).abs() < 1e-5 && (d - 12.0).abs() > 1e-7);
        let rows = scan(f, &[2.0], 0, 12.0, &[1e-2, 1e-4]).unwrap();
        assert!(rows[1].rel_diff < rows[0].rel_diff);
    }
}
