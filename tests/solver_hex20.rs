//! The sparse solvers on Hex20 stiffness matrices (issue: sparse solvers): profile = faer,
//! located zero-pivot errors for unsupported models, and inertia of shifted (indefinite)
//! stiffness matrices against a dense eigen-analysis.

mod common;

use common::BoxMesh;
use nalgebra::{DMatrix, SymmetricEigen};
use nonlin3d::element::{ElementKind, IntegrationRule};
use nonlin3d::laminate::{PlyStack, ShearCoupling, materials};
use nonlin3d::solver::{
    FaerMode, FaerSolver, FaerStructure, LinearSolver, ProfileLdlt, SolverError, SymmetricMatrix,
};

fn quasi_isotropic() -> nonlin3d::laminate::Stiffness {
    PlyStack::quasi_isotropic(materials::generic_graphite_epoxy(), 0.125e-3)
        .unwrap()
        .average_stiffness(ShearCoupling::Exact)
        .unwrap()
}

/// A cantilever plate: 6 × 4 × 2 Hex20 (2 × 2 × 0.5 mm), clamped at x = 0.
fn clamped_plate() -> (BoxMesh, SymmetricMatrix) {
    let mesh = BoxMesh::new(ElementKind::Hex20, [6, 4, 2], [2e-3, 2e-3, 0.5e-3]);
    let fixed: Vec<usize> = mesh
        .nodes_at_zero(0)
        .iter()
        .flat_map(|&n| [3 * n, 3 * n + 1, 3 * n + 2])
        .collect();
    let k = mesh.stiffness(&quasi_isotropic(), IntegrationRule::Gauss2, &fixed);
    (mesh, k)
}

#[test]
fn profile_and_faer_agree_on_a_clamped_hex20_plate() {
    let (mesh, k) = clamped_plate();
    let n = mesh.dofs();
    // A transverse tip load on every node at the far end, plus a second load case.
    let mut b = vec![0.0; 2 * n];
    for (i, g) in mesh.grid.iter().enumerate() {
        if g[0] == 2 * mesh.n[0] {
            b[3 * i + 2] = -1.0;
            b[n + 3 * i] = 2.0;
        }
    }
    let mut results = Vec::new();
    for mut s in [
        Box::new(ProfileLdlt::new()) as Box<dyn LinearSolver>,
        Box::new(FaerSolver::new(FaerMode::Ldlt)),
        Box::new(FaerSolver::new(FaerMode::Llt)),
        Box::new(FaerSolver::new(FaerMode::Ldlt).with_threads(2)),
        Box::new(FaerSolver::new(FaerMode::Ldlt).with_structure(FaerStructure::Simplicial)),
        Box::new(FaerSolver::new(FaerMode::Ldlt).with_structure(FaerStructure::Supernodal)),
        Box::new(FaerSolver::new(FaerMode::Llt).with_structure(FaerStructure::Supernodal)),
    ] {
        s.analyze(k.pattern()).unwrap();
        let f = s.factorize(&k).unwrap();
        assert_eq!(f.negative_pivots, 0, "{}", s.name());
        let mut x = b.clone();
        s.solve_in_place(&mut x, 2).unwrap();
        results.push((s.name(), x));
    }
    let (_, reference) = &results[0];
    let scale = reference.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    assert!(scale > 0.0);
    for (name, x) in &results[1..] {
        // Both are backward stable; with κ(K) ≈ 1e8 here the solutions agree to ~1e-16·κ.
        let diff = x
            .iter()
            .zip(reference)
            .fold(0.0f64, |a, (p, q)| a.max((p - q).abs()));
        assert!(
            diff <= 1e-10 * scale,
            "{name}: max difference {diff:e} vs scale {scale:e}"
        );
    }
    // The residual of the profile solution, relative to the load.
    let mut r = vec![0.0; n];
    k.matvec(&reference[..n], &mut r).unwrap();
    let res = r
        .iter()
        .zip(&b[..n])
        .map(|(p, q)| (p - q).powi(2))
        .sum::<f64>()
        .sqrt();
    let bn = b[..n].iter().map(|v| v * v).sum::<f64>().sqrt();
    assert!(res <= 1e-10 * bn, "residual {res:e}");
}

#[test]
fn forced_structures_are_what_they_say() {
    let (_, k) = clamped_plate();
    for (structure, expect) in [
        (FaerStructure::Simplicial, false),
        (FaerStructure::Supernodal, true),
    ] {
        let mut s = FaerSolver::new(FaerMode::Ldlt).with_structure(structure);
        assert_eq!(s.is_supernodal(), None);
        s.analyze(k.pattern()).unwrap();
        assert_eq!(s.is_supernodal(), Some(expect));
    }
}

#[test]
fn an_unsupported_model_is_a_located_zero_pivot() {
    let mesh = BoxMesh::new(ElementKind::Hex20, [3, 2, 2], [2e-3, 2e-3, 0.5e-3]);
    let k = mesh.stiffness(&quasi_isotropic(), IntegrationRule::Gauss2, &[]);
    for mut s in [
        Box::new(ProfileLdlt::new()) as Box<dyn LinearSolver>,
        Box::new(FaerSolver::new(FaerMode::Ldlt).with_structure(FaerStructure::Simplicial)),
        Box::new(FaerSolver::new(FaerMode::Ldlt).with_structure(FaerStructure::Supernodal)),
    ] {
        s.analyze(k.pattern()).unwrap();
        match s.factorize(&k) {
            Err(SolverError::ZeroPivot {
                dof,
                pivot,
                diagonal,
                ..
            }) => {
                assert!(dof < mesh.dofs());
                assert!(
                    pivot.abs() <= 1e-12 * diagonal,
                    "{}: pivot {pivot:e} vs {diagonal:e}",
                    s.name()
                );
            }
            other => panic!("{}: expected a zero pivot, got {other:?}", s.name()),
        }
    }
    let mut llt = FaerSolver::new(FaerMode::Llt);
    llt.analyze(k.pattern()).unwrap();
    assert!(matches!(
        llt.factorize(&k),
        Err(SolverError::ZeroPivot { .. }) | Err(SolverError::NotPositiveDefinite { .. })
    ));
}

/// K − σ·I for σ between eigenvalues of K has exactly as many negative eigenvalues as K has
/// eigenvalues below σ: both solvers must count them (Sylvester), on a model big enough for
/// faer to go supernodal.
#[test]
fn inertia_of_shifted_stiffness_matches_dense_eigenvalues() {
    let mesh = BoxMesh::new(ElementKind::Hex20, [4, 3, 2], [2e-3, 2e-3, 0.5e-3]);
    let fixed: Vec<usize> = mesh
        .nodes_at_zero(0)
        .iter()
        .flat_map(|&n| [3 * n, 3 * n + 1, 3 * n + 2])
        .collect();
    let k = mesh.stiffness(&quasi_isotropic(), IntegrationRule::Gauss3, &fixed);
    let n = mesh.dofs();
    let eig = SymmetricEigen::new(DMatrix::from_row_slice(n, n, &k.to_dense())).eigenvalues;
    let mut sorted: Vec<f64> = eig.iter().copied().collect();
    sorted.sort_by(f64::total_cmp);
    // The fixed DOFs carry unit diagonals: a cluster of eigenvalues at 1, far below the
    // stiffness's own (~1e7 N/m). Shift past it into gaps between the genuine eigenvalues.
    let base = fixed.len();
    assert!(sorted[base - 1] < 2.0 && sorted[base] > 1e3);
    for want in [base + 1, base + 7, base + 40, n / 2] {
        // The first gap at or after `want` that is wide (1e-6 relative) on both sides.
        let count = (want..n)
            .find(|&c| sorted[c] - sorted[c - 1] > 1e-6 * sorted[c])
            .unwrap();
        let sigma = 0.5 * (sorted[count - 1] + sorted[count]);
        let mut shifted = k.clone();
        for i in 0..n {
            shifted.add(i, i, -sigma).unwrap();
        }
        for mut s in [
            Box::new(ProfileLdlt::new()) as Box<dyn LinearSolver>,
            Box::new(FaerSolver::new(FaerMode::Ldlt).with_structure(FaerStructure::Simplicial)),
            Box::new(FaerSolver::new(FaerMode::Ldlt).with_structure(FaerStructure::Supernodal)),
        ] {
            s.analyze(shifted.pattern()).unwrap();
            let f = s.factorize(&shifted).unwrap();
            assert_eq!(f.negative_pivots, count, "{} at σ = {sigma:e}", s.name());
        }
    }
}
