//! Crack-face contact (thesis §2.7) against CalculiX 2.20 beyond the 30 mm circle of
//! tests/calculix_contact.rs: a thick sublaminate past its buckling strain, where the faces
//! behind the front on the load axis press on the base, and a semicircular edge delamination
//! (§5.5). Each scene is exported by `nonlin3d export` with its `*CONTACT PAIR` (node to
//! surface, hard, CalculiX's penalty K = 100·C₃₃/t) and run by `ccx`; nonlin3d holds the
//! pairs exactly (ties on the weighted gaps g̃ ≥ 0). Compared at the level's end: the closed
//! pairs one by one, the centre deflection, the total contact force and G along the front.

mod common;

use nonlin3d::results::{Faces, Results};
use nonlin3d::scene::Scene;
use nonlin3d_contact::CrackFaces;
use std::path::Path;

/// A scene of examples/scenes/ with the text edits `edits` (each must apply), coarsened to
/// `slices`, with contact `on` and `strains`.
fn scene(file: &str, edits: &[(&str, &str)], slices: usize, strains: &[f64]) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("examples/scenes")
        .join(file);
    let mut text = std::fs::read_to_string(path).unwrap();
    for (from, to) in edits {
        assert!(text.contains(from), "{file}: no {from:?}");
        text = text.replace(from, to);
    }
    let mut s = Scene::from_toml(&text).unwrap();
    s.mesh.slices = Some(slices);
    s.loads.strains = strains.to_vec();
    s.contact.crack_faces = nonlin3d::contact::CrackFacesName::On;
    s
}

/// What is compared at the end of the last level, in one code's displacements.
#[derive(Debug)]
struct Measures {
    /// Centre deflection (the `center_top` node), m.
    centre: f64,
    /// Pairs whose faces touch: weighted gap g̃ = T⁻ᵀ g below 1e-8 m (the basis of nonlin3d's
    /// contact test; g the normal gaps in nonlin3d, w_up − w_low in CalculiX).
    touching: Vec<usize>,
    /// Nodal gaps g of the pairs, m.
    gaps: Vec<f64>,
    /// Contact force on each upper crack-face node, N (pressing the faces together positive):
    /// f_int,z, the internal forces of all cells at these displacements (in equilibrium the
    /// contact force is the only load there once the perturbation force is off).
    forces: Vec<f64>,
    /// Σ `forces`, N.
    force: f64,
    /// G_T along the front by nonlin3d's VCCT (`front_table`, no contact applied), J/m².
    g_t: Vec<f64>,
}

/// The measures of displacements `u` (m) of `model`, with nodal gaps `gaps`.
fn measures(s: &Scene, model: &nonlin3d::model::Model, u: &[f64], gaps: Vec<f64>) -> Measures {
    let faces = CrackFaces::from_mesh(&model.mesh).unwrap();
    let problem = nonlin3d::analysis::build_problem(s, model).unwrap();
    let f = problem.assembler().assemble(u, None).unwrap().internal;
    let up = &model.mesh.node_sets["crack_upper"];
    let w = faces.weighted_gaps(&gaps);
    Measures {
        centre: u[3 * model.mesh.node_sets["center_top"][0] + 2],
        touching: (0..w.len()).filter(|&i| w[i] < 1e-8).collect(),
        gaps,
        forces: up.iter().map(|&v| f[3 * v + 2]).collect(),
        force: up.iter().map(|&v| f[3 * v + 2]).sum::<f64>(),
        g_t: nonlin3d::analysis::front_table(s, model, &problem, u)
            .unwrap()
            .iter()
            .map(|r| r.g_i + r.g_ii + r.g_iii)
            .collect(),
    }
}

/// nonlin3d (`run`) and CalculiX (the exported deck) at the end of the last level.
fn both(s: &Scene, name: &str) -> (Results, Measures, Measures) {
    let ours = nonlin3d::analysis::run(s, &mut |_| Ok(())).unwrap();
    let model = ours.model_data.as_ref().unwrap();
    let text = nonlin3d::export::deck_of(s, model).unwrap();
    assert!(text.contains("*CONTACT PAIR"));
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("ccx-{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join(format!("{name}.inp")), &text).unwrap();
    let blocks = common::ccx::displacements(&common::ccx::run(&dir, name), model.mesh.nodes.len());
    // Two steps per level: the last step's end is the last level's state.
    let end = (2 * s.loads.strains.len()) as f64;
    let (_, u) = blocks
        .iter()
        .find(|(t, _)| (t - end).abs() < 1e-9)
        .unwrap_or_else(|| panic!("no CalculiX output at the end of step {end}"));
    let faces = CrackFaces::from_mesh(&model.mesh).unwrap();
    let level = ours.levels.last().unwrap();
    // With contact no front point overlaps, and a closed one has G_I = 0.
    assert_eq!(level.overlapped(), 0, "{name}");
    for row in level.front.iter().filter(|r| r.faces == Faces::Closed) {
        assert_eq!(row.g_i, 0.0, "{name}: S = {} mm", row.s_mm);
    }
    let n = faces.normals(&level.displacements).unwrap();
    let g_ours = faces.gaps(&level.displacements, &n);
    let g_ccx = faces
        .pairs()
        .iter()
        .map(|p| u[3 * p.upper + 2] - u[3 * p.lower + 2])
        .collect();
    let m_ours = measures(s, model, &level.displacements, g_ours);
    let m_ccx = measures(s, model, u, g_ccx);
    eprintln!(
        "{name}: centre w nonlin3d {:.6} mm, CalculiX {:.6} mm ({:+.2e}); touching nonlin3d \
         {:?}, CalculiX {:?}; contact force nonlin3d {:.4} N, CalculiX {:.4} N; CalculiX's \
         largest overclosure {:.2e} mm",
        m_ours.centre * 1e3,
        m_ccx.centre * 1e3,
        m_ccx.centre / m_ours.centre - 1.0,
        m_ours.touching,
        m_ccx.touching,
        m_ours.force,
        m_ccx.force,
        m_ccx.gaps.iter().fold(0.0f64, |a, &g| a.max(-g)) * 1e3,
    );
    for (k, (a, b)) in m_ours.g_t.iter().zip(&m_ccx.g_t).enumerate() {
        eprintln!("{name}: point {k}: G_T nonlin3d {a:.3}, CalculiX {b:.3} J/m²");
    }
    for i in 0..m_ours.gaps.len() {
        if m_ours.forces[i].abs().max(m_ccx.forces[i].abs()) > 0.1 || m_ours.touching.contains(&i) {
            eprintln!(
                "{name}: pair {i}: g nonlin3d {:.2e} mm, CalculiX {:.2e} mm; force nonlin3d {:.4} N, CalculiX {:.4} N",
                m_ours.gaps[i] * 1e3,
                m_ccx.gaps[i] * 1e3,
                m_ours.forces[i],
                m_ccx.forces[i]
            );
        }
    }
    (ours, m_ours, m_ccx)
}

/// The checks common to both cases, with `extra` the most pairs nonlin3d may close beyond
/// CalculiX's and `force_ratio` the least F_CalculiX / F_nonlin3d:
/// - every pair that touches in CalculiX touches in nonlin3d; nonlin3d's extra pairs (at most
///   `extra`) are open by less than 1.5e-6 m in CalculiX. The two codes state contact
///   differently: nonlin3d holds the weighted gap g̃ = T⁻ᵀ g at 0 (a weak condition on the
///   quadratic face, which lets a closed pair keep nodal gaps of a few µm), CalculiX's
///   node-to-surface penalty each slave node's own gap (overclosure ≤ 1e-8 m here); 1.5e-6 m
///   is the bound tests/calculix_contact.rs states for the same difference;
/// - centre deflection within 0.5 % (as tests/calculix_contact.rs);
/// - G_T along the front (nonlin3d's VCCT from each code's displacements) within 1 % of its
///   largest value (G goes as the square of the deflection: twice 0.5 %);
/// - the total contact force compressive in both, and nonlin3d's the larger: it holds the
///   stricter admissible set (pairs CalculiX leaves open by µm, nodal gaps of µm it keeps
///   open), so the base pushes harder; CalculiX's at least `force_ratio` of it.
fn check(name: &str, a: &Measures, b: &Measures, extra: usize, force_ratio: f64) {
    assert!(
        b.touching.iter().all(|i| a.touching.contains(i)),
        "{name}: touching nonlin3d {:?}, CalculiX {:?}",
        a.touching,
        b.touching
    );
    let more: Vec<usize> = a
        .touching
        .iter()
        .copied()
        .filter(|i| !b.touching.contains(i))
        .collect();
    assert!(more.len() <= extra, "{name}: {more:?}");
    for &i in &more {
        assert!(
            b.gaps[i] < 1.5e-6,
            "{name}: pair {i} open by {:e} m",
            b.gaps[i]
        );
    }
    assert!(!b.touching.is_empty(), "{name}: no contact in CalculiX");
    assert!((b.centre / a.centre - 1.0).abs() < 5e-3, "{name}");
    let gt_max = a.g_t.iter().fold(0.0f64, |m, &g| m.max(g.abs()));
    let gt_diff = a
        .g_t
        .iter()
        .zip(&b.g_t)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    assert!(
        gt_diff <= 1e-2 * gt_max,
        "{name}: {gt_diff} of {gt_max} J/m²"
    );
    assert!(
        b.force > 0.0 && b.force <= a.force && b.force >= force_ratio * a.force,
        "{name}: contact force nonlin3d {} N, CalculiX {} N",
        a.force,
        b.force
    );
}

/// Thick sublaminate: h = 1.0 mm over the 30 mm circle (base 4 mm, 4 slices, 1123 nodes),
/// ε = −0.012, past its bifurcation (between −0.009 and −0.00975); without contact 2 of 5
/// front points overlap, with contact pairs behind the front on the load axis close.
#[test]
fn thick_sublaminate_against_calculix() {
    if !common::ccx::available() {
        return;
    }
    let s = scene(
        "fig_5_1_3_circle_30mm_contact.toml",
        &[("h_mm = 0.4 ", "h_mm = 1.0 ")],
        4,
        &[-0.012],
    );
    let (ours, a, b) = both(&s, "thick");
    let level = ours.levels.last().unwrap();
    assert!(level.contact.as_ref().unwrap().pairs_closed > 0);
    // The corner on the load axis (S = 23.41 mm) is held closed.
    assert!(level.front.iter().any(|r| r.faces == Faces::Closed));
    check("thick", &a, &b, 1, 0.75);
}

/// Edge delamination: the 15 mm semicircle of Fig. 5.5.1 (h = 0.4 mm, base 4 mm) on 2 slices,
/// ε = −0.004 (bifurcation between −0.00125 and −0.0015 on 4 slices).
#[test]
fn edge_delamination_against_calculix() {
    if !common::ccx::available() {
        return;
    }
    let s = scene("fig_5_5_1_edge_semicircle_15mm.toml", &[], 2, &[-0.004]);
    let (ours, a, b) = both(&s, "edge");
    let closed = ours
        .levels
        .last()
        .unwrap()
        .contact
        .as_ref()
        .unwrap()
        .pairs_closed;
    assert!(closed > 0);
    check("edge", &a, &b, 0, 0.25);
}
