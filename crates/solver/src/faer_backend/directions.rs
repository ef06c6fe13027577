//! Cheaper direction solves on a kept factor (issue 20): [`FaerDirections::Single`] keeps an
//! f32 copy L̃D̃L̃ᵀ of each f64 LDLᵀ factor and answers
//! [`LinearSolver::solve_direction_in_place`](crate::LinearSolver::solve_direction_in_place)
//! with it, for solves that need only an approximation of A⁻¹ (BFGS's H₀ = K₀⁻¹ on a kept
//! tangent: the direction only has to point downhill; the residual that decides convergence is
//! always f64). A triangular solve is memory-bound, so reading half the bytes makes it faster;
//! the copy's rounding (relative ε₃₂ = 6e-8 per entry) perturbs the solution by about
//! cond(A)·ε₃₂ relative. Solves of the answer (`solve_in_place`) never use it.

use super::{FaerMode, FaerSolver, SOLVE_PAR};
use crate::SolverError;
use faer::dyn_stack::MemStack;
use faer::sparse::linalg::cholesky::LdltRef;
use faer::{Conj, MatMut};

/// What [`FaerSolver`]'s `solve_direction_in_place` solves with.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FaerDirections {
    /// The factor itself: the same bits as `solve_in_place` (the default).
    #[default]
    Factor,
    /// An f32 copy of the unsplit f64 LDLᵀ factor, made after each f64 factorisation (half
    /// the factor's memory more). Where there is none (LLᵀ, a split or mixed-precision factor,
    /// an entry beyond f32's range or a pivot that rounds to zero) the factor itself is used.
    Single,
}

impl FaerSolver {
    /// After an f64 unsplit LDLᵀ factorisation: the f32 copy of `l_values` if
    /// [`FaerDirections::Single`] asks for one and every entry survives the rounding.
    pub(super) fn copy_for_directions(&mut self) -> Result<(), SolverError> {
        self.directions_l32.clear();
        if self.directions != FaerDirections::Single || self.mode != FaerMode::Ldlt {
            return Ok(());
        }
        let fits = self
            .l_values
            .iter()
            .all(|v| v.abs() <= f64::from(f32::MAX) && (*v == 0.0 || (*v as f32) != 0.0));
        if !fits {
            return Ok(());
        }
        if self.directions_l32.capacity() < self.l_values.len() {
            self.directions_l32 = super::mixed::try_zeros_f32(self.l_values.len())?;
            self.directions_l32.clear();
        }
        self.directions_l32
            .extend(self.l_values.iter().map(|&v| v as f32));
        Ok(())
    }

    /// x ≈ A⁻¹b with the f32 copy if there is one (each column scaled to ‖b‖∞ = 1 so small
    /// right-hand sides do not underflow), else with the factor.
    pub(super) fn solve_direction(
        &mut self,
        b: &mut [f64],
        nrhs: usize,
    ) -> Result<(), SolverError> {
        use crate::LinearSolver;
        self.check_rhs(b, nrhs)?;
        let (false, Some(symbolic), Some(buffer)) = (
            self.directions_l32.is_empty(),
            &self.symbolic,
            &mut self.buffer,
        ) else {
            return self.solve_in_place(b, nrhs);
        };
        let n = symbolic.nrows();
        let factor = LdltRef::<usize, f32>::new(symbolic, &self.directions_l32);
        let mut c = vec![0.0f32; n];
        for col in b.chunks_mut(n.max(1)) {
            let scale = col.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            if scale == 0.0 {
                continue;
            }
            for (ci, bi) in c.iter_mut().zip(col.iter()) {
                *ci = (bi / scale) as f32;
            }
            factor.solve_in_place_with_conj(
                Conj::No,
                MatMut::from_column_major_slice_mut(&mut c, n, 1),
                SOLVE_PAR,
                MemStack::new(buffer),
            );
            for (bi, ci) in col.iter_mut().zip(&c) {
                *bi = f64::from(*ci) * scale;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{LinearSolver, SymmetricMatrix, SymmetricPattern};
    use std::sync::Arc;

    /// tridiag(−1, 2, −1) of order n (a chain of unit springs between two walls): eigenvalues
    /// 2 − 2cos(kπ/(n+1)), so cond = (1 + cos(π/(n+1)))/(1 − cos(π/(n+1))).
    fn chain(n: usize) -> (SymmetricMatrix, f64) {
        let lists: Vec<Vec<usize>> = (0..n - 1).map(|i| vec![i, i + 1]).collect();
        let p = Arc::new(SymmetricPattern::from_dof_lists(n, &lists).unwrap());
        let mut a = SymmetricMatrix::zeros(p);
        for i in 0..n {
            a.add(i, i, 2.0).unwrap();
            if i + 1 < n {
                a.add(i + 1, i, -1.0).unwrap();
            }
        }
        let c = (std::f64::consts::PI / (n + 1) as f64).cos();
        (a, (1.0 + c) / (1.0 - c))
    }

    fn solved(s: &mut FaerSolver, b: &[f64], direction: bool) -> Vec<f64> {
        let mut x = b.to_vec();
        if direction {
            s.solve_direction_in_place(&mut x, 1).unwrap();
        } else {
            s.solve_in_place(&mut x, 1).unwrap();
        }
        x
    }

    /// `Factor` directions are the answer's solve, bit for bit; `Single` ones differ from it
    /// (the f32 copy is used) by at most 4·cond(A)·ε₃₂ relative: the copy is A + δA with
    /// ‖δA‖ ≲ 3ε₃₂‖|L̃||D̃||L̃ᵀ|‖ = 3ε₃₂‖A‖ (positive definite: |L||D||Lᵀ| = A's bound here, the
    /// chain's factor has |l| ≤ 1), plus the f32 solve's own rounding, so the forward error is
    /// about cond·(3 + 1)ε₃₂. n = 300: cond = 3.7e4, bound 1.8e-2. The answer's solve is
    /// unchanged by the copy (same bits as a solver without it).
    #[test]
    fn single_directions_are_within_cond_times_f32_rounding() {
        let (a, cond) = chain(300);
        let b: Vec<f64> = (0..a.n()).map(|i| 1.0 + (i % 5) as f64).collect();
        let mut exact = FaerSolver::new(FaerMode::Ldlt);
        exact.analyze(a.pattern()).unwrap();
        exact.factorize(&a).unwrap();
        let x = solved(&mut exact, &b, false);
        assert_eq!(solved(&mut exact, &b, true), x);
        let mut single = FaerSolver::new(FaerMode::Ldlt);
        single.directions = FaerDirections::Single;
        single.analyze(a.pattern()).unwrap();
        single.factorize(&a).unwrap();
        assert_eq!(solved(&mut single, &b, false), x);
        let d = solved(&mut single, &b, true);
        let norm = |v: &[f64]| v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let diff: Vec<f64> = d.iter().zip(&x).map(|(p, q)| p - q).collect();
        let relative = norm(&diff) / norm(&x);
        let bound = 4.0 * cond * f64::from(f32::EPSILON) / 2.0;
        assert!(relative > 0.0 && relative <= bound, "{relative} vs {bound}");
    }
}
