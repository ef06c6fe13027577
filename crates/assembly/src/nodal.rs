//! Strains and stresses at the nodes, for output (thesis §2.1): the kernels' Green–Lagrange
//! strains E and second Piola–Kirchhoff stresses S = C E at the integration points, the Cauchy
//! stresses σ = F S Fᵀ / det F there (F = I + ∂u/∂X), each extrapolated to the cell's nodes and
//! averaged per material region; and the internal nodal forces R = Σ_e ∫ Bᵀ S dV (eq. 2.3.1),
//! the reactions at constrained DOFs.
//!
//! Extrapolation: a least-squares fit over the stations of the richest polynomial space they
//! determine — the Hex20's 20 serendipity functions from the 27 points of the 3×3×3 rule, the
//! Hex8's 8 trilinear functions from 8 or 9 points (an exact inverse on the 2×2×2 rule, the
//! usual Abaqus/CalculiX extrapolation), a constant from one — evaluated at the nodes. Every
//! such space holds the linear functions of ξ, so a field linear in ξ (linear in x for an
//! affine cell) comes back exactly. A component not integrated at a station (the
//! selective-reduced Hex8 rule's shears off the centroid) takes there the mean over the
//! stations that integrate it.
//!
//! Regions: cells of the same material index and ply angle. A node shared by cells of several
//! regions becomes one output point per region (the [`NodalFields::mesh`] is split along
//! material interfaces), each with the mean of its own region's cells: fields are continuous
//! within a region and keep the jump across an interface that the physics has (σ_xx between
//! a 0° and a 90° ply).

use crate::AssemblyError;
use crate::stresses::{StressRules, cauchy, cell_material, deformation_gradient};
use nonlin3d_element::{
    ElementKind, ElementOutput, IntegrationRule, Kinematics, Material, ShapeTable, Workspace,
    evaluate,
};
use nonlin3d_mesh::Mesh;
use std::collections::BTreeMap;

/// Nodal fields of one state, on the mesh split along material regions.
#[derive(Debug, Clone)]
pub struct NodalFields {
    /// The mesh with one point per (node, region) pair; cells in the same order, node sets
    /// dropped.
    pub mesh: Mesh,
    /// The original node of each point.
    pub point_node: Vec<usize>,
    /// Green–Lagrange strain per point (linear strain for linear kinematics), tensor
    /// components xx, yy, zz, xy, yz, xz (shears ½γ).
    pub strain: Vec<[f64; 6]>,
    /// Second Piola–Kirchhoff stress per point, same order.
    pub pk2: Vec<[f64; 6]>,
    /// Cauchy stress per point (= `pk2` for linear kinematics), same order.
    pub cauchy: Vec<[f64; 6]>,
    /// Per cell, the mean over its stations of strain, S and σ.
    pub cell_strain: Vec<[f64; 6]>,
    /// Per cell, mean S.
    pub cell_pk2: Vec<[f64; 6]>,
    /// Per cell, mean σ.
    pub cell_cauchy: Vec<[f64; 6]>,
    /// Internal nodal forces per original node (x, y, z): the reaction at constrained DOFs,
    /// the applied load at loaded ones, ≈ 0 elsewhere (CalculiX's RF).
    pub forces: Vec<[f64; 3]>,
}

/// The extrapolation matrix of a cell kind and rule: row a gives node a's value as
/// Σ_g E_ag v_g over the stations g.
pub fn extrapolation(kind: ElementKind, rule: IntegrationRule) -> Vec<Vec<f64>> {
    let stations = rule.stations();
    let m = stations.len();
    let basis = |xi: [f64; 3], out: &mut Vec<f64>| {
        out.clear();
        if m >= 20 && kind == ElementKind::Hex20 {
            out.resize(20, 0.0);
            ElementKind::Hex20.shape_values(xi, out);
        } else if m >= 8 {
            out.resize(8, 0.0);
            ElementKind::Hex8.shape_values(xi, out);
        } else {
            out.push(1.0);
        }
    };
    let mut row = Vec::new();
    let a: Vec<Vec<f64>> = stations
        .iter()
        .map(|s| {
            basis(s.xi, &mut row);
            row.clone()
        })
        .collect();
    let p = a[0].len();
    // Normal equations (AᵀA) c = Aᵀ v: the fit's coefficients c = (AᵀA)⁻¹ Aᵀ v.
    let mut ata = vec![vec![0.0; p]; p];
    for r in &a {
        for i in 0..p {
            for j in 0..p {
                ata[i][j] += r[i] * r[j];
            }
        }
    }
    let inv = invert(ata);
    // P = (AᵀA)⁻¹ Aᵀ, p × m.
    let proj: Vec<Vec<f64>> = (0..p)
        .map(|i| {
            (0..m)
                .map(|g| (0..p).map(|k| inv[i][k] * a[g][k]).sum())
                .collect()
        })
        .collect();
    kind.reference_nodes()
        .iter()
        .map(|&xi| {
            basis(xi, &mut row);
            (0..m)
                .map(|g| (0..p).map(|i| row[i] * proj[i][g]).sum())
                .collect()
        })
        .collect()
}

/// Inverse of a small symmetric positive definite matrix by Gauss–Jordan with partial pivoting.
fn invert(mut a: Vec<Vec<f64>>) -> Vec<Vec<f64>> {
    let n = a.len();
    let mut inv: Vec<Vec<f64>> = (0..n)
        .map(|i| (0..n).map(|j| if i == j { 1.0 } else { 0.0 }).collect())
        .collect();
    for c in 0..n {
        let piv = (c..n)
            .max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs()))
            .unwrap_or(c);
        a.swap(c, piv);
        inv.swap(c, piv);
        let d = a[c][c];
        for j in 0..n {
            a[c][j] /= d;
            inv[c][j] /= d;
        }
        for r in 0..n {
            if r != c {
                let f = a[r][c];
                if f != 0.0 {
                    for j in 0..n {
                        a[r][j] -= f * a[c][j];
                        inv[r][j] -= f * inv[c][j];
                    }
                }
            }
        }
    }
    inv
}

/// Fills the components a station does not integrate with their mean over the stations that
/// do.
fn complete(values: &mut [[f64; 6]], table: &ShapeTable) {
    let st = table.stations();
    for i in 0..6 {
        let (mut sum, mut count) = (0.0, 0usize);
        for (v, s) in values.iter().zip(st) {
            if (s.first..s.last).contains(&i) {
                sum += v[i];
                count += 1;
            }
        }
        let mean = if count > 0 { sum / count as f64 } else { 0.0 };
        for (v, s) in values.iter_mut().zip(st) {
            if !(s.first..s.last).contains(&i) {
                v[i] = mean;
            }
        }
    }
}

struct KindData {
    kind: ElementKind,
    table: ShapeTable,
    ws: Workspace,
    eo: ElementOutput,
    extrapolate: Vec<Vec<f64>>,
}

/// Strains, stresses and internal forces of state `u` (three displacements per node) at the
/// nodes of `mesh`, extrapolated and averaged per region as the module says.
pub fn nodal_fields<M: Copy + Into<Material>>(
    mesh: &Mesh,
    rules: &StressRules<'_, M>,
    u: &[f64],
) -> Result<NodalFields, AssemblyError> {
    if u.len() != 3 * mesh.nodes.len() {
        return Err(AssemblyError::Length {
            what: "displacements",
            expected: 3 * mesh.nodes.len(),
            got: u.len(),
        });
    }
    // Points: one per (node, region), numbered in node order.
    let mut regions: BTreeMap<(usize, u64), usize> = BTreeMap::new();
    let region_of: Vec<usize> = mesh
        .cells
        .iter()
        .map(|c| {
            let next = regions.len();
            *regions
                .entry((c.material, c.ply_angle_deg.to_bits()))
                .or_insert(next)
        })
        .collect();
    let mut pairs: BTreeMap<(usize, usize), usize> = BTreeMap::new();
    for (c, cell) in mesh.cells.iter().enumerate() {
        for &n in &cell.nodes {
            pairs.insert((n, region_of[c]), 0);
        }
    }
    let mut point_node = Vec::with_capacity(pairs.len());
    for (k, ((n, _), p)) in pairs.iter_mut().enumerate() {
        *p = k;
        point_node.push(*n);
    }
    let np = point_node.len();
    let mut split = Mesh {
        nodes: point_node.iter().map(|&n| mesh.nodes[n]).collect(),
        cells: mesh.cells.clone(),
        ..Mesh::default()
    };
    for (c, cell) in split.cells.iter_mut().enumerate() {
        for n in cell.nodes.iter_mut() {
            *n = pairs[&(*n, region_of[c])];
        }
    }
    // Summed into: zeroed by writing (`crate::zeroed_by_writing`).
    let mut sums: [Vec<[f64; 6]>; 3] = std::array::from_fn(|_| crate::zeroed_by_writing(np));
    let mut count: Vec<usize> = crate::zeroed_by_writing(np);
    let mut cell_means = [
        Vec::with_capacity(mesh.cells.len()),
        Vec::with_capacity(mesh.cells.len()),
        Vec::with_capacity(mesh.cells.len()),
    ];
    let mut forces: Vec<[f64; 3]> = crate::zeroed_by_writing(mesh.nodes.len());
    let mut kinds: Vec<KindData> = Vec::new();
    for (c, cell) in mesh.cells.iter().enumerate() {
        let material = cell_material(mesh, rules, c)?;
        let k = match kinds.iter().position(|t| t.kind == cell.kind) {
            Some(k) => k,
            None => {
                let rule = match cell.kind {
                    ElementKind::Hex20 => rules.hex20_rule,
                    ElementKind::Hex8 => rules.hex8_rule,
                };
                let table = ShapeTable::new(cell.kind, rule)?;
                kinds.push(KindData {
                    kind: cell.kind,
                    ws: Workspace::new(&table),
                    eo: ElementOutput::new(&table),
                    extrapolate: extrapolation(cell.kind, rule),
                    table,
                });
                kinds.len() - 1
            }
        };
        let KindData {
            table,
            ws,
            eo,
            extrapolate,
            ..
        } = &mut kinds[k];
        let x = mesh.cell_coordinates(c);
        let d = mesh.cell_displacements(c, u);
        evaluate(table, &x, &d, &material, rules.kinematics, false, ws, eo)
            .map_err(|e| e.at_element(c))?;
        for (a, &n) in cell.nodes.iter().enumerate() {
            for r in 0..3 {
                forces[n][r] += eo.forces[3 * a + r];
            }
        }
        let mut strain: Vec<[f64; 6]> = eo
            .strains
            .iter()
            .map(|e| [e[0], e[1], e[2], 0.5 * e[3], 0.5 * e[4], 0.5 * e[5]])
            .collect();
        let mut pk2 = eo.stresses.clone();
        complete(&mut strain, table);
        complete(&mut pk2, table);
        let sigma: Vec<[f64; 6]> = match rules.kinematics {
            Kinematics::Linear => pk2.clone(),
            Kinematics::Nonlinear => pk2
                .iter()
                .enumerate()
                .map(|(g, s)| cauchy(s, &deformation_gradient(table, g, &x, &d)))
                .collect(),
        };
        for (f, station) in [&strain, &pk2, &sigma].into_iter().enumerate() {
            let mut mean = [0.0; 6];
            for v in station {
                for i in 0..6 {
                    mean[i] += v[i] / station.len() as f64;
                }
            }
            cell_means[f].push(mean);
            for (a, row) in extrapolate.iter().enumerate() {
                let p = split.cells[c].nodes[a];
                for (w, v) in row.iter().zip(station) {
                    for i in 0..6 {
                        sums[f][p][i] += w * v[i];
                    }
                }
            }
        }
        for &p in &split.cells[c].nodes {
            count[p] += 1;
        }
    }
    for f in sums.iter_mut() {
        for (v, &n) in f.iter_mut().zip(&count) {
            for x in v.iter_mut() {
                *x /= n.max(1) as f64;
            }
        }
    }
    let [strain, pk2, cauchy] = sums;
    let [cell_strain, cell_pk2, cell_cauchy] = cell_means;
    Ok(NodalFields {
        mesh: split,
        point_node,
        strain,
        pk2,
        cauchy,
        cell_strain,
        cell_pk2,
        cell_cauchy,
        forces,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use nonlin3d_laminate::{ShearCoupling, materials};
    use nonlin3d_mesh::{BoxParams, structured_box};

    /// Every (kind, rule) pair reproduces a field linear in ξ at the nodes to round-off (the
    /// fitted spaces hold the linear functions; the matrices are products of ≤ 27-term sums of
    /// O(1) numbers, so 1e-12 is a thousand times the round-off), and the 3×3×3 fit of the
    /// Hex20 also reproduces a quadratic of its serendipity space.
    #[test]
    fn extrapolation_reproduces_linear_fields() {
        let f = |x: [f64; 3]| 1.5 - 2.0 * x[0] + 0.25 * x[1] + 3.0 * x[2];
        for (kind, rule) in [
            (ElementKind::Hex20, IntegrationRule::Gauss3),
            (ElementKind::Hex20, IntegrationRule::Gauss2),
            (ElementKind::Hex8, IntegrationRule::Gauss2),
            (ElementKind::Hex8, IntegrationRule::SelectiveReduced),
        ] {
            let e = extrapolation(kind, rule);
            let v: Vec<f64> = rule.stations().iter().map(|s| f(s.xi)).collect();
            for (row, &xi) in e.iter().zip(kind.reference_nodes()) {
                let got: f64 = row.iter().zip(&v).map(|(w, v)| w * v).sum();
                assert!(
                    (got - f(xi)).abs() < 1e-12,
                    "{kind:?} {rule:?}: {got} vs {}",
                    f(xi)
                );
            }
        }
        let q = |x: [f64; 3]| x[0] * x[0] - 0.5 * x[1] * x[2] + x[0] * x[1] * x[2];
        let rule = IntegrationRule::Gauss3;
        let e = extrapolation(ElementKind::Hex20, rule);
        let v: Vec<f64> = rule.stations().iter().map(|s| q(s.xi)).collect();
        for (row, &xi) in e.iter().zip(ElementKind::Hex20.reference_nodes()) {
            let got: f64 = row.iter().zip(&v).map(|(w, v)| w * v).sum();
            assert!((got - q(xi)).abs() < 1e-12);
        }
    }

    /// Two regions (materials 0 and 1 side by side along x) under u = e·x: the interface nodes
    /// become two points each, each with its own material's stress C_r E; forces sum to zero
    /// (a self-equilibrated element set: Σ_a R_a = ∫ ∇·… = 0 to round-off).
    #[test]
    fn regions_split_the_interface() {
        let mut mesh = structured_box(&BoxParams::new(
            ElementKind::Hex20,
            [2, 1, 1],
            [2.0, 1.0, 1.0],
        ))
        .unwrap();
        mesh.cells[1].material = 1;
        let steel = materials::steel().stiffness().unwrap();
        let soft =
            nonlin3d_laminate::Stiffness::new(steel.c().map(|r| r.map(|v| 0.5 * v))).unwrap();
        let e = 1e-3;
        let u: Vec<f64> = mesh
            .nodes
            .iter()
            .flat_map(|p| [e * p[0], 0.0, 0.0])
            .collect();
        let rules = StressRules {
            materials: &[steel, soft],
            coupling: ShearCoupling::Exact,
            hex20_rule: IntegrationRule::Gauss3,
            hex8_rule: IntegrationRule::Gauss2,
            kinematics: Kinematics::Linear,
        };
        let f = nodal_fields(&mesh, &rules, &u).unwrap();
        // 3 × 2 × 2 corner columns … the interface x = 1 has 8 nodes (4 corners, 4 mid-edge).
        assert_eq!(f.point_node.len(), mesh.nodes.len() + 8);
        let s_steel = steel.stress(&[e, 0.0, 0.0, 0.0, 0.0, 0.0]);
        for (c, cell) in f.mesh.cells.iter().enumerate() {
            let scale = if c == 0 { 1.0 } else { 0.5 };
            for &p in &cell.nodes {
                for i in 0..6 {
                    assert!(
                        (f.pk2[p][i] - scale * s_steel[i]).abs() < 1e-9 * s_steel[0],
                        "{c} {p} {i}"
                    );
                }
                assert!((f.strain[p][0] - e).abs() < 1e-15);
            }
        }
        for r in 0..3 {
            let sum: f64 = f.forces.iter().map(|v| v[r]).sum();
            assert!(sum.abs() < 1e-9 * s_steel[0]);
        }
    }
}
