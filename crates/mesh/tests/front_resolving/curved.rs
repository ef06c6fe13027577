//! Mid-edge nodes on the mapped curves (issue 25, `EmbeddedParams::mid_edges`): every ring's
//! Hex20 mid-edge nodes at the planform map of the circular mesh's mid-edge points, so the
//! front's nodes all lie on the ellipse and each ring near the front is curved alike.

use super::{assert_conformal, graded, patch_test};
use nonlin3d_mesh::{
    DEFAULT_MESH, EllipticMap, EmbeddedParams, FrontBand, FrontWidths, LayerBand, MidEdges,
    embedded_delamination_with_front, quality,
};

/// The default mesh (`DEFAULT_MESH`) of an a × b ellipse with h = 0.4 mm, mid-edges `mid`.
fn default_mesh(a: f64, b: f64, mid: MidEdges) -> EmbeddedParams {
    let p = EmbeddedParams {
        a,
        b,
        map: EllipticMap::modified_for(a, b),
        ..EmbeddedParams::thesis_reference()
    };
    EmbeddedParams {
        mid_edges: mid,
        ..p.with_accuracy_row(&DEFAULT_MESH)
    }
}

/// (x/a)² + (y/b)² − 1 at a node.
fn off_ellipse(p: &EmbeddedParams, x: [f64; 3]) -> f64 {
    (x[0] / p.a).powi(2) + (x[1] / p.b).powi(2) - 1.0
}

/// With mapped mid-edges every front node, corner and mid-edge, lies on the ellipse to
/// round-off, on the circle, the 30 × 60 mm ellipse either way round; on chords the mid-edge
/// nodes sit inside it by their sagitta (the test would see a straight-edged front).
#[test]
fn mapped_mid_edges_put_the_whole_front_on_the_ellipse() {
    for (a, b) in [(15e-3, 15e-3), (15e-3, 30e-3), (30e-3, 15e-3)] {
        let p = default_mesh(a, b, MidEdges::Mapped);
        let (m, front) = embedded_delamination_with_front(&p).unwrap();
        assert_eq!(front.widths, FrontWidths::AlongEdges);
        for fp in &front.points {
            let e = off_ellipse(&p, m.nodes[fp.c]);
            assert!(e.abs() < 1e-12, "{a} × {b}, S = {}: {e}", fp.s);
        }
        let chords = default_mesh(a, b, MidEdges::Chords);
        let (mc, fc) = embedded_delamination_with_front(&chords).unwrap();
        assert_eq!(fc.widths, FrontWidths::Chords);
        let inside = fc
            .points
            .iter()
            .filter(|fp| !fp.corner)
            .map(|fp| off_ellipse(&chords, mc.nodes[fp.c]))
            .fold(f64::INFINITY, f64::min);
        assert!(inside < -1e-5, "{a} × {b}: chords' mid-edge nodes {inside}");
        // Corner nodes do not move.
        for (fp, fq) in front
            .points
            .iter()
            .zip(&fc.points)
            .filter(|(f, _)| f.corner)
        {
            assert_eq!(m.nodes[fp.c], mc.nodes[fq.c]);
        }
    }
}

/// The ring behind the front is curved as the front is (the consistency §2e's front-only
/// curving lacked): on the circle every node VCCT pairs with the front, a at the corners and
/// at the mid-edge points, lies at the same radius, so each closure strip is an annular
/// sector of depth Δa.
#[test]
fn the_ring_behind_the_front_is_curved_alike() {
    let p = default_mesh(15e-3, 15e-3, MidEdges::Mapped);
    let (m, front) = embedded_delamination_with_front(&p).unwrap();
    let radius = |n: usize| m.nodes[n][0].hypot(m.nodes[n][1]);
    let r = radius(front.points[0].a_upper);
    for fp in &front.points {
        for n in [fp.a_upper, fp.a_lower] {
            assert!((radius(n) - r).abs() < 1e-12 * r, "S = {}", fp.s);
        }
    }
    assert!(
        (p.a - r - 0.2 * p.h / 0.4).abs() < 1e-9,
        "Δa = e: {}",
        p.a - r
    );
}

/// Curving the front band's rings costs the default meshes no quality (minimum scaled Jacobian
/// 0.2952 against 0.2949 straight on the circle, 0.2872 for both on the 30 × 60 mm ellipse,
/// 0.2598 against 0.2594 on the 60 × 30 mm one), and the band transitions stay conformal and
/// fill the block.
#[test]
fn curved_default_meshes_keep_their_quality_and_fill_the_block() {
    for (a, b, floor) in [
        (15e-3, 15e-3, 0.29),
        (15e-3, 30e-3, 0.28),
        (30e-3, 15e-3, 0.25),
    ] {
        let p = default_mesh(a, b, MidEdges::Mapped);
        let (m, _) = embedded_delamination_with_front(&p).unwrap();
        let worst = quality(&m)
            .unwrap()
            .iter()
            .map(|c| c.min_scaled_jacobian)
            .fold(f64::INFINITY, f64::min);
        assert!(worst >= floor, "{a} × {b}: {worst}");
        if a == b {
            assert_conformal(&p, &m);
        }
    }
}

/// Patch test on curved meshes: a homogeneous strain is reproduced across the 1 → 3 and 1 → 2
/// transitions (their arcs blend the curved ones), the grading and the crack, and on a mesh
/// without bands whose every ring is curved. Curving keeps the elements isoparametric, so
/// linear fields stay exact; a mid-edge node placed differently by the two cells sharing an
/// edge would break it.
#[test]
fn a_homogeneous_strain_is_reproduced_across_curved_transitions() {
    let banded = EmbeddedParams {
        slices: 2,
        radial_inside: 4,
        radial_outside: 4,
        sub_layers: 2,
        base_layers: 2,
        front_band: Some(FrontBand {
            inside: 2,
            outside: 2,
        }),
        layer_band: Some(LayerBand {
            inside: 1,
            outside: 1,
        }),
        mid_edges: MidEdges::Mapped,
        ..graded(0.1e-3)
    };
    let plain = EmbeddedParams {
        slices: 4,
        radial_inside: 3,
        radial_outside: 3,
        mid_edges: MidEdges::Mapped,
        ..graded(0.1e-3)
    };
    for p in [banded, plain] {
        let (worst, scale) = patch_test(&p);
        assert!(worst <= 1e-6 * scale, "worst {worst} against {scale}");
    }
}
