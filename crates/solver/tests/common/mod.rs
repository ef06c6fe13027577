//! Test matrices shared by the solver's integration tests: a Hex20 box's pattern
//! (`nonlin3d_testkit::hex20_dof_lists`) with pseudo-random element values.
#![allow(dead_code)]

use nonlin3d_solver::{SymmetricMatrix, SymmetricPattern};
use nonlin3d_testkit::{Lcg, hex20_dof_lists};
use std::sync::Arc;

/// Σ_e (v_e v_eᵀ + I) over the elements of an nx×ny×nz Hex20 box, minus `shift`·I.
pub fn box_matrix([nx, ny, nz]: [usize; 3], shift: f64) -> SymmetricMatrix {
    let (n, lists) = hex20_dof_lists([nx, ny, nz]);
    let p = Arc::new(SymmetricPattern::from_dof_lists(n, &lists).unwrap());
    let mut a = SymmetricMatrix::zeros(p);
    let mut rng = Lcg::new(7);
    for l in &lists {
        let v: Vec<f64> = l.iter().map(|_| rng.uniform(-1.0, 1.0)).collect();
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
