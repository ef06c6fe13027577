//! Tests of the METIS ordering and of `FaerOrdering::Auto`'s choice among three.

use super::*;
use crate::{FaerMode, FaerOrdering, FaerSolver, LinearSolver, SymmetricMatrix};
use std::sync::Arc;

/// Hex20 connectivity (8 corners, 12 midsides) on nx×ny×nz elements, 3 DOFs per node.
fn hex20(nx: usize, ny: usize, nz: usize) -> SymmetricPattern {
    let (n, lists) = nonlin3d_testkit::hex20_dof_lists([nx, ny, nz]);
    SymmetricPattern::from_dof_lists(n, &lists).unwrap()
}

fn analysed(p: &Arc<SymmetricPattern>, ordering: FaerOrdering) -> (FaerSolver, crate::Analysis) {
    let mut s = FaerSolver::new(FaerMode::Ldlt).with_ordering(ordering);
    let a = s.analyze(p).unwrap();
    (s, a)
}

/// Each DOF exactly once, a node's 3 DOFs together, and the same order on every call, from
/// pools of 1, 2 and 3 threads, and from 3 threads calling at once (METIS's random state is
/// process-wide: without the lock and the fixed seed concurrent calls could interleave it).
#[test]
fn order_is_a_deterministic_permutation_on_any_thread_count() {
    let p = hex20(10, 8, 4);
    let first = metis_nested_dissection(&p).unwrap();
    let mut seen = first.forward().to_vec();
    seen.sort_unstable();
    assert_eq!(seen, (0..p.n()).collect::<Vec<_>>());
    for node in first.forward().chunks(3) {
        assert_eq!(node[0] / 3, node[2] / 3);
    }
    assert_eq!(metis_nested_dissection(&p).unwrap(), first);
    for threads in [1, 2, 3] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        assert_eq!(pool.install(|| metis_nested_dissection(&p).unwrap()), first);
        // Auto's analysis on that pool picks the same order with the same flops.
        let flops = pool.install(|| analysed(&Arc::new(p.clone()), FaerOrdering::Auto).1.flops);
        assert_eq!(
            flops,
            analysed(&Arc::new(p.clone()), FaerOrdering::Auto).1.flops
        );
    }
    let orders: Vec<Permutation> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..3)
            .map(|_| s.spawn(|| metis_nested_dissection(&p).unwrap()))
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    for o in orders {
        assert_eq!(o, first);
    }
}

/// METIS on a 3-D Hex20 box needs less fill than AMD (measured 0.55 of AMD's nnz(L) on
/// 14×14×6 elements; ask for 0.8). Below `AUTO_METIS_ONLY_DOFS` Auto keeps the candidate
/// with the fewest flops (its flops equal the smallest of the three analyses'); from it on
/// METIS's order, without the comparison.
#[test]
fn auto_keeps_the_fewest_flops_of_three_below_its_threshold_and_metis_from_it() {
    let small = Arc::new(hex20(8, 8, 4));
    assert!(small.n() < crate::AUTO_METIS_ONLY_DOFS);
    let (_, amd) = analysed(&small, FaerOrdering::Amd);
    let (_, nd) = analysed(&small, FaerOrdering::NestedDissection);
    let (_, metis) = analysed(&small, FaerOrdering::Metis);
    let (s, auto) = analysed(&small, FaerOrdering::Auto);
    let best = [
        (amd.flops, FaerOrdering::Amd),
        (nd.flops, FaerOrdering::NestedDissection),
        (metis.flops, FaerOrdering::Metis),
    ]
    .into_iter()
    .min_by(|a, b| a.0.total_cmp(&b.0))
    .unwrap();
    assert_eq!(auto.flops, best.0);
    assert_eq!(s.chosen_ordering(), Some(best.1));

    let big = Arc::new(hex20(14, 14, 6));
    assert!(big.n() >= crate::AUTO_METIS_ONLY_DOFS);
    let (_, amd) = analysed(&big, FaerOrdering::Amd);
    let (_, metis) = analysed(&big, FaerOrdering::Metis);
    assert!(
        (metis.lower_nonzeros as f64) < 0.8 * amd.lower_nonzeros as f64,
        "METIS {} vs AMD {}",
        metis.lower_nonzeros,
        amd.lower_nonzeros
    );
    let (s, auto) = analysed(&big, FaerOrdering::Auto);
    assert_eq!(s.chosen_ordering(), Some(FaerOrdering::Metis));
    assert_eq!(auto.flops, metis.flops);
}

/// On a path (a 1-D chain of springs) every order without fill is optimal: AMD finds one, so
/// Auto keeps AMD (ties go to it) — METIS's is never strictly better there.
#[test]
fn auto_keeps_amd_on_a_chain() {
    let n = 400;
    let lists: Vec<Vec<usize>> = (0..n - 1).map(|k| vec![k, k + 1]).collect();
    let p = Arc::new(SymmetricPattern::from_dof_lists(n, &lists).unwrap());
    let (_, amd) = analysed(&p, FaerOrdering::Amd);
    assert_eq!(amd.lower_nonzeros, 2 * n - 1);
    let (s, _) = analysed(&p, FaerOrdering::Auto);
    assert_eq!(s.chosen_ordering(), Some(FaerOrdering::Amd));
}

/// From `AUTO_WITHOUT_AMD_DOFS` on, AMD is not a candidate: on a chain of that many springs,
/// where AMD's order has no fill at all (and Auto takes it below the threshold, as the test
/// above shows: ties go to AMD), Auto takes nested dissection's or METIS's.
#[test]
fn auto_leaves_amd_out_from_its_threshold() {
    let n = crate::AUTO_WITHOUT_AMD_DOFS;
    assert!(n < crate::AUTO_METIS_ONLY_DOFS);
    let lists: Vec<Vec<usize>> = (0..n - 1).map(|k| vec![k, k + 1]).collect();
    let p = Arc::new(SymmetricPattern::from_dof_lists(n, &lists).unwrap());
    let (_, amd) = analysed(&p, FaerOrdering::Amd);
    assert_eq!(amd.lower_nonzeros, 2 * n - 1);
    let (s, auto) = analysed(&p, FaerOrdering::Auto);
    let chosen = s.chosen_ordering();
    assert!(
        matches!(
            chosen,
            Some(FaerOrdering::NestedDissection | FaerOrdering::Metis)
        ),
        "{chosen:?}"
    );
    assert!(auto.flops >= amd.flops);
}

/// A shifted Hex20 "Laplacian" (SPD, condition number about 10³) solved with METIS's order
/// and with AMD's: the two differ only by rounding, ≤ 1e-10 relative.
#[test]
fn solve_agrees_with_amd() {
    let (n, lists) = nonlin3d_testkit::hex20_dof_lists([6, 5, 3]);
    let p = Arc::new(SymmetricPattern::from_dof_lists(n, &lists).unwrap());
    let mut a = SymmetricMatrix::zeros(p.clone());
    for (e, l) in lists.iter().enumerate() {
        let m = l.len();
        let w = 1.0 + (e % 5) as f64 / 5.0;
        let k: Vec<f64> = (0..m * m)
            .map(|ij| {
                if ij / m == ij % m {
                    w * (m as f64 - 1.0) / m as f64 + 0.1
                } else {
                    -w / m as f64
                }
            })
            .collect();
        a.scatter_add(l, &k).unwrap();
    }
    let b: Vec<f64> = (0..n).map(|i| ((i * 31) % 13) as f64 - 6.0).collect();
    let solve = |o: FaerOrdering| {
        let (mut s, _) = analysed(&p, o);
        assert_eq!(s.factorize(&a).unwrap().negative_pivots, 0);
        let mut x = b.clone();
        s.solve_in_place(&mut x, 1).unwrap();
        x
    };
    let (x_m, x_a) = (solve(FaerOrdering::Metis), solve(FaerOrdering::Amd));
    let norm = x_a.iter().map(|v| v * v).sum::<f64>().sqrt();
    let diff = x_m
        .iter()
        .zip(&x_a)
        .map(|(a, b)| (a - b).powi(2))
        .sum::<f64>()
        .sqrt();
    assert!(diff <= 1e-10 * norm, "difference {diff} of {norm}");
}

/// Tiny and degenerate patterns: one DOF, one node, DOFs no element couples.
#[test]
fn degenerate_patterns_are_ordered() {
    for lists in [
        vec![vec![0]],
        vec![vec![0, 1, 2]],
        vec![vec![0], vec![1], vec![2]],
    ] {
        let n = lists.iter().flatten().max().unwrap() + 1;
        let p = SymmetricPattern::from_dof_lists(n, &lists).unwrap();
        let perm = metis_nested_dissection(&p).unwrap();
        let mut seen = perm.forward().to_vec();
        seen.sort_unstable();
        assert_eq!(seen, (0..n).collect::<Vec<_>>());
    }
}

/// GKlib swaps in its own SIGTERM handler for the length of a METIS call and puts the old one
/// back with `signal()`, which drops its flags (an `SA_SIGINFO` handler would then be called
/// with the wrong arguments): the disposition after the call is the one before, flags and all.
#[cfg(unix)]
#[test]
fn signal_dispositions_survive_a_call() {
    extern "C" fn on_term(_: libc::c_int, _: *mut libc::siginfo_t, _: *mut libc::c_void) {}
    let read = || {
        // SAFETY: querying a disposition into a zeroed struct.
        unsafe {
            let mut old: libc::sigaction = std::mem::zeroed();
            assert_eq!(
                libc::sigaction(libc::SIGTERM, std::ptr::null(), &mut old),
                0
            );
            (old.sa_sigaction, old.sa_flags)
        }
    };
    let before = {
        let _guard = METIS_LOCK.lock().unwrap_or_else(|e| e.into_inner());
        // SAFETY: installing a handler that does nothing, with SA_SIGINFO, in a test process.
        unsafe {
            let mut act: libc::sigaction = std::mem::zeroed();
            act.sa_sigaction = on_term as *const () as usize;
            act.sa_flags = libc::SA_SIGINFO;
            assert_eq!(
                libc::sigaction(libc::SIGTERM, &act, std::ptr::null_mut()),
                0
            );
        }
        read()
    };
    metis_nested_dissection(&hex20(3, 3, 2)).unwrap();
    // Read under the lock: another test's METIS call may be swapping handlers right now.
    let after = {
        let _guard = METIS_LOCK.lock().unwrap_or_else(|e| e.into_inner());
        read()
    };
    assert_eq!(after, before);
}

/// A pattern grown from the analysed one is analysed with the order Auto chose for it
/// (`reanalyze`): AMD on the chain, kept on the chain closed into a ring (the same flops as an
/// AMD analysis of the ring), without comparing again; Auto itself is left as it was, so the
/// next plain analysis compares the three orders again.
#[test]
fn a_grown_pattern_keeps_the_order_auto_chose() {
    let n = 400;
    let chain: Vec<Vec<usize>> = (0..n - 1).map(|k| vec![k, k + 1]).collect();
    let mut ring = chain.clone();
    ring.push(vec![0, n - 1]);
    let chain = Arc::new(SymmetricPattern::from_dof_lists(n, &chain).unwrap());
    let ring = Arc::new(SymmetricPattern::from_dof_lists(n, &ring).unwrap());
    let (mut s, _) = analysed(&chain, FaerOrdering::Auto);
    assert_eq!(s.chosen_ordering(), Some(FaerOrdering::Amd));
    let grown = s.reanalyze(&ring).unwrap();
    assert_eq!(s.chosen_ordering(), Some(FaerOrdering::Amd));
    let (_, amd) = analysed(&ring, FaerOrdering::Amd);
    assert_eq!(grown.flops, amd.flops);
    assert_eq!(grown.ordering, amd.ordering);
    let small = Arc::new(hex20(8, 8, 4));
    let (fresh, _) = analysed(&small, FaerOrdering::Auto);
    assert_ne!(fresh.chosen_ordering(), Some(FaerOrdering::Amd));
    s.analyze(&small).unwrap();
    assert_eq!(s.chosen_ordering(), fresh.chosen_ordering());
    // A solver that has chosen nothing yet compares as Auto does.
    let mut new = FaerSolver::new(FaerMode::Ldlt);
    new.reanalyze(&small).unwrap();
    assert_eq!(new.chosen_ordering(), fresh.chosen_ordering());
}
