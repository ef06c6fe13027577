//! Node pairs of the crack faces, the contact normal from the deformed lower face, and the gap
//! (thesis §2.7, Fig. 2.7.1): pure functions of coordinates and displacements.
//!
//! - pair i = (upper node, lower node), from the two paired node sets;
//! - lower-face facets: the faces of the cells below the crack whose nodes all lie on the lower
//!   face or on its rim (nodes the cells of both faces share: the front);
//! - n_i = the normalised mean of the unit outward normals of the lower-face facets around the
//!   lower node, each from the deformed corners x = X + u (the diagonals' cross product);
//! - g_i = n_i·(x_up − x_low): positive open, negative overlapping.

use crate::ContactError;
use crate::facet::{Basis, Facet, dot, sub};
use crate::facet::{cross, unit};
use nonlin3d_mesh::Mesh;
use nonlin3d_mesh::names::{CRACK_LOWER, CRACK_UPPER};
use std::collections::HashSet;

/// A candidate contact pair: a node of the upper crack face (the sublaminate's underside) and
/// its partner on the lower face (the base's top).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Pair {
    /// Upper-face node.
    pub upper: usize,
    /// Lower-face node.
    pub lower: usize,
}

impl std::fmt::Display for Pair {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "nodes {}/{}", self.upper, self.lower)
    }
}

/// The crack faces of a mesh: the pairs and the lower face's facets around each pair.
#[derive(Debug, Clone, PartialEq)]
pub struct CrackFaces {
    pairs: Vec<Pair>,
    facets: Vec<Facet>,
    /// Facets around each pair's lower node.
    around: Vec<Vec<usize>>,
    /// The pairs whose lower nodes share a facet with each pair's (itself included, sorted).
    near: Vec<Vec<usize>>,
    /// Reference coordinates (m).
    coords: Vec<[f64; 3]>,
    /// The transformed basis of each pair's lower node ([`recover`](Self::recover)).
    pub(crate) basis: Vec<Basis>,
}

impl CrackFaces {
    /// The pairs of the mesh's `crack_upper` and `crack_lower` node sets (paired by index).
    pub fn from_mesh(mesh: &Mesh) -> Result<Self, ContactError> {
        let set = |name: &'static str| {
            mesh.node_sets
                .get(name)
                .ok_or(ContactError::MissingSet { name })
        };
        Self::from_sets(mesh, set(CRACK_UPPER)?, set(CRACK_LOWER)?)
    }

    /// The pairs (`upper[i]`, `lower[i]`) of a mesh; the lower face's facets are derived from its
    /// cells. Errors: lists of different lengths, a node out of range or in both lists, a
    /// lower node on no facet.
    pub fn from_sets(mesh: &Mesh, upper: &[usize], lower: &[usize]) -> Result<Self, ContactError> {
        if upper.len() != lower.len() {
            return Err(ContactError::Pairing {
                upper: upper.len(),
                lower: lower.len(),
            });
        }
        let count = mesh.nodes.len();
        let up: HashSet<usize> = upper.iter().copied().collect();
        let lo: HashSet<usize> = lower.iter().copied().collect();
        if let Some(&node) = upper.iter().chain(lower).find(|&&v| v >= count) {
            return Err(ContactError::Node {
                node,
                reason: format!("out of range ({count} nodes)"),
            });
        }
        if let Some(&node) = upper.iter().find(|v| lo.contains(v)) {
            return Err(ContactError::Node {
                node,
                reason: "on both crack faces".into(),
            });
        }
        let facets = lower_facets(mesh, &up, &lo);
        let pairs: Vec<Pair> = upper
            .iter()
            .zip(lower)
            .map(|(&upper, &lower)| Pair { upper, lower })
            .collect();
        let mut around = vec![Vec::new(); pairs.len()];
        let mut index = vec![usize::MAX; count];
        for (i, p) in pairs.iter().enumerate() {
            index[p.lower] = i;
        }
        let mut near: Vec<Vec<usize>> = (0..pairs.len()).map(|i| vec![i]).collect();
        for (f, (_, nodes)) in facets.iter().enumerate() {
            let on: Vec<usize> = nodes
                .iter()
                .map(|&v| index[v])
                .filter(|&i| i < pairs.len())
                .collect();
            for &i in &on {
                around[i].push(f);
                near[i].extend_from_slice(&on);
            }
        }
        for list in &mut near {
            list.sort_unstable();
            list.dedup();
        }
        if let Some(i) = around.iter().position(Vec::is_empty) {
            return Err(ContactError::Node {
                node: pairs[i].lower,
                reason: "on the lower crack face but on no face of a cell below it".into(),
            });
        }
        let facets: Vec<Facet> = facets.into_iter().map(|(f, _)| f).collect();
        let basis = crate::recover::bases(&facets, &index, &mesh.nodes, pairs.len());
        Ok(Self {
            pairs,
            facets,
            around,
            near,
            coords: mesh.nodes.clone(),
            basis,
        })
    }

    /// The pairs, in the order of the node sets.
    pub fn pairs(&self) -> &[Pair] {
        &self.pairs
    }

    /// Number of pairs.
    pub fn len(&self) -> usize {
        self.pairs.len()
    }

    /// Whether there is no pair.
    pub fn is_empty(&self) -> bool {
        self.pairs.is_empty()
    }

    /// The pairs whose lower nodes lie on a lower-face facet with pair `i`'s (`i` included,
    /// in increasing order): one ring of neighbours.
    pub fn near(&self, i: usize) -> &[usize] {
        &self.near[i]
    }

    /// The pairs within `rings` rings of neighbours ([`near`](Self::near)) of the pairs
    /// flagged in `seeds` (the seeds included: `rings` = 0 gives them back).
    pub fn within(&self, seeds: &[bool], rings: usize) -> Vec<bool> {
        let mut out = seeds.to_vec();
        let mut front: Vec<usize> = (0..seeds.len()).filter(|&i| seeds[i]).collect();
        for _ in 0..rings {
            let mut next = Vec::new();
            for &i in &front {
                for &j in &self.near[i] {
                    if !out[j] {
                        out[j] = true;
                        next.push(j);
                    }
                }
            }
            front = next;
        }
        out
    }

    /// Number of lower-face facets.
    pub fn facet_count(&self) -> usize {
        self.facets.len()
    }

    /// The deformed position X + u of node `v`.
    fn at(&self, u: &[f64], v: usize) -> [f64; 3] {
        let x = self.coords[v];
        [x[0] + u[3 * v], x[1] + u[3 * v + 1], x[2] + u[3 * v + 2]]
    }

    /// The contact normal of each pair at displacements `u`: the normalised mean of the unit
    /// outward normals of the deformed lower-face facets around its lower node. Errors: `u`
    /// of the wrong length, a degenerate (zero-area or folded) neighbourhood.
    pub fn normals(&self, u: &[f64]) -> Result<Vec<[f64; 3]>, ContactError> {
        if u.len() != 3 * self.coords.len() {
            return Err(ContactError::Length {
                what: "displacements",
                expected: 3 * self.coords.len(),
                got: u.len(),
            });
        }
        let facet_normals: Vec<Option<[f64; 3]>> = self
            .facets
            .iter()
            .map(|f| self.facet_normal(f, u))
            .collect();
        let mut out = Vec::with_capacity(self.pairs.len());
        for (p, list) in self.pairs.iter().zip(&self.around) {
            let mut n = [0.0; 3];
            for &f in list {
                let Some(m) = facet_normals[f] else {
                    return Err(degenerate(p.lower));
                };
                for k in 0..3 {
                    n[k] += m[k];
                }
            }
            out.push(unit(n).ok_or_else(|| degenerate(p.lower))?);
        }
        Ok(out)
    }

    /// The unit outward normal of a deformed facet: (x₂ − x₀) × (x₃ − x₁), turned away from
    /// its cell's centroid; None if degenerate or not finite.
    fn facet_normal(&self, f: &Facet, u: &[f64]) -> Option<[f64; 3]> {
        let x = f.corners.map(|v| self.at(u, v));
        let d1 = sub(x[2], x[0]);
        let d2 = sub(x[3], x[1]);
        let mut n = cross(d1, d2);
        let mut centre = [0.0; 3];
        for &v in &f.cell {
            let y = self.at(u, v);
            for k in 0..3 {
                centre[k] += y[k] / f.cell.len() as f64;
            }
        }
        let mid = [0, 1, 2].map(|k| x.iter().map(|c| c[k]).sum::<f64>() / 4.0);
        if dot(n, sub(mid, centre)) < 0.0 {
            n = n.map(|c| -c);
        }
        unit(n)
    }

    /// The gap of each pair, g = n·(X_up + u_up − X_low − u_low) (m), with `normals` from
    /// [`normals`](Self::normals).
    pub fn gaps(&self, u: &[f64], normals: &[[f64; 3]]) -> Vec<f64> {
        self.pairs
            .iter()
            .zip(normals)
            .map(|(p, &n)| dot(n, sub(self.at(u, p.upper), self.at(u, p.lower))))
            .collect()
    }

    /// The initial gap of each pair along `normals`: g₀ = n·(X_up − X_low) (0 for coincident
    /// nodes).
    pub fn initial_gaps(&self, normals: &[[f64; 3]]) -> Vec<f64> {
        self.pairs
            .iter()
            .zip(normals)
            .map(|(p, &n)| dot(n, sub(self.coords[p.upper], self.coords[p.lower])))
            .collect()
    }

    /// The recovered nodal contact forces f̂ = T f (N, `recover`): ∫N̂_i p dA for a pressure p,
    /// positive at every node of a compressed face, linear or quadratic; the release test's
    /// quantity. `forces`: the nodal contact forces, one per pair.
    pub fn recovered(&self, forces: &[f64]) -> Vec<f64> {
        crate::recover::transformed(&self.basis, forces)
    }

    /// The gaps in the basis of the recovered forces, g̃ = T⁻ᵀ g (m, `active`): f̂·g̃ = f·g,
    /// g̃ = g at corners and on linear faces, (g_m − α Σ_ends g_c)/(1 − 2α) at mid-edge
    /// pairs; the closing test's quantity. `gaps`: the gaps g, one per pair.
    pub fn weighted_gaps(&self, gaps: &[f64]) -> Vec<f64> {
        crate::recover::weighted_gaps(&self.basis, gaps)
    }

    /// The pairs at the ends of pair `i`'s edge when its lower node is a mid-edge node of a
    /// quadratic face (empty otherwise): the pairs its weighted gap g̃ reads.
    pub fn ends(&self, i: usize) -> &[usize] {
        self.basis.get(i).map_or(&[], |b| b.ends.as_slice())
    }

    /// The contact pressure p̂_i = f̂_i / ∫N̂_i dA at each pair (Pa, compressive positive; the
    /// reference face's area) from the nodal contact forces `forces` (N): exact for a uniform
    /// pressure at every node.
    pub fn pressures(&self, forces: &[f64]) -> Vec<f64> {
        self.recovered(forces)
            .iter()
            .zip(&self.basis)
            .map(|(f, b)| f / b.weight)
            .collect()
    }

    /// The reference coordinates of node `v` (m).
    pub fn position(&self, v: usize) -> [f64; 3] {
        self.coords[v]
    }
}

fn degenerate(node: usize) -> ContactError {
    ContactError::Node {
        node,
        reason: "the deformed lower face around it has no normal (zero area or folded)".into(),
    }
}

/// The faces of cells that lie on the lower crack face: every node of the face on the lower
/// face or on its rim (nodes shared by a cell holding an upper-face node and a cell holding a
/// lower-face node, not themselves on either face: the front), at least one on the lower
/// face. Each with its cyclic corners, its cell's corners, and all its nodes.
fn lower_facets(mesh: &Mesh, up: &HashSet<usize>, lo: &HashSet<usize>) -> Vec<(Facet, Vec<usize>)> {
    let touching = |set: &HashSet<usize>| -> HashSet<usize> {
        mesh.cells
            .iter()
            .filter(|c| c.nodes.iter().any(|v| set.contains(v)))
            .flat_map(|c| c.nodes.iter().copied())
            .collect()
    };
    let above = touching(up);
    let rim: HashSet<usize> = touching(lo)
        .into_iter()
        .filter(|v| above.contains(v) && !up.contains(v) && !lo.contains(v))
        .collect();
    let mut out = Vec::new();
    for cell in &mesh.cells {
        if !cell.nodes.iter().any(|v| lo.contains(v)) || cell.nodes.iter().any(|v| up.contains(v)) {
            continue;
        }
        let reference = cell.kind.reference_nodes();
        for axis in 0..3 {
            for side in [-1.0, 1.0] {
                let on: Vec<usize> = (0..reference.len().min(cell.nodes.len()))
                    .filter(|&i| reference[i][axis] == side)
                    .collect();
                let nodes: Vec<usize> = on.iter().map(|&i| cell.nodes[i]).collect();
                let fits = nodes.iter().all(|v| lo.contains(v) || rim.contains(v));
                if !fits || !nodes.iter().any(|v| lo.contains(v)) {
                    continue;
                }
                // Corners in cyclic order over the two in-face axes: (−,−), (+,−), (+,+), (−,+).
                let (p, q) = ((axis + 1) % 3, (axis + 2) % 3);
                let corner = |a: f64, b: f64| {
                    on.iter()
                        .find(|&&i| i < 8 && reference[i][p] == a && reference[i][q] == b)
                        .map(|&i| cell.nodes[i])
                };
                let cyclic = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
                let corners: Option<Vec<usize>> =
                    cyclic.iter().map(|&(a, b)| corner(a, b)).collect();
                // A mid-edge node (reference index ≥ 8) has one in-face coordinate 0: its
                // corners are the two with the other coordinate equal to its own.
                let mids = on
                    .iter()
                    .filter(|&&i| i >= 8)
                    .filter_map(|&i| {
                        let (a, b) = (reference[i][p], reference[i][q]);
                        let ends = if a == 0.0 {
                            [corner(-1.0, b)?, corner(1.0, b)?]
                        } else {
                            [corner(a, -1.0)?, corner(a, 1.0)?]
                        };
                        Some((cell.nodes[i], ends))
                    })
                    .collect();
                if let Some(c) = corners {
                    out.push((
                        Facet {
                            corners: [c[0], c[1], c[2], c[3]],
                            cell: cell.nodes[..8.min(cell.nodes.len())].to_vec(),
                            mids,
                        },
                        nodes,
                    ));
                }
            }
        }
    }
    out
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use nonlin3d_element::ElementKind;
    use nonlin3d_mesh::Cell;

    /// Two unit Hex8 cubes, one on the other, with separate nodes on z = 1: the lower cube's top
    /// is the lower face, the upper cube's bottom the upper face, paired by position.
    pub(crate) fn stacked() -> (Mesh, Vec<usize>, Vec<usize>) {
        let mut nodes = Vec::new();
        for z in [0.0, 1.0, 1.0, 2.0] {
            for (x, y) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
                nodes.push([x, y, z]);
            }
        }
        let cell = |first: usize, second: usize| Cell {
            kind: ElementKind::Hex8,
            nodes: (first..first + 4).chain(second..second + 4).collect(),
            material: 0,
            ply_angle_deg: 0.0,
        };
        let mesh = Mesh {
            nodes,
            cells: vec![cell(0, 4), cell(8, 12)],
            ..Mesh::default()
        };
        (mesh, (8..12).collect(), (4..8).collect())
    }

    /// Undeformed: one facet, normal +z (outward from the lower cube), zero gaps; lifting the
    /// upper face by d opens every gap by d; tilting the lower face about x by a small angle θ
    /// (w = θ·y on its nodes) turns the normal to (0, −sin θ, cos θ).
    #[test]
    fn normals_follow_the_deformed_lower_face() {
        let (mesh, up, lo) = stacked();
        let faces = CrackFaces::from_sets(&mesh, &up, &lo).unwrap();
        assert_eq!((faces.len(), faces.facet_count()), (4, 1));
        let mut u = vec![0.0; 3 * mesh.nodes.len()];
        let n = faces.normals(&u).unwrap();
        assert!(n.iter().all(|n| *n == [0.0, 0.0, 1.0]));
        assert!(faces.gaps(&u, &n).iter().all(|&g| g == 0.0));
        for &v in &up {
            u[3 * v + 2] = 1e-3;
        }
        for g in faces.gaps(&u, &n) {
            assert_relative_eq!(g, 1e-3, max_relative = 1e-12);
        }
        let theta: f64 = 0.01;
        let mut u = vec![0.0; 3 * mesh.nodes.len()];
        for &v in &lo {
            let [_, y, z] = mesh.nodes[v];
            // A rigid rotation about the x axis through (·, 0, 1).
            u[3 * v + 1] = y * (theta.cos() - 1.0) - (z - 1.0) * theta.sin();
            u[3 * v + 2] = y * theta.sin() + (z - 1.0) * (theta.cos() - 1.0);
        }
        for n in faces.normals(&u).unwrap() {
            assert_relative_eq!(n[1], -theta.sin(), epsilon = 1e-14);
            assert_relative_eq!(n[2], theta.cos(), epsilon = 1e-14);
        }
    }

    /// Lists of different lengths, a node on both faces, and a lower node on no facet are
    /// refused by name.
    #[test]
    fn bad_pairings_are_refused() {
        let (mesh, up, lo) = stacked();
        let e = CrackFaces::from_sets(&mesh, &up[..3], &lo).unwrap_err();
        assert!(
            matches!(e, ContactError::Pairing { upper: 3, lower: 4 }),
            "{e}"
        );
        let e = CrackFaces::from_sets(&mesh, &[4], &[4]).unwrap_err();
        assert!(matches!(e, ContactError::Node { node: 4, .. }), "{e}");
        // Node 0 (bottom of the lower cube) is on no face between the two.
        let e = CrackFaces::from_sets(&mesh, &[8], &[0]).unwrap_err();
        assert!(matches!(e, ContactError::Node { node: 0, .. }), "{e}");
        assert!(matches!(
            CrackFaces::from_mesh(&mesh),
            Err(ContactError::MissingSet { .. })
        ));
    }
}
