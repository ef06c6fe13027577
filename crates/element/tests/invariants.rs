//! Property tests of the element kernels over random valid distorted elements, SPD
//! orthotropic materials and displacements of realistic size (strains ~2 %, rotations up to
//! 0.3 rad), for every (kind, rule) pair.

use nonlin3d_element::reference::evaluate_reference;
use nonlin3d_element::strategies::{apply, displacements, distorted_element, material, rotation};
use nonlin3d_element::{
    BatchInput, BatchOutput, ElementKind, ElementOutput, IntegrationRule, Kinematics, Prefetch,
    ShapeTable, Workspace, evaluate, evaluate_batch, evaluate_batch_with,
    evaluate_listed_prefetching, evaluate_listed_with,
};
use nonlin3d_laminate::Stiffness;
use proptest::prelude::*;

const CASES: [(ElementKind, IntegrationRule); 4] = [
    (ElementKind::Hex8, IntegrationRule::Gauss2),
    (ElementKind::Hex8, IntegrationRule::SelectiveReduced),
    (ElementKind::Hex20, IntegrationRule::Gauss2),
    (ElementKind::Hex20, IntegrationRule::Gauss3),
];

/// (table, coordinates, displacements, material) for one random case.
fn case(i: usize) -> impl Strategy<Value = (ShapeTable, Vec<[f64; 3]>, Vec<[f64; 3]>, Stiffness)> {
    let (kind, rule) = CASES[i];
    (distorted_element(kind), material()).prop_flat_map(move |(x, m)| {
        let table = ShapeTable::new(kind, rule).unwrap();
        (
            Just(table),
            Just(x.clone()),
            displacements(x, 0.02, 0.3),
            Just(m),
        )
    })
}

fn any_case() -> impl Strategy<Value = (ShapeTable, Vec<[f64; 3]>, Vec<[f64; 3]>, Stiffness)> {
    prop_oneof![case(0), case(1), case(2), case(3)]
}

fn run(
    t: &ShapeTable,
    x: &[[f64; 3]],
    u: &[[f64; 3]],
    m: &Stiffness,
    kin: Kinematics,
) -> ElementOutput {
    let mut out = ElementOutput::new(t);
    let mut ws = Workspace::new(t);
    evaluate(t, x, u, m, kin, true, &mut ws, &mut out).unwrap();
    out
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |a, b| a.max(b.abs()))
}

fn element_size(x: &[[f64; 3]]) -> f64 {
    let d = |a: usize, b: usize| {
        (0..3)
            .map(|r| (x[a][r] - x[b][r]).powi(2))
            .sum::<f64>()
            .sqrt()
    };
    d(0, 6)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, .. ProptestConfig::default() })]

    /// R = ∂U/∂q by central differences. Step h = 1e-7·L: truncation (h/L)² ≈ 1e-14, round-off
    /// ≈ 1e-16·U/h, which relative to the forces is ≲ 1e-16/(1e-7·strain) ≈ 1e-7. Tolerance
    /// 1e-6 of the largest force.
    #[test]
    fn forces_are_the_energy_gradient((t, x, u, m) in any_case()) {
        let out = run(&t, &x, &u, &m, Kinematics::Nonlinear);
        let h = 1e-7 * element_size(&x);
        let tol = 1e-6 * max_abs(&out.forces);
        for a in 0..t.dofs() {
            let (mut up, mut um) = (u.clone(), u.clone());
            up[a / 3][a % 3] += h;
            um[a / 3][a % 3] -= h;
            let ep = run(&t, &x, &up, &m, Kinematics::Nonlinear).energy;
            let em = run(&t, &x, &um, &m, Kinematics::Nonlinear).energy;
            let fd = (ep - em) / (2.0 * h);
            prop_assert!((fd - out.forces[a]).abs() <= tol, "dof {a}: fd {fd} vs {}", out.forces[a]);
        }
    }

    /// K = ∂R/∂q by central differences, same step; forces are smooth (quadratic in q, so the
    /// central difference is exact up to round-off ≈ 1e-16·R/h ≈ 1e-9·K). Tolerance 1e-6 of
    /// the largest entry. Also checks exact symmetry.
    #[test]
    fn tangent_is_the_force_jacobian((t, x, u, m) in any_case()) {
        let out = run(&t, &x, &u, &m, Kinematics::Nonlinear);
        let nd = t.dofs();
        let k = &out.tangent;
        let tol = 1e-6 * max_abs(k);
        let h = 1e-7 * element_size(&x);
        for b in 0..nd {
            let (mut up, mut um) = (u.clone(), u.clone());
            up[b / 3][b % 3] += h;
            um[b / 3][b % 3] -= h;
            let fp = run(&t, &x, &up, &m, Kinematics::Nonlinear).forces;
            let fm = run(&t, &x, &um, &m, Kinematics::Nonlinear).forces;
            for a in 0..nd {
                let fd = (fp[a] - fm[a]) / (2.0 * h);
                prop_assert!((fd - k[a * nd + b]).abs() <= tol, "K[{a}][{b}]: fd {fd} vs {}", k[a * nd + b]);
                prop_assert_eq!(k[a * nd + b], k[b * nd + a]);
            }
        }
    }

    /// Σ TᵀT (+ geometric) equals the textbook Bᵀ C B (+ Σ σ_i a_i) of the reference
    /// implementation, and the forces and energy agree; linear kinematics too. Both sum the
    /// same terms in different orders: 1e-11 of the largest entry covers the round-off.
    #[test]
    fn fast_kernel_equals_textbook_b_c_b((t, x, u, m) in any_case()) {
        for kin in [Kinematics::Nonlinear, Kinematics::Linear] {
            let fast = run(&t, &x, &u, &m, kin);
            let slow = evaluate_reference(&t, &x, &u, &m, kin).unwrap();
            let nd = t.dofs();
            let tol = 1e-11 * max_abs(&fast.tangent);
            for a in 0..nd {
                for b in 0..nd {
                    prop_assert!((fast.tangent[a * nd + b] - slow.tangent[(a, b)]).abs() <= tol);
                }
            }
            let ftol = 1e-11 * max_abs(&fast.forces);
            for a in 0..nd {
                prop_assert!((fast.forces[a] - slow.forces[a]).abs() <= ftol);
            }
            prop_assert!((fast.energy - slow.energy).abs() <= 1e-11 * fast.energy.abs());
        }
    }

    /// A finite rigid rotation R of the deformed element, u′ = R(x + u) − x, leaves the
    /// Green–Lagrange strains and the energy unchanged and rotates the internal forces
    /// (R′ = R·R). Tolerance: 1e-9 relative, the round-off of forming (x + u) at 1e-3 m and
    /// subtracting x back (1e-16·|x|/|u| with |u| ≳ 1e-7·|x|... amplified by 1/strain).
    #[test]
    fn frame_invariance((t, x, u, m) in any_case(), angles in proptest::array::uniform3(-3.0..3.0f64)) {
        let rot = rotation(angles[0], angles[1], angles[2]);
        let u2: Vec<[f64; 3]> = x.iter().zip(&u).map(|(p, d)| {
            let q = apply(&rot, [p[0] + d[0], p[1] + d[1], p[2] + d[2]]);
            [q[0] - p[0], q[1] - p[1], q[2] - p[2]]
        }).collect();
        let a = run(&t, &x, &u, &m, Kinematics::Nonlinear);
        let b = run(&t, &x, &u2, &m, Kinematics::Nonlinear);
        let emax = a.strains.iter().flatten().fold(0.0f64, |s, v| s.max(v.abs()));
        for (ea, eb) in a.strains.iter().zip(&b.strains) {
            for c in 0..6 {
                prop_assert!((ea[c] - eb[c]).abs() <= 1e-9 * emax.max(1e-6));
            }
        }
        prop_assert!((a.energy - b.energy).abs() <= 1e-8 * a.energy.abs().max(1e-30));
        let fmax = max_abs(&a.forces);
        for n in 0..t.nodes() {
            let fa = apply(&rot, [a.forces[3 * n], a.forces[3 * n + 1], a.forces[3 * n + 2]]);
            for r in 0..3 {
                prop_assert!((fa[r] - b.forces[3 * n + r]).abs() <= 1e-8 * fmax);
            }
        }
    }

    /// At zero displacement the nonlinear kernel is the linear one: same (zero) strains,
    /// forces, and the tangent reduces to the linear stiffness bit for bit (F = I, σ = 0).
    #[test]
    fn linear_equals_nonlinear_at_zero_displacement((t, x, _u, m) in any_case()) {
        let zero = vec![[0.0; 3]; t.nodes()];
        let a = run(&t, &x, &zero, &m, Kinematics::Nonlinear);
        let b = run(&t, &x, &zero, &m, Kinematics::Linear);
        prop_assert_eq!(a.tangent, b.tangent);
        prop_assert!(a.forces.iter().all(|&f| f == 0.0));
        prop_assert_eq!(a.energy, 0.0);
    }

    /// A linear displacement field u = A x + b is reproduced exactly by the isoparametric
    /// elements, distorted or not: the strains at every station are the Green–Lagrange strains
    /// of the constant gradient A (the element-level patch test). Round-off: 1e-12·|A|.
    #[test]
    fn homogeneous_deformation_gives_uniform_strain(
        (t, x, _u, m) in any_case(),
        a in proptest::array::uniform3(proptest::array::uniform3(-0.05..0.05f64)),
        shift in proptest::array::uniform3(-1e-4..1e-4f64),
    ) {
        let u: Vec<[f64; 3]> = x.iter().map(|p| {
            let mut v = shift;
            for i in 0..3 { for j in 0..3 { v[i] += a[i][j] * p[j]; } }
            v
        }).collect();
        let out = run(&t, &x, &u, &m, Kinematics::Nonlinear);
        let col = |p: usize, q: usize| (0..3).map(|i| a[i][p] * a[i][q]).sum::<f64>();
        let exact = [
            a[0][0] + 0.5 * col(0, 0),
            a[1][1] + 0.5 * col(1, 1),
            a[2][2] + 0.5 * col(2, 2),
            a[0][1] + a[1][0] + col(0, 1),
            a[1][2] + a[2][1] + col(1, 2),
            a[0][2] + a[2][0] + col(0, 2),
        ];
        for e in &out.strains {
            for c in 0..6 {
                prop_assert!((e[c] - exact[c]).abs() <= 1e-12, "{c}: {} vs {}", e[c], exact[c]);
            }
        }
    }

    /// The batch over many elements equals the single-element kernel bit for bit, and 1 and 2
    /// threads give identical bits.
    #[test]
    fn batch_equals_single_and_is_thread_independent(
        elems in proptest::collection::vec(case(2), 40..80),
    ) {
        let t = elems[0].0.clone();
        let coords: Vec<[f64; 3]> = elems.iter().flat_map(|e| e.1.clone()).collect();
        let disp: Vec<[f64; 3]> = elems.iter().flat_map(|e| e.2.clone()).collect();
        let materials: Vec<Stiffness> = elems.iter().map(|e| e.3).collect();
        let material_of: Vec<usize> = (0..elems.len()).collect();
        let input = BatchInput { coords: &coords, disp: &disp, materials: &materials, material_of: &material_of };
        let mut outs = Vec::new();
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let mut out = BatchOutput::new(&t, elems.len(), true);
            pool.install(|| evaluate_batch(&t, &input, Kinematics::Nonlinear, &mut out)).unwrap();
            outs.push(out);
        }
        prop_assert!(outs[0] == outs[1]);
        let nd = t.dofs();
        // The streaming variant hands the same bits to the consumer, in element order within
        // each chunk and chunks in order, whatever the thread count.
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let states = pool.install(|| evaluate_batch_with(&t, &input, Kinematics::Nonlinear, true, Vec::new, |seen: &mut Vec<(usize, f64, f64)>, e, out| {
                seen.push((e, out.energy, out.tangent[7 * nd + 3]));
            })).unwrap();
            let seen: Vec<(usize, f64, f64)> = states.into_iter().flatten().collect();
            prop_assert_eq!(seen.len(), elems.len());
            for (i, &(e, energy, k73)) in seen.iter().enumerate() {
                prop_assert_eq!(e, i);
                prop_assert_eq!(energy, outs[0].energy[e]);
                prop_assert_eq!(k73, outs[0].tangents[e * nd * nd + 7 * nd + 3]);
            }
        }
        // The listed variant, in reverse order on the calling thread: the same bits per element;
        // an index past the batch is refused.
        let list: Vec<usize> = (0..elems.len()).rev().collect();
        let mut seen = Vec::new();
        evaluate_listed_with(&t, &input, Kinematics::Nonlinear, true, &list, |e, out| {
            seen.push((e, out.energy, out.tangent[7 * nd + 3]));
        }).unwrap();
        prop_assert_eq!(seen.len(), elems.len());
        for (i, &(e, energy, k73)) in seen.iter().enumerate() {
            prop_assert_eq!(e, elems.len() - 1 - i);
            prop_assert_eq!(energy, outs[0].energy[e]);
            prop_assert_eq!(k73, outs[0].tangents[e * nd * nd + 7 * nd + 3]);
        }
        // With prefetch hints (a real buffer for some elements, wild addresses for others) the
        // whole tangent is the same, bit for bit: hints only move cache lines.
        let buffer = vec![0.0f64; 4096];
        let near: Vec<u32> = (0..300).map(|k| (k * 13) % 4096).collect();
        let wild: Vec<u32> = (0..50).map(|k| k * 0x0300_0001).collect();
        let mut hinted = Vec::new();
        evaluate_listed_prefetching(&t, &input, Kinematics::Nonlinear, true, &list, |k| {
            if k % 2 == 0 { Prefetch::new(buffer.as_ptr(), &near) } else { Prefetch::new(std::ptr::null(), &wild) }
        }, |e, out| hinted.push((e, out.tangent.clone()))).unwrap();
        for (e, k) in hinted {
            prop_assert_eq!(&outs[0].tangents[e * nd * nd..(e + 1) * nd * nd], &k[..]);
        }
        let past_the_end = evaluate_listed_with(&t, &input, Kinematics::Nonlinear, false, &[elems.len()], |_, _| ());
        prop_assert!(past_the_end.is_err());
        for (e, (_, x, u, m)) in elems.iter().enumerate() {
            let one = run(&t, x, u, m, Kinematics::Nonlinear);
            prop_assert_eq!(&outs[0].forces[e * nd..(e + 1) * nd], &one.forces[..]);
            prop_assert_eq!(&outs[0].tangents[e * nd * nd..(e + 1) * nd * nd], &one.tangent[..]);
            prop_assert_eq!(outs[0].energy[e], one.energy);
        }
    }
}

proptest! {
    /// Shape functions: partition of unity, gradients sum to zero, and linear fields
    /// reproduced (Σ N^m x^m = x, Σ ∂N^m/∂ξ ⊗ ξ^m = I) at random points; round-off 1e-14.
    #[test]
    fn shape_function_identities(xi in proptest::array::uniform3(-1.0..=1.0f64)) {
        for kind in [ElementKind::Hex8, ElementKind::Hex20] {
            let nn = kind.nodes();
            let mut n = vec![0.0; nn];
            let mut dn = vec![[0.0; 3]; nn];
            kind.shape_values(xi, &mut n);
            kind.shape_gradients(xi, &mut dn);
            prop_assert!((n.iter().sum::<f64>() - 1.0).abs() < 1e-14);
            for r in 0..3 {
                prop_assert!(dn.iter().map(|d| d[r]).sum::<f64>().abs() < 1e-14);
                let interp: f64 = n.iter().zip(kind.reference_nodes()).map(|(v, p)| v * p[r]).sum();
                prop_assert!((interp - xi[r]).abs() < 1e-14);
                for s in 0..3 {
                    let g: f64 = dn.iter().zip(kind.reference_nodes()).map(|(d, p)| d[s] * p[r]).sum();
                    let e = if r == s { 1.0 } else { 0.0 };
                    prop_assert!((g - e).abs() < 1e-14);
                }
            }
        }
    }
}

#[test]
fn inverted_element_and_bad_input_are_located_errors() {
    use nonlin3d_element::ElementError;
    let t = ShapeTable::new(ElementKind::Hex20, IntegrationRule::Gauss2).unwrap();
    let m = nonlin3d_laminate::materials::steel().stiffness().unwrap();
    let mut x: Vec<[f64; 3]> = ElementKind::Hex20
        .reference_nodes()
        .iter()
        .map(|p| [p[0], p[1], p[2]])
        .collect();
    let u = vec![[0.0; 3]; 20];
    // Pull corner 7 through the opposite face: inverted near it.
    x[6] = [-2.0, -2.0, -2.0];
    let mut out = ElementOutput::new(&t);
    let mut ws = Workspace::new(&t);
    let err = evaluate(
        &t,
        &x,
        &u,
        &m,
        Kinematics::Nonlinear,
        true,
        &mut ws,
        &mut out,
    )
    .unwrap_err();
    assert!(
        matches!(err, ElementError::NonPositiveJacobian { element: None, det, .. } if det <= 0.0),
        "{err}"
    );
    x[6] = [1.0, 1.0, f64::NAN];
    let err = evaluate(
        &t,
        &x,
        &u,
        &m,
        Kinematics::Nonlinear,
        true,
        &mut ws,
        &mut out,
    )
    .unwrap_err();
    assert!(
        matches!(
            err,
            ElementError::NonFiniteInput {
                node: 6,
                what: "coordinates",
                ..
            }
        ),
        "{err}"
    );
    x[6] = [1.0, 1.0, 1.0];
    let err = evaluate(
        &t,
        &x[..19],
        &u,
        &m,
        Kinematics::Nonlinear,
        true,
        &mut ws,
        &mut out,
    )
    .unwrap_err();
    assert!(
        matches!(
            err,
            ElementError::LengthMismatch {
                expected: 20,
                got: 19,
                ..
            }
        ),
        "{err}"
    );
    // Selective-reduced Hex8 with a material whose γyz couples with εyy (a ply tilted about
    // x) is refused, naming the material. (C56 alone, from rotation about z, is fine.)
    let sri = ShapeTable::new(ElementKind::Hex8, IntegrationRule::SelectiveReduced).unwrap();
    let (s, c) = 0.5f64.sin_cos();
    let ply = nonlin3d_laminate::materials::generic_graphite_epoxy()
        .stiffness()
        .unwrap()
        .rotated(&[[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
        .unwrap();
    let x8: Vec<[f64; 3]> = x[..8].to_vec();
    let err = nonlin3d_element::linear_stiffness(&sri, &x8, &ply).unwrap_err();
    assert!(
        matches!(err, ElementError::CoupledTransverseShear { .. }),
        "{err}"
    );
    assert!(matches!(
        ShapeTable::new(ElementKind::Hex20, IntegrationRule::SelectiveReduced),
        Err(ElementError::UnsupportedRule { .. })
    ));
    // In a batch the failing element is named.
    let mut coords: Vec<[f64; 3]> = Vec::new();
    for e in 0..5 {
        let mut xe: Vec<[f64; 3]> = ElementKind::Hex20.reference_nodes().to_vec();
        if e == 3 {
            xe[6] = [-2.0, -2.0, -2.0];
        }
        coords.extend(xe);
    }
    let disp = vec![[0.0; 3]; coords.len()];
    let mats = [m];
    let of = [0usize; 5];
    let input = BatchInput {
        coords: &coords,
        disp: &disp,
        materials: &mats,
        material_of: &of,
    };
    let mut bo = BatchOutput::new(&t, 5, false);
    let err = evaluate_batch(&t, &input, Kinematics::Nonlinear, &mut bo).unwrap_err();
    assert!(
        matches!(
            err,
            ElementError::NonPositiveJacobian {
                element: Some(3),
                ..
            }
        ),
        "{err}"
    );
}
