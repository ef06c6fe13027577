//! Test support shared by the nonlin3d crates (not published).
//!
//! Everything here works on plain arrays and depends on no crate of the workspace, so that any
//! crate — the element kernels at the bottom as much as the facade at the top — can take it as
//! a dev-dependency without a second copy of its own types:
//! - [`block`]: structured blocks of hexahedra from a reference-node pattern (Hex8, Hex20, …),
//!   the box every crate's tests need, and a Hex20 box's DOF lists for sparsity patterns
//!   ([`hex20_dof_lists`]);
//! - [`diff`]: central finite differences, to check a gradient or a tangent against the
//!   function it derives from;
//! - [`dense`]: dense oracles (Gaussian elimination with partial pivoting, matrix–vector
//!   products, norms) to check sparse solvers and assembled systems;
//! - [`blister`]: the closed form of the straight-sided buckle-driven blister (Hutchinson & Suo
//!   1992), G and the mode-mix angle ψ, for the through-width delamination;
//! - [`Lcg`]: a small seeded generator for reproducible test data.
//!
//! A seeded random right-hand side, solved with the dense oracle and checked by its product:
//!
//! ```
//! use nonlin3d_testkit::{Lcg, dense};
//!
//! let mut rng = Lcg::new(42);
//! let a = [4.0, 1.0, 0.0, 1.0, 3.0, 1.0, 0.0, 1.0, 2.0]; // row-major 3 × 3, SPD
//! let b: Vec<f64> = (0..3).map(|_| rng.uniform(-1.0, 1.0)).collect();
//! let x = dense::solve(&a, &b).expect("non-singular");
//! let r: Vec<f64> = dense::mat_vec(&a, &x).iter().zip(&b).map(|(p, q)| p - q).collect();
//! assert!(dense::max_abs(&r) < 1e-14);
//! ```
#![deny(missing_docs)]

pub mod blister;
pub mod block;
pub mod dense;
pub mod diff;

pub use block::{Block, hex20_dof_lists};

/// A linear congruential generator (Knuth's MMIX constants): reproducible test data without a
/// dependency. Not for statistics.
#[derive(Debug, Clone)]
pub struct Lcg(u64);

impl Lcg {
    /// A generator seeded with `seed`.
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    /// The next number, uniform in [0, 1) (the top 53 bits of the state).
    pub fn next_f64(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    /// The next number, uniform in [lo, hi).
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next_f64()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lcg_is_reproducible_and_in_range() {
        let (mut a, mut b) = (Lcg::new(7), Lcg::new(7));
        for _ in 0..1000 {
            let x = a.next_f64();
            assert_eq!(x.to_bits(), b.next_f64().to_bits());
            assert!((0.0..1.0).contains(&x));
        }
        assert_ne!(Lcg::new(1).next_f64(), Lcg::new(2).next_f64());
    }
}
