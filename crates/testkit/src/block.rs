//! Structured blocks of n₀ × n₁ × n₂ hexahedra of size h, for tests.
//!
//! A node is keyed by its doubled integer grid coordinates g (corner nodes even, mid-edge nodes
//! of a serendipity element odd in one coordinate), at x = h·g/2, so neighbouring cells share
//! nodes exactly. The element's node order is given by its reference nodes (ξ, η, ζ ∈ {−1, 0, 1})
//! in the order the element numbers them, e.g. `ElementKind::reference_nodes()`.

use std::collections::HashMap;

/// A structured block of hexahedra.
#[derive(Debug, Clone)]
pub struct Block {
    /// Cells along x, y, z.
    pub n: [usize; 3],
    /// Node coordinates.
    pub coords: Vec<[f64; 3]>,
    /// Doubled integer grid coordinates of each node, 0 … 2·n.
    pub grid: Vec<[usize; 3]>,
    /// Node indices of each cell, in the element's order.
    pub cells: Vec<Vec<usize>>,
}

impl Block {
    /// The block of `n` cells of size `h`, each cell's nodes at `reference` (ξ, η, ζ ∈ {−1, 0, 1}),
    /// cells numbered x fastest, then y, then z.
    pub fn new(reference: &[[f64; 3]], n: [usize; 3], h: [f64; 3]) -> Self {
        let mut ids: HashMap<[usize; 3], usize> = HashMap::new();
        let (mut coords, mut grid, mut cells) = (Vec::new(), Vec::new(), Vec::new());
        for k in 0..n[2] {
            for j in 0..n[1] {
                for i in 0..n[0] {
                    let cell = reference
                        .iter()
                        .map(|p| {
                            let at =
                                |c: usize, r: f64| (2 * c as i64 + 1 + r.round() as i64) as usize;
                            let g = [at(i, p[0]), at(j, p[1]), at(k, p[2])];
                            *ids.entry(g).or_insert_with(|| {
                                coords.push([
                                    0.5 * h[0] * g[0] as f64,
                                    0.5 * h[1] * g[1] as f64,
                                    0.5 * h[2] * g[2] as f64,
                                ]);
                                grid.push(g);
                                coords.len() - 1
                            })
                        })
                        .collect();
                    cells.push(cell);
                }
            }
        }
        Self {
            n,
            coords,
            grid,
            cells,
        }
    }

    /// Degrees of freedom, three per node.
    pub fn dofs(&self) -> usize {
        3 * self.coords.len()
    }

    /// The DOFs of each cell, node-major (3·node + direction).
    pub fn cell_dofs(&self) -> Vec<Vec<usize>> {
        self.cells
            .iter()
            .map(|c| {
                c.iter()
                    .flat_map(|&v| [3 * v, 3 * v + 1, 3 * v + 2])
                    .collect()
            })
            .collect()
    }

    /// Nodes on the face where coordinate `axis` is 0.
    pub fn nodes_at_zero(&self, axis: usize) -> Vec<usize> {
        (0..self.coords.len())
            .filter(|&v| self.grid[v][axis] == 0)
            .collect()
    }

    /// Whether node `v` lies on the block's outer boundary.
    pub fn on_boundary(&self, v: usize) -> bool {
        let g = self.grid[v];
        (0..3).any(|r| g[r] == 0 || g[r] == 2 * self.n[r])
    }
}

/// The DOF lists of a box of n₀ × n₁ × n₂ Hex20 cells (8 corners, 12 mid-edges), 3 DOFs a
/// node, for sparsity patterns: the nodes are the points of the doubled grid with at most one
/// odd coordinate, numbered in grid order (x fastest, then y, then z), and each cell lists its
/// 20 nodes in that order too (not the element's numbering: only which DOFs meet counts).
/// Returns the number of DOFs and the lists, cells x fastest.
pub fn hex20_dof_lists([nx, ny, nz]: [usize; 3]) -> (usize, Vec<Vec<usize>>) {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The eight corners, ξ fastest then η then ζ, in the counter-clockwise order of a Hex8.
    fn hex8() -> Vec<[f64; 3]> {
        let ring = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
        [-1.0, 1.0]
            .iter()
            .flat_map(|&z| ring.iter().map(move |&(x, y)| [x, y, z]))
            .collect()
    }

    #[test]
    fn a_block_of_hex8_has_the_node_count_of_its_grid() {
        let b = Block::new(&hex8(), [3, 2, 1], [1.0, 0.5, 0.25]);
        assert_eq!(b.coords.len(), 4 * 3 * 2);
        assert_eq!(b.cells.len(), 6);
        assert_eq!(b.nodes_at_zero(0).len(), 3 * 2);
        assert_eq!(b.coords[b.cells[5][6]], [3.0, 1.0, 0.25]);
        assert!(b.on_boundary(0));
        assert_eq!(b.cell_dofs()[0][..3], [0, 1, 2]);
    }

    /// A Hex20 box has a node at every corner and edge middle of its grid, 20 in each cell,
    /// and cells side by side share the 8 nodes of their common face.
    #[test]
    fn a_hex20_box_lists_corners_and_mid_edges() {
        let [nx, ny, nz] = [3, 2, 1];
        let (n, lists) = hex20_dof_lists([nx, ny, nz]);
        let corners = (nx + 1) * (ny + 1) * (nz + 1);
        let edges = nx * (ny + 1) * (nz + 1) + (nx + 1) * ny * (nz + 1) + (nx + 1) * (ny + 1) * nz;
        assert_eq!(n, 3 * (corners + edges));
        assert_eq!(lists.len(), nx * ny * nz);
        assert!(lists.iter().all(|l| l.len() == 60));
        let shared = lists[0].iter().filter(|d| lists[1].contains(d)).count();
        assert_eq!(shared, 3 * 8);
        let mut all: Vec<usize> = lists.concat();
        all.sort_unstable();
        all.dedup();
        assert_eq!(all, (0..n).collect::<Vec<_>>());
    }
}
