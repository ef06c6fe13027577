//! The linear region's DOFs for a condensation (thesis §2.6): each DOF of the linear sub-mesh
//! an interface DOF (b), a free interior DOF (i) or a prescribed one (p), with the region's
//! prescribed values and loads taken from the full mesh's constraints.

use crate::partition::values_at_0_and_1;
use crate::{Partition, SubstructureError};
use nonlin3d_assembly::Constraints;

/// Where a DOF of the linear sub-mesh goes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Class {
    /// Interface DOF k (3 per interface node, in interface order).
    Boundary(usize),
    /// Free interior DOF k (a row of K_ii).
    Interior(usize),
    /// Prescribed interior DOF k.
    Prescribed(usize),
}

/// The linear region's DOFs, split, with their prescribed values and loads (linear sub-mesh
/// numbering).
pub(crate) struct Split {
    pub class: Vec<Class>,
    /// Linear DOF of each free interior DOF.
    pub interior: Vec<usize>,
    /// Linear DOF of each interface DOF.
    pub boundary: Vec<usize>,
    /// Prescribed values at λ = 0 (base) and per unit λ (v), zero at unprescribed DOFs.
    pub base: Vec<f64>,
    pub value: Vec<f64>,
    /// External force per unit λ and dead (λ-independent), every DOF.
    pub load: Vec<f64>,
    pub dead: Vec<f64>,
}

/// Classifies the linear sub-mesh's DOFs and gathers the region's constraints and loads from
/// the full mesh's `constraints`.
pub(crate) fn split(
    partition: &Partition,
    constraints: &Constraints,
) -> Result<Split, SubstructureError> {
    partition.check_full("constraints", constraints.n())?;
    let interior_node = |v: usize| partition.interior().binary_search(&v).is_ok();
    for t in constraints.ties() {
        let touched = std::iter::once(t.slave)
            .chain(t.masters.iter().map(|m| m.0))
            .find(|&d| interior_node(d / 3));
        if let Some(d) = touched {
            return Err(SubstructureError::TieInLinearRegion {
                slave: t.slave,
                node: d / 3,
            });
        }
    }
    let nodes = partition.linear_nodes();
    let n = 3 * nodes.len();
    let (at0, at1) = values_at_0_and_1(constraints);
    let mut s = Split {
        class: Vec::with_capacity(n),
        interior: Vec::new(),
        boundary: vec![0; 3 * partition.interface().len()],
        base: vec![0.0; n],
        value: vec![0.0; n],
        load: vec![0.0; n],
        dead: vec![0.0; n],
    };
    let mut prescribed = 0;
    for (l, &v) in nodes.iter().enumerate() {
        let on_interface = partition.interface().binary_search(&v).ok();
        for r in 0..3 {
            let (d, full) = (3 * l + r, 3 * v + r);
            s.load[d] = at1.forces[full] - at0.forces[full];
            s.dead[d] = at0.forces[full];
            let class = if let Some(k) = on_interface {
                s.boundary[3 * k + r] = d;
                Class::Boundary(3 * k + r)
            } else if constraints.is_constrained(full) {
                s.base[d] = at0.values[full];
                s.value[d] = at1.values[full] - at0.values[full];
                prescribed += 1;
                Class::Prescribed(prescribed - 1)
            } else {
                s.interior.push(d);
                Class::Interior(s.interior.len() - 1)
            };
            s.class.push(class);
        }
    }
    Ok(s)
}
