//! Decks written by `nonlin3d_mesh::inp` run unchanged in CalculiX 2.20, and CalculiX's linear
//! displacements equal those of nonlin3d's own element kernels (C3D20 ↔ Hex20 3×3×3) and sparse
//! solver: an isotropic steel cantilever, and a graphite/epoxy block with its plies at 30°
//! (which checks the `*ORIENTATION` convention against `Stiffness::rotated_about_z`).
//!
//! Needs `ccx` on PATH. Outside CI the test is skipped with a notice when it is missing; in CI
//! (`CI` set) a missing `ccx` fails it, and `.ci/run` installs it.

mod common;

use nonlin3d::element::{ElementKind, IntegrationRule, ShapeTable, linear_stiffness};
use nonlin3d::laminate::{ShearCoupling, Stiffness, materials};
use nonlin3d::mesh::inp::{
    InpBoundary, InpCload, InpDeck, InpElastic, InpMaterial, InpStep, inp_string,
};
use nonlin3d::mesh::{BoxParams, Mesh, structured_box};
use nonlin3d::solver::{SolverKind, SymmetricMatrix, SymmetricPattern, solve};
use std::path::Path;
use std::sync::Arc;

/// Runs `ccx` on `deck` in a fresh directory and returns the node displacements of the last
/// step from its .dat file, by node index.
fn run_ccx(name: &str, deck: &str, nodes: usize) -> Vec<[f64; 3]> {
    run_ccx_blocks(name, deck, nodes)
        .pop()
        .map(|b| b.1)
        .unwrap_or_else(|| vec![[f64::NAN; 3]; nodes])
}

/// Runs `ccx` and returns every printed displacement block: (total time, displacements by node
/// index). With steps of period 1, the block at time k is the end of step k.
fn run_ccx_blocks(name: &str, deck: &str, nodes: usize) -> Vec<(f64, Vec<[f64; 3]>)> {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join(format!("{name}.inp")), deck).unwrap();
    let dat = common::ccx::run(&dir, name);
    let mut blocks = Vec::new();
    for block in dat.split("displacements").skip(1) {
        let mut lines = block.lines();
        let time = lines
            .next()
            .and_then(|h| h.split_whitespace().last())
            .and_then(|t| t.parse::<f64>().ok())
            .unwrap_or(f64::NAN);
        let mut u = vec![[f64::NAN; 3]; nodes];
        for line in lines {
            let f: Vec<&str> = line.split_whitespace().collect();
            if f.len() != 4 {
                if !f.is_empty() {
                    break;
                }
                continue;
            }
            let (Ok(id), Ok(x), Ok(y), Ok(z)) = (
                f[0].parse::<usize>(),
                f[1].parse::<f64>(),
                f[2].parse::<f64>(),
                f[3].parse::<f64>(),
            ) else {
                break;
            };
            u[id - 1] = [x, y, z];
        }
        blocks.push((time, u));
    }
    blocks
}

/// nonlin3d's linear solution: Hex20 3×3×3 stiffness, clamped set, point loads.
fn solve_linear(
    mesh: &Mesh,
    stiffness: &[Stiffness],
    clamped: &str,
    loads: &[InpCload],
) -> Vec<[f64; 3]> {
    let table = ShapeTable::new(ElementKind::Hex20, IntegrationRule::Gauss3).unwrap();
    let n = 3 * mesh.nodes.len();
    let dofs = mesh.cell_dofs();
    let pattern = Arc::new(SymmetricPattern::from_dof_lists(n, &dofs).unwrap());
    let mut k = SymmetricMatrix::zeros(pattern);
    let mut fixed = vec![false; n];
    for &node in &mesh.node_sets[clamped] {
        for r in 0..3 {
            fixed[3 * node + r] = true;
        }
    }
    for (c, cell) in mesh.cells.iter().enumerate() {
        let mut ke = linear_stiffness(&table, &mesh.cell_coordinates(c), &stiffness[c]).unwrap();
        let ne = dofs[c].len();
        for a in 0..ne {
            for b in 0..ne {
                if fixed[dofs[c][a]] || fixed[dofs[c][b]] {
                    ke[a * ne + b] = 0.0;
                }
            }
        }
        let _ = cell;
        k.scatter_add(&dofs[c], &ke).unwrap();
    }
    let mut f = vec![0.0; n];
    for d in (0..n).filter(|&d| fixed[d]) {
        k.add(d, d, 1.0).unwrap();
    }
    for l in loads {
        f[3 * l.node + l.dof as usize - 1] += l.value;
    }
    let (x, _) = solve(SolverKind::FaerLdlt, &k, &f).unwrap();
    x.chunks(3).map(|c| [c[0], c[1], c[2]]).collect()
}

fn compare(ours: &[[f64; 3]], theirs: &[[f64; 3]]) -> f64 {
    let scale = ours.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
    let diff = ours
        .iter()
        .flatten()
        .zip(theirs.iter().flatten())
        .fold(0.0f64, |a, (p, q)| a.max((p - q).abs()));
    assert!(scale > 0.0 && diff.is_finite());
    eprintln!("max |u_nonlin3d − u_ccx| / max |u| = {:.2e}", diff / scale);
    diff / scale
}

/// Isotropic steel as a deck material.
fn steel_material() -> [InpMaterial; 1] {
    let steel = materials::steel();
    [InpMaterial {
        name: "STEEL".into(),
        elastic: InpElastic::Isotropic {
            e: steel.e11,
            nu: steel.nu12,
        },
    }]
}

/// `mesh` in steel, clamped on `x0` under `loads`: CalculiX's linear solution of our deck
/// against ours, as [`compare`] measures it.
fn steel_against_ccx(name: &str, mesh: &Mesh, loads: &[InpCload]) -> f64 {
    let deck = linear_deck(&format!("nonlin3d {name}"), mesh, &steel_material(), loads);
    let theirs = run_ccx(name, &deck, mesh.nodes.len());
    let steel = materials::steel().stiffness().unwrap();
    let ours = solve_linear(mesh, &vec![steel; mesh.cells.len()], "x0", loads);
    compare(&ours, &theirs)
}

/// A one-step linear deck clamping `x0` under `loads`.
fn linear_deck(
    heading: &str,
    mesh: &Mesh,
    materials: &[InpMaterial],
    loads: &[InpCload],
) -> String {
    let step = InpStep {
        nlgeom: false,
        increment: 1.0,
        period: 1.0,
        boundaries: vec![InpBoundary {
            nset: "x0".into(),
            first: 1,
            last: 3,
            value: 0.0,
        }],
        cloads: loads.to_vec(),
    };
    inp_string(&InpDeck {
        heading: heading.into(),
        mesh,
        materials,
        steps: vec![step],
    })
    .unwrap()
}

fn tip_loads(mesh: &Mesh, total: f64, dof: u8) -> Vec<InpCload> {
    let tip = &mesh.node_sets["x1"];
    tip.iter()
        .map(|&node| InpCload {
            node,
            dof,
            value: total / tip.len() as f64,
        })
        .collect()
}

#[test]
fn calculix_runs_our_decks_and_agrees_with_our_linear_solution() {
    if !common::ccx::available() {
        return;
    }
    // 1. Steel cantilever 30 × 5 × 4 mm, 6 × 2 × 2 C3D20, clamped at x = 0, 100 N down at x = L.
    let mesh = structured_box(&BoxParams::new(
        ElementKind::Hex20,
        [6, 2, 2],
        [30e-3, 5e-3, 4e-3],
    ))
    .unwrap();
    let loads = tip_loads(&mesh, -100.0, 3);
    let step = |nlgeom: bool| InpStep {
        nlgeom,
        increment: 1.0,
        period: 1.0,
        boundaries: vec![InpBoundary {
            nset: "x0".into(),
            first: 1,
            last: 3,
            value: 0.0,
        }],
        cloads: loads.clone(),
    };
    let mats = steel_material();
    // Same element, same quadrature, both direct solvers in double precision: agreement to
    // round-off of κ(K) ≈ 1e8 times 1e-16, far below the 1e-8 asserted; CalculiX prints 6–7
    // significant digits in the .dat file, which sets the floor (≈ 1e-6 relative).
    let rel = steel_against_ccx("cantilever", &mesh, &loads);
    assert!(rel < 2e-6, "cantilever: max relative difference {rel:e}");
    // The NLGEOM variant of the deck runs unchanged too.
    let deck_nl = inp_string(&InpDeck {
        heading: "nonlin3d cantilever NLGEOM".into(),
        mesh: &mesh,
        materials: &mats,
        steps: vec![step(true)],
    })
    .unwrap();
    let theirs_nl = run_ccx("cantilever_nlgeom", &deck_nl, mesh.nodes.len());
    assert!(theirs_nl.iter().flatten().all(|v| v.is_finite()));

    // 2. Graphite/epoxy block with plies at 30° (ENGINEERING CONSTANTS + ORIENTATION) against
    // our exact rotation of C about z.
    let mut block = structured_box(&BoxParams::new(
        ElementKind::Hex20,
        [4, 3, 2],
        [8e-3, 6e-3, 2e-3],
    ))
    .unwrap();
    for c in &mut block.cells {
        c.ply_angle_deg = 30.0;
    }
    let ge = materials::generic_graphite_epoxy();
    let rotated = ge
        .stiffness()
        .unwrap()
        .rotated_about_z(30f64.to_radians(), ShearCoupling::Exact)
        .unwrap();
    let loads = [tip_loads(&block, 50.0, 1), tip_loads(&block, -20.0, 3)].concat();
    let mats = [InpMaterial {
        name: "GR-EP".into(),
        elastic: InpElastic::Engineering(ge),
    }];
    let deck = linear_deck(
        "nonlin3d orthotropic block at 30 degrees",
        &block,
        &mats,
        &loads,
    );
    let theirs = run_ccx("ortho30", &deck, block.nodes.len());
    let ours = solve_linear(&block, &vec![rotated; block.cells.len()], "x0", &loads);
    let rel = compare(&ours, &theirs);
    assert!(
        rel < 2e-6,
        "orthotropic 30° block: max relative difference {rel:e}"
    );
    // And the same block through ANISO with the rotated C, no orientation.
    for c in &mut block.cells {
        c.ply_angle_deg = 0.0;
    }
    let mats = [InpMaterial {
        name: "GR-EP-30".into(),
        elastic: InpElastic::Anisotropic(Box::new(rotated)),
    }];
    let deck = linear_deck("nonlin3d aniso block", &block, &mats, &loads);
    let theirs = run_ccx("aniso30", &deck, block.nodes.len());
    let rel = compare(&ours, &theirs);
    assert!(rel < 2e-6, "ANISO block: max relative difference {rel:e}");
    // The unrotated ply through ORTHO with a 30° orientation.
    for c in &mut block.cells {
        c.ply_angle_deg = 30.0;
    }
    let mats = [InpMaterial {
        name: "GR-EP-ORTHO".into(),
        elastic: InpElastic::Orthotropic(Box::new(ge.stiffness().unwrap())),
    }];
    let deck = linear_deck("nonlin3d ortho block", &block, &mats, &loads);
    let theirs = run_ccx("ortho_d30", &deck, block.nodes.len());
    let rel = compare(&ours, &theirs);
    assert!(rel < 2e-6, "ORTHO block: max relative difference {rel:e}");
}

/// Curved Hex20 edges (`MidEdges::Mapped`, docs/MESH.md): an embedded-delamination mesh with
/// its front band's rings curved, steel, clamped on x = 0 and pulled down on x = W, solved by
/// CalculiX from our deck and by nonlin3d. The same isoparametric C3D20 on the same mid-edge
/// nodes gives the same linear solution (to the printed digits, as above); a mid-edge node read
/// or placed differently would not.
#[test]
fn calculix_reads_curved_mid_edge_nodes_as_we_do() {
    if !common::ccx::available() {
        return;
    }
    use nonlin3d::mesh::{EmbeddedParams, FrontBand, MidEdges, embedded_delamination_with_front};
    let p = EmbeddedParams {
        slices: 2,
        radial_inside: 3,
        radial_outside: 3,
        sub_layers: 1,
        base_layers: 2,
        front_band: Some(FrontBand {
            inside: 1,
            outside: 1,
        }),
        mid_edges: MidEdges::Mapped,
        ..EmbeddedParams::thesis_reference()
    };
    let (mesh, front) = embedded_delamination_with_front(&p).unwrap();
    // The front's mid-edge nodes are on the circle, off their chords' midpoints.
    let mid = front.points.iter().find(|f| !f.corner).unwrap().c;
    let x = mesh.nodes[mid];
    assert!((x[0].hypot(x[1]) - p.a).abs() < 1e-15);
    let loads = tip_loads(&mesh, -100.0, 3);
    let rel = steel_against_ccx("curved", &mesh, &loads);
    assert!(
        rel < 2e-6,
        "curved embedded mesh: max relative difference {rel:e}"
    );
}

/// Geometrically nonlinear: the same cantilever under a 3 kN tip load (linear deflection ≈ 16 %
/// of the span), solved by nonlin3d's Newton path following (Hex20 3×3×3, total Lagrangian,
/// St. Venant–Kirchhoff, dead loads) and by CalculiX with NLGEOM (C3D20, same material law and
/// loads). The converged equilibria are the same discrete solution; the difference measures
/// the two codes' convergence tolerances and the 7 printed digits.
#[test]
fn calculix_nlgeom_agrees_with_our_newton_solution() {
    use nonlin3d::assembly::{Assembler, Constraints};
    use nonlin3d::element::Kinematics;
    use nonlin3d::newton::{NewtonSettings, Stepping, StructuralProblem, follow_path};
    if !common::ccx::available() {
        return;
    }
    let mesh = structured_box(&BoxParams::new(
        ElementKind::Hex20,
        [6, 2, 2],
        [30e-3, 5e-3, 4e-3],
    ))
    .unwrap();
    let steel = materials::steel();
    let loads = tip_loads(&mesh, -3000.0, 3);
    let mats = [InpMaterial {
        name: "STEEL".into(),
        elastic: InpElastic::Isotropic {
            e: steel.e11,
            nu: steel.nu12,
        },
    }];
    let step = InpStep {
        nlgeom: true,
        increment: 0.1,
        period: 1.0,
        boundaries: vec![InpBoundary {
            nset: "x0".into(),
            first: 1,
            last: 3,
            value: 0.0,
        }],
        cloads: loads.clone(),
    };
    let deck = inp_string(&InpDeck {
        heading: "nonlin3d NLGEOM cantilever".into(),
        mesh: &mesh,
        materials: &mats,
        steps: vec![step],
    })
    .unwrap();
    let theirs = run_ccx("nlgeom_cantilever", &deck, mesh.nodes.len());

    let assembler = Assembler::new(
        &mesh,
        &[steel.stiffness().unwrap()],
        ShearCoupling::Exact,
        IntegrationRule::Gauss3,
        IntegrationRule::Gauss2,
        Kinematics::Nonlinear,
    )
    .unwrap();
    let mut constraints = Constraints::new(assembler.n());
    for r in 0..3 {
        constraints.fix_nodes(&mesh.node_sets["x0"], r).unwrap();
    }
    for l in &loads {
        constraints
            .add_load(3 * l.node + l.dof as usize - 1, l.value)
            .unwrap();
    }
    let mut problem = StructuralProblem::new(assembler, constraints).unwrap();
    let mut u = vec![0.0; problem.assembler().n()];
    let settings = NewtonSettings {
        force_tolerance: 1e-6,
        relative_tolerance: 1e-10,
        ..NewtonSettings::default()
    };
    let path = follow_path(
        &mut problem,
        &mut u,
        &[1.0],
        &settings,
        &Stepping::default(),
    )
    .unwrap();
    let ours: Vec<[f64; 3]> = u.chunks(3).map(|c| [c[0], c[1], c[2]]).collect();
    let rel = compare(&ours, &theirs);
    // Against the linear solution the tip moves by a few per cent: the comparison is sensitive.
    let linear = solve_linear(
        &mesh,
        &vec![steel.stiffness().unwrap(); mesh.cells.len()],
        "x0",
        &loads,
    );
    let nonlinearity = compare(&ours, &linear);
    eprintln!(
        "NLGEOM: {} increments, nonlinear vs linear {:.2e}, vs CalculiX {rel:.2e}",
        path.attempts.len(),
        nonlinearity
    );
    assert!(
        nonlinearity > 1e-2,
        "the load must be in the nonlinear range"
    );
    assert!(
        rel < 1e-4,
        "NLGEOM cantilever: max relative difference {rel:e}"
    );
    for a in &path.attempts {
        assert!(a.converged());
        assert_eq!(a.negative_pivots(), Some(0));
    }
}

/// `nonlin3d export` → CalculiX: the exported deck of a coarse embedded-delamination scene
/// (4 slices, two strains above buckling) runs unchanged, and CalculiX's postbuckled state at
/// each level (end of the perturbation-removal step) matches `nonlin3d run`'s: centre
/// deflection within 0.5 % (measured < 0.001 %, the digits CalculiX prints: both use the same mesh, the 2×2×2 rule (C3D20R)
/// and NLGEOM total Lagrangian; the difference is each code's residual tolerance).
#[test]
fn calculix_runs_the_exported_scene_and_lands_on_the_same_buckled_branch() {
    if !common::ccx::available() {
        return;
    }
    let mut scene = nonlin3d::Scene::from_toml(
        &nonlin3d::scene::THESIS_SCENE
            .replace("slices = 8", "slices = 4")
            .replace(
                "strains = [-0.001, -0.002, -0.003, -0.004, -0.005]",
                "strains = [-0.002, -0.003]",
            ),
    )
    .unwrap();
    // Both without contact (the default `auto` engages it in `run` once the faces overlap, at
    // −0.003 here, and `export` writes it only for `on`): tests/calculix_contact.rs compares
    // the two with contact.
    scene.contact.crack_faces = nonlin3d::scene::CrackFacesName::Off;
    let ours = nonlin3d::analysis::run(&scene, &mut |_| Ok(())).unwrap();
    let model = ours.model_data.as_ref().unwrap();
    let deck = nonlin3d::export::deck_of(&scene, model).unwrap();
    let blocks = run_ccx_blocks("scene", &deck, model.mesh.nodes.len());
    let top = model.mesh.node_sets["center_top"][0];
    for (k, level) in ours.levels.iter().enumerate() {
        let end = 2.0 * (k + 1) as f64;
        let (_, theirs) = blocks
            .iter()
            .find(|(t, _)| (t - end).abs() < 1e-9)
            .unwrap_or_else(|| panic!("no CalculiX output at the end of step {end}"));
        let w_ours = level.displacements[3 * top + 2];
        let w_ccx = theirs[top][2];
        eprintln!(
            "strain {}: centre w nonlin3d {w_ours:e} m, CalculiX {w_ccx:e} m ({:+.3} %)",
            level.value,
            100.0 * (w_ccx / w_ours - 1.0)
        );
        assert!(w_ours > 0.1 * 0.4e-3);
        assert!((w_ccx / w_ours - 1.0).abs() < 5e-3);
    }
}

#[path = "decks/dat.rs"]
#[allow(dead_code)]
mod dat;

/// The feature decks' committed CalculiX answers (`tests/decks/NAME.ccx.dat`, which
/// `tests/decks.rs` compares nonlin3d with) are what the installed CalculiX computes: each
/// deck is run again in a scratch folder with its included mesh, and every block equals the
/// committed one to the 7 printed digits (same program, same input: 1e-6 of the block's
/// largest value leaves room for a last-digit difference from another build).
#[test]
fn calculix_reproduces_the_committed_deck_answers() {
    if !common::ccx::available() {
        return;
    }
    let decks = Path::new("tests/decks");
    for name in common::ccx::FEATURE_DECKS {
        let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("ccx-{name}"));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        for f in [
            "cantilever_mesh.inp",
            "block_mesh.inp",
            &format!("{name}.inp"),
        ] {
            std::fs::copy(decks.join(f), dir.join(f)).unwrap();
        }
        let now = dat::parse_dat(&common::ccx::run(&dir, name));
        let committed = dat::parse_dat(
            &std::fs::read_to_string(decks.join(format!("{name}.ccx.dat"))).unwrap(),
        );
        let worst = dat::compare(name, &now, &committed)
            .into_iter()
            .fold(0.0f64, |a, b| a.max(b.1));
        eprintln!("{name}: CalculiX now vs committed {worst:.1e}");
        assert!(worst <= 1e-6, "{name}: {worst:e}");
    }
}
