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

/// Σ_e (v_e v_eᵀ + I) over the elements of an nx×ny×nz Hex20 box (v pseudo-random), minus
/// `shift`·I: positive definite at shift 0, indefinite at 1.5 (some eigenvalues of the sum
/// lie below 1.5). The bits, not the physics, are what the tests below compare.
fn box_matrix(cells: [usize; 3], shift: f64) -> SymmetricMatrix {
    let (n, lists) = nonlin3d_testkit::hex20_dof_lists(cells);
    let p = Arc::new(SymmetricPattern::from_dof_lists(n, &lists).unwrap());
    let mut a = SymmetricMatrix::zeros(p);
    let mut rng = nonlin3d_testkit::Lcg::new(5);
    for l in &lists {
        let v: Vec<f64> = l.iter().map(|_| rng.uniform(-1.0, 1.0)).collect();
        let m = l.len();
        let k: Vec<f64> = (0..m * m)
            .map(|e| v[e / m] * v[e % m] + if e / m == e % m { 1.0 } else { 0.0 })
            .collect();
        a.scatter_add(l, &k).unwrap();
    }
    for i in 0..n {
        a.add(i, i, -shift).unwrap();
    }
    a
}

/// How many entries of `x` and `y` differ in their bits (f32 widens to f64 exactly).
fn differing<T: Copy + Into<f64>>(x: &[T], y: &[T]) -> usize {
    assert_eq!(x.len(), y.len());
    x.iter()
        .zip(y)
        .filter(|(p, q)| (**p).into().to_bits() != (**q).into().to_bits())
        .count()
}

/// faer's own numeric factorisation of `values` (A's, in precision T) on `s`'s symbolic
/// factor: `factorize_numeric_ldlt`/`_llt`, which permute A into scratch first (the path the
/// gather map replaced). `None` if it met a bad pivot.
fn faer_own_factor<T: faer::traits::ComplexField + Copy>(
    s: &FaerSolver,
    values: &[T],
    zero: T,
) -> Option<Vec<T>> {
    let (pattern, symbolic) = (s.pattern.as_ref().unwrap(), s.symbolic.as_ref().unwrap());
    let n = pattern.n();
    let sym =
        SymbolicSparseColMatRef::new_checked(n, n, pattern.col_ptr(), None, pattern.row_idx());
    let mat = faer::sparse::SparseColMatRef::new(sym, values);
    let mut l = vec![zero; symbolic.len_val()];
    let ldlt = s.mode == FaerMode::Ldlt;
    let req = if ldlt {
        symbolic.factorize_numeric_ldlt_scratch::<T>(s.par, Default::default())
    } else {
        symbolic.factorize_numeric_llt_scratch::<T>(s.par, Default::default())
    };
    let mut buffer = MemBuffer::new(req);
    let stack = MemStack::new(&mut buffer);
    let done = if ldlt {
        symbolic
            .factorize_numeric_ldlt(
                &mut l,
                mat,
                Side::Lower,
                Default::default(),
                s.par,
                stack,
                Default::default(),
            )
            .is_ok()
    } else {
        symbolic
            .factorize_numeric_llt(
                &mut l,
                mat,
                Side::Lower,
                Default::default(),
                s.par,
                stack,
                Default::default(),
            )
            .is_ok()
    };
    done.then_some(l)
}

/// The gather map's factorisation (issue 20) gives faer's own factor bit for bit, on the
/// positive definite and an indefinite box, simplicial and supernodal, AMD, nested-dissection
/// and METIS orders, 1 and 2 threads, LDLᵀ and LLᵀ (positive definite only), f64 and the
/// mixed path's f32; each factor is used twice (the values are refilled, not appended), and
/// the solution equals the one from faer's own factor, bit for bit. It fails if the copy's
/// entries, their order within a column (the simplicial kernel's sums follow it) or the
/// side each kernel reads differ from faer's.
#[test]
fn the_gather_map_gives_faers_own_factor_bit_for_bit() {
    let orders = [
        FaerOrdering::Amd,
        FaerOrdering::NestedDissection,
        FaerOrdering::Metis,
    ];
    let mut cases = 0;
    for shift in [0.0, 1.5] {
        let a = box_matrix([4, 3, 3], shift);
        let scaled = {
            let mut b = a.clone();
            b.values_mut().iter_mut().for_each(|v| *v *= 1.25);
            b
        };
        for structure in [FaerStructure::Simplicial, FaerStructure::Supernodal] {
            for ordering in orders {
                for threads in [1, 2] {
                    let modes: &[FaerMode] = if shift == 0.0 {
                        &[FaerMode::Ldlt, FaerMode::Llt]
                    } else {
                        &[FaerMode::Ldlt]
                    };
                    for &mode in modes {
                        let mut s = FaerSolver::new(mode)
                            .with_structure(structure)
                            .with_ordering(ordering)
                            .with_threads(threads);
                        s.analyze(a.pattern()).unwrap();
                        let what = format!("{shift} {structure:?} {ordering:?} {threads} {mode:?}");
                        assert_eq!(
                            s.is_supernodal(),
                            Some(structure == FaerStructure::Supernodal)
                        );
                        for m in [&a, &scaled] {
                            s.factorize(m).unwrap();
                            let own = faer_own_factor(&s, m.values(), 0.0).expect(&what);
                            assert_eq!(differing(&s.l_values, &own), 0, "{what}");
                            let b: Vec<f64> = (0..m.n()).map(|i| 1.0 + (i % 7) as f64).collect();
                            let mut x = b.clone();
                            s.solve_in_place(&mut x, 1).unwrap();
                            let symbolic = s.symbolic.as_ref().unwrap();
                            let mut y = b;
                            let rhs = MatMut::from_column_major_slice_mut(&mut y, m.n(), 1);
                            let mut buffer = MemBuffer::new(
                                symbolic.solve_in_place_scratch::<f64>(1, SOLVE_PAR),
                            );
                            let stack = MemStack::new(&mut buffer);
                            match mode {
                                FaerMode::Ldlt => LdltRef::new(symbolic, &own)
                                    .solve_in_place_with_conj(Conj::No, rhs, SOLVE_PAR, stack),
                                FaerMode::Llt => LltRef::new(symbolic, &own)
                                    .solve_in_place_with_conj(Conj::No, rhs, SOLVE_PAR, stack),
                            }
                            assert_eq!(differing(&x, &y), 0, "{what}");
                            cases += 1;
                        }
                        if mode == FaerMode::Llt {
                            continue;
                        }
                        // The mixed path's f32 factor.
                        s.precision = FaerPrecision::mixed();
                        s.analyze(a.pattern()).unwrap();
                        s.factorize(&a).unwrap();
                        assert_eq!(s.mixed_stats().double_factorizations, 0, "{what}");
                        let narrow: Vec<f32> = a.values().iter().map(|&v| v as f32).collect();
                        let own = faer_own_factor(&s, &narrow, 0.0f32).expect(&what);
                        assert_eq!(differing(&s.mixed.l32, &own), 0, "f32 {what}");
                    }
                }
            }
        }
    }
    // 2 shifts × 2 structures × 3 orders × 2 thread counts × (2 + 1 modes... ) × 2 matrices.
    assert_eq!(cases, 2 * 3 * 2 * 2 * (2 + 1));
}

/// faer's own kernels take the solver's threads only from `kernel_threads_from` DOFs on
/// (0: always); below, one thread.
#[test]
fn kernel_threads_start_at_their_threshold() {
    let mut s = FaerSolver::new(FaerMode::Ldlt).with_threads(2);
    assert_eq!(s.kernel_threads_from, KERNEL_THREADS_FROM_DOFS);
    assert_eq!(s.kernel_par(KERNEL_THREADS_FROM_DOFS - 1).degree(), 1);
    assert_eq!(s.kernel_par(KERNEL_THREADS_FROM_DOFS).degree(), 2);
    s.kernel_threads_from = 0;
    assert_eq!(s.kernel_par(10).degree(), 2);
    let one = FaerSolver::new(FaerMode::Ldlt);
    assert_eq!(one.kernel_par(KERNEL_THREADS_FROM_DOFS).degree(), 1);
}
