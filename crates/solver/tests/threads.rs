//! The faer LDLᵀ numeric factorisation and solve give the same bits on 1, 2 and 3 threads.
//!
//! The matrix has a Hex20 box's pattern (10×10×6 cells, 3 DOFs per node, 9 339 DOF) so that
//! nested dissection makes real supernodes (the top separators are dense blocks of several
//! hundred columns, where faer's dense kernels split work between threads). The box must be
//! this large: on 6×6×4 cells even faer's parallel one-column solve (which splits its sums
//! between threads, hence `SOLVE_PAR`) gave the same bits; here it does not. Its values are a
//! pseudo-random Σ (element rank-one + diagonal) blocks assembly shifted to be indefinite: bitwise
//! equality depends on the order of the sums, not on the physics of the values.

use nonlin3d_solver::{
    FaerMode, FaerOrdering, FaerSolver, FaerStructure, LinearSolver, SymmetricMatrix,
    SymmetricPattern,
};
use std::sync::Arc;

/// Element DOF lists of a Hex20 box of nx×ny×nz cells (8 corners, 12 midsides per cell).
fn hex20_lists(nx: usize, ny: usize, nz: usize) -> (usize, Vec<Vec<usize>>) {
    let (lx, ly) = (2 * nx + 1, 2 * ny + 1);
    let mut id = vec![usize::MAX; lx * ly * (2 * nz + 1)];
    let mut count = 0;
    for k in 0..=2 * nz {
        for j in 0..ly {
            for i in 0..lx {
                if (i % 2) + (j % 2) + (k % 2) <= 1 {
                    id[(k * ly + j) * lx + i] = count;
                    count += 1;
                }
            }
        }
    }
    let mut lists = Vec::new();
    for ez in 0..nz {
        for ey in 0..ny {
            for ex in 0..nx {
                let mut l = Vec::new();
                for k in 2 * ez..=2 * ez + 2 {
                    for j in 2 * ey..=2 * ey + 2 {
                        for i in 2 * ex..=2 * ex + 2 {
                            let node = id[(k * ly + j) * lx + i];
                            if node != usize::MAX {
                                l.extend((0..3).map(|d| 3 * node + d));
                            }
                        }
                    }
                }
                lists.push(l);
            }
        }
    }
    (3 * count, lists)
}

/// A deterministic pseudo-random number in [−1, 1) (64-bit LCG).
fn lcg(state: &mut u64) -> f64 {
    *state = state
        .wrapping_mul(6_364_136_223_846_793_005)
        .wrapping_add(1_442_695_040_888_963_407);
    (*state >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}

/// Σ_e (v_e v_eᵀ + I) over the elements, minus `shift`·I.
fn box_matrix(shift: f64) -> SymmetricMatrix {
    let (n, lists) = hex20_lists(10, 10, 6);
    let p = Arc::new(SymmetricPattern::from_dof_lists(n, &lists).unwrap());
    let mut a = SymmetricMatrix::zeros(p);
    let mut seed = 7;
    for l in &lists {
        let v: Vec<f64> = l.iter().map(|_| lcg(&mut seed)).collect();
        let m = l.len();
        let mut k = vec![0.0; m * m];
        for i in 0..m {
            for j in 0..m {
                k[i * m + j] = v[i] * v[j] + if i == j { 1.0 } else { 0.0 };
            }
        }
        a.scatter_add(l, &k).unwrap();
    }
    for i in 0..n {
        a.add(i, i, -shift).unwrap();
    }
    a
}

/// The solution of A x = b (b pseudo-random) and the inertia on `threads` threads.
fn solve_on(a: &SymmetricMatrix, threads: usize) -> (Vec<f64>, usize) {
    let mut s = FaerSolver::new(FaerMode::Ldlt)
        .with_structure(FaerStructure::Supernodal)
        .with_ordering(FaerOrdering::NestedDissection)
        .with_threads(threads);
    s.analyze(a.pattern()).unwrap();
    let f = s.factorize(a).unwrap();
    let mut seed = 11;
    let mut x: Vec<f64> = (0..a.n()).map(|_| lcg(&mut seed)).collect();
    s.solve_in_place(&mut x, 1).unwrap();
    (x, f.negative_pivots)
}

/// Same bits on 1, 2 and 3 threads, positive definite (shift 0) and indefinite (shift 1.5:
/// each DOF's diagonal is its element count plus rank-one terms, so some eigenvalues of
/// Σ(v vᵀ + I) lie below 1.5 and the factor has negative pivots).
#[test]
fn factors_and_solutions_are_bitwise_equal_on_1_2_and_3_threads() {
    for shift in [0.0, 1.5] {
        let a = box_matrix(shift);
        let (x1, neg1) = solve_on(&a, 1);
        for threads in [2, 3] {
            let (x, neg) = solve_on(&a, threads);
            assert_eq!(neg, neg1, "shift {shift}, {threads} threads");
            let differ = x
                .iter()
                .zip(&x1)
                .filter(|(p, q)| p.to_bits() != q.to_bits())
                .count();
            assert_eq!(
                differ, 0,
                "shift {shift}, {threads} threads: {differ} entries differ"
            );
        }
        if shift > 0.0 {
            assert!(neg1 > 0, "the shifted matrix should be indefinite");
        }
    }
}
