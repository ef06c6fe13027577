//! Exactness of the condensation (issue 18): for a linear problem, substructured = monolithic
//! (displacements everywhere after recovery, reactions), K_red symmetric, and an unsupported
//! region's K_red with exactly the six rigid-body modes.

mod common;

use common::*;
use nonlin3d_assembly::{Constraints, System};
use nonlin3d_element::Kinematics;
use nonlin3d_mesh::{Mesh, names};
use nonlin3d_substructure::{CondenseSettings, Partition, SubstructureError, condense};

/// The 6 × 4 × 3 Hex20 box over 6 × 4 × 3 m: clamped on x = 0; on x = 6, u = 1 mm prescribed
/// (λ-scaled), a load of 10 kN per node in z (λ-scaled) and a dead load of 5 kN in y on one node
/// (λ-independent); supports, prescribed values and loads thus fall on both regions whichever
/// half is linear.
fn problem() -> (Mesh, Constraints) {
    let mesh = hex20_box([6, 4, 3], [6.0, 4.0, 3.0]);
    let mut c = clamped(&mesh, names::X0);
    let end = &mesh.node_sets[names::X1];
    for &v in end {
        c.prescribe(3 * v, 1e-3).unwrap();
        c.add_load(3 * v + 2, 1e4).unwrap();
    }
    c.set_dead_load(3 * end[end.len() / 2] + 1, 5e3).unwrap();
    (mesh, c)
}

/// The problem solved monolithically and with the cells on one side of x = 3 condensed (the
/// linear side holding the clamp, then the loaded end), at λ = 1 and λ = 0.4 (the condensed
/// load scales with λ, the dead part does not): displacements and reactions agree to 1e-9
/// relative. Both are direct solves of the same linear equations in double precision;
/// ε·κ(K) ≈ 1e-16 · 1e5 for this box (aspect 1, no thin layers) leaves four orders to the bound.
#[test]
fn substructured_equals_monolithic_for_a_linear_problem() {
    let (mesh, c) = problem();
    let whole = System::builder(c.clone())
        .contribution(assembler(&mesh, Kinematics::Linear))
        .build()
        .unwrap();
    let left = cells_below(&mesh, 0, 3.0);
    for (name, p) in [
        (
            "clamped half",
            Partition::from_linear_cells(&mesh, &left).unwrap(),
        ),
        (
            "loaded half",
            Partition::from_nonlinear_cells(&mesh, &left).unwrap(),
        ),
    ] {
        let mut done = condense(
            &p,
            &assembler(p.linear_mesh(), Kinematics::Linear),
            &c,
            &CondenseSettings::default(),
        )
        .unwrap();
        assert_eq!(done.report.interface_dofs, 3 * 51, "{name}");
        let sub = System::builder(p.nonlinear_constraints(&c).unwrap())
            .contribution(assembler(p.nonlinear_mesh(), Kinematics::Linear))
            .contribution(done.superelement.clone())
            .build()
            .unwrap();
        for lambda in [1.0, 0.4] {
            let (u_whole, r_whole) = solve_linear(&whole, lambda);
            let (u_sub, r_sub) = solve_linear(&sub, lambda);
            let rec = done.recovery.recover(&u_sub, lambda).unwrap();
            let mut reactions = rec.reactions.clone();
            for (s, &v) in p.nonlinear_nodes().iter().enumerate() {
                for r in 0..3 {
                    reactions[3 * v + r] += r_sub[3 * s + r];
                }
            }
            let du = relative_difference(&rec.displacements, &u_whole);
            let dr = relative_difference(&reactions, &r_whole);
            println!("{name}, λ = {lambda}: displacements {du:.1e}, reactions {dr:.1e}");
            assert!(
                du < 1e-9 && dr < 1e-9,
                "{name}, λ = {lambda}: {du:e}, {dr:e}"
            );
        }
        // K_red symmetric before symmetrising, to the rounding of the solves (ε·κ(K_ii)).
        println!("{name}: asymmetry {:.1e}", done.report.asymmetry);
        assert!(done.report.asymmetry < 1e-10);
        let (k, nb) = (done.superelement.stiffness(), done.report.interface_dofs);
        assert!((0..nb).all(|a| (0..a).all(|b| k[a * nb + b] == k[b * nb + a])));
    }
}

/// The linear region's forces K·u (the monolithic solid's internal forces restricted to the
/// linear cells) are the same recovered as computed on the whole: checked through equilibrium,
/// f_lin + f_nonlin = f_ext + reactions at every node, in the exactness test above; here the
/// same numbers at the interface, where both regions contribute: the linear region's force on
/// Γ is K_red u_b − f_c.
#[test]
fn recovered_forces_on_the_interface_are_the_superelement_forces() {
    let (mesh, c) = problem();
    let left = cells_below(&mesh, 0, 3.0);
    let p = Partition::from_nonlinear_cells(&mesh, &left).unwrap();
    let mut done = condense(
        &p,
        &assembler(p.linear_mesh(), Kinematics::Nonlinear),
        &c,
        &CondenseSettings {
            block: 7,
            ..CondenseSettings::default()
        },
    )
    .unwrap();
    let sub = System::builder(p.nonlinear_constraints(&c).unwrap())
        .contribution(assembler(p.nonlinear_mesh(), Kinematics::Linear))
        .contribution(done.superelement.clone())
        .build()
        .unwrap();
    let lambda = 0.8;
    let (u, _) = solve_linear(&sub, lambda);
    let rec = done.recovery.recover(&u, lambda).unwrap();
    let se = &done.superelement;
    let mut kred_u = vec![0.0; u.len()];
    nonlin3d_assembly::Contribution::add_product(se, &u, &u, &mut kred_u).unwrap();
    let mut f_c = vec![0.0; u.len()];
    nonlin3d_assembly::Contribution::add_external(se, lambda, &mut f_c);
    let scale = rec.linear_forces.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    for (&v, d) in p.interface().iter().zip(se.dofs().chunks(3)) {
        for r in 0..3 {
            let want = kred_u[d[r]] - f_c[d[r]];
            let got = rec.linear_forces[3 * v + r];
            assert!(
                (got - want).abs() < 1e-9 * scale,
                "node {v}: {got} vs {want}"
            );
        }
    }
}

/// A region with no support keeps the rigid-body modes: K_red has exactly six eigenvalues
/// below 1e-10·λ_max. In exact arithmetic they are zero; rounding leaves them at about
/// ε·κ(K_ii)·λ_max ≈ 1e-16 · 1e5 · λ_max, while the smallest elastic mode of the half box on
/// its 4 × 3 m interface sits some 1e-4 λ_max up (printed): 1e-10 separates the two by
/// orders either way.
#[test]
fn an_unsupported_region_keeps_six_rigid_body_modes() {
    let mesh = hex20_box([6, 4, 3], [6.0, 4.0, 3.0]);
    let p = Partition::from_linear_cells(&mesh, &cells_below(&mesh, 0, 3.0)).unwrap();
    let c = Constraints::new(3 * mesh.nodes.len());
    let done = condense(
        &p,
        &assembler(p.linear_mesh(), Kinematics::Linear),
        &c,
        &CondenseSettings::default(),
    )
    .unwrap();
    let nb = done.report.interface_dofs;
    let k = nalgebra::DMatrix::from_row_slice(nb, nb, done.superelement.stiffness());
    let mut eig: Vec<f64> = k.symmetric_eigen().eigenvalues.iter().copied().collect();
    eig.sort_by(f64::total_cmp);
    let top = eig[nb - 1];
    let zero = eig.iter().filter(|e| e.abs() < 1e-10 * top).count();
    println!(
        "λ_max {top:.3e}; |λ_6| / λ_max {:.1e}, λ_7 / λ_max {:.1e}",
        eig[5].abs() / top,
        eig[6] / top
    );
    assert_eq!(zero, 6);
    assert!(eig[0] > -1e-10 * top);
}

/// A part of the linear region attached neither to the interface nor to a support (here a
/// second box beside the first, sharing no node) makes K_ii singular: the error names a DOF of
/// that part. Hex8 cells (2×2×2 Gauss is their full rule): a lone Hex20 cell under 2×2×2 Gauss
/// held on one face keeps a spurious zero-energy mode of its own, and its K_ii is singular too
/// (found writing this test; the error named its node).
#[test]
fn a_floating_part_of_the_linear_region_is_a_singular_interior() {
    let one = nonlin3d_mesh::structured_box(&nonlin3d_mesh::BoxParams::new(
        nonlin3d_element::ElementKind::Hex8,
        [2, 1, 1],
        [2.0, 1.0, 1.0],
    ))
    .unwrap();
    let mut mesh = one.clone();
    let shift = one.nodes.len();
    mesh.nodes
        .extend(one.nodes.iter().map(|p| [p[0] + 5.0, p[1], p[2]]));
    let mut cell = one.cells[0].clone();
    cell.nodes.iter_mut().for_each(|v| *v += shift);
    mesh.cells.push(cell);
    let p = Partition::from_linear_cells(&mesh, &[0, 2]).unwrap();
    let err = condense(
        &p,
        &assembler(p.linear_mesh(), Kinematics::Linear),
        &Constraints::new(3 * mesh.nodes.len()),
        &CondenseSettings::default(),
    );
    match err {
        Err(SubstructureError::SingularInterior { dof, .. }) => {
            assert!(dof / 3 >= shift, "DOF {dof} is not in the floating box");
        }
        Err(e) => panic!("another error: {e}"),
        Ok(_) => panic!("a floating part was condensed"),
    }
}
