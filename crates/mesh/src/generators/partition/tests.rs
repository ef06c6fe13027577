//! Tests of the thesis's partition (§3.2, Fig. 3.2.2) on every delamination model the
//! generators make: properties, not counts (the counts are printed).
#![allow(clippy::unwrap_used)]

use super::*;
use crate::generators::{
    EllipticMap, EmbeddedParams, PlyLayout, ThroughWidthParams, edge_delamination,
    embedded_delamination, thin_film, through_width_delamination,
};
use nonlin3d_element::ElementKind;

/// The checks every thesis partition must pass, for ℓ > 0: its cells are sublaminate cells
/// whose nodes all lie ≥ ℓ inside the front; every other sublaminate cell has a node closer
/// than ℓ (the set is the largest such); every cell with a node on the front is linear; the
/// interface nodes are used by no base cell (the crack faces are split, so the contour through
/// the sublaminate is the whole interface) and lie ≥ ℓ inside, as the realised range says.
/// Returns the region.
fn check(mesh: &Mesh, front: &FrontShape, offset_m: f64, label: &str) -> NonlinearRegion {
    let region = nonlinear_region(mesh, front, Partition::Thesis { offset_m }).unwrap();
    let tol = 1e-9 * front.max_inside_distance();
    let d = |n: usize| front.inside_distance(mesh.nodes[n][0], mesh.nodes[n][1]);
    let sub = &mesh.cell_sets[names::SUBLAMINATE];
    assert!(!region.cells.is_empty(), "{label}");
    for &c in sub {
        let deepest_ok = mesh.cells[c].nodes.iter().all(|&n| d(n) >= offset_m - tol);
        assert_eq!(
            region.cells.binary_search(&c).is_ok(),
            deepest_ok,
            "{label}: cell {c}"
        );
    }
    assert!(region.cells.iter().all(|c| sub.contains(c)), "{label}");
    let front_nodes = &mesh.node_sets[names::FRONT];
    for &c in &region.cells {
        let on_front = mesh.cells[c].nodes.iter().any(|n| front_nodes.contains(n));
        assert!(!on_front, "{label}: nonlinear cell {c} touches the front");
    }
    let base = mesh.cell_sets.get(names::BASE).cloned().unwrap_or_default();
    for &c in &base {
        let shared = mesh.cells[c]
            .nodes
            .iter()
            .find(|n| region.interface.binary_search(n).is_ok());
        assert!(shared.is_none(), "{label}: base cell {c} on the interface");
    }
    assert!(!region.interface.is_empty(), "{label}");
    let (lo, hi) = region.realised_offset_m.unwrap();
    assert!(
        lo >= offset_m - tol && hi >= lo,
        "{label}: realised {lo}..{hi}"
    );
    let linear = region.linear_cells(mesh);
    assert_eq!(
        linear.len() + region.cells.len(),
        mesh.cells.len(),
        "{label}"
    );
    println!(
        "{label}: ℓ = {:.3} mm: {} nonlinear / {} linear cells, {} interface nodes, \
         realised ℓ {:.3}–{:.3} mm",
        1e3 * offset_m,
        region.cells.len(),
        linear.len(),
        region.interface.len(),
        1e3 * lo,
        1e3 * hi
    );
    region
}

/// ℓ = 0.5h, h, 2h, 4h: each set contains the next.
fn check_nested(mesh: &Mesh, front: &FrontShape, h: f64, label: &str) {
    let sets: Vec<Vec<usize>> = [0.5, 1.0, 2.0, 4.0]
        .iter()
        .map(|f| check(mesh, front, f * h, &format!("{label} {f}h")).cells)
        .collect();
    for pair in sets.windows(2) {
        assert!(pair[1].iter().all(|c| pair[0].contains(c)), "{label}");
    }
}

#[test]
fn the_reference_circle_at_l_equal_h_keeps_the_front_linear() {
    // 30 mm circle, h = 0.4 mm, the default (reference) mesh.
    let p = EmbeddedParams::thesis_reference();
    let mesh = embedded_delamination(&p).unwrap();
    let front = p.front_shape();
    let region = check(&mesh, &front, p.h, "reference");
    // The contour is one ring of the mesh through one Hex20 layer: per slice line two corner
    // nodes (z = H, H + h) and a mid-thickness one, per arc two mid-edge nodes: 5·slices + 3.
    // (Thesis Table 2's model 4, also 8 slices and one layer, shares 1 475 + 653 − 2 085 = 43.)
    assert_eq!(region.interface.len(), 5 * p.slices + 3);
    check_nested(&mesh, &front, p.h, "reference");
}

#[test]
fn the_whole_sublaminate_is_the_conservative_partition() {
    let p = EmbeddedParams::thesis_reference();
    let mesh = embedded_delamination(&p).unwrap();
    let region = nonlinear_region(&mesh, &p.front_shape(), Partition::Sublaminate).unwrap();
    let mut sub = mesh.cell_sets[names::SUBLAMINATE].clone();
    sub.sort_unstable();
    assert_eq!(region.cells, sub);
    // Its interface is the bonded plane z = H outside the front, front included: every
    // interface node lies on z = H, none inside the front.
    // The Hex20 mid-edge front nodes sit on chords, inside the circle by the sagitta
    // R(1 − cos(π/(4·slices))) (0.072 mm here); the far corner (W, W) is 55.7 mm outside.
    let (lo, hi) = region.realised_offset_m.unwrap();
    let sagitta = p.a * (1.0 - (std::f64::consts::PI / (4.0 * p.slices as f64)).cos());
    assert!(
        hi > 0.0 && hi <= sagitta * (1.0 + 1e-9),
        "{hi} vs {sagitta}"
    );
    assert!((lo + (p.w * 2f64.sqrt() - p.a)).abs() < 1e-12, "{lo}");
    for &n in &region.interface {
        assert!(
            (mesh.nodes[n][2] - p.base).abs() < 1e-12 * p.base,
            "node {n}"
        );
    }
    println!(
        "sublaminate: {} nonlinear cells, {} interface nodes",
        region.cells.len(),
        region.interface.len()
    );
}

/// With the base cells under the delamination, both faces of every crack pair are in the
/// nonlinear region and off its interface (contact acts on them, never on a condensed node);
/// the added cells are base cells, each with a node on the lower face.
#[test]
fn the_crack_base_joins_the_sublaminate_for_contact() {
    let p = EmbeddedParams::thesis_reference();
    let mesh = embedded_delamination(&p).unwrap();
    let plain = nonlinear_region(&mesh, &p.front_shape(), Partition::Sublaminate).unwrap();
    let region =
        nonlinear_region(&mesh, &p.front_shape(), Partition::SublaminateAndCrackBase).unwrap();
    let lower = &mesh.node_sets[names::CRACK_LOWER];
    let upper = &mesh.node_sets[names::CRACK_UPPER];
    let mut in_region = vec![false; mesh.nodes.len()];
    for &c in &region.cells {
        for &n in &mesh.cells[c].nodes {
            in_region[n] = true;
        }
    }
    for &n in lower.iter().chain(upper) {
        assert!(in_region[n], "crack node {n} outside the nonlinear region");
        assert!(region.interface.binary_search(&n).is_err(), "node {n}");
    }
    let sub = &mesh.cell_sets[names::SUBLAMINATE];
    let added: Vec<usize> = region
        .cells
        .iter()
        .copied()
        .filter(|c| plain.cells.binary_search(c).is_err())
        .collect();
    assert!(!added.is_empty());
    for c in added {
        assert!(!sub.contains(&c), "cell {c}");
        assert!(
            mesh.cells[c].nodes.iter().any(|n| lower.contains(n)),
            "cell {c}"
        );
    }
}

#[test]
fn every_delamination_model_partitions_with_the_same_properties() {
    let reference = EmbeddedParams::thesis_reference();
    let ellipses = [(15e-3, 7.5e-3), (7.5e-3, 22.5e-3), (22.5e-3, 7.5e-3)];
    for (a, b) in ellipses {
        let p = EmbeddedParams {
            a,
            b,
            map: EllipticMap::modified_for(a, b),
            radial_inside: EmbeddedParams::radial_inside_for(a, b),
            ..reference.clone()
        };
        let mesh = embedded_delamination(&p).unwrap();
        check_nested(&mesh, &p.front_shape(), p.h, &format!("ellipse {a}×{b}"));
    }
    let edge = EmbeddedParams::thesis_reference();
    let (mesh, _) = edge_delamination(&edge).unwrap();
    check_nested(&mesh, &edge.front_shape(), edge.h, "edge");
    let rect = EmbeddedParams {
        a: 12.7e-3,
        b: 25.4e-3,
        map: EllipticMap::Rectangle,
        ..reference.clone()
    };
    let mesh = embedded_delamination(&rect).unwrap();
    check_nested(&mesh, &rect.front_shape(), rect.h, "rectangle");
    let plies = EmbeddedParams {
        h: 0.4e-3,
        plies: Some(PlyLayout {
            ply_thickness: 0.1e-3,
            sublaminate: vec![0.0, 90.0, 90.0, 0.0],
            base_below: vec![0.0, 90.0],
        }),
        ..reference.clone()
    };
    let mesh = embedded_delamination(&plies).unwrap();
    check_nested(&mesh, &plies.front_shape(), plies.h, "ply-level");
    let hex8 = EmbeddedParams {
        kind: ElementKind::Hex8,
        ..reference.clone()
    };
    let mesh = embedded_delamination(&hex8).unwrap();
    check_nested(&mesh, &hex8.front_shape(), hex8.h, "Hex8");
    let mesh = thin_film(&reference).unwrap();
    check_nested(&mesh, &reference.front_shape(), reference.h, "thin film");
    let tw = ThroughWidthParams::example();
    let (mesh, _) = through_width_delamination(&tw).unwrap();
    check_nested(&mesh, &tw.front_shape(), tw.h, "through-width");
}

#[test]
fn an_offset_out_of_range_names_the_largest_that_works() {
    let p = EmbeddedParams::thesis_reference();
    let mesh = embedded_delamination(&p).unwrap();
    let front = p.front_shape();
    for bad in [-1e-4, f64::NAN, f64::INFINITY, 0.99 * p.a.min(p.b)] {
        let err = nonlinear_region(&mesh, &front, Partition::Thesis { offset_m: bad });
        assert!(
            matches!(err, Err(MeshError::Offset { .. })),
            "ℓ = {bad}: {err:?}"
        );
    }
    // The largest ℓ the message gives leaves cells; a little more leaves none.
    let err = nonlinear_region(&mesh, &front, Partition::Thesis { offset_m: 14.9e-3 })
        .unwrap_err()
        .to_string();
    let largest_mm: f64 = err
        .split("on this mesh is ")
        .nth(1)
        .and_then(|s| s.split(' ').next())
        .unwrap()
        .parse()
        .unwrap();
    assert!(largest_mm > 0.0 && largest_mm < 1e3 * p.a, "{err}");
    let at = |mm: f64| {
        nonlinear_region(
            &mesh,
            &front,
            Partition::Thesis {
                offset_m: mm * 1e-3,
            },
        )
    };
    assert!(!at(largest_mm - 1e-3).unwrap().cells.is_empty());
    assert!(at(largest_mm + 1e-3).is_err());
    // ℓ = 0: every sublaminate cell inside the front; the front is then on the interface.
    let zero = at(0.0).unwrap();
    let front_nodes = &mesh.node_sets[names::FRONT];
    assert!(front_nodes.iter().all(|n| zero.interface.contains(n)));
}

#[test]
fn a_mesh_without_its_sets_or_with_another_front_is_refused() {
    let p = EmbeddedParams::thesis_reference();
    let mesh = embedded_delamination(&p).unwrap();
    let thesis = Partition::Thesis { offset_m: p.h };
    let mut no_sub = mesh.clone();
    no_sub.cell_sets.remove(names::SUBLAMINATE);
    for partition in [thesis, Partition::Sublaminate] {
        let err = nonlinear_region(&no_sub, &p.front_shape(), partition).unwrap_err();
        assert!(
            matches!(err, MeshError::MissingSet { name, .. } if name == names::SUBLAMINATE),
            "{err}"
        );
    }
    let mut no_front = mesh.clone();
    no_front.node_sets.remove(names::FRONT);
    let err = nonlinear_region(&no_front, &p.front_shape(), thesis).unwrap_err();
    assert!(
        matches!(err, MeshError::MissingSet { name, .. } if name == names::FRONT),
        "{err}"
    );
    // The front of a 32 mm circle on the 30 mm circle's mesh: its nodes lie 1 mm inside.
    let other = FrontShape::Ellipse { a: 16e-3, b: 16e-3 };
    let err = nonlinear_region(&mesh, &other, thesis).unwrap_err();
    match err {
        MeshError::FrontMismatch { distance_mm, .. } => {
            assert!((distance_mm - 1.0).abs() < 1e-9, "{distance_mm}")
        }
        e => panic!("{e}"),
    }
}
