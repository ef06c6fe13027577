//! Static condensation of the linear region onto the interface (thesis §2.6, which numbers no
//! equation: its "restraint forces for a unit displacement" are the columns of K_red):
//!
//! [K_bb K_bi; K_ib K_ii] [u_b; u_i] = [f_b; f_i] − [K_bp; K_ip] u_p
//! ⇒ K_red = K_bb − K_bi K_ii⁻¹ K_ib,
//!   f_c(λ) = −K_bi K_ii⁻¹ (f_i(λ) − K_ip u_p(λ)) − K_bp u_p(λ),
//!
//! b the interface DOFs, i the interior's free DOFs, p its prescribed DOFs (u_p = base + λ v).
//! The linear region's internal force on the interface is K_red u_b − f_c(λ): the superelement
//! adds K_red u_b to the internal force and f_c(λ) to the external one.
//!
//! K_red is the trailing block of one partial LDLᵀ of [K_ii K_ib; K_bi K_bb], the interior in a
//! fill-reducing order and the interface last ([`SchurComplement`]); the loads' −K_bi K_ii⁻¹ x
//! are the interface rows of its forward sweeps. The trailing block is updated by the interior
//! and read, never factored, so K_red is exact also where it is singular (an interface that
//! leaves the interior free to move as a rigid body). With [`CondenseSettings::schur`] = false,
//! K_ii alone is factorised and K_ii⁻¹K_ib formed in blocks of right-hand sides.

use crate::dofs::split;
use crate::reduce::{by_blocks, by_schur};
use crate::{Partition, Recovery, SubstructureError, Superelement};
use nonlin3d_assembly::{Assembler, Constraints};
use nonlin3d_solver::{FaerOrdering, SolverError};
use std::time::Instant;

/// How a linear region is condensed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CondenseSettings {
    /// Right-hand sides per block of K_ii⁻¹K_ib (the dense block is interior DOFs × `block`
    /// values). 0 = all interface DOFs at once.
    pub block: usize,
    /// Threads of K_ii's numeric factorisation for the block solves (1 = sequential); the
    /// partial factorisation runs on one thread (0.11–0.33 s on the scenes measured).
    pub threads: usize,
    /// The fill-reducing ordering of K_ii.
    pub ordering: FaerOrdering,
    /// K_red from one partial factorisation with the interface last (true), or from K_ii's
    /// factor and block solves (false).
    pub schur: bool,
}

impl Default for CondenseSettings {
    /// Blocks of 64 columns (measured: see docs/PERFORMANCE.md, "Substructuring"), sequential.
    fn default() -> Self {
        Self {
            block: 64,
            threads: 1,
            ordering: FaerOrdering::Auto,
            schur: true,
        }
    }
}

/// What one condensation did and found.
#[derive(Debug, Clone, PartialEq)]
pub struct CondensationReport {
    /// Interface DOFs (the superelement's size, 3 per interface node).
    pub interface_dofs: usize,
    /// Free interior DOFs (the order of K_ii).
    pub interior_dofs: usize,
    /// Prescribed interior DOFs (supports and prescribed values of the linear region).
    pub prescribed_dofs: usize,
    /// Entries of K_ii's factor.
    pub factor_entries: usize,
    /// Right-hand sides per block used (0: K_red from the partial factorisation).
    pub block: usize,
    /// max |K_red − K_redᵀ| / max |K_red| before symmetrising (rounding of the block solves;
    /// 0 from the partial factorisation, symmetric by construction).
    pub asymmetry: f64,
    /// Seconds: assembly of K, factorisation of K_ii, the block solves and products.
    pub seconds: [f64; 3],
}

/// A condensed linear region: the superelement for the nonlinear problem, what recovers the
/// region afterwards, and the report.
pub struct Condensed {
    /// K_red and f_c on the interface, a [`Contribution`](nonlin3d_assembly::Contribution).
    pub superelement: Superelement,
    /// The factorised K_ii and the region's K, to recover u_i, forces and reactions.
    pub recovery: Recovery,
    /// Sizes, asymmetry, times.
    pub report: CondensationReport,
}

/// Condenses the linear region of `partition` onto its interface (module docs): `linear` is an
/// [`Assembler`] on [`Partition::linear_mesh`] (its tangent at u = 0 is the small-strain K
/// whatever its kinematics: no stress, no geometric stiffness, B_NL = 0), `constraints` those
/// of the full mesh (the region's interior supports, prescribed values and loads are taken
/// from them; what falls on the interface stays with the nonlinear problem:
/// [`Partition::nonlinear_constraints`]).
pub fn condense(
    partition: &Partition,
    linear: &Assembler,
    constraints: &Constraints,
    settings: &CondenseSettings,
) -> Result<Condensed, SubstructureError> {
    let n = 3 * partition.linear_nodes().len();
    if linear.n() != n {
        return Err(SubstructureError::Length {
            what: "the linear region's assembler (build it on Partition::linear_mesh) DOFs",
            expected: n,
            got: linear.n(),
        });
    }
    let s = split(partition, constraints)?;
    let clock = Instant::now();
    let mut k = linear.new_tangent();
    linear.assemble(&vec![0.0; n], Some(&mut k))?;
    let assembled = clock.elapsed().as_secs_f64();

    // Condensed loads: three right-hand sides f_i per unit λ, −K_ip v, dead − K_ip base.
    let mut kv = vec![0.0; n];
    let mut kbase = vec![0.0; n];
    k.matvec(&s.value, &mut kv)?;
    k.matvec(&s.base, &mut kbase)?;
    let rhs = [
        s.interior.iter().map(|&d| s.load[d]).collect(),
        s.interior.iter().map(|&d| -kv[d]).collect(),
        s.interior.iter().map(|&d| s.dead[d] - kbase[d]).collect(),
    ];
    let singular = |e| singular_interior(e, partition);
    let r = match settings.schur {
        true => by_schur(&k, &s, settings.ordering, &rhs).map_err(singular)?,
        false => by_blocks(
            &k,
            &s,
            (settings.block, settings.threads, settings.ordering),
            &rhs,
        )
        .map_err(singular)?,
    };
    let [load, prescribed, dead] = r.loads;
    let boundary = |x: Vec<f64>, k: &[f64]| -> Vec<f64> {
        x.iter().zip(&s.boundary).map(|(x, &d)| x - k[d]).collect()
    };
    let prescribed = boundary(prescribed, &kv);
    let dead = boundary(dead, &kbase);
    let solved = clock.elapsed().as_secs_f64();
    let nb = s.boundary.len();
    let report = CondensationReport {
        interface_dofs: nb,
        interior_dofs: s.interior.len(),
        prescribed_dofs: s.class.len() - s.interior.len() - nb,
        factor_entries: r.factor_entries,
        block: r.block,
        asymmetry: r.asymmetry,
        seconds: [assembled, r.factored_s, solved - assembled - r.factored_s],
    };
    let superelement = Superelement::new(
        partition.interface_dofs_nonlinear(),
        r.kred,
        crate::CondensedLoad {
            load,
            prescribed,
            dead,
        },
    )?;
    let recovery = Recovery::new(partition, k, s, r.interior);
    Ok(Condensed {
        superelement,
        recovery,
        report,
    })
}

/// A zero pivot of K_ii (the linear sub-mesh's DOF) named by its full-mesh DOF.
fn singular_interior(e: SubstructureError, partition: &Partition) -> SubstructureError {
    match e {
        SubstructureError::Solver(SolverError::ZeroPivot {
            dof,
            pivot,
            diagonal,
            ..
        }) => SubstructureError::SingularInterior {
            dof: partition
                .from_linear(dof / 3)
                .map_or(dof, |v| 3 * v + dof % 3),
            pivot,
            diagonal,
        },
        e => e,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nonlin3d_element::{ElementKind, IntegrationRule, Kinematics};
    use nonlin3d_laminate::ShearCoupling;
    use nonlin3d_mesh::{BoxParams, Mesh, names, structured_box};

    fn assembler(mesh: &Mesh, kinematics: Kinematics) -> Assembler {
        let steel = nonlin3d_laminate::materials::steel().stiffness().unwrap();
        Assembler::new(
            mesh,
            &[steel],
            ShearCoupling::Exact,
            IntegrationRule::Gauss2,
            IntegrationRule::Gauss2,
            kinematics,
        )
        .unwrap()
    }

    /// At u = 0 the total Lagrangian tangent is the small-strain K: no stress (no geometric
    /// stiffness) and B_NL = 0, so both kinematics give the same entries to rounding
    /// (1e-14 of the largest; they take different code paths).
    #[test]
    fn the_tangent_at_zero_is_the_small_strain_stiffness() {
        let mesh = structured_box(&BoxParams::new(
            ElementKind::Hex20,
            [2, 2, 1],
            [2.0, 1.5, 0.5],
        ))
        .unwrap();
        let tangent = |k: Kinematics| {
            let a = assembler(&mesh, k);
            let mut t = a.new_tangent();
            a.assemble(&vec![0.0; a.n()], Some(&mut t)).unwrap();
            t.values().to_vec()
        };
        let (nl, l) = (tangent(Kinematics::Nonlinear), tangent(Kinematics::Linear));
        let scale = l.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let diff = nl
            .iter()
            .zip(&l)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(diff <= 1e-14 * scale, "{diff:e} of {scale:e}");
    }

    /// A 4 × 2 × 2 Hex8 box whose bottom layer (cells 0–7) is the linear region.
    fn bottom_layer_linear() -> (Mesh, Partition) {
        let mesh = structured_box(&BoxParams::new(
            ElementKind::Hex8,
            [4, 2, 2],
            [4.0, 2.0, 2.0],
        ))
        .unwrap();
        let p = Partition::from_linear_cells(&mesh, &(0..8).collect::<Vec<_>>()).unwrap();
        (mesh, p)
    }

    /// K_red does not depend on how it is formed: the partial factorisation against block
    /// solves of 1, 5 and all columns at once, equal to rounding (1e-12 of the largest
    /// entry; the same elimination in another grouping), loads likewise.
    #[test]
    fn the_partial_factorisation_and_the_block_widths_agree() {
        let (mesh, p) = bottom_layer_linear();
        // x = 0 clamped (u = 0.1 along x) and z = 0 held along z: the linear region (the
        // bottom layer) cannot move with its interface free, K_red is regular.
        let mut c = Constraints::new(3 * mesh.nodes.len());
        for &v in &mesh.node_sets[names::X0] {
            for (r, value) in [0.1, 0.0, 0.0].into_iter().enumerate() {
                c.prescribe(3 * v + r, value).unwrap();
            }
        }
        for &v in &mesh.node_sets[names::Z0] {
            if !c.is_constrained(3 * v + 2) {
                c.prescribe(3 * v + 2, 0.0).unwrap();
            }
        }
        let a = assembler(p.linear_mesh(), Kinematics::Linear);
        let k = |block: Option<usize>| {
            let s = CondenseSettings {
                block: block.unwrap_or(64),
                schur: block.is_none(),
                ..CondenseSettings::default()
            };
            let done = condense(&p, &a, &c, &s).unwrap();
            assert_eq!(done.report.block == 0, block.is_none());
            (
                done.superelement.stiffness().to_vec(),
                done.superelement.load().clone(),
            )
        };
        let (k0, l0) = k(None);
        let scale = k0.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let close = |x: &[f64], y: &[f64], what: &str| {
            let size = y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let diff = x
                .iter()
                .zip(y)
                .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
            assert!(
                diff <= 1e-12 * size.max(scale * 1e-6),
                "{what}: {diff:e} of {size:e}"
            );
        };
        for block in [0, 1, 5] {
            let (kb, lb) = k(Some(block));
            close(&kb, &k0, "K_red");
            close(&lb.load, &l0.load, "load");
            close(&lb.prescribed, &l0.prescribed, "prescribed");
            close(&lb.dead, &l0.dead, "dead");
        }
        assert!(l0.prescribed.iter().any(|&x| x != 0.0));
    }

    /// With x = 0 held along x only, the linear region (the bottom layer) can slide and turn
    /// with its interface free: K_red is singular. The partial factorisation reads it from the
    /// interface's updated block, never factoring it, so it forms it all the same, and as block
    /// solves with K_ii's own factor do (to 1e-12 of the largest entry: both are one
    /// elimination of the same K_ii, in other orders).
    #[test]
    fn a_singular_reduced_stiffness_is_formed_by_the_partial_factorisation() {
        let (mesh, p) = bottom_layer_linear();
        let mut c = Constraints::new(3 * mesh.nodes.len());
        for &v in &mesh.node_sets[names::X0] {
            c.prescribe(3 * v, 0.1).unwrap();
        }
        let a = assembler(p.linear_mesh(), Kinematics::Linear);
        let done = condense(&p, &a, &c, &CondenseSettings::default()).unwrap();
        assert_eq!(done.report.block, 0);
        let blocks = CondenseSettings {
            schur: false,
            ..CondenseSettings::default()
        };
        let by_blocks = condense(&p, &a, &c, &blocks).unwrap();
        assert_eq!(by_blocks.report.block, 64);
        let (k0, k1) = (
            done.superelement.stiffness(),
            by_blocks.superelement.stiffness(),
        );
        let scale = k1.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let diff = k0
            .iter()
            .zip(k1)
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
        assert!(diff <= 1e-12 * scale, "K_red: {diff:e} of {scale:e}");
        let (l0, l1) = (
            &done.superelement.load().prescribed,
            &by_blocks.superelement.load().prescribed,
        );
        assert!(l1.iter().any(|&x| x != 0.0));
        let size = l1.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let diff = l0
            .iter()
            .zip(l1)
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
        assert!(
            diff <= 1e-12 * size,
            "prescribed load: {diff:e} of {size:e}"
        );
    }
}
