//! A symmetric sparse matrix on a fixed [`SymmetricPattern`].

use crate::{SolverError, SymmetricPattern};
use std::sync::Arc;

/// Values of the lower triangle of a symmetric matrix on a shared, fixed pattern: built once
/// from connectivity, re-zeroed and re-filled every Newton iteration.
#[derive(Debug, Clone, PartialEq)]
pub struct SymmetricMatrix {
    pattern: Arc<SymmetricPattern>,
    values: Vec<f64>,
}

impl SymmetricMatrix {
    /// A zero matrix on `pattern`.
    pub fn zeros(pattern: Arc<SymmetricPattern>) -> Self {
        let values = vec![0.0; pattern.nnz_lower()];
        Self { pattern, values }
    }

    /// A zero matrix on `pattern`, or [`SolverError::OutOfMemory`] if the system refuses the
    /// memory (8 bytes per stored entry).
    pub fn try_zeros(pattern: Arc<SymmetricPattern>) -> Result<Self, SolverError> {
        let values = crate::budget::try_zeros(pattern.nnz_lower(), "the matrix values")?;
        Ok(Self { pattern, values })
    }

    /// A matrix from its lower-triangle values (in the pattern's order).
    pub fn from_values(
        pattern: Arc<SymmetricPattern>,
        values: Vec<f64>,
    ) -> Result<Self, SolverError> {
        if values.len() != pattern.nnz_lower() {
            return Err(SolverError::DimensionMismatch {
                what: "values",
                expected: pattern.nnz_lower(),
                got: values.len(),
            });
        }
        Ok(Self { pattern, values })
    }

    /// The pattern.
    pub fn pattern(&self) -> &Arc<SymmetricPattern> {
        &self.pattern
    }

    /// Dimension n.
    pub fn n(&self) -> usize {
        self.pattern.n()
    }

    /// Checks that this matrix lives on `pattern` (the one a solver analysed) and holds only
    /// finite values.
    pub fn check_for(&self, pattern: &Arc<SymmetricPattern>) -> Result<(), SolverError> {
        self.check_pattern(pattern)?;
        self.check_finite()
    }

    /// Checks that this matrix lives on `pattern` (the values are not read).
    pub(crate) fn check_pattern(&self, pattern: &Arc<SymmetricPattern>) -> Result<(), SolverError> {
        if !Arc::ptr_eq(pattern, &self.pattern) && **pattern != *self.pattern {
            return Err(SolverError::DimensionMismatch {
                what: "matrix pattern (not the analysed one)",
                expected: pattern.nnz_lower(),
                got: self.pattern.nnz_lower(),
            });
        }
        Ok(())
    }

    /// Lower-triangle values in the pattern's order.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// Mutable lower-triangle values.
    pub fn values_mut(&mut self) -> &mut [f64] {
        &mut self.values
    }

    /// Sets every value to zero, keeping the pattern.
    pub fn set_zero(&mut self) {
        self.values.fill(0.0);
    }

    /// a_ij += v (either triangle addresses the same stored entry).
    pub fn add(&mut self, i: usize, j: usize, v: f64) -> Result<(), SolverError> {
        let p = self
            .pattern
            .position(i, j)
            .ok_or(SolverError::PatternMismatch { row: i, col: j })?;
        self.values[p] += v;
        Ok(())
    }

    /// The entry a_ij (zero if not stored).
    pub fn get(&self, i: usize, j: usize) -> f64 {
        self.pattern.position(i, j).map_or(0.0, |p| self.values[p])
    }

    /// Adds a dense symmetric element matrix `k` (row-major, `dofs.len()`²) at global DOFs
    /// `dofs`; only entries with global row ≥ column are read.
    pub fn scatter_add(&mut self, dofs: &[usize], k: &[f64]) -> Result<(), SolverError> {
        let ne = dofs.len();
        if k.len() != ne * ne {
            return Err(SolverError::DimensionMismatch {
                what: "element matrix",
                expected: ne * ne,
                got: k.len(),
            });
        }
        for (a, &i) in dofs.iter().enumerate() {
            for (b, &j) in dofs.iter().enumerate() {
                if i >= j {
                    let p = self
                        .pattern
                        .position(i, j)
                        .ok_or(SolverError::PatternMismatch { row: i, col: j })?;
                    self.values[p] += k[a * ne + b];
                }
            }
        }
        Ok(())
    }

    /// Adds a dense element matrix through a map from [`SymmetricPattern::scatter_map`].
    pub fn scatter_add_mapped(
        &mut self,
        map: &[Option<usize>],
        k: &[f64],
    ) -> Result<(), SolverError> {
        if k.len() != map.len() {
            return Err(SolverError::DimensionMismatch {
                what: "element matrix",
                expected: map.len(),
                got: k.len(),
            });
        }
        for (p, v) in map.iter().zip(k) {
            if let Some(p) = *p {
                match self.values.get_mut(p) {
                    Some(slot) => *slot += v,
                    None => {
                        return Err(SolverError::DimensionMismatch {
                            what: "scatter map",
                            expected: self.values.len(),
                            got: p,
                        });
                    }
                }
            }
        }
        Ok(())
    }

    /// y = A x: over the pattern's 3×3 node blocks when it has them (one index read per nine
    /// values), else column by column; both give the same bits
    /// ([`matvec_by_columns`](Self::matvec_by_columns)).
    pub fn matvec(&self, x: &[f64], y: &mut [f64]) -> Result<(), SolverError> {
        self.check_lengths(x, y)?;
        match self.pattern.nodes() {
            Some(blocks) => blocks.matvec(self.pattern.col_ptr(), &self.values, x, y),
            None => self.columns_matvec(x, y),
        }
        Ok(())
    }

    /// y = A x column by column: for each column j, y(i) += a_ij·x_j below the diagonal and
    /// y(j) += a_jj·x_j + Σ_{i>j} a_ij·x_i. The reference order of operations of
    /// [`matvec`](Self::matvec) (for tests and benchmarks).
    pub fn matvec_by_columns(&self, x: &[f64], y: &mut [f64]) -> Result<(), SolverError> {
        self.check_lengths(x, y)?;
        self.columns_matvec(x, y);
        Ok(())
    }

    fn check_lengths(&self, x: &[f64], y: &[f64]) -> Result<(), SolverError> {
        let n = self.n();
        for (what, got) in [("x", x.len()), ("y", y.len())] {
            if got != n {
                return Err(SolverError::DimensionMismatch {
                    what,
                    expected: n,
                    got,
                });
            }
        }
        Ok(())
    }

    fn columns_matvec(&self, x: &[f64], y: &mut [f64]) {
        let n = self.n();
        y.fill(0.0);
        let (cp, ri) = (self.pattern.col_ptr(), self.pattern.row_idx());
        for j in 0..n {
            let (s, e) = (cp[j], cp[j + 1]);
            let xj = x[j];
            let mut acc = self.values[s] * xj;
            for (&i, &a) in ri[s + 1..e].iter().zip(&self.values[s + 1..e]) {
                y[i] += a * xj;
                acc += a * x[i];
            }
            y[j] += acc;
        }
    }

    /// The diagonal a_jj.
    pub fn diagonal(&self) -> Vec<f64> {
        let cp = self.pattern.col_ptr();
        (0..self.n()).map(|j| self.values[cp[j]]).collect()
    }

    /// Rejects NaN or infinite entries, naming the first.
    pub fn check_finite(&self) -> Result<(), SolverError> {
        let (cp, ri) = (self.pattern.col_ptr(), self.pattern.row_idx());
        for j in 0..self.n() {
            for p in cp[j]..cp[j + 1] {
                if !self.values[p].is_finite() {
                    return Err(SolverError::NonFinite {
                        row: ri[p],
                        col: j,
                        value: self.values[p],
                    });
                }
            }
        }
        Ok(())
    }

    /// The full matrix, dense row-major (for tests and small problems).
    pub fn to_dense(&self) -> Vec<f64> {
        let n = self.n();
        let mut d = vec![0.0; n * n];
        let (cp, ri) = (self.pattern.col_ptr(), self.pattern.row_idx());
        for j in 0..n {
            for p in cp[j]..cp[j + 1] {
                let i = ri[p];
                d[i * n + j] = self.values[p];
                d[j * n + i] = self.values[p];
            }
        }
        d
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scatter_and_matvec_match_dense() {
        let p =
            Arc::new(SymmetricPattern::from_dof_lists(4, &[vec![0, 2], vec![2, 3, 1]]).unwrap());
        let mut a = SymmetricMatrix::zeros(p.clone());
        a.scatter_add(&[0, 2], &[4.0, 1.0, 1.0, 5.0]).unwrap();
        a.scatter_add(
            &[2, 3, 1],
            &[2.0, -1.0, 0.5, -1.0, 3.0, 0.25, 0.5, 0.25, 6.0],
        )
        .unwrap();
        let map = p.scatter_map(&[0, 2]).unwrap();
        a.scatter_add_mapped(&map, &[1.0, 0.0, 0.0, 1.0]).unwrap();
        let d = a.to_dense();
        assert_eq!(d[0], 5.0);
        assert_eq!(d[2 * 4 + 2], 8.0);
        assert_eq!(d[3 * 4 + 2], -1.0);
        assert_eq!(d[2 * 4 + 3], -1.0);
        let x = [1.0, -2.0, 0.5, 3.0];
        let mut y = [0.0; 4];
        a.matvec(&x, &mut y).unwrap();
        for i in 0..4 {
            let e: f64 = (0..4).map(|j| d[i * 4 + j] * x[j]).sum();
            assert!((y[i] - e).abs() < 1e-14);
        }
        assert!(matches!(
            a.add(0, 3, 1.0),
            Err(SolverError::PatternMismatch { row: 0, col: 3 })
        ));
        a.values_mut()[1] = f64::NAN;
        assert!(matches!(
            a.check_finite(),
            Err(SolverError::NonFinite { .. })
        ));
    }
}
