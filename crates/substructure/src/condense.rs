//! Static condensation of the linear region onto the interface (thesis §2.6, which numbers no
//! equation: its "restraint forces for a unit displacement" are the columns of K_red):
//!
//! [K_bb K_bi; K_ib K_ii] [u_b; u_i] = [f_b; f_i] − [K_bp; K_ip] u_p
//! ⇒ K_red = K_bb − K_bi K_ii⁻¹ K_ib,
//!   f_c(λ) = −K_bi K_ii⁻¹ (f_i(λ) − K_ip u_p(λ)) − K_bp u_p(λ),
//!
//! b the interface DOFs, i the interior's free DOFs, p its prescribed DOFs (u_p = base + λ v).
//! The linear region's internal force on the interface is K_red u_b − f_c(λ): the superelement
//! adds K_red u_b to the internal force and f_c(λ) to the external one. K_ii is factorised once
//! (faer LDLᵀ, AMD) and K_ii⁻¹K_ib formed in blocks of right-hand sides.

use crate::partition::values_at_0_and_1;
use crate::{Partition, Recovery, SubstructureError, Superelement};
use nonlin3d_assembly::{Assembler, Constraints};
use nonlin3d_solver::{
    FaerMode, FaerOrdering, FaerSolver, LinearSolver, SolverError, SymmetricMatrix,
    SymmetricPattern,
};
use std::sync::Arc;
use std::time::Instant;

/// How a linear region is condensed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CondenseSettings {
    /// Right-hand sides per block of K_ii⁻¹K_ib (the dense block is interior DOFs × `block`
    /// values). 0 = all interface DOFs at once.
    pub block: usize,
    /// Threads of the factorisation's numeric phase (1 = sequential).
    pub threads: usize,
    /// The fill-reducing ordering of K_ii.
    pub ordering: FaerOrdering,
}

impl Default for CondenseSettings {
    /// Blocks of 64 columns (measured: see docs/PERFORMANCE.md, "Substructuring"), sequential.
    fn default() -> Self {
        Self {
            block: 64,
            threads: 1,
            ordering: FaerOrdering::Auto,
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
    /// Right-hand sides per block used.
    pub block: usize,
    /// max |K_red − K_redᵀ| / max |K_red| before symmetrising (rounding of the solves).
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
fn split(partition: &Partition, constraints: &Constraints) -> Result<Split, SubstructureError> {
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

/// The blocks of K the condensation needs: K_ii (sparse, factorised), K_ib by interface column
/// (interior index, value), K_bb dense row-major.
struct Blocks {
    kii: SymmetricMatrix,
    kib: Vec<Vec<(usize, f64)>>,
    kbb: Vec<f64>,
}

/// Splits the lower-triangle `k` into K_ii, K_ib and K_bb by `class`.
fn blocks(k: &SymmetricMatrix, s: &Split) -> Result<Blocks, SubstructureError> {
    let (ni, nb) = (s.interior.len(), s.boundary.len());
    let (cp, ri) = (k.pattern().col_ptr(), k.pattern().row_idx());
    let mut columns: Vec<Vec<usize>> = vec![Vec::new(); ni];
    let mut kib: Vec<Vec<(usize, f64)>> = vec![Vec::new(); nb];
    let mut kbb = vec![0.0; nb * nb];
    let mut ii = Vec::new();
    for j in 0..k.n() {
        for p in cp[j]..cp[j + 1] {
            let (i, v) = (ri[p], k.values()[p]);
            match (s.class[i], s.class[j]) {
                // Interior numbering follows the linear numbering: i ≥ j stays lower.
                (Class::Interior(a), Class::Interior(b)) => {
                    columns[b].push(a);
                    ii.push((a, b, v));
                }
                (Class::Interior(a), Class::Boundary(b))
                | (Class::Boundary(b), Class::Interior(a)) => {
                    kib[b].push((a, v));
                }
                (Class::Boundary(a), Class::Boundary(b)) => {
                    kbb[a * nb + b] = v;
                    kbb[b * nb + a] = v;
                }
                _ => {}
            }
        }
    }
    let pattern = Arc::new(SymmetricPattern::from_lower_columns(ni, &columns)?);
    // K's columns hold their rows ascending with the diagonal, and the interior numbering
    // follows the linear one, so the values came in the pattern's order (no search per entry);
    // the slow path only if the pattern had to add a diagonal.
    let kii = if pattern.nnz_lower() == ii.len() {
        SymmetricMatrix::from_values(pattern, ii.into_iter().map(|(_, _, v)| v).collect())?
    } else {
        let mut kii = SymmetricMatrix::zeros(pattern);
        for (a, b, v) in ii {
            kii.add(a, b, v)?;
        }
        kii
    };
    Ok(Blocks { kii, kib, kbb })
}

/// Factorises K_ii, naming the full-mesh DOF of a zero pivot.
fn factorise(
    kii: &SymmetricMatrix,
    s: &Split,
    partition: &Partition,
    settings: &CondenseSettings,
) -> Result<(FaerSolver, usize), SubstructureError> {
    let mut solver = FaerSolver::new(FaerMode::Ldlt)
        .with_threads(settings.threads)
        .with_ordering(settings.ordering);
    let analysis = solver.analyze(kii.pattern())?;
    let full = |k: usize| {
        let d = s.interior[k];
        partition.from_linear(d / 3).map_or(d, |v| 3 * v + d % 3)
    };
    match solver.factorize(kii) {
        Ok(f) if f.negative_pivots > 0 => Err(SubstructureError::IndefiniteInterior {
            count: f.negative_pivots,
        }),
        Ok(_) => Ok((solver, analysis.factor_entries)),
        Err(SolverError::ZeroPivot {
            dof,
            pivot,
            diagonal,
            ..
        }) => Err(SubstructureError::SingularInterior {
            dof: full(dof),
            pivot,
            diagonal,
        }),
        Err(e) => Err(e.into()),
    }
}

/// y = K_bi x for one interior vector x (K_bi = K_ibᵀ by interface column).
fn times_kbi(kib: &[Vec<(usize, f64)>], x: &[f64]) -> Vec<f64> {
    kib.iter()
        .map(|col| col.iter().map(|&(i, v)| v * x[i]).sum())
        .collect()
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
    let b = blocks(&k, &s)?;
    let (mut solver, factor_entries) = factorise(&b.kii, &s, partition, settings)?;
    let factored = clock.elapsed().as_secs_f64();
    let (ni, nb) = (s.interior.len(), s.boundary.len());

    // Condensed loads: three right-hand sides f_i per unit λ, −K_ip v, dead − K_ip base.
    let mut kv = vec![0.0; n];
    let mut kbase = vec![0.0; n];
    k.matvec(&s.value, &mut kv)?;
    k.matvec(&s.base, &mut kbase)?;
    let mut rhs = vec![0.0; 3 * ni];
    for (a, &d) in s.interior.iter().enumerate() {
        rhs[a] = s.load[d];
        rhs[ni + a] = -kv[d];
        rhs[2 * ni + a] = s.dead[d] - kbase[d];
    }
    solver.solve_in_place(&mut rhs, 3)?;
    let load = times_kbi(&b.kib, &rhs[..ni]).iter().map(|x| -x).collect();
    let prescribed = times_kbi(&b.kib, &rhs[ni..2 * ni])
        .iter()
        .zip(&s.boundary)
        .map(|(x, &d)| -x - kv[d])
        .collect();
    let dead = times_kbi(&b.kib, &rhs[2 * ni..])
        .iter()
        .zip(&s.boundary)
        .map(|(x, &d)| -x - kbase[d])
        .collect();

    // K_red = K_bb − K_bi (K_ii⁻¹ K_ib), block of columns by block.
    let block = if settings.block == 0 {
        nb.max(1)
    } else {
        settings.block
    };
    let mut kred = b.kbb;
    let mut x = vec![0.0; ni * block.min(nb.max(1))];
    for start in (0..nb).step_by(block) {
        let w = block.min(nb - start);
        let x = &mut x[..ni * w];
        x.fill(0.0);
        for c in 0..w {
            for &(i, v) in &b.kib[start + c] {
                x[c * ni + i] = v;
            }
        }
        solver.solve_in_place(x, w)?;
        for c in 0..w {
            let col = &x[c * ni..(c + 1) * ni];
            for (a, kib) in b.kib.iter().enumerate() {
                let dot: f64 = kib.iter().map(|&(i, v)| v * col[i]).sum();
                kred[a * nb + start + c] -= dot;
            }
        }
    }
    let asymmetry = symmetrise(&mut kred, nb);
    let solved = clock.elapsed().as_secs_f64();
    let report = CondensationReport {
        interface_dofs: nb,
        interior_dofs: ni,
        prescribed_dofs: s.class.len() - ni - nb,
        factor_entries,
        block,
        asymmetry,
        seconds: [assembled, factored - assembled, solved - factored],
    };
    let superelement = Superelement::new(
        partition.interface_dofs_nonlinear(),
        kred,
        crate::CondensedLoad {
            load,
            prescribed,
            dead,
        },
    )?;
    let recovery = Recovery::new(partition, k, s, solver);
    Ok(Condensed {
        superelement,
        recovery,
        report,
    })
}

/// K ← (K + Kᵀ)/2 for a dense row-major n × n `k`; returns max |K − Kᵀ| / max |K| before.
pub(crate) fn symmetrise(k: &mut [f64], n: usize) -> f64 {
    let scale = k.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut worst = 0.0f64;
    for a in 0..n {
        for b in 0..a {
            let (x, y) = (k[a * n + b], k[b * n + a]);
            worst = worst.max((x - y).abs());
            let m = 0.5 * (x + y);
            k[a * n + b] = m;
            k[b * n + a] = m;
        }
    }
    if scale > 0.0 { worst / scale } else { 0.0 }
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

    /// K_red does not depend on the block width (1, 5 and all columns at once): the same
    /// solves in another grouping, equal to rounding.
    #[test]
    fn the_block_width_changes_nothing() {
        let mesh = structured_box(&BoxParams::new(
            ElementKind::Hex8,
            [4, 2, 2],
            [4.0, 2.0, 2.0],
        ))
        .unwrap();
        let p = Partition::from_linear_cells(&mesh, &(0..8).collect::<Vec<_>>()).unwrap();
        let mut c = Constraints::new(3 * mesh.nodes.len());
        for &v in &mesh.node_sets[names::X0] {
            c.prescribe(3 * v, 0.1).unwrap();
        }
        let a = assembler(p.linear_mesh(), Kinematics::Linear);
        let k = |block: usize| {
            let s = CondenseSettings {
                block,
                ..CondenseSettings::default()
            };
            let done = condense(&p, &a, &c, &s).unwrap();
            (
                done.superelement.stiffness().to_vec(),
                done.superelement.load().clone(),
            )
        };
        let (k0, l0) = k(0);
        let scale = k0.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for block in [1, 5] {
            let (kb, lb) = k(block);
            let diff = kb
                .iter()
                .zip(&k0)
                .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
            assert!(diff <= 1e-12 * scale, "block {block}: {diff:e}");
            assert_eq!(lb, l0);
        }
        assert!(l0.prescribed.iter().any(|&x| x != 0.0));
    }
}
