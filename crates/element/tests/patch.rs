//! Patch tests on meshes of distorted elements: a homogeneous strain field is reproduced
//! exactly (linear solve), and a homogeneous finite deformation leaves the interior nodes in
//! equilibrium (nonlinear).

mod common;

use common::block;
use nalgebra::{DMatrix, DVector};
use nonlin3d_element::{
    ElementKind, ElementOutput, IntegrationRule, Kinematics, ShapeTable, Workspace, evaluate,
};
use nonlin3d_laminate::{ShearCoupling, materials};

const CASES: [(ElementKind, IntegrationRule); 4] = [
    (ElementKind::Hex8, IntegrationRule::Gauss2),
    (ElementKind::Hex8, IntegrationRule::SelectiveReduced),
    (ElementKind::Hex20, IntegrationRule::Gauss2),
    (ElementKind::Hex20, IntegrationRule::Gauss3),
];

/// A 2×2×2 block (1 × 1 × 0.5 mm elements) whose interior nodes are moved by up to 20 % of
/// the element size by a fixed pseudo-random sequence.
fn distorted_block(kind: ElementKind) -> common::Block {
    let mut b = block(kind, [2, 2, 2], [1e-3, 1e-3, 0.5e-3]);
    let mut seed = 12345u64;
    let mut next = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    };
    for i in 0..b.coords.len() {
        if !b.on_boundary(i) {
            b.coords[i][0] += 0.2e-3 * next();
            b.coords[i][1] += 0.2e-3 * next();
            b.coords[i][2] += 0.1e-3 * next();
        }
    }
    b
}

const A: [[f64; 3]; 3] = [
    [1.0e-3, 0.4e-3, -0.2e-3],
    [0.3e-3, -2.0e-3, 0.5e-3],
    [-0.6e-3, 0.1e-3, 1.5e-3],
];

fn field(a: &[[f64; 3]; 3], p: [f64; 3]) -> [f64; 3] {
    let mut v = [2e-6, -1e-6, 3e-6];
    for i in 0..3 {
        for j in 0..3 {
            v[i] += a[i][j] * p[j];
        }
    }
    v
}

#[test]
fn linear_patch_test_reproduces_homogeneous_strain() {
    let m = materials::generic_graphite_epoxy()
        .stiffness()
        .unwrap()
        .rotated_about_z(0.6, ShearCoupling::Exact)
        .unwrap();
    for (kind, rule) in CASES {
        let table = ShapeTable::new(kind, rule).unwrap();
        let b = distorted_block(kind);
        let nn = b.coords.len();
        let zero = vec![[0.0; 3]; nn];
        let (k, _) = b.assemble(&table, &m, &zero, Kinematics::Linear);
        let nd = 3 * nn;
        let k = DMatrix::from_row_slice(nd, nd, &k);
        let free: Vec<usize> = (0..nd).filter(|&d| !b.on_boundary(d / 3)).collect();
        let fixed: Vec<usize> = (0..nd).filter(|&d| b.on_boundary(d / 3)).collect();
        assert!(free.len() >= 3, "the patch must have interior nodes");
        let exact: Vec<f64> = (0..nd).map(|d| field(&A, b.coords[d / 3])[d % 3]).collect();
        let kff = DMatrix::from_fn(free.len(), free.len(), |i, j| k[(free[i], free[j])]);
        let rhs = DVector::from_fn(free.len(), |i, _| {
            -fixed
                .iter()
                .map(|&c| k[(free[i], c)] * exact[c])
                .sum::<f64>()
        });
        let sol = kff
            .cholesky()
            .expect("K_ff is SPD with the boundary fixed")
            .solve(&rhs);
        // Conditioning of K_ff (~1e4 for these elements) times 1e-16: 1e-10 relative is ample.
        let scale = exact.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        for (i, &d) in free.iter().enumerate() {
            assert!(
                (sol[i] - exact[d]).abs() <= 1e-10 * scale,
                "{kind:?} {rule:?} dof {d}: {} vs {}",
                sol[i],
                exact[d]
            );
        }
        // Stresses in every element equal C·ε(A) at every station (on its components).
        let eps = [
            A[0][0],
            A[1][1],
            A[2][2],
            A[0][1] + A[1][0],
            A[1][2] + A[2][1],
            A[0][2] + A[2][0],
        ];
        let sig = m.stress(&eps);
        let mut full = exact.clone();
        for (i, &d) in free.iter().enumerate() {
            full[d] = sol[i];
        }
        let mut out = ElementOutput::new(&table);
        let mut ws = Workspace::new(&table);
        let smax = sig.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        for cell in &b.cells {
            let x: Vec<_> = cell.iter().map(|&n| b.coords[n]).collect();
            let u: Vec<_> = cell
                .iter()
                .map(|&n| [full[3 * n], full[3 * n + 1], full[3 * n + 2]])
                .collect();
            evaluate(
                &table,
                &x,
                &u,
                &m,
                Kinematics::Linear,
                false,
                &mut ws,
                &mut out,
            )
            .unwrap();
            for (st, s) in table.stations().iter().zip(&out.stresses) {
                for c in st.first..st.last {
                    // σ_c on a station's components is Σ over those components only; with the
                    // full rule that is C·ε. The selective-reduced stations split C by blocks,
                    // equal to C·ε because this material has no cross-block coupling.
                    assert!(
                        (s[c] - sig[c]).abs() <= 1e-8 * smax,
                        "{kind:?} {rule:?} σ{c}: {} vs {}",
                        s[c],
                        sig[c]
                    );
                }
            }
        }
    }
}

#[test]
fn nonlinear_patch_test_interior_nodes_are_in_equilibrium() {
    // A finite homogeneous deformation: 20° rotation about an oblique axis times a stretch.
    let m = materials::im7_8551_7()
        .stiffness()
        .unwrap()
        .rotated_about_z(-0.3, ShearCoupling::Exact)
        .unwrap();
    let (s, c) = 20f64.to_radians().sin_cos();
    let rot = [
        [c, -s, 0.0],
        [s * 0.8, c * 0.8, 0.6],
        [-s * 0.6, -c * 0.6, 0.8],
    ];
    let stretch = [[1.01, 0.003, 0.0], [0.0, 0.985, 0.002], [0.001, 0.0, 1.02]];
    let mut a = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            a[i][j] = (0..3).map(|k| rot[i][k] * stretch[k][j]).sum::<f64>()
                - if i == j { 1.0 } else { 0.0 };
        }
    }
    for (kind, rule) in CASES {
        let table = ShapeTable::new(kind, rule).unwrap();
        let b = distorted_block(kind);
        let u: Vec<[f64; 3]> = b.coords.iter().map(|&p| field(&a, p)).collect();
        let (_, f) = b.assemble(&table, &m, &u, Kinematics::Nonlinear);
        let fmax = f.iter().fold(0.0f64, |acc, v| acc.max(v.abs()));
        assert!(fmax > 0.0);
        for n in (0..b.coords.len()).filter(|&n| !b.on_boundary(n)) {
            for r in 0..3 {
                // Uniform stress: element contributions cancel to round-off, 1e-12 of the
                // boundary forces.
                assert!(
                    f[3 * n + r].abs() <= 1e-12 * fmax,
                    "{kind:?} {rule:?} node {n}: {}",
                    f[3 * n + r]
                );
            }
        }
    }
}
