//! Test matrices shared by the solver's integration tests: a Hex20 box's pattern with
//! pseudo-random element values.
#![allow(dead_code)]

use nonlin3d_solver::{SymmetricMatrix, SymmetricPattern};
use std::sync::Arc;

/// Element DOF lists of a Hex20 box of nx×ny×nz cells (8 corners, 12 midsides per cell).
pub fn hex20_lists(nx: usize, ny: usize, nz: usize) -> (usize, Vec<Vec<usize>>) {
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
pub fn lcg(state: &mut u64) -> f64 {
    *state = state
        .wrapping_mul(6_364_136_223_846_793_005)
        .wrapping_add(1_442_695_040_888_963_407);
    (*state >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}

/// Σ_e (v_e v_eᵀ + I) over the elements of an nx×ny×nz Hex20 box, minus `shift`·I.
pub fn box_matrix([nx, ny, nz]: [usize; 3], shift: f64) -> SymmetricMatrix {
    let (n, lists) = hex20_lists(nx, ny, nz);
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
