//! Helpers shared by the element integration tests: structured blocks and dense assembly.
#![allow(dead_code)]

use nonlin3d_element::{ElementKind, ElementOutput, Kinematics, ShapeTable, Workspace, evaluate};
use nonlin3d_laminate::Stiffness;
use std::collections::HashMap;

/// A structured block of nx×ny×nz elements of size h, nodes keyed by doubled integer grid
/// coordinates (so Hex20 mid-edge nodes have an odd coordinate).
pub struct Block {
    pub kind: ElementKind,
    pub coords: Vec<[f64; 3]>,
    pub grid: Vec<[i64; 3]>,
    pub cells: Vec<Vec<usize>>,
    pub n: [i64; 3],
}

pub fn block(kind: ElementKind, n: [i64; 3], h: [f64; 3]) -> Block {
    let mut ids: HashMap<[i64; 3], usize> = HashMap::new();
    let mut coords = Vec::new();
    let mut grid = Vec::new();
    let mut cells = Vec::new();
    for k in 0..n[2] {
        for j in 0..n[1] {
            for i in 0..n[0] {
                let mut cell = Vec::new();
                for p in kind.reference_nodes() {
                    let g = [
                        2 * i + 1 + p[0] as i64,
                        2 * j + 1 + p[1] as i64,
                        2 * k + 1 + p[2] as i64,
                    ];
                    let id = *ids.entry(g).or_insert_with(|| {
                        coords.push([
                            0.5 * h[0] * g[0] as f64,
                            0.5 * h[1] * g[1] as f64,
                            0.5 * h[2] * g[2] as f64,
                        ]);
                        grid.push(g);
                        coords.len() - 1
                    });
                    cell.push(id);
                }
                cells.push(cell);
            }
        }
    }
    Block {
        kind,
        coords,
        grid,
        cells,
        n,
    }
}

impl Block {
    /// Whether node `i` lies on the outer boundary of the block.
    pub fn on_boundary(&self, i: usize) -> bool {
        let g = self.grid[i];
        (0..3).any(|r| g[r] == 0 || g[r] == 2 * self.n[r])
    }

    /// Dense row-major global matrix and internal-force vector at displacements `u`.
    pub fn assemble(
        &self,
        table: &ShapeTable,
        material: &Stiffness,
        u: &[[f64; 3]],
        kinematics: Kinematics,
    ) -> (Vec<f64>, Vec<f64>) {
        let nd = 3 * self.coords.len();
        let mut k = vec![0.0; nd * nd];
        let mut f = vec![0.0; nd];
        let mut ws = Workspace::new(table);
        let mut out = ElementOutput::new(table);
        let ed = table.dofs();
        for cell in &self.cells {
            let x: Vec<_> = cell.iter().map(|&i| self.coords[i]).collect();
            let ue: Vec<_> = cell.iter().map(|&i| u[i]).collect();
            evaluate(
                table, &x, &ue, material, kinematics, true, &mut ws, &mut out,
            )
            .unwrap();
            for (a, &na) in cell.iter().enumerate() {
                for r in 0..3 {
                    f[3 * na + r] += out.forces[3 * a + r];
                    for (b, &nb) in cell.iter().enumerate() {
                        for s in 0..3 {
                            k[(3 * na + r) * nd + 3 * nb + s] +=
                                out.tangent[(3 * a + r) * ed + 3 * b + s];
                        }
                    }
                }
            }
        }
        (k, f)
    }
}
