//! VCCT (thesis §2.8) against beam theory and against the energy of two solutions.
//!
//! Beam specimens are the through-width generator with the base as thick as the sublaminate
//! (two arms of thickness h), plane strain (v = 0 on both sides), isotropic aluminium-like
//! material, linear kinematics and small loads.

use nonlin3d::assembly::{Assembler, Constraints};
use nonlin3d::element::{ElementKind, IntegrationRule, Kinematics};
use nonlin3d::laminate::{Orthotropic, ShearCoupling, Stiffness};
use nonlin3d::mesh::{Front, Mesh, ThroughWidthParams, through_width_delamination};
use nonlin3d::newton::{NewtonSettings, StructuralProblem, solve_increment};
use nonlin3d::vcct::{FrontRelease, cells_above, closure_energy, release_rates};

const E: f64 = 70e9;
const NU: f64 = 0.3;

fn material() -> Stiffness {
    Orthotropic::isotropic(E, NU).stiffness().unwrap()
}

/// Plane-strain modulus E′ = E/(1 − ν²).
fn e_plane() -> f64 {
    E / (1.0 - NU * NU)
}

/// Linear solution of `mesh` with `constraints` and nodal `loads` (DOF, N); returns the
/// assembler (for forces and energy) and u.
fn solve_linear(
    mesh: &Mesh,
    constraints: impl FnOnce(&mut Constraints),
    loads: &[(usize, f64)],
) -> (Assembler, Vec<f64>) {
    let asm = Assembler::new(
        mesh,
        &[material()],
        ShearCoupling::Exact,
        IntegrationRule::Gauss2,
        IntegrationRule::Gauss2,
        Kinematics::Linear,
    )
    .unwrap();
    let mut c = Constraints::new(asm.n());
    constraints(&mut c);
    for &(d, f) in loads {
        c.add_load(d, f).unwrap();
    }
    let mut problem = StructuralProblem::new(asm, c).unwrap();
    let settings = NewtonSettings::default();
    let mut solver = settings.solver.build();
    solver
        .analyze(&problem.assembler().pattern().clone())
        .unwrap();
    let mut k = problem.assembler().new_tangent();
    let mut u = vec![0.0; problem.assembler().n()];
    let report = solve_increment(
        &mut problem,
        &mut u,
        1.0,
        &settings,
        solver.as_mut(),
        &mut k,
    )
    .unwrap();
    assert!(report.converged(), "{:?}", report.termination);
    (problem.into_parts().unwrap().0, u)
}

fn rates(mesh: &Mesh, front: &Front, asm: &Assembler, u: &[f64]) -> Vec<FrontRelease> {
    let f = asm
        .partial_internal(&cells_above(front), u, Kinematics::Linear)
        .unwrap();
    release_rates(front, &mesh.nodes, u, &f).unwrap()
}

/// Nodes of `set` with |coordinate `axis` − value| < tol.
fn nodes_at(mesh: &Mesh, set: &str, axis: usize, value: f64) -> Vec<usize> {
    mesh.node_sets[set]
        .iter()
        .copied()
        .filter(|&n| (mesh.nodes[n][axis] - value).abs() < 1e-9)
        .collect()
}

/// A line load of `p` N (total over the width) in direction `dir` on the nodes of `line` (one
/// element across: corners 1/6, the midside 4/6 — the consistent weights of a quadratic edge).
fn line_load(mesh: &Mesh, line: &[usize], width: f64, dir: usize, p: f64) -> Vec<(usize, f64)> {
    line.iter()
        .map(|&n| {
            let y = mesh.nodes[n][1];
            let w = if (y - 0.5 * width).abs() < 1e-9 {
                4.0 / 6.0
            } else {
                1.0 / 6.0
            };
            (3 * n + dir, w * p)
        })
        .collect()
}

/// A DCB from `p` (arms of thickness h = p.h, width b = p.width): opening line loads ±`load`
/// at the arms' mid-planes on x = 0, the uncracked end x = L clamped, plane strain. Returns the
/// mesh, front, assembler and linear solution.
fn solve_dcb(p: &ThroughWidthParams, load: f64) -> (Mesh, Front, Assembler, Vec<f64>) {
    let (h, b) = (p.h, p.width);
    let (mesh, front) = through_width_delamination(p).unwrap();
    let top = nodes_at(&mesh, "x0", 2, 1.5 * h);
    let bottom = nodes_at(&mesh, "x0", 2, 0.5 * h);
    let mut loads = line_load(&mesh, &top, b, 2, load);
    loads.extend(line_load(&mesh, &bottom, b, 2, -load));
    let (asm, u) = solve_linear(
        &mesh,
        |c| {
            for r in 0..3 {
                c.fix_nodes(&mesh.node_sets["x1"], r).unwrap();
            }
            c.fix_nodes(&mesh.node_sets["y0"], 1).unwrap();
            c.fix_nodes(&mesh.node_sets["y1"], 1).unwrap();
        },
        &loads,
    );
    (mesh, front, asm, u)
}

fn beam(
    a: f64,
    length: f64,
    h: f64,
    inside: usize,
    outside: usize,
    grading: f64,
) -> ThroughWidthParams {
    ThroughWidthParams {
        a,
        length,
        width: 1e-3,
        h,
        base: h,
        inside,
        outside,
        front_grading: grading,
        across: 1,
        sub_layers: 2,
        base_layers: 2,
        base_grading: 1.0,
        ..ThroughWidthParams::example()
    }
}

/// Spread of G_T over the corners of a front: (max − min)/mean.
fn spread(r: &[FrontRelease], g: impl Fn(&FrontRelease) -> f64) -> f64 {
    let v: Vec<f64> = r.iter().map(g).collect();
    let (lo, hi) = v
        .iter()
        .fold((f64::MAX, f64::MIN), |m, &x| (m.0.min(x), m.1.max(x)));
    (hi - lo) / (v.iter().sum::<f64>() / v.len() as f64)
}

/// Mode I: double cantilever beam, arms of thickness h, crack length a, opening loads ±P at the
/// cracked end, the uncracked end clamped. Beam theory with the root-rotation correction:
/// G = 12 P² (a + χh)² / (B² E′ h³), χ = 0.67 for isotropic arms (Li, Wang & Thouless, J. Mech.
/// Phys. Solids 52 (2004) 193–214, from 2-D elasticity; Kanninen's elastic-foundation model,
/// Int. J. Fracture 9 (1973) 83–92, gives 0.64 — the two differ by 0.3 % here). Uncorrected
/// beam theory is 6.8 % low at a/h = 20; the tolerance with the correction is 3 %.
#[test]
fn dcb_mode_i_matches_corrected_beam_theory() {
    let (a, h, b) = (20e-3, 1e-3, 1e-3);
    let load = 1.0; // N over the width
    let (mesh, front, asm, u) = solve_dcb(&beam(a, 40e-3, h, 24, 16, 0.3), load);
    let r = rates(&mesh, &front, &asm, &u);
    let g_beam =
        |chi: f64| 12.0 * load * load * (a + chi * h).powi(2) / (b * b * e_plane() * h.powi(3));
    let g = r.iter().map(|x| x.g_i).sum::<f64>() / r.len() as f64;
    eprintln!(
        "DCB: VCCT G_I = {g:.4} J/m², beam {:.4}, corrected (0.67h) {:.4}: ratio {:.4}; G_II/G_I = {:.1e}; spread {:.1e}",
        g_beam(0.0),
        g_beam(0.67),
        g / g_beam(0.67),
        r[0].g_ii / r[0].g_i,
        spread(&r, |x| x.g_t)
    );
    assert!((g / g_beam(0.67) - 1.0).abs() < 0.03);
    // Pure mode I by symmetry: the shear modes vanish to rounding of the solve.
    for x in &r {
        assert!(x.g_ii.abs() < 1e-6 * x.g_i && x.g_iii.abs() < 1e-6 * x.g_i);
        assert!(x.open());
    }
    // Uniform front (plane strain): corner-to-corner spread < 1 %.
    assert!(spread(&r, |x| x.g_t) < 0.01);
}

/// Mode II: end-notched flexure, simply supported span S on the bottom face, load P on the top
/// at x_p ≈ S/2, crack 0 ≤ x < a from the supported end. Beam theory (two arms bending together
/// in the cracked part): G_II = 9 M² / (4 B² E′ h³) with M = R₁·a the moment at the front,
/// R₁ = P (S − x_p)/S (= 9P²a²/(16B²E′h³) for x_p = S/2), corrected a → a + 0.42χh with
/// χ = √(E/11G)·(3 − 2(Γ/(1 + Γ))²), Γ = 1.18 E/G (Wang & Williams, Compos. Sci. Technol. 43
/// (1992) 251–256; χ = 0.905 for ν = 0.3; the formula was fitted for orthotropic arms and
/// over-corrects isotropic ones: measured 0.973 of it with 2 and 4 layers per arm, 1.018 of the
/// uncorrected value). There is no contact in nonlin3d yet, so instead of the lower arm pushing
/// the upper one through the crack faces, both arm ends are supported at x = 0 (w = 0 on the
/// end face): in beam theory each arm then takes half the reaction and the two bend together,
/// exactly the ENF state; the faces neither open nor overlap (|G_I| < 1e-6 G_II asserted).
/// The load-point compliance is checked against beam theory too ((3a³ + 2L³)/(8E′Bh³), 2 %).
#[test]
fn enf_mode_ii_matches_corrected_beam_theory() {
    let (a, h, b, span) = (25e-3, 1.5e-3, 1e-3, 100e-3);
    let p = beam(a, span, h, 30, 50, 0.5);
    let (mesh, front) = through_width_delamination(&p).unwrap();
    // The top node line closest to mid-span carries the load (x_p = 50.15 mm here).
    let top_z = 2.0 * h;
    let xp = mesh
        .nodes
        .iter()
        .filter(|q| (q[2] - top_z).abs() < 1e-9)
        .map(|q| q[0])
        .min_by(|x, y| (x - 0.5 * span).abs().total_cmp(&(y - 0.5 * span).abs()))
        .unwrap();
    let line: Vec<usize> = (0..mesh.nodes.len())
        .filter(|&n| {
            (mesh.nodes[n][2] - top_z).abs() < 1e-9 && (mesh.nodes[n][0] - xp).abs() < 1e-9
        })
        .collect();
    let load = 1.0;
    let loads = line_load(&mesh, &line, b, 2, -load);
    let left = mesh.node_sets["x0"].clone();
    let right = nodes_at(&mesh, "x1", 2, 0.0);
    let (asm, u) = solve_linear(
        &mesh,
        |c| {
            c.fix_nodes(&left, 2).unwrap();
            c.fix_nodes(&right, 2).unwrap();
            c.fix_nodes(&right, 0).unwrap();
            c.fix_nodes(&mesh.node_sets["y0"], 1).unwrap();
            c.fix_nodes(&mesh.node_sets["y1"], 1).unwrap();
        },
        &loads,
    );
    let r = rates(&mesh, &front, &asm, &u);
    let w = line.iter().map(|&n| -u[3 * n + 2]).sum::<f64>() / line.len() as f64;
    let hl = 0.5 * span;
    let beam_w = load * (3.0 * a.powi(3) + 2.0 * hl.powi(3)) / (8.0 * e_plane() * b * h.powi(3));
    eprintln!("ENF load-point deflection {w:e} m, beam theory {beam_w:e}");
    assert!((w / beam_w - 1.0).abs() < 0.02);
    let gr = E / (2.0 * (1.0 + NU));
    let big = 1.18 * E / gr;
    let chi = (E / (11.0 * gr)).sqrt() * (3.0 - 2.0 * (big / (1.0 + big)).powi(2));
    let r1 = load * (span - xp) / span;
    let g_beam = |c: f64| 9.0 * (r1 * (a + c * h)).powi(2) / (4.0 * b * b * e_plane() * h.powi(3));
    let g = r.iter().map(|x| x.g_ii).sum::<f64>() / r.len() as f64;
    let gi = r.iter().map(|x| x.g_i.abs()).fold(0.0, f64::max);
    eprintln!(
        "ENF: x_p = {xp:e}, χ = {chi:.3}; VCCT G_II = {g:.5}, beam {:.5}, corrected {:.5}: ratio {:.4}; |G_I| max {gi:.2e}, G_III {:.1e}",
        g_beam(0.0),
        g_beam(0.42 * chi),
        g / g_beam(0.42 * chi),
        r[0].g_iii
    );
    assert!((g / g_beam(0.42 * chi) - 1.0).abs() < 0.03);
    assert!(gi < 1e-6 * g);
    assert!(spread(&r, |x| x.g_t) < 0.01);
}

/// VCCT against −ΔU/ΔA: two DCB solutions at equal load with the front one element further
/// on; at fixed load G = +ΔU/ΔA of the strain energy (Clapeyron: the compliance energy grows by
/// G·ΔA). The front element must be the same size in both meshes, so both use uniform elements
/// along x and differ by one element inside. 3 % (the bound): the finite difference is a
/// secant over Δa, VCCT the value at the front.
#[test]
fn vcct_matches_the_energy_of_two_solutions() {
    let (h, b, dx) = (1e-3, 1e-3, 0.5e-3);
    let load = 1.0;
    let solve = |kind: ElementKind, cells_inside: usize| {
        let a = dx * cells_inside as f64;
        let p = ThroughWidthParams {
            kind,
            ..beam(a, 40e-3, h, cells_inside, 80 - cells_inside, 1.0)
        };
        let (mesh, front, asm, u) = solve_dcb(&p, load);
        let energy = asm.assemble(&u, None).unwrap().energy;
        let r = rates(&mesh, &front, &asm, &u);
        (energy, closure_energy(&r) / (dx * b), r)
    };
    let (u0, g0, _) = solve(ElementKind::Hex20, 30);
    let (u1, g1, _) = solve(ElementKind::Hex20, 31);
    let g_energy = (u1 - u0) / (dx * b);
    let g_vcct = 0.5 * (g0 + g1);
    eprintln!(
        "ΔU/ΔA = {g_energy:.5} J/m², VCCT {g0:.5} → {g1:.5} (mean {g_vcct:.5}): ratio {:.4}",
        g_vcct / g_energy
    );
    assert!((g_vcct / g_energy - 1.0).abs() < 0.03);
    // Hex8 fronts (corners only, G = Ē/(Δa · half the neighbouring spacings)): the same
    // energy check, and a uniform front.
    let (u0, g0, r0) = solve(ElementKind::Hex8, 30);
    let (u1, g1, _) = solve(ElementKind::Hex8, 31);
    let g_energy = (u1 - u0) / (dx * b);
    let g_vcct = 0.5 * (g0 + g1);
    eprintln!(
        "Hex8: ΔU/ΔA = {g_energy:.5} J/m², VCCT mean {g_vcct:.5}: ratio {:.4}",
        g_vcct / g_energy
    );
    assert!(r0.iter().all(|x| x.g_i > 0.0));
    assert!(spread(&r0, |x| x.g_t) < 0.01);
    assert!((g_vcct / g_energy - 1.0).abs() < 0.03);
}
