//! Which path [`FaerSolver`]'s factorisations and solves take: f32 (mixed precision) or f64,
//! split at the top separator or not.

use super::{FaerMode, FaerPrecision, FaerSolver};
use crate::{Factorization, SolverError, SymmetricMatrix};

impl FaerSolver {
    /// Whether factorisations go through the f32 path.
    pub(super) fn uses_mixed(&self) -> bool {
        self.precision != FaerPrecision::Double && self.mode == FaerMode::Ldlt && !self.below_mixed
    }

    /// The f64 factorisation: split when the analysis split, else unsplit.
    pub(super) fn factorize_f64(
        &mut self,
        a: &SymmetricMatrix,
    ) -> Result<Factorization, SolverError> {
        if self.split_state.is_some() {
            self.factorize_split(a)
        } else {
            self.factorize_double(a)
        }
    }

    /// Solves with the f64 factor, split or not.
    pub(super) fn solve_f64(&mut self, b: &mut [f64], nrhs: usize) -> Result<(), SolverError> {
        if self.solve_split(b, nrhs) {
            Ok(())
        } else {
            self.solve_double(b, nrhs)
        }
    }
}
