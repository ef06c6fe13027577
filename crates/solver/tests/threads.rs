//! The faer LDLᵀ numeric factorisation and solve give the same bits on 1, 2 and 3 threads.
//!
//! The matrix has a Hex20 box's pattern (10×10×6 cells, 3 DOFs per node, 9 339 DOF) so that
//! nested dissection makes real supernodes (the top separators are dense blocks of several
//! hundred columns, where faer's dense kernels split work between threads). The box must be
//! this large: on 6×6×4 cells even faer's parallel one-column solve (which splits its sums
//! between threads, hence `SOLVE_PAR`) gave the same bits; here it does not. Its values are a
//! pseudo-random Σ (element rank-one + diagonal) blocks assembly shifted to be indefinite: bitwise
//! equality depends on the order of the sums, not on the physics of the values. Both the
//! unsplit factor and the split one (`FaerSplit::Halves`: halves on two threads, S on all) are
//! checked, in f64 and with f32 halves refined in f64 (`FaerPrecision::mixed()`), the split on
//! our nested-dissection order and on METIS's.

mod common;

use common::box_matrix;
use nonlin3d_solver::{
    FaerMode, FaerOrdering, FaerPrecision, FaerSolver, FaerSplit, FaerStructure, LinearSolver,
    SymmetricMatrix,
};
use nonlin3d_testkit::Lcg;

/// The solution of A x = b (b pseudo-random) and the inertia on `threads` threads, unsplit
/// or split at the top separator.
fn solve_on(
    a: &SymmetricMatrix,
    threads: usize,
    split: FaerSplit,
    precision: FaerPrecision,
    ordering: FaerOrdering,
) -> (Vec<f64>, usize) {
    let mut s = FaerSolver::new(FaerMode::Ldlt)
        .with_structure(FaerStructure::Supernodal)
        .with_ordering(ordering)
        .with_threads(threads);
    s.split = split;
    s.precision = precision;
    // faer's dense kernels on the pool's threads at this size too (the split's halves then
    // run theirs on them, so a thread the shorter half leaves free takes the longer one's
    // tiles): the path the large systems take.
    s.kernel_threads_from = 0;
    s.analyze(a.pattern()).unwrap();
    assert_eq!(s.split_sizes().is_some(), split == FaerSplit::Halves);
    let f = s.factorize(a).unwrap();
    assert_eq!(s.split_fallback(), None);
    let mut rng = Lcg::new(11);
    let mut x: Vec<f64> = (0..a.n()).map(|_| rng.uniform(-1.0, 1.0)).collect();
    s.solve_in_place(&mut x, 1).unwrap();
    if precision != FaerPrecision::Double {
        // The f32 factor itself (not an f64 fallback) is what must give the same bits.
        assert_eq!(s.mixed_stats().double_factorizations, 0, "{split:?}");
    }
    (x, f.negative_pivots)
}

/// Same bits on 1, 2 and 3 threads, positive definite (shift 0) and indefinite (shift 1.5:
/// each DOF's diagonal is its element count plus rank-one terms, so some eigenvalues of
/// Σ(v vᵀ + I) lie below 1.5 and the factor has negative pivots).
#[test]
fn factors_and_solutions_are_bitwise_equal_on_1_2_and_3_threads() {
    let mixed = FaerPrecision::mixed();
    let (nd, metis) = (FaerOrdering::NestedDissection, FaerOrdering::Metis);
    for (shift, split, precision, ordering) in [0.0, 1.5].into_iter().flat_map(|s| {
        [
            (s, FaerSplit::Off, FaerPrecision::Double, nd),
            (s, FaerSplit::Halves, FaerPrecision::Double, nd),
            (s, FaerSplit::Halves, mixed, nd),
            (s, FaerSplit::Halves, FaerPrecision::Double, metis),
            (s, FaerSplit::Halves, mixed, metis),
        ]
    }) {
        let a = box_matrix([10, 10, 6], shift);
        let (x1, neg1) = solve_on(&a, 1, split, precision, ordering);
        for threads in [2, 3] {
            let (x, neg) = solve_on(&a, threads, split, precision, ordering);
            assert_eq!(neg, neg1, "shift {shift}, {threads} threads");
            let differ = x
                .iter()
                .zip(&x1)
                .filter(|(p, q)| p.to_bits() != q.to_bits())
                .count();
            assert_eq!(
                differ, 0,
                "shift {shift}, {split:?}, {precision:?}, {ordering:?}, {threads} threads: {differ} entries differ"
            );
        }
        if shift > 0.0 {
            assert!(neg1 > 0, "the shifted matrix should be indefinite");
        }
    }
}
