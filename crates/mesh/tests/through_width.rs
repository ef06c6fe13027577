//! The through-width delamination model (thesis Fig. 3.2.3).

use nonlin3d_element::ElementKind;
use nonlin3d_mesh::{ThroughWidthParams, quality, through_width_delamination};
use std::collections::HashMap;

#[test]
fn through_width_geometry_crack_and_front() {
    for kind in [ElementKind::Hex20, ElementKind::Hex8] {
        for across in [1, 3] {
            let p = ThroughWidthParams {
                kind,
                across,
                ..ThroughWidthParams::example()
            };
            let (m, front) = through_width_delamination(&p).unwrap();
            let exact = p.length * p.width * (p.base + p.h);
            assert!((m.volume().unwrap() - exact).abs() < 1e-10 * exact);
            assert!(
                quality(&m)
                    .unwrap()
                    .iter()
                    .all(|q| (q.min_scaled_jacobian - 1.0).abs() < 1e-12)
            );
            // Crack pairs coincide, lie on z = H with x < a; no other coincident nodes.
            let (up, lo) = (&m.node_sets["crack_upper"], &m.node_sets["crack_lower"]);
            // Corner lines (y at element boundaries) carry corners and mid-edge nodes along x;
            // Hex20 mid-edge lines (y at element middles) only the mid-edge nodes along y
            // (no face-centre nodes in the serendipity element).
            let lines = if kind == ElementKind::Hex20 {
                2 * across + 1
            } else {
                across + 1
            };
            let expected = match kind {
                ElementKind::Hex20 => (across + 1) * 2 * p.inside + across * p.inside,
                ElementKind::Hex8 => (across + 1) * p.inside,
            };
            assert_eq!(up.len(), expected);
            for (&u, &l) in up.iter().zip(lo) {
                assert_eq!(m.nodes[u], m.nodes[l]);
                assert!(m.nodes[u][0] < p.a && (m.nodes[u][2] - p.base).abs() < 1e-15);
            }
            let mut seen: HashMap<[i64; 3], usize> = HashMap::new();
            let mut dup = 0;
            for x in &m.nodes {
                if seen
                    .insert(x.map(|v| (v * 1e9).round() as i64), 0)
                    .is_some()
                {
                    dup += 1;
                }
            }
            assert_eq!(dup, up.len());
            // Front: a straight line x = a from y = W to 0, θ = −90°, normal +x, Δa = first
            // element behind the front.
            assert_eq!(front.points.len(), lines);
            assert!(
                (front.points[0].y - p.width).abs() < 1e-15
                    && front.points.last().unwrap().y.abs() < 1e-15
            );
            for pt in &front.points {
                assert!((pt.x - p.a).abs() < 1e-15);
                assert_eq!(pt.theta_deg, -90.0);
                assert_eq!(pt.normal, [1.0, 0.0]);
                assert!(pt.delta_a > 0.0 && pt.delta_a < p.a / p.inside as f64);
                assert_eq!(m.nodes[pt.a_upper], m.nodes[pt.a_lower]);
                assert!(!pt.cells_above.is_empty());
                if kind == ElementKind::Hex20 && pt.corner {
                    assert!(pt.b_upper.is_some() && pt.b_lower.is_some() && pt.d.is_some());
                    assert!((m.nodes[pt.d.unwrap()][0] - p.a) > 0.0);
                }
            }
            assert!((front.points.last().unwrap().s - p.width).abs() < 1e-15);
        }
    }
    assert!(
        through_width_delamination(&ThroughWidthParams {
            a: 40e-3,
            ..ThroughWidthParams::example()
        })
        .is_err()
    );
}
