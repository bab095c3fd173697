//! The 8-node serendipity quadrilateral reference element and its 3x3 Gauss rule.
//!
//! Node order (the VTK `QUADRATIC_QUAD` order): corners 0 (-1,-1), 1 (1,-1), 2 (1,1),
//! 3 (-1,1), then mid-sides 4 (0,-1), 5 (1,0), 6 (0,1), 7 (-1,0), counter-clockwise.

/// Reference coordinates `(xi, eta)` of the eight nodes.
pub const NODES: [[f64; 2]; 8] = [
    [-1.0, -1.0],
    [1.0, -1.0],
    [1.0, 1.0],
    [-1.0, 1.0],
    [0.0, -1.0],
    [1.0, 0.0],
    [0.0, 1.0],
    [-1.0, 0.0],
];

/// Shape function values `N_a(xi, eta)`, a = 0..8.
pub fn shape(xi: f64, eta: f64) -> [f64; 8] {
    let mut n = [0.0; 8];
    for (a, &[xa, ya]) in NODES.iter().enumerate() {
        n[a] = if a < 4 {
            0.25 * (1.0 + xi * xa) * (1.0 + eta * ya) * (xi * xa + eta * ya - 1.0)
        } else if xa == 0.0 {
            0.5 * (1.0 - xi * xi) * (1.0 + eta * ya)
        } else {
            0.5 * (1.0 + xi * xa) * (1.0 - eta * eta)
        };
    }
    n
}

/// Shape function gradients `[dN_a/dxi, dN_a/deta]`, a = 0..8.
pub fn shape_gradients(xi: f64, eta: f64) -> [[f64; 2]; 8] {
    let mut d = [[0.0; 2]; 8];
    for (a, &[xa, ya]) in NODES.iter().enumerate() {
        d[a] = if a < 4 {
            [
                0.25 * xa * (1.0 + eta * ya) * (2.0 * xi * xa + eta * ya),
                0.25 * ya * (1.0 + xi * xa) * (xi * xa + 2.0 * eta * ya),
            ]
        } else if xa == 0.0 {
            [-xi * (1.0 + eta * ya), 0.5 * ya * (1.0 - xi * xi)]
        } else {
            [0.5 * xa * (1.0 - eta * eta), -eta * (1.0 + xi * xa)]
        };
    }
    d
}

/// The 3x3 Gauss-Legendre rule on [-1, 1]^2: points `(xi, eta)` and weights (sum 4).
pub fn gauss3x3() -> [([f64; 2], f64); 9] {
    let p = (0.6f64).sqrt();
    let pts = [-p, 0.0, p];
    let wts = [5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0];
    let mut out = [([0.0; 2], 0.0); 9];
    for j in 0..3 {
        for i in 0..3 {
            out[3 * j + i] = ([pts[i], pts[j]], wts[i] * wts[j]);
        }
    }
    out
}

/// Jacobian `[[dr/dxi, dr/deta], [dz/dxi, dz/deta]]` of the map at `(xi, eta)` for nodal
/// coordinates `x` (each `[r, z]`), and its determinant.
pub fn jacobian(x: &[[f64; 2]; 8], xi: f64, eta: f64) -> ([[f64; 2]; 2], f64) {
    let d = shape_gradients(xi, eta);
    let mut j = [[0.0; 2]; 2];
    for a in 0..8 {
        for (row, xa) in j.iter_mut().zip(x[a]) {
            row[0] += xa * d[a][0];
            row[1] += xa * d[a][1];
        }
    }
    let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
    (j, det)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn partition_of_unity_and_kronecker_property() {
        for (a, &[x, y]) in NODES.iter().enumerate() {
            let n = shape(x, y);
            for (b, v) in n.iter().enumerate() {
                assert!((v - if a == b { 1.0 } else { 0.0 }).abs() < 1e-15);
            }
        }
        let n = shape(0.31, -0.77);
        assert!((n.iter().sum::<f64>() - 1.0).abs() < 1e-15);
        let d = shape_gradients(0.31, -0.77);
        assert!(d.iter().map(|g| g[0]).sum::<f64>().abs() < 1e-15);
        assert!(d.iter().map(|g| g[1]).sum::<f64>().abs() < 1e-15);
    }

    #[test]
    fn gradients_match_central_differences() {
        let (x, y, h) = (0.23, 0.61, 1e-6);
        let d = shape_gradients(x, y);
        let (xp, xm) = (shape(x + h, y), shape(x - h, y));
        let (yp, ym) = (shape(x, y + h), shape(x, y - h));
        for a in 0..8 {
            assert!(((xp[a] - xm[a]) / (2.0 * h) - d[a][0]).abs() < 1e-9);
            assert!(((yp[a] - ym[a]) / (2.0 * h) - d[a][1]).abs() < 1e-9);
        }
    }

    #[test]
    fn gauss_rule_integrates_quintics_exactly() {
        let s: f64 = gauss3x3()
            .iter()
            .map(|([x, y], w)| w * x.powi(4) * y.powi(2))
            .sum();
        assert!((s - (2.0 / 5.0) * (2.0 / 3.0)).abs() < 1e-14);
    }
}
