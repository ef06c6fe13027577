//! The stability of a contact state counted on the pairs that hold it. A closed pair is a
//! bilateral tie in the system (w_upper = w_lower along the normal, §2.7), but contact is
//! unilateral: a pair whose recovered force f̂ is not compressive beyond the force tolerance
//! would open as soon as the faces moved apart, so it cannot lend the state its stiffness.
//! Counted with every closed pair tied, a flat sublaminate past its bifurcation whose faces
//! merely touch (f̂ = 0 at every pair) looks stable — the ties suppress the buckling mode that
//! lifts it off the base. Counted with only the carrying pairs tied, the same state shows the
//! negative pivot of that mode (Sylvester's law of inertia on K_T).

use super::{Contact, ContactState};
use crate::ContactError;
use nonlin3d_newton::{PathSolver, StructuralProblem};

impl Contact {
    /// Negative pivots of the tangent at (u, λ) with only the carrying closed pairs tied
    /// (f̂_i > the state's force tolerance), or None when every closed pair carries force (the
    /// count with the whole set then stands). The whole set is installed again afterwards and
    /// the session's factorisation is dropped (it belongs to the reduced set).
    pub fn holding_inertia(
        &mut self,
        problem: &mut StructuralProblem,
        u: &[f64],
        lambda: f64,
        state: &ContactState,
        session: &mut PathSolver,
    ) -> Result<Option<usize>, ContactError> {
        let carrying = carrying(state);
        if carrying == state.active {
            return Ok(None);
        }
        self.install(problem, u, &carrying)?;
        let pivots = session.inertia_at(problem, u, lambda);
        session.invalidate();
        self.install(problem, u, &state.active)?;
        Ok(Some(pivots?))
    }
}

/// The closed pairs whose recovered force is compressive beyond the force tolerance.
fn carrying(state: &ContactState) -> Vec<bool> {
    state
        .active
        .iter()
        .zip(&state.recovered)
        .map(|(&a, &f)| a && f > state.force_tolerance)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state(active: Vec<bool>, recovered: Vec<f64>) -> ContactState {
        let n = active.len();
        ContactState {
            normals: vec![[0.0, 0.0, 1.0]; n],
            gaps: vec![0.0; n],
            weighted_gaps: vec![0.0; n],
            forces: recovered.clone(),
            recovered,
            pressures: vec![0.0; n],
            active,
            force_tolerance: 1e-6,
            residual: 0.0,
            total: [0.0; 3],
        }
    }

    #[test]
    fn only_compressive_pairs_beyond_the_tolerance_carry() {
        let s = state(
            vec![true, true, true, false, true],
            vec![2.0, 0.0, 1e-7, 5.0, -1.0],
        );
        assert_eq!(carrying(&s), vec![true, false, false, false, false]);
        let all = state(vec![true, false], vec![3.0, 0.0]);
        assert_eq!(carrying(&all), all.active);
    }
}
