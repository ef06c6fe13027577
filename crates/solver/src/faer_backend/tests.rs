//! Unit tests of the faer backend.

use super::*;

/// A matrix singular only in the coupled pair (1, 7) (the block [1 1; 1 1 + δ], DOF 1
/// also coupled, with zero values, to DOFs 0, 2, 3, 4 so that the ordering moves it):
/// whichever structure, and whether faer meets an exact zero (δ = 0) or the pivot test
/// catches a tiny one (δ = 1e-14), the zero pivot is named at DOF 1 or 7 with their
/// diagonal, not at a neighbour.
#[test]
fn a_zero_pivot_names_its_own_dof() {
    let n = 9;
    let mut lists: Vec<Vec<usize>> = (0..n).map(|i| vec![i]).collect();
    lists.push(vec![1, 7]);
    lists.push(vec![0, 1, 2, 3, 4]);
    let p = Arc::new(SymmetricPattern::from_dof_lists(n, &lists).unwrap());
    for delta in [0.0, 1e-14] {
        let mut a = SymmetricMatrix::zeros(p.clone());
        for i in (0..n).filter(|&i| i != 1 && i != 7) {
            a.add(i, i, 10.0 + i as f64).unwrap();
        }
        a.scatter_add(&[1, 7], &[1.0, 1.0, 1.0, 1.0 + delta])
            .unwrap();
        for structure in [FaerStructure::Simplicial, FaerStructure::Supernodal] {
            let mut s = FaerSolver::new(FaerMode::Ldlt).with_structure(structure);
            s.analyze(&p).unwrap();
            match s.factorize(&a) {
                Err(SolverError::ZeroPivot { dof, diagonal, .. }) => {
                    assert!(dof == 1 || dof == 7, "{structure:?}, δ {delta}: DOF {dof}");
                    assert!((diagonal - 1.0).abs() < 1e-12);
                }
                other => panic!("{structure:?}, δ {delta}: {other:?}"),
            }
        }
    }
}
