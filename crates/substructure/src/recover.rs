//! Recovery of the linear region from the interface displacements (thesis §2.6: "the
//! displacements at the interface nodes are specified"): u_i = K_ii⁻¹ (f_i(λ) − K_ib u_b − K_ip u_p(λ)), u_p = base + λ v; then the
//! region's nodal forces K u (the linear force kinematics VCCT uses in a linear region, §2.8)
//! and the reactions K u − f_ext at its prescribed DOFs.

use crate::dofs::{Class, Split};
use crate::reduce::Interior;
use crate::{Partition, SubstructureError};
use nonlin3d_solver::SymmetricMatrix;

/// The linear region's state, in the full mesh's numbering (3 DOFs per node).
#[derive(Debug, Clone, PartialEq)]
pub struct Recovered {
    /// Displacements: the linear region's recovered, the nonlinear region's as given (zero at
    /// nodes in no cell).
    pub displacements: Vec<f64>,
    /// K u of the linear region's cells alone (small strain), zero outside it.
    pub linear_forces: Vec<f64>,
    /// K u − f_ext(λ) at the linear region's interior prescribed DOFs, zero elsewhere.
    pub reactions: Vec<f64>,
}

/// What recovers a condensed region: its K (linear sub-mesh numbering), what solves with K_ii,
/// the DOF split and the node maps. Made by [`condense`](crate::condense).
pub struct Recovery {
    k: SymmetricMatrix,
    split: Split,
    interior: Interior,
    /// Linear sub-mesh node → full node.
    linear_to_full: Vec<usize>,
    /// Nonlinear sub-mesh DOF of each interface DOF.
    boundary_nonlinear: Vec<usize>,
    /// Nonlinear sub-mesh node → full node.
    nonlinear_to_full: Vec<usize>,
    full_nodes: usize,
}

impl Recovery {
    pub(crate) fn new(
        partition: &Partition,
        k: SymmetricMatrix,
        split: Split,
        interior: Interior,
    ) -> Self {
        Self {
            k,
            split,
            interior,
            linear_to_full: partition.linear_nodes().to_vec(),
            boundary_nonlinear: partition.interface_dofs_nonlinear(),
            nonlinear_to_full: partition.nonlinear_nodes().to_vec(),
            full_nodes: partition.full_nodes(),
        }
    }

    /// The linear region's K at u = 0 (linear sub-mesh numbering).
    pub fn stiffness(&self) -> &SymmetricMatrix {
        &self.k
    }

    /// The linear region's displacements (linear sub-mesh numbering) for the nonlinear
    /// region's displacements `u_nonlinear` (its sub-mesh numbering) at load factor λ.
    pub fn linear_displacements(
        &mut self,
        u_nonlinear: &[f64],
        lambda: f64,
    ) -> Result<Vec<f64>, SubstructureError> {
        let expected = 3 * self.nonlinear_to_full.len();
        if u_nonlinear.len() != expected {
            return Err(SubstructureError::Length {
                what: "nonlinear region's displacements",
                expected,
                got: u_nonlinear.len(),
            });
        }
        let s = &self.split;
        let n = s.class.len();
        // u with the interface and prescribed entries set, the interior's zero.
        let mut u = vec![0.0; n];
        for (d, class) in s.class.iter().enumerate() {
            match *class {
                Class::Boundary(k) => u[d] = u_nonlinear[self.boundary_nonlinear[k]],
                Class::Prescribed(_) => u[d] = s.base[d] + lambda * s.value[d],
                Class::Interior(_) => {}
            }
        }
        let mut ku = vec![0.0; n];
        self.k.matvec(&u, &mut ku)?;
        let mut ui: Vec<f64> = s
            .interior
            .iter()
            .map(|&d| lambda * s.load[d] + s.dead[d] - ku[d])
            .collect();
        self.interior.solve(&mut ui)?;
        for (&d, x) in s.interior.iter().zip(&ui) {
            u[d] = *x;
        }
        Ok(u)
    }

    /// The full mesh's displacements, the linear region's forces and reactions (see
    /// [`Recovered`]) for the nonlinear region's displacements `u_nonlinear` at λ.
    pub fn recover(
        &mut self,
        u_nonlinear: &[f64],
        lambda: f64,
    ) -> Result<Recovered, SubstructureError> {
        let u = self.linear_displacements(u_nonlinear, lambda)?;
        let mut ku = vec![0.0; u.len()];
        self.k.matvec(&u, &mut ku)?;
        let n = 3 * self.full_nodes;
        let mut out = Recovered {
            displacements: vec![0.0; n],
            linear_forces: vec![0.0; n],
            reactions: vec![0.0; n],
        };
        for (s, &v) in self.nonlinear_to_full.iter().enumerate() {
            out.displacements[3 * v..3 * v + 3].copy_from_slice(&u_nonlinear[3 * s..3 * s + 3]);
        }
        for (l, &v) in self.linear_to_full.iter().enumerate() {
            for r in 0..3 {
                let (d, full) = (3 * l + r, 3 * v + r);
                out.displacements[full] = u[d];
                out.linear_forces[full] = ku[d];
                if let Class::Prescribed(_) = self.split.class[d] {
                    let f = lambda * self.split.load[d] + self.split.dead[d];
                    out.reactions[full] = ku[d] - f;
                }
            }
        }
        Ok(out)
    }
}
