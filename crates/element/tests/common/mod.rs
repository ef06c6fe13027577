//! Helpers shared by the element integration tests: structured blocks and dense assembly.
#![allow(dead_code)]

use nonlin3d_element::{ElementKind, ElementOutput, Kinematics, ShapeTable, Workspace, evaluate};
use nonlin3d_laminate::Stiffness;

/// A structured block of nx×ny×nz elements of size h (`nonlin3d_testkit::Block`: nodes keyed by
/// doubled integer grid coordinates, so Hex20 mid-edge nodes have an odd coordinate), with the
/// element kind it was built for.
pub struct Block {
    pub kind: ElementKind,
    pub block: nonlin3d_testkit::Block,
}

impl std::ops::Deref for Block {
    type Target = nonlin3d_testkit::Block;
    fn deref(&self) -> &Self::Target {
        &self.block
    }
}

impl std::ops::DerefMut for Block {
    fn deref_mut(&mut self) -> &mut Self::Target {
        &mut self.block
    }
}

pub fn block(kind: ElementKind, n: [usize; 3], h: [f64; 3]) -> Block {
    Block {
        kind,
        block: nonlin3d_testkit::Block::new(kind.reference_nodes(), n, h),
    }
}

impl Block {
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
