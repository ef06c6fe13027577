//! Structured Hex8/Hex20 boxes and their assembled linear stiffness, shared by the end-to-end
//! tests and the solver benchmarks (`#[path]`-included there). The mesh crate will supersede it.
#![allow(dead_code)]

pub mod ccx;

use nonlin3d::element::{ElementKind, IntegrationRule, ShapeTable, linear_stiffness};
use nonlin3d::laminate::Stiffness;
use nonlin3d::solver::{SymmetricMatrix, SymmetricPattern};
use std::sync::Arc;

/// A structured box of n[0]×n[1]×n[2] elements with element sizes h (graded nothing): the
/// shared test block (`nonlin3d_testkit::Block`) with the element kind it was built for.
pub struct BoxMesh {
    pub kind: ElementKind,
    pub block: nonlin3d_testkit::Block,
}

impl std::ops::Deref for BoxMesh {
    type Target = nonlin3d_testkit::Block;
    fn deref(&self) -> &Self::Target {
        &self.block
    }
}

impl BoxMesh {
    pub fn new(kind: ElementKind, n: [usize; 3], h: [f64; 3]) -> Self {
        Self {
            kind,
            block: nonlin3d_testkit::Block::new(kind.reference_nodes(), n, h),
        }
    }

    /// The linear stiffness, with the DOFs in `fixed` replaced by unit rows and columns (so
    /// the matrix keeps its pattern and its size).
    pub fn stiffness(
        &self,
        material: &Stiffness,
        rule: IntegrationRule,
        fixed: &[usize],
    ) -> SymmetricMatrix {
        self.stiffness_with(material, rule, fixed, false)
    }

    /// [`Self::stiffness`], with the DOFs in `fixed` also taken out of the pattern when
    /// `decouple` (each a lone unit diagonal, as a matrix assembled and then masked by a
    /// sparse product that drops zeros has them).
    pub fn stiffness_with(
        &self,
        material: &Stiffness,
        rule: IntegrationRule,
        fixed: &[usize],
        decouple: bool,
    ) -> SymmetricMatrix {
        let table = ShapeTable::new(self.kind, rule).unwrap();
        let mut is_fixed = vec![false; self.dofs()];
        for &d in fixed {
            is_fixed[d] = true;
        }
        let lists = self.cell_dofs();
        let pattern = if decouple {
            let mut kept: Vec<Vec<usize>> = lists
                .iter()
                .map(|l| l.iter().copied().filter(|&d| !is_fixed[d]).collect())
                .collect();
            kept.extend(fixed.iter().map(|&d| vec![d]));
            SymmetricPattern::from_dof_lists(self.dofs(), &kept)
        } else {
            SymmetricPattern::from_dof_lists(self.dofs(), &lists)
        };
        let mut a = SymmetricMatrix::zeros(Arc::new(pattern.unwrap()));
        for (cell, dofs) in self.cells.iter().zip(&lists) {
            let x: Vec<[f64; 3]> = cell.iter().map(|&n| self.coords[n]).collect();
            let mut k = linear_stiffness(&table, &x, material).unwrap();
            let ne = dofs.len();
            for (r, &i) in dofs.iter().enumerate() {
                for (c, &j) in dofs.iter().enumerate() {
                    if is_fixed[i] || is_fixed[j] {
                        k[r * ne + c] = 0.0;
                    }
                }
            }
            if decouple {
                // Only the free DOFs are in the pattern: their entries one by one.
                for (r, &i) in dofs.iter().enumerate() {
                    for (c, &j) in dofs.iter().enumerate() {
                        if i >= j && !is_fixed[i] && !is_fixed[j] {
                            a.add(i, j, k[r * ne + c]).unwrap();
                        }
                    }
                }
            } else {
                a.scatter_add(dofs, &k).unwrap();
            }
        }
        for &d in fixed {
            a.add(d, d, 1.0).unwrap();
        }
        a
    }
}

/// The benchmark model: a Hex20 box of n elements of size h, homogeneous quasi-isotropic
/// graphite/epoxy (eq. 2.9.1), clamped on x = 0, 2×2×2 points.
pub fn clamped_box_stiffness(n: [usize; 3], h: [f64; 3]) -> SymmetricMatrix {
    let material = nonlin3d::laminate::PlyStack::quasi_isotropic(
        nonlin3d::laminate::materials::generic_graphite_epoxy(),
        0.125e-3,
    )
    .and_then(|s| s.average_stiffness(nonlin3d::laminate::ShearCoupling::Exact))
    .unwrap_or_else(|e| panic!("{e}"));
    let mesh = BoxMesh::new(ElementKind::Hex20, n, h);
    let fixed: Vec<usize> = mesh
        .nodes_at_zero(0)
        .iter()
        .flat_map(|&v| [3 * v, 3 * v + 1, 3 * v + 2])
        .collect();
    mesh.stiffness(&material, IntegrationRule::Gauss2, &fixed)
}

/// The cube as the PARDISO/CHOLMOD anchor script (`factor_anchor.py`, outside this repository)
/// builds it for those solvers:
/// the same Hex20 box clamped on z = 0 (its largest face) instead of x = 0, the clamped DOFs
/// lone unit rows (the script masks with a sparse product, which drops the zeros). Values
/// differ (the script's steel), the pattern, and so every ordering's fill, is the same.
pub fn anchor_box_stiffness(n: [usize; 3], h: [f64; 3]) -> SymmetricMatrix {
    let material = nonlin3d::laminate::materials::steel().stiffness().unwrap();
    let mesh = BoxMesh::new(ElementKind::Hex20, n, h);
    let fixed: Vec<usize> = mesh
        .nodes_at_zero(2)
        .iter()
        .flat_map(|&v| [3 * v, 3 * v + 1, 3 * v + 2])
        .collect();
    mesh.stiffness_with(&material, IntegrationRule::Gauss2, &fixed, true)
}

/// A structural problem on `mesh` (one material for every cell, no ply rotation), nonlinear
/// kinematics, Hex20 and Hex8 with `rule`, with DOF `r` fixed on each named node set.
pub fn structural_problem(
    mesh: &nonlin3d::mesh::Mesh,
    material: Stiffness,
    rule: IntegrationRule,
    fixes: &[(&str, usize)],
) -> nonlin3d::newton::StructuralProblem {
    use nonlin3d::assembly::{Assembler, Constraints};
    let assembler = Assembler::new(
        mesh,
        &[material],
        nonlin3d::laminate::ShearCoupling::Exact,
        rule,
        rule,
        nonlin3d::element::Kinematics::Nonlinear,
    )
    .unwrap();
    let mut c = Constraints::new(assembler.n());
    for &(set, r) in fixes {
        c.fix_nodes(&mesh.node_sets[set], r).unwrap();
    }
    nonlin3d::newton::StructuralProblem::new(assembler, c).unwrap()
}

/// The thesis reference scene (`THESIS_SCENE`) on the tiny mesh of tests/error_estimate.rs (4 slices,
/// 2 + 3 rings, 1 + 2 layers: 1 773 DOF, companion 513) at the strains `strains` (TOML array).
pub fn tiny_scene_text(strains: &str) -> String {
    nonlin3d::scene::THESIS_SCENE
        .replace(
            "slices = 8",
            "slices = 4\ninside = 2\noutside = 3\nsub_layers = 1\nbase_layers = 2",
        )
        .replace(
            "strains = [-0.001, -0.002, -0.003, -0.004, -0.005]",
            &format!("strains = {strains}"),
        )
}

/// `nonlin3d ARGS…` (the program under test), asserted to succeed with its stderr in the
/// message: what it wrote.
pub fn nonlin3d_ok<I, S>(args: I) -> std::process::Output
where
    I: IntoIterator<Item = S>,
    S: AsRef<std::ffi::OsStr>,
{
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_nonlin3d"))
        .args(args)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// The `results.json` a run wrote into `out`.
pub fn results_json(out: &std::path::Path) -> serde_json::Value {
    let text = std::fs::read_to_string(out.join("results.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}
