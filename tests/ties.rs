//! Linear ties between DOFs (`Constraints::tie`, multi-point constraints u_s = Σ c·u_m + λ·b):
//! a mesh cut in two and tied back together behaves as the uncut mesh; a tie with general
//! coefficients equals the explicit reduction TᵀKT x = Tᵀf, u = Tx; bad ties are refused.

use nonlin3d::assembly::{Assembler, AssemblyError, Constraints};
use nonlin3d::element::{ElementKind, IntegrationRule, Kinematics};
use nonlin3d::laminate::{ShearCoupling, materials};
use nonlin3d::mesh::{BoxParams, Mesh, structured_box};
use nonlin3d::newton::{NewtonSettings, Stepping, StructuralProblem, follow_path};

fn assembler(mesh: &Mesh, kin: Kinematics) -> Assembler {
    Assembler::new(
        mesh,
        &[materials::steel().stiffness().unwrap()],
        ShearCoupling::Exact,
        IntegrationRule::Gauss2,
        IntegrationRule::Gauss2,
        kin,
    )
    .unwrap()
}

/// Cuts `mesh` at x = `cut`: cells right of it get copies of the nodes on the plane. Returns
/// the cut mesh and (copy, original) node pairs.
fn cut(mesh: &Mesh, at: f64) -> (Mesh, Vec<(usize, usize)>) {
    let mut m = mesh.clone();
    let mut copy = std::collections::HashMap::new();
    for c in 0..m.cells.len() {
        let cx = m.cells[c]
            .nodes
            .iter()
            .map(|&n| mesh.nodes[n][0])
            .sum::<f64>()
            / m.cells[c].nodes.len() as f64;
        if cx < at {
            continue;
        }
        for k in 0..m.cells[c].nodes.len() {
            let n = m.cells[c].nodes[k];
            if (mesh.nodes[n][0] - at).abs() < 1e-12 {
                let id = *copy.entry(n).or_insert_with(|| {
                    m.nodes.push(mesh.nodes[n]);
                    m.nodes.len() - 1
                });
                m.cells[c].nodes[k] = id;
            }
        }
    }
    let pairs: Vec<(usize, usize)> = copy.into_iter().map(|(o, c)| (c, o)).collect();
    (m, pairs)
}

/// A Hex20 cantilever (clamped at x = 0, tip load −z at x = L), large deflection: the mesh cut at
/// mid-length and tied back (u_copy = u_original, 3 ties per node) gives the uncut mesh's
/// displacements at every original node, to 1e-9 of the tip deflection. The two systems are
/// algebraically identical, but each Newton run stops at its own iterate: at the default 1e-4 N
/// the states differ by ~tolerance/stiffness ≈ 4e-11 m (1.3e-9 of the tip); converged to 1e-8 N
/// both sit at the same solution to rounding.
#[test]
fn a_cut_mesh_tied_back_equals_the_uncut_mesh() {
    let mesh = structured_box(&BoxParams::new(
        ElementKind::Hex20,
        [6, 1, 2],
        [60e-3, 5e-3, 4e-3],
    ))
    .unwrap();
    let (tied_mesh, pairs) = cut(&mesh, 30e-3);
    assert_eq!(
        pairs.len(),
        13,
        "8 corner + 5 mid-edge nodes on the cut (1 × 2 Hex20 faces)"
    );
    let solve = |m: &Mesh, ties: &[(usize, usize)]| {
        let asm = assembler(m, Kinematics::Nonlinear);
        let mut c = Constraints::new(asm.n());
        for r in 0..3 {
            c.fix_nodes(&m.node_sets["x0"], r).unwrap();
        }
        let tip = &m.node_sets["x1"];
        for &n in tip {
            c.add_load(3 * n + 2, -3000.0 / tip.len() as f64).unwrap();
        }
        for &(s, o) in ties {
            for r in 0..3 {
                c.tie(3 * s + r, &[(3 * o + r, 1.0)], 0.0).unwrap();
            }
        }
        let mut p = StructuralProblem::new(asm, c).unwrap();
        let mut u = vec![0.0; p.assembler().n()];
        let tight = NewtonSettings {
            force_tolerance: 1e-8,
            relative_tolerance: 1e-14,
            ..NewtonSettings::default()
        };
        follow_path(&mut p, &mut u, &[1.0], &tight, &Stepping::default()).unwrap();
        u
    };
    let whole = solve(&mesh, &[]);
    let tied = solve(&tied_mesh, &pairs);
    let scale = whole.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    assert!(scale > 1e-3, "a large deflection: {scale}");
    let diff = (0..whole.len())
        .map(|d| (whole[d] - tied[d]).abs())
        .fold(0.0, f64::max);
    eprintln!("tip scale {scale:e} m, largest difference {diff:e} m");
    assert!(diff < 1e-9 * scale);
    for &(s, o) in &pairs {
        for r in 0..3 {
            assert_eq!(tied[3 * s + r], tied[3 * o + r]);
        }
    }
}

/// A tie with general coefficients and an offset, against the explicit reduction: with
/// u = T x + λ·b e_s, K′ = TᵀKT, f′ = Tᵀ(f − K b e_s), dense (nalgebra), linear kinematics.
#[test]
fn a_general_tie_equals_the_explicit_reduction() {
    let mesh = structured_box(&BoxParams::new(
        ElementKind::Hex8,
        [2, 1, 1],
        [2e-3, 1e-3, 1e-3],
    ))
    .unwrap();
    let asm = assembler(&mesh, Kinematics::Linear);
    let n = asm.n();
    let fixed: Vec<usize> = mesh.node_sets["x0"]
        .iter()
        .flat_map(|&a| [3 * a, 3 * a + 1, 3 * a + 2])
        .collect();
    let tip = mesh.node_sets["x1"].clone();
    // Slave: w of the first tip node = 0.7·w(second) − 0.2·u(third) + 1e-6 m.
    let (s, m1, m2, b) = (3 * tip[0] + 2, 3 * tip[1] + 2, 3 * tip[2], 1e-6);
    let load = (3 * tip[3] + 2, -50.0);
    let mut c = Constraints::new(n);
    for &d in &fixed {
        c.prescribe(d, 0.0).unwrap();
    }
    c.add_load(load.0, load.1).unwrap();
    c.tie(s, &[(m1, 0.7), (m2, -0.2)], b).unwrap();
    let mut p = StructuralProblem::new(asm, c).unwrap();
    let mut u = vec![0.0; n];
    follow_path(
        &mut p,
        &mut u,
        &[1.0],
        &NewtonSettings::default(),
        &Stepping::default(),
    )
    .unwrap();

    // Explicit: free DOFs = all but fixed and the slave.
    let plain = assembler(&mesh, Kinematics::Linear);
    let mut kfull = plain.new_tangent();
    plain.assemble(&vec![0.0; n], Some(&mut kfull)).unwrap();
    let k = nalgebra::DMatrix::from_row_slice(n, n, &kfull.to_dense());
    let free: Vec<usize> = (0..n).filter(|d| !fixed.contains(d) && *d != s).collect();
    let mut t = nalgebra::DMatrix::<f64>::zeros(n, free.len());
    for (j, &d) in free.iter().enumerate() {
        t[(d, j)] = 1.0;
        if d == m1 {
            t[(s, j)] = 0.7;
        }
        if d == m2 {
            t[(s, j)] = -0.2;
        }
    }
    let mut f = nalgebra::DVector::<f64>::zeros(n);
    f[load.0] = load.1;
    let mut shift = nalgebra::DVector::<f64>::zeros(n);
    shift[s] = b;
    let kr = t.transpose() * &k * &t;
    let fr = t.transpose() * (f - &k * &shift);
    let x = kr.lu().solve(&fr).unwrap();
    let expected = &t * x + shift;
    let scale = expected.amax();
    for d in 0..n {
        assert!(
            (u[d] - expected[d]).abs() < 1e-9 * scale,
            "DOF {d}: {} vs {}",
            u[d],
            expected[d]
        );
    }
    assert!((u[s] - (0.7 * u[m1] - 0.2 * u[m2] + b)).abs() < 1e-15);
    // The tie's force is reported as the slave's reaction.
    assert!(p.reactions()[s].abs() > 0.0);
}

#[test]
fn bad_ties_are_refused_by_name() {
    let mut c = Constraints::new(30);
    c.prescribe(0, 0.0).unwrap();
    let slave = |e: AssemblyError| match e {
        AssemblyError::Tie { slave, .. } => slave,
        other => panic!("{other}"),
    };
    assert_eq!(slave(c.tie(0, &[(3, 1.0)], 0.0).unwrap_err()), 0); // prescribed slave
    assert_eq!(slave(c.tie(4, &[(4, 1.0)], 0.0).unwrap_err()), 4); // self
    assert_eq!(slave(c.tie(5, &[(31, 1.0)], 0.0).unwrap_err()), 5); // out of range
    assert_eq!(slave(c.tie(5, &[(6, f64::NAN)], 0.0).unwrap_err()), 5);
    assert_eq!(slave(c.tie(5, &[(6, 1.0), (6, 2.0)], 0.0).unwrap_err()), 5); // twice
    c.tie(7, &[(8, 1.0)], 0.0).unwrap();
    assert_eq!(slave(c.tie(9, &[(7, 1.0)], 0.0).unwrap_err()), 9); // chain: master is a slave
    assert_eq!(slave(c.tie(8, &[(10, 1.0)], 0.0).unwrap_err()), 8); // chain: slave is a master
    assert_eq!(slave(c.tie(7, &[(11, 1.0)], 0.0).unwrap_err()), 7); // slave twice
    assert!(c.prescribe(7, 0.0).is_err()); // a slave cannot be prescribed
}
