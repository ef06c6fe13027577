//! The clamped-box deck generator of `benches/box_deck.rs` (issue 20's 1 M-DOF solve) at a
//! few thousand DOF: the deck it writes reads, checks and solves as a linear static step, and
//! the tip deflection is the cantilever's.

#[path = "../benches/box_deck/deck.rs"]
mod deck;

use deck::BoxDeck;
use nonlin3d::deck::{StepOptions, solve_deck};
use nonlin3d::mesh::read_inp;

/// 16 × 3 × 3 elements, 160 × 12 × 12 mm, 100 N: Timoshenko's tip deflection
/// F L³ / (3 E I) + F L / (κ G A) = 0.37625 + 0.00165 = 0.3779 mm (I = 12⁴/12 mm⁴,
/// κ = 5/6, G = E / 2.6). The deck clamps the whole root face, which also stops its Poisson
/// contraction: that stiffens a zone about h long, a change of order ν h / L = 0.3 · 12/160
/// = 2.3 % at most; Hex20 on 16 cells is far more accurate than that. So 3 %.
#[test]
fn generated_box_deck_solves_to_the_cantilever_deflection() {
    let b = BoxDeck {
        cells: [16, 3, 3],
        size: [160.0, 12.0, 12.0],
        load: 100.0,
    };
    let mut text = Vec::new();
    b.write(&mut text).unwrap();
    let model = read_inp(std::str::from_utf8(&text).unwrap()).unwrap();
    let (dofs, lists) = b.dof_lists();
    assert_eq!(dofs, 3 * model.node_ids.len());
    assert_eq!(lists.len(), 16 * 3 * 3);
    let results = solve_deck(&model, &StepOptions::default()).unwrap();
    let step = results.last().unwrap();
    assert!(step.complete && !step.nlgeom);
    // Mean u_z over the loaded face (nodes at x = 160 mm).
    let tip: Vec<f64> = model
        .mesh
        .nodes
        .iter()
        .zip(&step.displacements)
        .filter(|(x, _)| (x[0] - 160.0).abs() < 1e-9)
        .map(|(_, u)| u[2])
        .collect();
    assert_eq!(tip.len(), 7 * 7 - 9);
    let mean = tip.iter().sum::<f64>() / tip.len() as f64;
    let e = 210_000.0;
    let (i, a, g) = (12f64.powi(4) / 12.0, 144.0, 210_000.0 / 2.6);
    let beam = 100.0 * 160f64.powi(3) / (3.0 * e * i) + 100.0 * 160.0 / (5.0 / 6.0 * g * a);
    eprintln!("tip deflection {:.5} mm, beam {beam:.5} mm", -mean);
    assert!((-mean / beam - 1.0).abs() < 0.03, "{mean} vs {beam}");
}
