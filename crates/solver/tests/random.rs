//! Random sparse symmetric systems: the profile and faer solvers against dense nalgebra.
//!
//! Matrices are assembled from random dense "element" blocks on random DOF subsets. SPD cases:
//! Σ MᵀM + 0.1·I per block. Indefinite cases: random symmetric blocks, then each diagonal set to
//! ±(1 + Σ|off-diagonal|) with random signs: strictly diagonally dominant, so elimination without
//! pivoting is stable and the factorisation exists, and the condition number stays small enough
//! that 1e-10 relative residuals are guaranteed.

use nalgebra::{DMatrix, DVector, SymmetricEigen};
use nonlin3d_solver::{
    FaerMode, FaerSolver, FaerStructure, LinearSolver, ProfileLdlt, SymmetricMatrix,
    SymmetricPattern,
};
use proptest::prelude::*;
use std::sync::Arc;

#[derive(Debug, Clone)]
struct Case {
    n: usize,
    lists: Vec<Vec<usize>>,
    blocks: Vec<Vec<f64>>,
    signs: Vec<bool>,
    rhs: Vec<f64>,
}

/// One SPD block B = MᵀM + 0.1·I per DOF list, M from the random numbers `raw` (36 per list).
/// The indefinite variant re-signs the assembled diagonal later.
fn spd_blocks(lists: &[Vec<usize>], raw: &[f64]) -> Vec<Vec<f64>> {
    lists
        .iter()
        .enumerate()
        .map(|(e, l)| {
            let m = l.len();
            let r = &raw[e * 36..e * 36 + m * m];
            let mut b = vec![0.0; m * m];
            for i in 0..m {
                for j in 0..m {
                    b[i * m + j] = (0..m).map(|k| r[k * m + i] * r[k * m + j]).sum::<f64>();
                }
                b[i * m + i] += 0.1;
            }
            b
        })
        .collect()
}

fn case() -> impl Strategy<Value = Case> {
    (2usize..60).prop_flat_map(|n| {
        let list = proptest::collection::btree_set(0..n, 1..=6.min(n))
            .prop_map(|s| s.into_iter().collect::<Vec<_>>());
        with_lists(n, proptest::collection::vec(list, 1..(2 * n)))
    })
}

/// Cases of `n` DOFs on the DOF lists that `lists` draws: a block per list ([`spd_blocks`], 36
/// random numbers each), the signs of the indefinite variant and a right-hand side.
fn with_lists(
    n: usize,
    lists: impl Strategy<Value = Vec<Vec<usize>>>,
) -> impl Strategy<Value = Case> {
    (
        Just(n),
        lists,
        proptest::collection::vec(-1.0..1.0f64, 36 * 2 * n),
        proptest::collection::vec(any::<bool>(), n),
        proptest::collection::vec(-1.0..1.0f64, n),
    )
        .prop_map(|(n, lists, raw, signs, rhs)| {
            let blocks = spd_blocks(&lists, &raw);
            Case {
                n,
                lists,
                blocks,
                signs,
                rhs,
            }
        })
}

fn assemble(c: &Case, indefinite: bool) -> SymmetricMatrix {
    let p = Arc::new(SymmetricPattern::from_dof_lists(c.n, &c.lists).unwrap());
    let mut a = SymmetricMatrix::zeros(p.clone());
    for (l, b) in c.lists.iter().zip(&c.blocks) {
        a.scatter_add(l, b).unwrap();
    }
    // Every DOF gets at least a unit diagonal (DOFs no block touches would be singular).
    for i in 0..c.n {
        a.add(i, i, 1.0).unwrap();
    }
    if indefinite {
        let d = a.to_dense();
        for i in 0..c.n {
            let off: f64 = (0..c.n)
                .filter(|&j| j != i)
                .map(|j| d[i * c.n + j].abs())
                .sum();
            let target = (1.0 + off) * if c.signs[i] { -1.0 } else { 1.0 };
            a.add(i, i, target - d[i * c.n + i]).unwrap();
        }
    }
    a
}

fn check(c: &Case, indefinite: bool) -> Result<(), TestCaseError> {
    let a = assemble(c, indefinite);
    let n = c.n;
    let dense = DMatrix::from_row_slice(n, n, &a.to_dense());
    let negative = SymmetricEigen::new(dense.clone())
        .eigenvalues
        .iter()
        .filter(|&&l| l < 0.0)
        .count();
    let exact = dense
        .clone()
        .lu()
        .solve(&DVector::from_column_slice(&c.rhs))
        .unwrap();
    let mut solvers: Vec<Box<dyn LinearSolver>> = vec![
        Box::new(ProfileLdlt::new()),
        Box::new(FaerSolver::new(FaerMode::Ldlt)),
        Box::new(FaerSolver::new(FaerMode::Ldlt).with_structure(FaerStructure::Supernodal)),
    ];
    if !indefinite {
        solvers.push(Box::new(FaerSolver::new(FaerMode::Llt)));
    }
    let bnorm = c.rhs.iter().map(|v| v * v).sum::<f64>().sqrt().max(1e-300);
    for s in &mut solvers {
        s.analyze(a.pattern()).unwrap();
        let f = s.factorize(&a).unwrap();
        prop_assert_eq!(f.negative_pivots, negative, "{} inertia", s.name());
        let mut x = c.rhs.clone();
        s.solve_in_place(&mut x, 1).unwrap();
        let mut ax = vec![0.0; n];
        a.matvec(&x, &mut ax).unwrap();
        let res = ax
            .iter()
            .zip(&c.rhs)
            .map(|(p, q)| (p - q).powi(2))
            .sum::<f64>()
            .sqrt();
        prop_assert!(res <= 1e-10 * bnorm, "{} residual {res}", s.name());
        for i in 0..n {
            prop_assert!(
                (x[i] - exact[i]).abs() <= 1e-9 * exact.amax().max(1e-12),
                "{} x[{i}]",
                s.name()
            );
        }
    }
    Ok(())
}

/// Larger banded systems (100–400 equations, elements on windows of nearby DOFs) so the
/// profile factorisation runs through several row blocks (64 rows each) and its blocked phase.
fn banded_case() -> impl Strategy<Value = Case> {
    (100usize..400).prop_flat_map(|n| {
        let list = (0..n - 8, proptest::collection::btree_set(0usize..8, 2..=6))
            .prop_map(|(s, offs)| offs.into_iter().map(|o| s + o).collect::<Vec<_>>());
        with_lists(n, proptest::collection::vec(list, n..(2 * n)))
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, .. ProptestConfig::default() })]

    #[test]
    fn banded_systems_across_row_blocks(c in banded_case(), indefinite in any::<bool>()) {
        check(&c, indefinite)?;
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 128, .. ProptestConfig::default() })]

    #[test]
    fn spd_systems(c in case()) {
        check(&c, false)?;
    }

    #[test]
    fn indefinite_systems(c in case()) {
        check(&c, true)?;
    }

    /// Refactoring new values on the same pattern gives what a fresh solver gives.
    #[test]
    fn refactorisation_equals_fresh_factorisation(c in case()) {
        let a1 = assemble(&c, false);
        let a2 = assemble(&c, true);
        for make in [|| Box::new(ProfileLdlt::new()) as Box<dyn LinearSolver>, || Box::new(FaerSolver::new(FaerMode::Ldlt)) as Box<dyn LinearSolver>] {
            let mut reused = make();
            reused.analyze(a1.pattern()).unwrap();
            reused.factorize(&a1).unwrap();
            let f2 = reused.factorize(&a2).unwrap();
            let mut x = c.rhs.clone();
            reused.solve_in_place(&mut x, 1).unwrap();
            let mut fresh = make();
            fresh.analyze(a2.pattern()).unwrap();
            let g2 = fresh.factorize(&a2).unwrap();
            let mut y = c.rhs.clone();
            fresh.solve_in_place(&mut y, 1).unwrap();
            prop_assert_eq!(f2.negative_pivots, g2.negative_pivots);
            prop_assert_eq!(x, y);
        }
    }
}

#[test]
fn many_right_hand_sides_and_errors() {
    let c = Case {
        n: 3,
        lists: vec![vec![0, 1], vec![1, 2]],
        blocks: vec![vec![2.0, -1.0, -1.0, 2.0], vec![2.0, -1.0, -1.0, 2.0]],
        signs: vec![false; 3],
        rhs: vec![1.0, 0.0, 0.0],
    };
    let a = assemble(&c, false);
    for mut s in [
        Box::new(ProfileLdlt::new()) as Box<dyn LinearSolver>,
        Box::new(FaerSolver::default()),
    ] {
        assert!(
            s.factorize(&a).is_err(),
            "factorize before analyze must fail"
        );
        s.analyze(a.pattern()).unwrap();
        s.factorize(&a).unwrap();
        let mut b = vec![1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
        s.solve_in_place(&mut b, 3).unwrap();
        // A⁻¹ is symmetric: compare the solution columns.
        assert!((b[1] - b[3]).abs() < 1e-14 && (b[2] - b[6]).abs() < 1e-14);
        assert!(s.solve_in_place(&mut [0.0; 4], 1).is_err());
        assert!(s.solve_in_place(&mut [f64::NAN, 0.0, 0.0], 1).is_err());
    }
    // A matrix on another pattern is refused.
    let other = assemble(
        &Case {
            n: 3,
            lists: vec![vec![0, 1, 2]],
            blocks: vec![vec![3.0, 1.0, 1.0, 1.0, 3.0, 1.0, 1.0, 1.0, 3.0]],
            ..c.clone()
        },
        false,
    );
    let mut s = ProfileLdlt::new();
    s.analyze(a.pattern()).unwrap();
    assert!(s.factorize(&other).is_err());
    // Non-finite values are rejected with their position.
    let mut bad = a.clone();
    bad.values_mut()[0] = f64::INFINITY;
    assert!(matches!(
        s.factorize(&bad),
        Err(nonlin3d_solver::SolverError::NonFinite { row: 0, col: 0, .. })
    ));
}
