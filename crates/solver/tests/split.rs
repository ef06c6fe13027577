//! The split LDLᵀ (`FaerSplit::Halves`) against the unsplit factor on the same
//! nested-dissection order (ours, whose top separator the ordering reports, and METIS's, whose
//! top separator is found from the order): the same inertia, backward errors of the same size, and solutions
//! that differ by no more than the condition number allows.
//!
//! Tolerance: both solutions x, x̂ of A x = b come from backward-stable factorisations, with
//! normwise backward errors ω, ω̂ (measured), so ‖x − x̂‖∞ / ‖x‖∞ ≤ κ∞(A)(ω + ω̂) to first
//! order, with κ∞(A) = ‖A‖∞‖A⁻¹‖∞ estimated by Hager's method (a lower bound, hence the factor
//! 10 of slack). The split's own backward error must stay within 10× the unsplit one's or
//! 1e-15 (rounding of the extra sums S = S′₁ + S′₂ − Aₛₛ, of order nₛ ε).
//!
//! Mixed precision inside the split (f32 halves, S in f64, refinement in f64): the f32 factor
//! must be kept (no fallback: these boxes have cond ≈ 1e2–1e4, so each refinement step gains
//! cond·ε₃₂ ≤ 1e-3) and refined to the refinement target 1e-14; the same inertia. With a
//! wrong Schur assembly the f32 split is no approximate inverse, refinement stalls and falls
//! back, which the test refuses.

mod common;

use common::box_matrix;
use nonlin3d_solver::{
    FaerMode, FaerOrdering, FaerPrecision, FaerSolver, FaerSplit, LinearSolver, SPLIT_FROM_DOFS,
    SymmetricMatrix,
};
use nonlin3d_testkit::Lcg;

fn solver(split: FaerSplit, ordering: FaerOrdering) -> FaerSolver {
    let mut s = FaerSolver::new(FaerMode::Ldlt).with_ordering(ordering);
    s.split = split;
    s
}

fn inf_norm(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

/// ‖A‖∞ (row sums of |a_ij| over both triangles).
fn matrix_norm(a: &SymmetricMatrix) -> f64 {
    let p = a.pattern();
    let mut rows = vec![0.0f64; a.n()];
    for j in 0..a.n() {
        for (k, &i) in p.column(j).iter().enumerate() {
            let v = a.values()[p.col_ptr()[j] + k].abs();
            rows[i] += v;
            if i != j {
                rows[j] += v;
            }
        }
    }
    inf_norm(&rows)
}

/// ‖b − A x‖∞ / (‖A‖∞‖x‖∞ + ‖b‖∞).
fn backward_error(a: &SymmetricMatrix, x: &[f64], b: &[f64]) -> f64 {
    let mut ax = vec![0.0; a.n()];
    a.matvec(x, &mut ax).unwrap();
    let r: Vec<f64> = ax.iter().zip(b).map(|(p, q)| q - p).collect();
    inf_norm(&r) / (matrix_norm(a) * inf_norm(x) + inf_norm(b))
}

/// Hager's lower estimate of ‖A⁻¹‖₁ (= ‖A⁻¹‖∞, A symmetric), with a factored solver.
fn inverse_norm(s: &mut FaerSolver, n: usize) -> f64 {
    let mut x = vec![1.0 / n as f64; n];
    let mut estimate = 0.0;
    for _ in 0..5 {
        s.solve_in_place(&mut x, 1).unwrap();
        let norm: f64 = x.iter().map(|v| v.abs()).sum();
        if norm <= estimate {
            break;
        }
        estimate = norm;
        let mut z: Vec<f64> = x.iter().map(|v| v.signum()).collect();
        s.solve_in_place(&mut z, 1).unwrap();
        let (j, _) =
            z.iter().enumerate().fold(
                (0, 0.0),
                |(bj, bv), (j, v)| if v.abs() > bv { (j, v.abs()) } else { (bj, bv) },
            );
        x = vec![0.0; n];
        x[j] = 1.0;
    }
    estimate
}

/// SPD (shift 0) and indefinite (shift 1.5) 6×6×4-cell Hex20 boxes (3 k DOF), split in f64
/// and with f32 halves: the split is made (the top level is dissected), the inertia is the
/// unsplit one, and the solutions agree within κ∞(ω + ω̂).
#[test]
fn split_matches_the_unsplit_factor() {
    let orderings = [FaerOrdering::NestedDissection, FaerOrdering::Metis];
    for (shift, precision, ordering) in [0.0, 1.5].into_iter().flat_map(|s| {
        [FaerPrecision::Double, FaerPrecision::mixed()]
            .into_iter()
            .flat_map(move |p| orderings.map(|o| (s, p, o)))
    }) {
        let a = box_matrix([6, 6, 4], shift);
        let n = a.n();
        let mut rng = Lcg::new(5);
        let b: Vec<f64> = (0..n).map(|_| rng.uniform(-1.0, 1.0)).collect();
        let mut whole = solver(FaerSplit::Off, ordering);
        whole.analyze(a.pattern()).unwrap();
        let f = whole.factorize(&a).unwrap();
        let mut x = b.clone();
        whole.solve_in_place(&mut x, 1).unwrap();
        let mut split = solver(FaerSplit::Halves, ordering);
        split.precision = precision;
        split.analyze(a.pattern()).unwrap();
        let (n0, n1, ns) = split.split_sizes().expect("the box is dissected");
        assert_eq!(n0 + n1 + ns, n);
        assert!(n0 > ns && n1 > ns, "halves {n0}, {n1}, separator {ns}");
        let g = split.factorize(&a).unwrap();
        assert_eq!(split.split_fallback(), None);
        let case = format!("shift {shift}, {precision:?}, {ordering:?}");
        assert_eq!(g.negative_pivots, f.negative_pivots, "{case}");
        if shift > 0.0 {
            assert!(
                f.negative_pivots > 0,
                "the shifted box should be indefinite"
            );
        }
        let mut y = b.clone();
        split.solve_in_place(&mut y, 1).unwrap();
        let (omega, omega_split) = (backward_error(&a, &x, &b), backward_error(&a, &y, &b));
        if precision == FaerPrecision::Double {
            assert!(
                omega_split <= (10.0 * omega).max(1e-15),
                "{case}: backward error {omega_split:.1e} split, {omega:.1e} unsplit"
            );
        } else {
            // The f32 split itself, refined (a fallback would hide a wrong f32 path).
            let m = split.mixed_stats();
            assert_eq!(
                (m.single_factorizations, m.double_factorizations),
                (1, 0),
                "{case}: {m:?}"
            );
            assert!(omega_split <= 1e-14, "{case}: ω {omega_split:.1e}");
        }
        let kappa = matrix_norm(&a) * inverse_norm(&mut whole, n);
        let diff: Vec<f64> = x.iter().zip(&y).map(|(p, q)| p - q).collect();
        let relative = inf_norm(&diff) / inf_norm(&x);
        assert!(
            relative <= 10.0 * kappa * (omega + omega_split),
            "{case}: ‖x − x̂‖/‖x‖ = {relative:.1e}, κ {kappa:.1e}, ω {omega:.1e} + {omega_split:.1e}"
        );
    }
}

/// The default, `FaerSplit::Auto`: a box below `SPLIT_FROM_DOFS` is factored whole; one at or
/// above it is split, with the same bits as `Halves` on one thread and on two (the split is
/// decided by the size, never by the thread count).
#[test]
fn auto_splits_from_its_threshold_whatever_the_threads() {
    assert_eq!(FaerSolver::new(FaerMode::Ldlt).split, FaerSplit::Auto);
    let small = box_matrix([6, 6, 4], 0.0);
    assert!(small.n() < SPLIT_FROM_DOFS);
    let mut s = FaerSolver::new(FaerMode::Ldlt);
    s.analyze(small.pattern()).unwrap();
    assert_eq!(s.split_sizes(), None);
    let large = box_matrix([8, 8, 5], 0.0);
    assert!(large.n() >= SPLIT_FROM_DOFS, "{} DOF", large.n());
    let mut rng = Lcg::new(11);
    let b: Vec<f64> = (0..large.n()).map(|_| rng.uniform(-1.0, 1.0)).collect();
    let solve = |split: FaerSplit, threads: usize| {
        let mut s = FaerSolver::new(FaerMode::Ldlt).with_threads(threads);
        s.split = split;
        s.analyze(large.pattern()).unwrap();
        s.factorize(&large).unwrap();
        let mut x = b.clone();
        s.solve_in_place(&mut x, 1).unwrap();
        (s.split_sizes(), x)
    };
    let (sizes, x) = solve(FaerSplit::Auto, 1);
    assert!(sizes.is_some(), "{} DOF not split", large.n());
    for (split, threads) in [(FaerSplit::Auto, 2), (FaerSplit::Halves, 1)] {
        let (_, y) = solve(split, threads);
        assert!(
            x.iter().zip(&y).all(|(p, q)| p.to_bits() == q.to_bits()),
            "{split:?} on {threads} threads"
        );
    }
}
