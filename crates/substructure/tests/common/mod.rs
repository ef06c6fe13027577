//! Shared set-up of the substructuring tests: a box, its assemblers, a direct linear solve.
#![allow(dead_code)]

use nonlin3d_assembly::{Assembler, Constraints, System};
use nonlin3d_element::{ElementKind, IntegrationRule, Kinematics};
use nonlin3d_laminate::{ShearCoupling, Stiffness};
use nonlin3d_mesh::{BoxParams, Mesh, structured_box};
use nonlin3d_solver::SolverKind;

pub fn steel() -> Stiffness {
    nonlin3d_laminate::materials::steel().stiffness().unwrap()
}

/// A Hex20 box of `cells` cells over `size` (m).
pub fn hex20_box(cells: [usize; 3], size: [f64; 3]) -> Mesh {
    structured_box(&BoxParams::new(ElementKind::Hex20, cells, size)).unwrap()
}

/// Steel, 2×2×2 Gauss, with `kinematics`.
pub fn assembler(mesh: &Mesh, kinematics: Kinematics) -> Assembler {
    Assembler::new(
        mesh,
        &[steel()],
        ShearCoupling::Exact,
        IntegrationRule::Gauss2,
        IntegrationRule::Gauss2,
        kinematics,
    )
    .unwrap()
}

/// The cells whose centre has coordinate `axis` below `value`.
pub fn cells_below(mesh: &Mesh, axis: usize, value: f64) -> Vec<usize> {
    (0..mesh.cells.len())
        .filter(|&c| {
            let x = mesh.cell_coordinates(c);
            x.iter().map(|p| p[axis]).sum::<f64>() / x.len() as f64 <= value
        })
        .collect()
}

/// The solution of a linear `system` at λ: u with the prescribed values, one direct solve
/// K Δu = −r, and the reactions of the solution (a second evaluation).
pub fn solve_linear(system: &System, lambda: f64) -> (Vec<f64>, Vec<f64>) {
    let mut u = vec![0.0; system.n()];
    system.prescribe(&mut u, lambda);
    let mut k = system.new_tangent();
    let e = system.evaluate(&u, lambda, Some(&mut k)).unwrap();
    let mut s = SolverKind::FaerLdlt.build();
    s.analyze(k.pattern()).unwrap();
    s.factorize(&k).unwrap();
    let mut du = e.residual.clone();
    s.solve_in_place(&mut du, 1).unwrap();
    for (u, d) in u.iter_mut().zip(&du) {
        *u -= d;
    }
    let e = system.evaluate(&u, lambda, None).unwrap();
    (u, e.reactions)
}

/// max |a − b| / max |b|.
pub fn relative_difference(a: &[f64], b: &[f64]) -> f64 {
    let scale = b.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let diff = a
        .iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    diff / scale
}

/// Constraints of the full box: `clamped` nodes fixed in x, y, z.
pub fn clamped(mesh: &Mesh, clamped: &str) -> Constraints {
    let mut c = Constraints::new(3 * mesh.nodes.len());
    for r in 0..3 {
        c.fix_nodes(&mesh.node_sets[clamped], r).unwrap();
    }
    c
}
