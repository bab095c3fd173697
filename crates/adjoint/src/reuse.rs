//! The forward's factorization handed to the adjoint (docs/validation-load-control.md §6,
//! "The forward's factor"): a linear law's run keeps one factor of its unconstrained
//! tangent and the capacitance columns `K^-1 e_c` of every dof it prescribed, keyed by
//! the parameters, the step length and the tangent; the sweep of that run's trajectory
//! needs the same ones for its last steps (all of them when the step length is one).

use indentify_contact::DirectSolver;

use crate::Adjoint;

impl<'m> Adjoint<'m> {
    /// Takes the factorization `solver` kept of its last run (a solver on this adjoint's
    /// model; `false`, nothing taken, otherwise) for the next sweep or sensitivity pass,
    /// giving the solver this workspace's last one in exchange
    /// ([`indentify_contact::RecordedContact::exchange_factor`]). Call it between the
    /// forward run that recorded a trajectory and the gradient of that trajectory: the
    /// steps under the kept key (the parameters bit for bit, the step length and the
    /// tangent to 1e-12 relative) then take no factorization and no column solve, the
    /// others factorize as before; a factor of other parameters, another step length or
    /// another law is never used. The gradient equals the one without it bit for bit
    /// where the forward keyed the segment with the tangent the fresh sweep would (the
    /// same `K`, factor and columns: `tests/factor_reuse.rs`), and to round-off where
    /// the segment's step lengths, hence tangents, differ in their last bits (the sweep
    /// then transposes the forward's own `K`). Only the next pass keeps it: the ones
    /// after start from a new system's state again.
    pub fn take_factor(&mut self, solver: &mut DirectSolver<'m>) -> bool {
        self.contact.exchange_factor(solver)
    }
}
