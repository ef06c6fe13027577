//! Unit tests of mixed precision: refinement, the fallbacks to f64, the size rule.

use super::*;
use crate::{FaerMode, FaerOrdering, LinearSolver, SymmetricPattern};
use std::sync::Arc;

/// A chain of n unit springs between two walls (the 1-D Laplacian tridiag(−1, 2, −1)),
/// times `scale`, minus `shift`·I. Eigenvalues scale·(2 − 2 cos(kπ/(n+1))) − shift, so
/// cond ≈ 4(n+1)²/π² unshifted; every pivot of any elimination order is ≥ 1/n of its
/// diagonal (the Schur complement onto a node is the spring to the walls, ≥ 2/(n+1)).
fn chain(n: usize, scale: f64, shift: f64) -> SymmetricMatrix {
    let lists: Vec<Vec<usize>> = (0..n - 1).map(|i| vec![i, i + 1]).collect();
    let p = Arc::new(SymmetricPattern::from_dof_lists(n, &lists).unwrap());
    let mut a = SymmetricMatrix::zeros(p);
    for i in 0..n {
        a.add(i, i, scale * 2.0 - shift).unwrap();
        if i + 1 < n {
            a.add(i + 1, i, -scale).unwrap();
        }
    }
    a
}

fn solver(precision: FaerPrecision) -> FaerSolver {
    let mut s = FaerSolver::new(FaerMode::Ldlt).with_ordering(FaerOrdering::NestedDissection);
    s.precision = precision;
    s
}

/// (x, negative pivots) of A x = b with b_i = 1 + i mod 3.
fn solve(s: &mut dyn LinearSolver, a: &SymmetricMatrix) -> (Vec<f64>, usize) {
    s.analyze(a.pattern()).unwrap();
    let f = s.factorize(a).unwrap();
    let mut x: Vec<f64> = (0..a.n()).map(|i| 1.0 + (i % 3) as f64).collect();
    s.solve_in_place(&mut x, 1).unwrap();
    (x, f.negative_pivots)
}

/// `solve_to_residual` stops refining once ‖b − A x‖∞ is within the caller's bound: fewer
/// steps than the 1e-14 backward-error target takes, the residual within the bound (checked
/// here in f64), and never worse than the first f32 solve. A bound the first solve already
/// meets takes that one step; a bound of 0 is the backward-error target itself.
#[test]
fn a_residual_bound_stops_refinement_early() {
    let a = chain(300, 1.0, 0.0);
    let b: Vec<f64> = (0..a.n()).map(|i| 1.0 + (i % 3) as f64).collect();
    let residual_of = |x: &[f64]| {
        let mut ax = vec![0.0; x.len()];
        a.matvec(x, &mut ax).unwrap();
        b.iter()
            .zip(&ax)
            .fold(0.0f64, |m, (p, q)| m.max((p - q).abs()))
    };
    let steps_for = |bound: Option<f64>| {
        let mut s = solver(FaerPrecision::mixed());
        s.analyze(a.pattern()).unwrap();
        s.factorize(&a).unwrap();
        let mut x = b.clone();
        match bound {
            Some(t) => s.solve_to_residual(&mut x, t).unwrap(),
            None => s.solve_in_place(&mut x, 1).unwrap(),
        }
        (s.mixed_stats().refinement_steps, residual_of(&x))
    };
    let (full, full_residual) = steps_for(None);
    let (zero, zero_residual) = steps_for(Some(0.0));
    assert_eq!(
        (zero, zero_residual.to_bits()),
        (full, full_residual.to_bits())
    );
    // ‖b‖∞ = 3; f32's first solve leaves about cond·ε₃₂·‖b‖ ≈ 1e-2 at most.
    let (loose, loose_residual) = steps_for(Some(1.0));
    assert_eq!(loose, 1);
    assert!(loose_residual <= 1.0);
    // Each step gains about cond·ε₃₂ ≈ 4e-3: a tenth of the first solve's residual is met
    // by the second step, before the backward-error target.
    let bound = 0.1 * loose_residual;
    let (early, early_residual) = steps_for(Some(bound));
    assert!(early < full, "{early} steps against {full}");
    assert!(early_residual <= bound, "{early_residual}");
}

/// A factor whose checked first solve met a loose bound (‖b − A x‖∞ ≤ 1 for ‖b‖∞ = 3; the
/// first f32 solve leaves about cond·ε₃₂·‖b‖∞ ≲ 1e-2) at a quarter of it or better serves the
/// next `UNCHECKED_IN_A_ROW` solves to such bounds unchecked, then the next is checked again.
/// An unchecked solve gives the bits a checked one gives where its first step meets the bound.
/// A new factorisation, a tight bound (a tenth of what the first solve leaves) and a solve
/// without a bound are always checked.
#[test]
fn a_factor_that_met_its_bounds_with_room_serves_unchecked_solves() {
    let a = chain(300, 1.0, 0.0);
    let b: Vec<f64> = (0..a.n()).map(|i| 1.0 + (i % 3) as f64).collect();
    let mut s = solver(FaerPrecision::mixed());
    s.analyze(a.pattern()).unwrap();
    s.factorize(&a).unwrap();
    let counts = |s: &FaerSolver| {
        let m = s.mixed_stats();
        (m.refinement_steps, m.unchecked_solves)
    };
    let solve_with = |s: &mut FaerSolver, bound: f64| {
        let mut x = b.clone();
        s.solve_to_residual(&mut x, bound).unwrap();
        x
    };
    let first = solve_with(&mut s, 1.0);
    assert_eq!(counts(&s), (1, 0));
    for k in 1..=UNCHECKED_IN_A_ROW {
        let x = solve_with(&mut s, 1.0);
        assert_eq!(counts(&s), (1, k));
        assert!(
            x.iter()
                .zip(&first)
                .all(|(p, q)| p.to_bits() == q.to_bits())
        );
    }
    solve_with(&mut s, 1.0);
    assert_eq!(counts(&s), (2, UNCHECKED_IN_A_ROW));
    // The residual the first solve leaves, then a bound a tenth of it: refined, every time.
    let mut ax = vec![0.0; a.n()];
    a.matvec(&first, &mut ax).unwrap();
    let left = b
        .iter()
        .zip(&ax)
        .fold(0.0f64, |m, (p, q)| m.max((p - q).abs()));
    assert!(left > 0.0 && left < 0.25, "{left}");
    let before = counts(&s);
    solve_with(&mut s, 0.1 * left);
    solve_with(&mut s, 0.1 * left);
    let after = counts(&s);
    assert!(
        after.0 >= before.0 + 4 && after.1 == before.1,
        "{before:?} → {after:?}"
    );
    // A new factor is checked first; a solve without a bound is always checked.
    s.factorize(&a).unwrap();
    let before = counts(&s);
    solve_with(&mut s, 1.0);
    assert_eq!(counts(&s), (before.0 + 1, before.1));
    let mut x = b.clone();
    s.solve_in_place(&mut x, 1).unwrap();
    assert!(counts(&s).0 > before.0 + 1 && counts(&s).1 == before.1);
}

/// n = 300: cond ≈ 3.7e4, so each refinement step gains a factor cond·ε₃₂ ≈ 4e-3: the
/// f32 factor is kept and refinement reaches 1e-14 in a few steps. Both solutions then have
/// backward error ≤ 1e-14, so they differ by at most 2·cond·1e-14 ≈ 1e-9 relative.
#[test]
fn refinement_reaches_the_f64_solution() {
    let a = chain(300, 1.0, 0.0);
    let (x64, _) = solve(&mut solver(FaerPrecision::Double), &a);
    let mut s = solver(FaerPrecision::mixed());
    let (x, neg) = solve(&mut s, &a);
    let m = s.mixed_stats();
    assert_eq!(
        (neg, m.single_factorizations, m.double_factorizations),
        (0, 1, 0)
    );
    assert!((2..=6).contains(&m.refinement_steps), "{m:?}");
    assert!(m.last_backward_error <= DEFAULT_REFINEMENT_TOLERANCE);
    let scale = x64.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for (p, q) in x.iter().zip(&x64) {
        assert!((p - q).abs() <= 1e-9 * scale, "{p} vs {q}");
    }
}

/// Conjugate gradients need a positive definite preconditioner: on the chain shifted to be
/// indefinite (shift 0.01 puts the lowest eigenvalues of tridiag(−1, 2, −1), 2 − 2cos(kπ/301)
/// ≈ (kπ/301)², below zero for k ≤ 9, so the factor has 9 negative pivots), a target below
/// f64's rounding stalls refinement and the solver falls back without trying them.
#[test]
fn an_indefinite_factor_falls_back_without_conjugate_gradients() {
    let a = chain(300, 1.0, 0.01);
    let mut s = solver(FaerPrecision::Mixed {
        tolerance: 1e-30,
        pivot_floor: 0.0,
    });
    let (_, neg) = solve(&mut s, &a);
    let m = s.mixed_stats();
    assert_eq!(neg, 9, "{m:?}");
    assert_eq!(m.last_fallback, Some("refinement stalled"), "{m:?}");
    assert_eq!(m.conjugate_gradient_steps, 0, "{m:?}");
    assert!(m.refinement_steps >= 2, "{m:?}");
}

/// A tolerance below f64's own rounding floor (backward errors of ~1e-17 here): refinement
/// stops gaining and must fall back; the answer is then the f64 factor's, bit for bit.
#[test]
fn a_stalled_refinement_falls_back_to_f64() {
    let a = chain(300, 1.0, 0.0);
    let (x64, _) = solve(&mut solver(FaerPrecision::Double), &a);
    let mut s = solver(FaerPrecision::Mixed {
        tolerance: 1e-30,
        pivot_floor: SINGLE_PIVOT_FLOOR,
    });
    let (x, _) = solve(&mut s, &a);
    let m = s.mixed_stats();
    assert_eq!(
        m.last_fallback,
        Some("refinement and conjugate gradients stalled"),
        "{m:?}"
    );
    assert_eq!((m.single_factorizations, m.double_factorizations), (1, 1));
    assert!(x.iter().zip(&x64).all(|(p, q)| p.to_bits() == q.to_bits()));
}

/// A free chain held only by springs ε = 1e-8 to ground at every node (A = L + εI, L the
/// singular free-free Laplacian): f32 rounds 2 + ε to 2 (its spacing at 2 is 2.4e-7), so
/// the f32 matrix is singular and its last pivot is rounding noise. That factor is refused
/// and the f64 one (smallest eigenvalue ε, well inside f64) gives the answer.
#[test]
fn a_doubtful_f32_pivot_falls_back_to_f64() {
    let n = 400;
    let mut a = chain(n, 1.0, -1e-8);
    // Free ends: one spring fewer at each.
    a.add(0, 0, -1.0).unwrap();
    a.add(n - 1, n - 1, -1.0).unwrap();
    let (x64, neg) = solve(&mut solver(FaerPrecision::Double), &a);
    assert_eq!(neg, 0);
    let mut s = solver(FaerPrecision::mixed());
    let (x, _) = solve(&mut s, &a);
    let m = s.mixed_stats();
    assert!(
        matches!(
            m.last_fallback,
            Some("an f32 pivot is too small to trust its sign")
                | Some("f32 elimination met a zero pivot")
        ),
        "{m:?}"
    );
    assert_eq!((m.single_factorizations, m.double_factorizations), (0, 1));
    assert!(x.iter().zip(&x64).all(|(p, q)| p.to_bits() == q.to_bits()));
}

/// The inertia: an SPD factor in f32, then A − 0.5·I (the eigenvalues below 0.5 turn
/// negative): the count changed, so it comes from an f64 factor and equals the f64 solver's;
/// the same matrix again keeps the f32 factor (its count agrees).
#[test]
fn a_changed_negative_pivot_count_is_confirmed_in_f64() {
    let (spd, shifted) = (chain(200, 1.0, 0.0), chain(200, 1.0, 0.5));
    let (_, expected) = solve(&mut solver(FaerPrecision::Double), &shifted);
    // 2 − 2cos(kπ/201) < 0.5 for k < 201·acos(0.75)/π = 46.3: 46 negative eigenvalues.
    assert_eq!(expected, 46);
    let mut s = solver(FaerPrecision::mixed());
    s.analyze(spd.pattern()).unwrap();
    assert_eq!(s.factorize(&spd).unwrap().negative_pivots, 0);
    assert_eq!(s.mixed_stats().double_factorizations, 0);
    assert_eq!(s.factorize(&shifted).unwrap().negative_pivots, expected);
    let m = s.mixed_stats();
    assert_eq!(m.last_fallback, Some("the negative pivot count changed"));
    assert_eq!((m.single_factorizations, m.double_factorizations), (1, 1));
    assert_eq!(s.factorize(&shifted).unwrap().negative_pivots, expected);
    assert_eq!(s.mixed_stats().single_factorizations, 2);
}

/// A stall (a tolerance refinement cannot reach) before any f32 factor has served gives
/// f32 up at once: the second factorisation goes straight to f64. After f32 has served, it
/// takes two refusals in a row; a change of the pivot count alone does not count (the test
/// above keeps f32 after one). A new analysis tries f32 again.
#[test]
fn f32_refused_before_it_served_or_twice_in_a_row_goes_to_f64() {
    const GIVEN_UP: Option<&str> =
        Some("f32 refused before it served, or twice in a row: f64 for a while");
    let a = chain(300, 1.0, 0.0);
    let mut s = solver(FaerPrecision::Mixed {
        tolerance: 1e-30,
        pivot_floor: SINGLE_PIVOT_FLOOR,
    });
    s.analyze(a.pattern()).unwrap();
    let mut b = vec![1.0; a.n()];
    for _ in 0..2 {
        s.factorize(&a).unwrap();
        s.solve_in_place(&mut b, 1).unwrap();
    }
    let m = s.mixed_stats();
    assert_eq!(
        (m.single_factorizations, m.double_factorizations),
        (1, 2),
        "{m:?}"
    );
    assert_eq!(m.last_fallback, GIVEN_UP);
    // After f32 served: one refusal keeps it, the second in a row gives it up.
    let mut s = solver(FaerPrecision::mixed());
    s.analyze(a.pattern()).unwrap();
    s.factorize(&a).unwrap();
    s.solve_in_place(&mut b, 1).unwrap();
    s.mixed.refuse();
    s.factorize(&a).unwrap();
    assert_eq!(s.mixed_stats().single_factorizations, 2);
    s.mixed.refuse();
    s.factorize(&a).unwrap();
    let m = s.mixed_stats();
    assert_eq!(
        (m.single_factorizations, m.double_factorizations),
        (2, 1),
        "{m:?}"
    );
    assert_eq!(m.last_fallback, GIVEN_UP);
    // A new analysis tries f32 again.
    s.analyze(a.pattern()).unwrap();
    s.factorize(&a).unwrap();
    assert_eq!(s.mixed_stats().single_factorizations, 1);
}

/// A mixed `kind`'s size rule: f64 below `threshold` DOFs (no mixed stats, the f64 solver's
/// bits), an f32 factor from it on. The chains are shifted by I (eigenvalues in [1, 5]) so
/// that f32 suffices at any length.
fn f64_below_and_f32_from(kind: crate::SolverKind, threshold: usize) {
    let mut s = kind.build();
    let below = chain(threshold - 1, 1.0, -1.0);
    let (x, _) = solve(&mut *s, &below);
    assert_eq!(s.mixed_stats(), None);
    let (y, _) = solve(&mut *crate::SolverKind::FaerLdltThreads(1).build(), &below);
    assert!(x.iter().zip(&y).all(|(p, q)| p.to_bits() == q.to_bits()));
    solve(&mut *s, &chain(threshold, 1.0, -1.0));
    let m = s.mixed_stats().unwrap();
    assert_eq!(
        (m.single_factorizations, m.double_factorizations),
        (1, 0),
        "{m:?}"
    );
}

/// `SolverKind::FaerLdltAuto`'s size rule, at `MIXED_FROM_DOFS`.
#[test]
fn auto_precision_is_f64_below_its_threshold_and_f32_from_it() {
    f64_below_and_f32_from(crate::SolverKind::FaerLdltAuto(1), crate::MIXED_FROM_DOFS);
}

/// `SolverKind::FaerLdltKept`'s size rule, at `KEPT_MIXED_FROM_DOFS`.
#[test]
fn kept_precision_is_f64_below_its_threshold_and_f32_from_it() {
    f64_below_and_f32_from(
        crate::SolverKind::FaerLdltKept(1),
        crate::KEPT_MIXED_FROM_DOFS,
    );
}

/// Entries beyond f32's range (3.4e38) go to f64 and give the f64 answer.
#[test]
fn entries_beyond_f32_go_to_f64() {
    let a = chain(50, 1e39, 0.0);
    let (x64, _) = solve(&mut solver(FaerPrecision::Double), &a);
    let mut s = solver(FaerPrecision::mixed());
    let (x, _) = solve(&mut s, &a);
    assert_eq!(
        s.mixed_stats().last_fallback,
        Some("an entry does not fit f32")
    );
    assert_eq!(x, x64);
}

/// The one pass over A before an f32 factorisation refuses a NaN or an infinity by its place
/// (the first in column order, as `check_finite` names it), in f32 and once f32 is given up,
/// leaving no factor to solve with, and gives ‖A‖∞ (max row sum of |a_ij| over both
/// triangles) and max |a_ij|.
#[test]
fn the_pass_over_a_refuses_non_finite_values_and_gives_the_norms() {
    let a = chain(40, 1.0, 0.0);
    let (mut copy, mut rows) = (vec![0.0; a.values().len()], Vec::new());
    let (norm, largest) = take_values(&a, &mut copy, &mut rows).unwrap();
    // Rows 1..n−2 hold 1 + 2 + 1.
    assert_eq!((norm, largest), (4.0, 2.0));
    assert_eq!(copy, a.values());
    for given_up in [false, true] {
        let mut s = solver(FaerPrecision::mixed());
        s.analyze(a.pattern()).unwrap();
        if given_up {
            s.mixed.refused_in_a_row = REFUSALS_BEFORE_F64;
        }
        for bad in [f64::NAN, f64::NEG_INFINITY] {
            let mut b = a.clone();
            // Column 6's entry in row 7 and column 3's diagonal: the first in column order is named.
            let p = b.pattern().position(7, 6).unwrap();
            b.values_mut()[p] = bad;
            let q = b.pattern().position(3, 3).unwrap();
            b.values_mut()[q] = bad;
            s.factorize(&a).unwrap();
            match s.factorize(&b) {
                Err(SolverError::NonFinite { row: 3, col: 3, .. }) => {}
                other => panic!("given up {given_up}, {bad}: {other:?}"),
            }
            // The factor of `a` before it is not solved with.
            let mut x = vec![1.0; a.n()];
            assert!(matches!(
                s.solve_in_place(&mut x, 1),
                Err(SolverError::NotReady(_))
            ));
        }
    }
}

/// Given up, f32 is tried again after `RETRY_F32_AFTER` f64 factorisations (or the solver's
/// `retry_f32_after`: `KEPT_RETRY_F32_AFTER` = 1 for `SolverKind::FaerLdltKept`), the wait
/// doubling after each refused retry: a matrix f32 can never serve (a 1e-30 refinement target)
/// makes 1 + 3 f32 attempts in 1 + r + 1 + 2r + 1 + 4r + 1 factorisations; one that was
/// refused only at first (a stall, then a matrix f32 serves) is back in f32 at the first retry
/// and stays there.
#[test]
fn f32_given_up_is_retried_after_a_doubling_wait() {
    for r in [RETRY_F32_AFTER, crate::KEPT_RETRY_F32_AFTER] {
        retried_after(r);
    }
}

fn retried_after(r: usize) {
    let a = chain(300, 1.0, 0.0);
    let never = FaerPrecision::Mixed {
        tolerance: 1e-30,
        pivot_floor: SINGLE_PIVOT_FLOOR,
    };
    let mut s = solver(never);
    s.retry_f32_after = r;
    s.analyze(a.pattern()).unwrap();
    let mut b = vec![1.0; a.n()];
    let total = 1 + r + 1 + 2 * r + 1 + 4 * r + 1;
    let mut singles = Vec::new();
    for k in 0..total {
        let before = s.mixed_stats().single_factorizations;
        s.factorize(&a).unwrap();
        s.solve_in_place(&mut b, 1).unwrap();
        if s.mixed_stats().single_factorizations > before {
            singles.push(k);
        }
    }
    assert_eq!(singles, [0, r + 1, 3 * r + 2, 7 * r + 3], "wait {r}");
    assert_eq!(s.mixed_stats().double_factorizations, total);
    // Refused at first only: the stall, then the default target f32 reaches.
    let mut s = solver(never);
    s.retry_f32_after = r;
    s.analyze(a.pattern()).unwrap();
    s.factorize(&a).unwrap();
    s.solve_in_place(&mut b, 1).unwrap();
    s.precision = FaerPrecision::mixed();
    for _ in 0..2 * r {
        s.factorize(&a).unwrap();
        s.solve_in_place(&mut b, 1).unwrap();
    }
    let m = s.mixed_stats();
    assert_eq!(
        (m.single_factorizations, m.double_factorizations),
        (1 + r, 1 + r),
        "wait {r}: {m:?}"
    );
}
