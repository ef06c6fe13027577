//! The Schur complement of a symmetric matrix's interior block onto its boundary, from one
//! partial LDLᵀ (static condensation, thesis §2.6):
//!
//! A = [A_ii A_ib; A_bi A_bb] ⇒ S = A_bb − A_bi A_ii⁻¹ A_ib.
//!
//! M = [A_ii A_ib; A_bi A_bb] is factored with the interior in a fill-reducing order and the
//! boundary last (a split [`Half`] whose separator is the boundary), stopped before the
//! boundary: its trailing block, updated by the interior's columns and left unfactored, is S
//! (`partial.rs`), so S costs one partial sparse factorisation instead of one solve with A_ii
//! per boundary column, and it is formed whether or not it is singular. The same factor solves A_ii x = b (the forward
//! sweep over the interior, then the backward one with the boundary held at zero) and gives
//! −A_bi A_ii⁻¹ b (the boundary rows of the forward sweep).

use super::{Half, PivotRule};
use crate::{
    FaerOrdering, SolverError, SymmetricMatrix, SymmetricPattern, approximate_minimum_degree,
    metis_nested_dissection, nested_dissection,
};

/// Pivots of A_ii at or below this fraction of their diagonal entry are zero pivots (an error
/// naming the DOF), as the f64 LDLᵀ judges them.
const ZERO_PIVOT: f64 = 1e-13;

/// A's interior block factored with the boundary appended (module docs). Made once per
/// pattern by [`analyze`](Self::analyze); [`factorize`](Self::factorize) per set of values.
pub struct SchurComplement {
    /// None when A has no DOF in either list (nothing to factor).
    half: Option<Half>,
    /// Interior DOFs of A in the caller's order.
    interior: Vec<usize>,
    /// Local interior position (elimination order) → index in `interior`.
    order: Vec<usize>,
    boundary: usize,
    ordering: FaerOrdering,
    flops: f64,
    /// Whether the last factorisation succeeded (the sweeps need it).
    factored: bool,
}

/// What [`SchurComplement::factorize`] found.
#[derive(Debug, Clone, PartialEq)]
pub struct SchurOutcome {
    /// S = A_bb − A_bi A_ii⁻¹ A_ib, row-major, nb × nb, in the boundary's order (symmetric:
    /// both triangles written from the lower one).
    pub schur: Vec<f64>,
    /// Negative pivots of A_ii.
    pub negative_pivots: usize,
}

impl SchurComplement {
    /// The structure for A of pattern `pattern` (lower triangle, A's numbering) with the
    /// interior DOFs `interior` and boundary DOFs `boundary` (disjoint; any other DOF of A is
    /// left out, e.g. a prescribed one). The interior is ordered by `ordering`: AMD, our nested
    /// dissection, METIS, or (`Auto`) METIS, our nested dissection if METIS fails (measured on
    /// the substructure bench's plates, 4.7 k and 11.5 k interior DOFs: METIS's order gave the
    /// fastest condensation, 56 and 244 ms against 64 and 306 ms with AMD; ordering by both
    /// and keeping the fewer flops took 90 and 285 ms).
    pub fn analyze(
        pattern: &SymmetricPattern,
        interior: &[usize],
        boundary: &[usize],
        ordering: FaerOrdering,
    ) -> Result<Self, SolverError> {
        let n = pattern.n();
        let mut local = vec![usize::MAX; n];
        for (k, &d) in interior.iter().chain(boundary).enumerate() {
            let slot = local.get_mut(d).ok_or(SolverError::BlockDof {
                dof: d,
                n,
                reason: "out of range",
            })?;
            if *slot != usize::MAX {
                return Err(SolverError::BlockDof {
                    dof: d,
                    n,
                    reason: "listed twice (the interior and the boundary are disjoint)",
                });
            }
            *slot = k;
        }
        let ni = interior.len();
        let mut columns: Vec<Vec<usize>> = vec![Vec::new(); ni];
        for &j in interior {
            for &i in pattern.column(j) {
                let (a, b) = (local[i], local[j]);
                if a < ni && i != j {
                    columns[a.min(b)].push(a.max(b));
                }
            }
        }
        let inner = SymmetricPattern::from_lower_columns(ni, &columns)?;
        drop(columns);
        let (chosen, order) = match ordering {
            FaerOrdering::Amd => (ordering, approximate_minimum_degree(&inner)?),
            FaerOrdering::NestedDissection => (ordering, nested_dissection(&inner)?),
            FaerOrdering::Metis => (ordering, metis_nested_dissection(&inner)?),
            FaerOrdering::Auto => match metis_nested_dissection(&inner) {
                Ok(p) => (FaerOrdering::Metis, p),
                Err(_) => (FaerOrdering::NestedDissection, nested_dissection(&inner)?),
            },
        };
        let order = order.forward().to_vec();
        let mut dofs: Vec<usize> = order.iter().map(|&k| interior[k]).collect();
        dofs.extend_from_slice(boundary);
        let half = match dofs.is_empty() {
            true => None,
            false => Some(Half::new(pattern, dofs, ni, 0)?),
        };
        let flops = half
            .as_ref()
            .map_or(0.0, |h| super::super::factor_flops(&h.symbolic));
        Ok(Self {
            half,
            interior: interior.to_vec(),
            order,
            boundary: boundary.len(),
            ordering: chosen,
            flops,
            factored: false,
        })
    }

    /// The ordering the interior got ([`FaerOrdering::Amd`], `NestedDissection` or `Metis`).
    pub fn ordering(&self) -> FaerOrdering {
        self.ordering
    }

    /// Entries of the factor (the interior's columns and the boundary's dense block).
    pub fn factor_entries(&self) -> usize {
        self.half.as_ref().map_or(0, |h| h.symbolic.len_val())
    }

    /// Σc² over the factor's column counts.
    pub fn flops(&self) -> f64 {
        self.flops
    }

    /// Factors A (`a` on the pattern given to [`analyze`](Self::analyze)) in f64 on one
    /// thread and forms S, singular or not (a boundary that leaves the interior free to move
    /// as a rigid body gives a singular S, exactly). Errors: a zero pivot of A_ii (naming its
    /// DOF of A).
    pub fn factorize(&mut self, a: &SymmetricMatrix) -> Result<SchurOutcome, SolverError> {
        self.factored = false;
        let diag = a.diagonal();
        let rule = PivotRule::Double {
            tolerance: ZERO_PIVOT,
        };
        let Some(half) = self.half.as_mut() else {
            self.factored = true;
            return Ok(SchurOutcome {
                schur: Vec::new(),
                negative_pivots: 0,
            });
        };
        let negative_pivots =
            match half.factorize::<f64>(a.values(), &diag, rule, faer::Par::Seq)? {
                Ok(count) => count,
                // An f64 elimination judges its pivots by errors, never by a reason to retry.
                Err(reason) => return Err(SolverError::Faer(reason.into())),
            };
        self.factored = true;
        let nb = self.boundary;
        // S's lower triangle added straight into the row-major result (a column-major view of
        // it, transposed, is the matrix itself), then mirrored up.
        let mut schur = vec![0.0; nb * nb];
        half.add_separator_block::<f64>(
            faer::MatMut::from_column_major_slice_mut(&mut schur, nb, nb).transpose_mut(),
        );
        for i in 0..nb {
            for j in 0..i {
                schur[j * nb + i] = schur[i * nb + j];
            }
        }
        Ok(SchurOutcome {
            schur,
            negative_pivots,
        })
    }

    /// The local vector of interior values `x` (in the order of `interior` given to
    /// [`analyze`](Self::analyze)) with the boundary's zero.
    fn local(&self, x: &[f64]) -> Vec<f64> {
        let mut z = vec![0.0; self.order.len() + self.boundary];
        for (slot, &k) in z.iter_mut().zip(&self.order) {
            *slot = x[k];
        }
        z
    }

    fn check(&self, x: &[f64]) -> Result<(), SolverError> {
        match x.len() == self.interior.len() {
            true => Ok(()),
            false => Err(SolverError::DimensionMismatch {
                what: "interior values of a Schur complement",
                expected: self.interior.len(),
                got: x.len(),
            }),
        }
    }

    /// −A_bi A_ii⁻¹ x for interior values `x` (the order of `interior`), in the boundary's
    /// order: the boundary rows of the forward sweep. Needs a factorisation.
    pub fn reduce(&self, x: &[f64]) -> Result<Vec<f64>, SolverError> {
        self.check(x)?;
        let (half, l) = self.factor()?;
        let mut z = self.local(x);
        if let Some(half) = half {
            half.forward::<f64>(l, &mut z);
        }
        Ok(z.split_off(self.order.len()))
    }

    /// x ← A_ii⁻¹ x for interior values `x` (the order of `interior`): the forward sweep, the
    /// boundary rows set to zero, the backward sweep. Needs a factorisation.
    pub fn solve_interior(&self, x: &mut [f64]) -> Result<(), SolverError> {
        self.check(x)?;
        let (half, l) = self.factor()?;
        let Some(half) = half else {
            return Ok(());
        };
        let mut z = self.local(x);
        half.forward::<f64>(l, &mut z);
        let ni = self.order.len();
        z[ni..].fill(0.0);
        half.backward::<f64>(l, &mut z);
        for (v, &k) in z.iter().zip(&self.order) {
            x[k] = *v;
        }
        Ok(())
    }

    /// The half and its factor values (no half: nothing was factored, nothing to sweep).
    fn factor(&self) -> Result<(Option<&Half>, &[f64]), SolverError> {
        match self.factored {
            true => Ok(match &self.half {
                Some(h) => (Some(h), <f64 as super::Real>::view(&h.l)),
                None => (None, &[]),
            }),
            false => Err(SolverError::NotReady(
                "a Schur complement's sweeps before a successful factorisation",
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;

    /// A 1-D chain of springs with a diagonal shift: tridiagonal, SPD.
    fn chain(n: usize) -> SymmetricMatrix {
        let columns: Vec<Vec<usize>> = (0..n)
            .map(|j| if j + 1 < n { vec![j, j + 1] } else { vec![j] })
            .collect();
        let p = Arc::new(SymmetricPattern::from_lower_columns(n, &columns).unwrap());
        let mut a = SymmetricMatrix::zeros(p);
        for j in 0..n {
            a.add(j, j, 2.5 + 0.1 * j as f64).unwrap();
            if j + 1 < n {
                a.add(j + 1, j, -1.0).unwrap();
            }
        }
        a
    }

    fn dense(a: &SymmetricMatrix) -> Vec<Vec<f64>> {
        let n = a.n();
        let mut m = vec![vec![0.0; n]; n];
        for j in 0..n {
            for (p, &i) in a.pattern().column(j).iter().enumerate() {
                let v = a.values()[a.pattern().col_ptr()[j] + p];
                m[i][j] = v;
                m[j][i] = v;
            }
        }
        m
    }

    /// Dense Gaussian elimination of m x = b.
    fn solve_dense(mut m: Vec<Vec<f64>>, mut b: Vec<f64>) -> Vec<f64> {
        let n = b.len();
        for k in 0..n {
            for i in k + 1..n {
                let f = m[i][k] / m[k][k];
                for j in k..n {
                    m[i][j] -= f * m[k][j];
                }
                b[i] -= f * b[k];
            }
        }
        let mut x = vec![0.0; n];
        for k in (0..n).rev() {
            let s: f64 = (k + 1..n).map(|j| m[k][j] * x[j]).sum();
            x[k] = (b[k] - s) / m[k][k];
        }
        x
    }

    /// S, A_ii⁻¹ b and −A_bi A_ii⁻¹ b against dense elimination on a chain whose boundary is
    /// scattered through it (DOFs 0, 7, 13 of 20; 19 left out as if prescribed), with every
    /// ordering: the same numbers to rounding (1e-12 of their size).
    #[test]
    fn schur_solve_and_reduce_match_dense_elimination() {
        let a = chain(20);
        let full = dense(&a);
        let boundary = [7, 0, 13];
        let interior: Vec<usize> = (1..19).filter(|d| !boundary.contains(d)).rev().collect();
        let sub = |rows: &[usize], cols: &[usize]| -> Vec<Vec<f64>> {
            rows.iter()
                .map(|&i| cols.iter().map(|&j| full[i][j]).collect())
                .collect()
        };
        let aii = sub(&interior, &interior);
        let x: Vec<f64> = (0..interior.len())
            .map(|k| (k as f64 * 0.7).sin())
            .collect();
        let y = solve_dense(aii.clone(), x.clone());
        let abi = sub(&boundary, &interior);
        let reduced: Vec<f64> = abi
            .iter()
            .map(|row| -row.iter().zip(&y).map(|(a, b)| a * b).sum::<f64>())
            .collect();
        for ordering in [
            FaerOrdering::Amd,
            FaerOrdering::NestedDissection,
            FaerOrdering::Metis,
            FaerOrdering::Auto,
        ] {
            let mut s =
                SchurComplement::analyze(a.pattern(), &interior, &boundary, ordering).unwrap();
            let out = s.factorize(&a).unwrap();
            assert_eq!(out.negative_pivots, 0);
            for (bi, &i) in boundary.iter().enumerate() {
                for (bj, &j) in boundary.iter().enumerate() {
                    let col: Vec<f64> = interior.iter().map(|&k| full[k][j]).collect();
                    let z = solve_dense(aii.clone(), col);
                    let want = full[i][j]
                        - interior
                            .iter()
                            .zip(&z)
                            .map(|(&k, v)| full[i][k] * v)
                            .sum::<f64>();
                    let got = out.schur[bi * 3 + bj];
                    assert!(
                        (got - want).abs() <= 1e-12 * want.abs().max(1.0),
                        "{ordering:?}"
                    );
                }
            }
            let mut solved = x.clone();
            s.solve_interior(&mut solved).unwrap();
            for (g, w) in solved.iter().zip(&y) {
                assert!((g - w).abs() <= 1e-12, "{ordering:?}: {g} against {w}");
            }
            for (g, w) in s.reduce(&x).unwrap().iter().zip(&reduced) {
                assert!((g - w).abs() <= 1e-12, "{ordering:?}: {g} against {w}");
            }
        }
    }

    /// No boundary: S is empty and the factor is A_ii's, which still solves; neither: nothing
    /// to factor; no interior: S is A.
    #[test]
    fn an_empty_boundary_gives_an_empty_complement() {
        let a = chain(6);
        let interior: Vec<usize> = (0..6).collect();
        let mut s =
            SchurComplement::analyze(a.pattern(), &interior, &[], FaerOrdering::Auto).unwrap();
        let out = s.factorize(&a).unwrap();
        assert!(out.schur.is_empty());
        let mut x = vec![1.0; 6];
        s.solve_interior(&mut x).unwrap();
        let mut ax = vec![0.0; 6];
        a.matvec(&x, &mut ax).unwrap();
        assert!(ax.iter().all(|v| (v - 1.0).abs() < 1e-12), "{ax:?}");
        assert!(s.reduce(&x).unwrap().is_empty());
        // Nothing in either list (every DOF left out): nothing to factor.
        let mut s = SchurComplement::analyze(a.pattern(), &[], &[], FaerOrdering::Auto).unwrap();
        assert_eq!(s.factorize(&a).unwrap().schur, Vec::<f64>::new());
        s.solve_interior(&mut []).unwrap();
        assert!(s.reduce(&[]).unwrap().is_empty());
        // No interior: S is A itself.
        let mut s =
            SchurComplement::analyze(a.pattern(), &[], &interior, FaerOrdering::Auto).unwrap();
        let out = s.factorize(&a).unwrap();
        let full = dense(&a);
        for i in 0..6 {
            for j in 0..6 {
                assert!(
                    (out.schur[i * 6 + j] - full[i][j]).abs() < 1e-12,
                    "({i}, {j})"
                );
            }
        }
    }

    /// An interior that the boundary does not hold (a chain cut off from it) is singular:
    /// the zero pivot is an error naming a DOF of A. A singular S is formed exactly: it is
    /// read from the boundary's block, never rebuilt from a factor of it.
    #[test]
    fn a_singular_interior_is_an_error_and_a_singular_schur_complement_is_exact() {
        let p = Arc::new(
            SymmetricPattern::from_lower_columns(3, &[vec![0, 1], vec![1], vec![2]]).unwrap(),
        );
        let mut a = SymmetricMatrix::zeros(p);
        for (i, j, v) in [(0, 0, 1.0), (1, 0, -1.0), (1, 1, 1.0), (2, 2, 1.0)] {
            a.add(i, j, v).unwrap();
        }
        // Interior {0, 1}: the free spring pair, singular.
        let mut s =
            SchurComplement::analyze(a.pattern(), &[0, 1], &[2], FaerOrdering::Amd).unwrap();
        assert!(matches!(
            s.factorize(&a),
            Err(SolverError::ZeroPivot { dof: 0 | 1, .. })
        ));
        // Interior {0}, boundary {1, 2}: S = [1 − 1·1⁻¹·1, 0; 0, 1] = [0 0; 0 1], singular.
        let mut s =
            SchurComplement::analyze(a.pattern(), &[0], &[1, 2], FaerOrdering::Amd).unwrap();
        let out = s.factorize(&a).unwrap();
        assert_eq!(out.schur, vec![0.0, 0.0, 0.0, 1.0]);
        // A_ii = [1]: A_ii⁻¹·2 = 2; −A_bi A_ii⁻¹·2 = (2, 0).
        let mut x = [2.0];
        s.solve_interior(&mut x).unwrap();
        assert_eq!(x, [2.0]);
        assert_eq!(s.reduce(&[2.0]).unwrap(), vec![2.0, 0.0]);
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig {
            cases: 64, ..proptest::prelude::ProptestConfig::default()
        })]

        /// For a diagonally dominant (so positive definite) random sparse matrix and a random
        /// split of its DOFs into interior, boundary and left out, S and A_ii⁻¹ x equal dense
        /// elimination's to 1e-10 of their size (the pivots are bounded below by the
        /// dominance margin, so the rounding is of order n·ε·‖A‖).
        #[test]
        fn schur_matches_dense_elimination_on_random_systems(
            n in 3usize..24,
            seed in 0u64..10_000,
            roles in proptest::collection::vec(0u8..3, 24),
        ) {
            let mut rng = nonlin3d_testkit::Lcg::new(seed);
            let mut entries = Vec::new();
            for j in 0..n {
                for i in j + 1..n {
                    if rng.uniform(0.0, 1.0) < 0.3 {
                        entries.push((i, j, rng.uniform(-1.0, 1.0)));
                    }
                }
            }
            let mut columns: Vec<Vec<usize>> = (0..n).map(|j| vec![j]).collect();
            for &(i, j, _) in &entries {
                columns[j].push(i);
            }
            let p = Arc::new(SymmetricPattern::from_lower_columns(n, &columns).unwrap());
            let mut a = SymmetricMatrix::zeros(p);
            let mut row_sum = vec![0.0; n];
            for &(i, j, v) in &entries {
                a.add(i, j, v).unwrap();
                row_sum[i] += v.abs();
                row_sum[j] += v.abs();
            }
            for (j, r) in row_sum.iter().enumerate() {
                a.add(j, j, 1.0 + r).unwrap();
            }
            let interior: Vec<usize> = (0..n).filter(|&d| roles[d] == 0).collect();
            let boundary: Vec<usize> = (0..n).filter(|&d| roles[d] == 1).collect();
            let full = dense(&a);
            let sub = |rows: &[usize], cols: &[usize]| -> Vec<Vec<f64>> {
                rows.iter().map(|&i| cols.iter().map(|&j| full[i][j]).collect()).collect()
            };
            let mut s = SchurComplement::analyze(a.pattern(), &interior, &boundary, FaerOrdering::Auto)
                .unwrap();
            let out = s.factorize(&a).unwrap();
            proptest::prop_assert_eq!(out.negative_pivots, 0);
            let nb = boundary.len();
            let aii = sub(&interior, &interior);
            for (bj, &j) in boundary.iter().enumerate() {
                let col: Vec<f64> = interior.iter().map(|&k| full[k][j]).collect();
                let z = if interior.is_empty() { Vec::new() } else { solve_dense(aii.clone(), col) };
                for (bi, &i) in boundary.iter().enumerate() {
                    let want = full[i][j]
                        - interior.iter().zip(&z).map(|(&k, v)| full[i][k] * v).sum::<f64>();
                    let got = out.schur[bi * nb + bj];
                    proptest::prop_assert!((got - want).abs() <= 1e-10 * want.abs().max(1.0));
                }
            }
            if !interior.is_empty() {
                let x: Vec<f64> = (0..interior.len()).map(|k| (k as f64).cos()).collect();
                let want = solve_dense(aii, x.clone());
                let mut got = x;
                s.solve_interior(&mut got).unwrap();
                for (g, w) in got.iter().zip(&want) {
                    proptest::prop_assert!((g - w).abs() <= 1e-10 * w.abs().max(1.0));
                }
            }
        }
    }
}
