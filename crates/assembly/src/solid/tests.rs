//! Tests of the solid's engine: the plain element-by-element sum, bitwise independence of the
//! thread count, errors naming the cell, nodes in no cell, partial forces, tie masks.

use super::*;
use nonlin3d_element::{ElementError, ElementOutput, Workspace, evaluate};
use nonlin3d_laminate::Stiffness;
use nonlin3d_mesh::{BoxParams, EmbeddedParams, embedded_delamination, structured_box};

/// A 2×2×2, nonlinear-kinematics assembler for `mesh` and a deterministic displacement
/// field of size `scale` (m) over its DOFs.
fn nonlinear_gauss2(mesh: &Mesh, mats: &[Stiffness], scale: f64) -> (Assembler, Vec<f64>) {
    let asm = Assembler::new(
        mesh,
        mats,
        ShearCoupling::Exact,
        IntegrationRule::Gauss2,
        IntegrationRule::Gauss2,
        Kinematics::Nonlinear,
    )
    .unwrap();
    let u = (0..asm.n())
        .map(|d| scale * ((d * 7919) % 23) as f64 / 23.0)
        .collect();
    (asm, u)
}

/// A Hex20 box of 2 × 1 × 1 (m) in `cells` cells.
fn hex20_box(cells: [usize; 3]) -> Mesh {
    structured_box(&BoxParams::new(ElementKind::Hex20, cells, [2.0, 1.0, 1.0])).unwrap()
}

/// Steel's stiffness.
fn steel() -> Stiffness {
    nonlin3d_laminate::materials::steel().stiffness().unwrap()
}

/// A rayon pool of `threads` threads.
fn pool_of(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
}

/// The owner-computes assembly equals the plain element-by-element sum (each cell's
/// `evaluate` added through `SymmetricMatrix::scatter_add`, an independent path) to
/// summation-order rounding (1e-12 of the largest entry), and is bitwise the same on 1 to 4
/// threads, with prefetch hints on and off, and with more parts than threads (cells across
/// a split handed over, or evaluated by the lower part when it gets there first), on a
/// swept model with two materials and ply angles.
#[test]
fn assembly_equals_the_plain_sum_on_any_thread_count() {
    use nonlin3d_laminate::materials;
    let mut mesh = embedded_delamination(&EmbeddedParams {
        slices: 4,
        ..EmbeddedParams::thesis_reference()
    })
    .unwrap();
    for (c, cell) in mesh.cells.iter_mut().enumerate() {
        cell.material = c % 2;
        cell.ply_angle_deg = [0.0, 45.0, -45.0, 90.0][c % 4];
    }
    let mats = [
        materials::generic_graphite_epoxy().stiffness().unwrap(),
        materials::steel().stiffness().unwrap(),
    ];
    let (mut asm, u) = nonlinear_gauss2(&mesh, &mats, 1e-5);
    let mut runs = Vec::new();
    // With and without prefetch hints (hints only move cache lines), a fresh tangent (new
    // alignment, so a new hint plan) each time.
    for hints in [true, false] {
        asm.set_prefetch(hints);
        for threads in 1..=4 {
            let pool = pool_of(threads);
            let mut k = asm.new_tangent();
            // Stale values must not survive.
            k.values_mut().fill(7.0);
            let a = pool.install(|| asm.assemble(&u, Some(&mut k))).unwrap();
            runs.push((a, k));
        }
    }
    // More parts than threads: on one thread the lower part runs first and evaluates the
    // cells it would have been handed; on two, either may happen cell by cell.
    for (threads, parts) in [(1, 2), (1, 5), (2, 3), (2, 7)] {
        let pool = pool_of(threads);
        let mut k = asm.new_tangent();
        let a = pool.install(|| asm.assemble_in_parts(&u, Some(&mut k), parts));
        runs.push((a.unwrap(), k));
        // Forces alone hand over forces alone.
        let f = pool
            .install(|| asm.assemble_in_parts(&u, None, parts))
            .unwrap();
        assert!(
            f == runs[0].0,
            "{parts} parts: forces without the tangent differ"
        );
    }
    for r in &runs[1..] {
        assert!(r.0 == runs[0].0, "forces or energy depend on the threads");
        assert!(r.1 == runs[0].1, "the tangent depends on the threads");
    }
    let mut reference = asm.new_tangent();
    let mut f = vec![0.0; asm.n()];
    let mut energy = 0.0;
    for (c, dofs) in asm.dofs.iter().enumerate() {
        let (gi, i) = asm.place[c];
        let g = &asm.groups[gi];
        let nn = g.table.nodes();
        let disp: Vec<[f64; 3]> = dofs
            .chunks(3)
            .map(|d| [u[d[0]], u[d[1]], u[d[2]]])
            .collect();
        let mut out = ElementOutput::new(&g.table);
        let mut ws = Workspace::new(&g.table);
        evaluate(
            &g.table,
            &g.coords[i * nn..(i + 1) * nn],
            &disp,
            &asm.stiffness[g.material_of[i]],
            Kinematics::Nonlinear,
            true,
            &mut ws,
            &mut out,
        )
        .unwrap();
        reference.scatter_add(dofs, &out.tangent).unwrap();
        for (a, &d) in dofs.iter().enumerate() {
            f[d] += out.forces[a];
        }
        energy += out.energy;
    }
    let (a, k) = &runs[0];
    let kmax = reference
        .values()
        .iter()
        .fold(0.0_f64, |m, v| m.max(v.abs()));
    for (x, y) in k.values().iter().zip(reference.values()) {
        assert!((x - y).abs() <= 1e-12 * kmax, "{x} vs {y}");
    }
    let fmax = f.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    for (x, y) in a.internal.iter().zip(&f) {
        assert!((x - y).abs() <= 1e-12 * fmax, "{x} vs {y}");
    }
    assert!((a.energy - energy).abs() <= 1e-12 * energy.abs());
}

/// A non-finite displacement fails the assembly with a cell holding that node named (mesh
/// numbering), on one thread and on several, where the cell may straddle a split and be
/// evaluated by either part.
#[test]
fn a_bad_cell_is_named_on_any_thread_count() {
    let mesh = embedded_delamination(&EmbeddedParams {
        slices: 4,
        ..EmbeddedParams::thesis_reference()
    })
    .unwrap();
    let steel = steel();
    let (asm, mut u) = nonlinear_gauss2(&mesh, &[steel], 1e-6);
    for bad in [0, mesh.cells.len() / 2, mesh.cells.len() - 1] {
        let v = mesh.cells[bad].nodes[5];
        let keep = u[3 * v + 1];
        u[3 * v + 1] = f64::NAN;
        for threads in 1..=3 {
            let pool = pool_of(threads);
            let mut k = asm.new_tangent();
            let err = match pool.install(|| asm.assemble(&u, Some(&mut k))) {
                Ok(_) => panic!("node {v} has a NaN displacement, yet the assembly succeeded"),
                Err(e) => e,
            };
            let AssemblyError::Element(ElementError::NonFiniteInput {
                element: Some(c),
                what: "displacements",
                ..
            }) = err
            else {
                panic!("{err}");
            };
            assert!(
                mesh.cells[c].nodes.contains(&v),
                "cell {c} does not hold node {v}"
            );
        }
        u[3 * v + 1] = keep;
    }
}

/// A node in no cell (a stray node of a deck) keeps a zero diagonal block in a node-blocked
/// pattern; every tangent value is written (the matrix starts as NaN), and the other nodes'
/// entries are those of the mesh without it (1e-12 of the largest: summation order).
#[test]
fn a_node_in_no_cell_gets_a_zero_block() {
    let mesh = hex20_box([2, 1, 1]);
    let mut stray = mesh.clone();
    stray.nodes.push([5.0, 5.0, 5.0]);
    let v = mesh.nodes.len();
    let steel = steel();
    let (plain, u) = nonlinear_gauss2(&mesh, std::slice::from_ref(&steel), 1e-3);
    let (asm, mut us) = nonlinear_gauss2(&stray, &[steel], 1e-3);
    us[..u.len()].copy_from_slice(&u);
    let mut k = asm.new_tangent();
    k.values_mut().fill(f64::NAN);
    let a = asm.assemble(&us, Some(&mut k)).unwrap();
    assert!(k.values().iter().all(|x| x.is_finite()));
    assert_eq!(&a.internal[3 * v..], &[0.0; 3]);
    for c in 3 * v..3 * v + 3 {
        assert_eq!(asm.pattern().column(c).len(), 3 * v + 3 - c);
        assert_eq!(k.get(c, c), 0.0);
    }
    let mut kp = plain.new_tangent();
    plain.assemble(&u, Some(&mut kp)).unwrap();
    let kmax = kp.values().iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    for col in 0..plain.n() {
        for &row in plain.pattern().column(col) {
            let (x, y) = (k.get(row, col), kp.get(row, col));
            assert!((x - y).abs() <= 1e-12 * kmax, "({row}, {col})");
        }
    }
}

/// The forces of all cells through `partial_internal` are the assembled internal forces,
/// and the two halves of a split cell list add up to them (to rounding: 1e-12 relative).
#[test]
fn partial_internal_adds_up_to_the_assembly() {
    let mesh = hex20_box([3, 2, 2]);
    let steel = steel();
    let (asm, u) = nonlinear_gauss2(&mesh, &[steel], 1e-3);
    let full = asm.assemble(&u, None).unwrap().internal;
    let all: Vec<usize> = (0..mesh.cells.len()).collect();
    let (a, b) = all.split_at(5);
    let fa = asm.partial_internal(a, &u, Kinematics::Nonlinear).unwrap();
    let fb = asm.partial_internal(b, &u, Kinematics::Nonlinear).unwrap();
    let scale = full.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    for d in 0..asm.n() {
        assert!((fa[d] + fb[d] - full[d]).abs() <= 1e-12 * scale, "dof {d}");
    }
    let lin = asm.partial_internal(&all, &u, Kinematics::Linear).unwrap();
    assert!(
        lin.iter()
            .zip(&full)
            .any(|(l, f)| (l - f).abs() > 1e-9 * scale)
    );
    assert!(asm.partial_internal(&[99], &u, Kinematics::Linear).is_err());
}

/// The slave rows and columns found for one tie set are not reused for another: folding
/// set B after set A on one assembler gives bitwise what a fresh assembler gives for B.
#[test]
fn a_new_tie_set_gets_its_own_slave_positions() {
    let mesh = hex20_box([2, 1, 1]);
    let steel = steel();
    let (mut asm, u) = nonlinear_gauss2(&mesh, &[steel], 1e-3);
    let n = asm.n();
    // The pattern is extended for both sets at once; each is then folded on its own.
    let nodes = &mesh.cells[0].nodes;
    let (p, q) = (3 * nodes[0], 3 * nodes[5]);
    let mut a = Constraints::new(n);
    a.tie(p, &[(q + 1, 0.5)], 0.0).unwrap();
    let mut b = Constraints::new(n);
    b.tie(q, &[(p + 2, -0.3), (p + 1, 0.2)], 1e-4).unwrap();
    let mut both = a.clone();
    both.tie(q, &[(p + 2, -0.3), (p + 1, 0.2)], 1e-4).unwrap();
    asm.tie(&both).unwrap();
    let (mut fresh, _) = nonlinear_gauss2(&mesh, &[steel], 1e-3);
    fresh.tie(&both).unwrap();
    let mut k = asm.new_tangent();
    asm.residual(&u, 1.0, &a, Some(&mut k)).unwrap();
    let got = asm.residual(&u, 1.0, &b, Some(&mut k)).unwrap();
    let mut k_fresh = fresh.new_tangent();
    let want = fresh.residual(&u, 1.0, &b, Some(&mut k_fresh)).unwrap();
    assert!(got == want, "residual or reactions differ");
    assert!(k == k_fresh, "the tangent kept set A's slave positions");
}
