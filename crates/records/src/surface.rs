//! The contact found on the stiffness instead of the force: the first sample where the
//! median over 5 samples of `|dF/dh|` (central differences, one-sided at the ends) exceeds a
//! threshold. indentationGUI's "rate to find surface" (1 mN/µm on fused silica); it finds
//! the surface of a multi-cycle test whose first cycles stay below the force threshold
//! (docs/analysis.md, "Against indentationGUI and the vendor").

/// The first sample where the 5-sample median of `|dF/dh|` (zero beyond the ends and where
/// the depth does not change) exceeds `stiffness` (N/mm), or `None`.
pub(crate) fn stiffness_contact(h: &[f64], f: &[f64], stiffness: f64) -> Option<usize> {
    let n = h.len().min(f.len());
    if n < 2 {
        return None;
    }
    let slope = |i: usize| {
        let (a, b) = (i.saturating_sub(1), (i + 1).min(n - 1));
        let d = ((f[b] - f[a]) / (h[b] - h[a])).abs();
        if d.is_finite() { d } else { 0.0 }
    };
    let d: Vec<f64> = (0..n).map(slope).collect();
    (0..n).find(|&i| {
        let mut w = [0.0; 5];
        for (k, x) in w.iter_mut().enumerate() {
            *x = (i + k)
                .checked_sub(2)
                .and_then(|j| d.get(j))
                .copied()
                .unwrap_or(0.0);
        }
        w.sort_by(f64::total_cmp);
        w[2] > stiffness
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_contact_after_a_flat_approach_is_found_where_the_slope_rises() {
        // approach: 20 samples, force flat with +-1 uN noise; contact at sample 20, then
        // F = 10 N/mm (h - h_c) (a stiff linear rise), 1 nm steps
        let h: Vec<f64> = (0..60).map(|i| 1e-6 * i as f64).collect();
        let f: Vec<f64> = (0..60)
            .map(|i| {
                if i < 20 {
                    if i % 2 == 0 { 1e-6 } else { -1e-6 }
                } else {
                    10.0 * 1e-6 * (i - 20) as f64
                }
            })
            .collect();
        // the noise's central differences cancel (0, 2 N/mm at the first sample); the
        // median of 5 passes 5 N/mm at sample 20 (5.5, 10, 10 of the rise among its 5)
        assert_eq!(stiffness_contact(&h, &f, 5.0), Some(20));
        assert_eq!(stiffness_contact(&h, &f, 20.0), None);
        assert_eq!(stiffness_contact(&h[..1], &f[..1], 5.0), None);
    }
}
