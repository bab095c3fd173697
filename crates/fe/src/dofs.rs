//! Dof numbering: global displacement dofs (2 per node) to equation numbers, with the
//! fixed Dirichlet dofs (u = 0: axis u_r, bottom u_z) eliminated.

/// Marker for a dof without an equation (eliminated).
pub const NO_EQ: u32 = u32::MAX;

/// Maps every global dof `2 n + c` (c = 0 for u_r, 1 for u_z) to an equation or [`NO_EQ`].
#[derive(Clone, Debug, PartialEq)]
pub struct DofMap {
    /// Equation of each global dof, or [`NO_EQ`] for an eliminated (fixed-zero) dof.
    pub eq: Vec<u32>,
    /// Number of equations.
    pub n_eq: usize,
}

impl DofMap {
    /// Numbers the dofs in order, skipping those in `fixed` (fixed to zero).
    pub fn new(n_dofs: usize, fixed: &[usize]) -> DofMap {
        let mut is_fixed = vec![false; n_dofs];
        for &d in fixed {
            is_fixed[d] = true;
        }
        let mut eq = vec![NO_EQ; n_dofs];
        let mut n_eq = 0;
        for (d, e) in eq.iter_mut().enumerate() {
            if !is_fixed[d] {
                *e = n_eq as u32;
                n_eq += 1;
            }
        }
        DofMap { eq, n_eq }
    }

    /// The standard supports of the cylinder: `u_r = 0` on `axis`, `u_z = 0` on `bottom`.
    pub fn cylinder(mesh: &indentify_mesh::Mesh) -> DofMap {
        let mut fixed: Vec<usize> = mesh.node_set("axis").iter().map(|n| 2 * n).collect();
        fixed.extend(mesh.node_set("bottom").iter().map(|n| 2 * n + 1));
        DofMap::new(2 * mesh.nodes.len(), &fixed)
    }

    /// Equation of dof `d`, if it has one.
    #[inline]
    pub fn equation(&self, d: usize) -> Option<usize> {
        let e = self.eq[d];
        (e != NO_EQ).then_some(e as usize)
    }

    /// Copies the free entries of a full dof vector into an equation vector.
    pub fn restrict(&self, full: &[f64], out: &mut [f64]) {
        for (d, &e) in self.eq.iter().enumerate() {
            if e != NO_EQ {
                out[e as usize] = full[d];
            }
        }
    }
}
