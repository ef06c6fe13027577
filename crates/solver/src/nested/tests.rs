//! Tests of the nested-dissection ordering.

use super::bisect::bisect;
use super::*;
use crate::{FaerMode, FaerOrdering, FaerSolver, LinearSolver, SymmetricMatrix};
use std::sync::Arc;

/// Trilinear-brick connectivity on an (nx+1)×(ny+1)×(nz+1) node grid with `dofs` DOFs per
/// node (nz = 0: bilinear quads), as DOF lists per element.
fn grid_lists(nx: usize, ny: usize, nz: usize, dofs: usize) -> (usize, Vec<Vec<usize>>) {
    let node = |i: usize, j: usize, k: usize| (k * (ny + 1) + j) * (nx + 1) + i;
    let mut lists = Vec::new();
    for k in 0..nz.max(1) {
        for j in 0..ny {
            for i in 0..nx {
                let mut l = Vec::new();
                for dk in 0..=usize::from(nz > 0) {
                    for dj in 0..2 {
                        for di in 0..2 {
                            let n = node(i + di, j + dj, k + dk);
                            l.extend((0..dofs).map(|d| dofs * n + d));
                        }
                    }
                }
                lists.push(l);
            }
        }
    }
    (dofs * (nx + 1) * (ny + 1) * (nz + 1), lists)
}

fn grid(nx: usize, ny: usize, nz: usize, dofs: usize) -> SymmetricPattern {
    let (n, lists) = grid_lists(nx, ny, nz, dofs);
    SymmetricPattern::from_dof_lists(n, &lists).unwrap()
}

/// Hex20 connectivity (8 corners, 12 midsides) on nx×ny×nz elements, 3 DOFs per node.
fn hex20(nx: usize, ny: usize, nz: usize) -> SymmetricPattern {
    let (n, lists) = nonlin3d_testkit::hex20_dof_lists([nx, ny, nz]);
    SymmetricPattern::from_dof_lists(n, &lists).unwrap()
}

fn lower_nonzeros(p: &Arc<SymmetricPattern>, ordering: FaerOrdering) -> usize {
    let mut s = FaerSolver::new(FaerMode::Ldlt).with_ordering(ordering);
    s.analyze(p).unwrap().lower_nonzeros
}

/// Each DOF exactly once, and the same order on every call and on 1 or 3 threads (the box
/// has about 3 000 nodes, so its first levels split between threads).
#[test]
fn order_is_a_deterministic_permutation() {
    let p = hex20(12, 10, 4);
    let first = nested_dissection(&p).unwrap();
    let mut seen = first.forward().to_vec();
    seen.sort_unstable();
    assert_eq!(seen, (0..p.n()).collect::<Vec<_>>());
    assert_eq!(nested_dissection(&p).unwrap(), first);
    for threads in [1, 3] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        assert_eq!(pool.install(|| nested_dissection(&p).unwrap()), first);
    }
    // The 3 DOFs of a node stay together (supervariables).
    for node in first.forward().chunks(3) {
        assert_eq!(node[0] / 3, node[2] / 3);
    }
}

/// A separator separates: no edge between the two sides, both sides non-empty, neither
/// above the balance bound; on a 24×12×6 brick grid the best plane has 13·7 = 91 nodes.
#[test]
fn separator_has_no_edge_across() {
    let p = grid(24, 12, 6, 3);
    let (_, g) = compress(&p);
    let part = bisect(&g);
    let weight = |s: u8| (0..g.n()).filter(|&v| part[v] == s).count();
    for v in 0..g.n() {
        for (w, _) in g.nbrs(v) {
            assert!(
                part[v] == 2 || part[w] == 2 || part[v] == part[w],
                "edge {v}-{w}"
            );
        }
    }
    let n = g.n() as f64;
    for s in [0, 1] {
        assert!(weight(s) > 0 && weight(s) as f64 <= BALANCE * n + 1.0);
    }
    // A plane across the longest side; a bad separator would be several times larger.
    assert!(weight(2) <= 2 * 91, "separator of {} nodes", weight(2));
}

/// 2-D grids (bilinear quads, 9-point graph): nested dissection's fill grows like
/// n log n (George 1973: at most 31/4 · n log₂ n + O(n) for the 9-point grid), so going
/// from 63² to 127² nodes (n × 4.03) multiplies it by about 4.03 · 14/12 ≈ 4.7, where an
/// n^1.5 growth would give 8.1; and at 127² it is at most AMD's (measured 0.93 of it).
#[test]
fn grid_fill_grows_like_n_log_n() {
    let fill = |k: usize, o: FaerOrdering| {
        let p = Arc::new(grid(k, k, 0, 1));
        (p.n() as f64, lower_nonzeros(&p, o) as f64)
    };
    let (n1, nd1) = fill(63, FaerOrdering::NestedDissection);
    let (n2, nd2) = fill(127, FaerOrdering::NestedDissection);
    let (_, amd2) = fill(127, FaerOrdering::Amd);
    assert!(nd2 <= 31.0 / 4.0 * n2 * n2.log2(), "fill {nd2} at n = {n2}");
    let growth = nd2 / nd1;
    let n_log_n = n2 * n2.log2() / (n1 * n1.log2());
    assert!(
        (growth / n_log_n - 1.0).abs() < 0.15,
        "growth {growth}, n log n {n_log_n}"
    );
    assert!(nd2 <= amd2, "ND {nd2} vs AMD {amd2}");
}

/// On a 3-D Hex20 box nested dissection needs less fill than AMD, and more so the larger the
/// box (measured 0.90 of AMD's nnz(L) on 10×10×4 elements, 0.61 on 20×20×8): ask for 5 %.
#[test]
fn hex20_box_fill_below_amd() {
    let p = Arc::new(hex20(10, 10, 4));
    let nd = lower_nonzeros(&p, FaerOrdering::NestedDissection);
    let amd = lower_nonzeros(&p, FaerOrdering::Amd);
    assert!((nd as f64) < 0.95 * amd as f64, "ND {nd} vs AMD {amd}");
    let mut s = FaerSolver::new(FaerMode::Ldlt).with_ordering(FaerOrdering::Auto);
    s.analyze(&p).unwrap();
    assert_ne!(s.chosen_ordering(), Some(FaerOrdering::Amd));
}

/// The same SPD system (a shifted grid Laplacian with varying weights) solved with both
/// orderings: only the rounding differs, well below 1e-10 relative for a matrix whose
/// condition number is about 10³ (shift 0.1 against weights of order 1 to 2).
#[test]
fn solve_agrees_with_amd() {
    let (n, lists) = grid_lists(12, 10, 5, 3);
    let p = Arc::new(SymmetricPattern::from_dof_lists(n, &lists).unwrap());
    let mut a = SymmetricMatrix::zeros(p.clone());
    for (e, l) in lists.iter().enumerate() {
        let m = l.len();
        let w = 1.0 + (e % 7) as f64 / 7.0;
        let mut k = vec![0.0; m * m];
        for i in 0..m {
            for j in 0..m {
                k[i * m + j] = if i == j {
                    w * (m as f64 - 1.0) / m as f64 + 0.1
                } else {
                    -w / m as f64
                };
            }
        }
        a.scatter_add(l, &k).unwrap();
    }
    let b: Vec<f64> = (0..n).map(|i| ((i * 37) % 11) as f64 - 5.0).collect();
    let solve = |o: FaerOrdering| {
        let mut s = FaerSolver::new(FaerMode::Ldlt).with_ordering(o);
        s.analyze(&p).unwrap();
        assert_eq!(s.factorize(&a).unwrap().negative_pivots, 0);
        let mut x = b.clone();
        s.solve_in_place(&mut x, 1).unwrap();
        x
    };
    let (x_nd, x_amd) = (
        solve(FaerOrdering::NestedDissection),
        solve(FaerOrdering::Amd),
    );
    let norm = x_amd.iter().map(|v| v * v).sum::<f64>().sqrt();
    let diff = x_nd
        .iter()
        .zip(&x_amd)
        .map(|(a, b)| (a - b).powi(2))
        .sum::<f64>()
        .sqrt();
    assert!(diff <= 1e-10 * norm, "difference {diff} of {norm}");
}

/// A pattern with many DOFs no element couples (diagonal only) beside a grid: the parts fall
/// apart into single vertices that coarsening cannot merge; the order stays valid and quick
/// (the greedy growing is O(E log n), not O(n²)).
#[test]
fn isolated_dofs_are_ordered() {
    let (n, mut lists) = grid_lists(8, 8, 2, 3);
    let extra = 20_000;
    lists.extend((n..n + extra).map(|d| vec![d]));
    let p = SymmetricPattern::from_dof_lists(n + extra, &lists).unwrap();
    let perm = nested_dissection(&p).unwrap();
    assert_eq!(perm.len(), n + extra);
}
