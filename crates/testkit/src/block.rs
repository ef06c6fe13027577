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
}
