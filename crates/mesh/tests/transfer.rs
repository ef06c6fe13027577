//! [`Transfer`] between the companion mesh and the mesh it coarsens (nested iteration): a
//! field linear in x is carried exactly across the whole model, crack faces included, and each
//! crack face's nodes take the values of the source cells on their own side.

use nonlin3d_mesh::names::{CRACK_LOWER, CRACK_UPPER};
use nonlin3d_mesh::{EmbeddedParams, FrontBand, LayerBand, Mesh, Transfer, embedded_delamination};

/// The reference circle's mesh R with the front and layer bands (the accuracy candidate) and
/// the thesis default, each with its companion.
fn pairs() -> Vec<(Mesh, Mesh)> {
    let default = EmbeddedParams::thesis_reference();
    let banded = EmbeddedParams {
        slices: 6,
        radial_inside: 7,
        radial_outside: 6,
        sub_layers: 2,
        base_layers: 2,
        front_element: Some(0.3e-3),
        front_band: Some(FrontBand {
            inside: 5,
            outside: 3,
        }),
        layer_band: Some(LayerBand {
            inside: 3,
            outside: 2,
        }),
        ..EmbeddedParams::thesis_reference()
    };
    let ellipse = EmbeddedParams {
        a: 15e-3,
        b: 30e-3,
        ..EmbeddedParams::thesis_reference()
    };
    [default, banded, ellipse]
        .iter()
        .map(|p| {
            (
                embedded_delamination(&p.coarsened()).unwrap(),
                embedded_delamination(p).unwrap(),
            )
        })
        .collect()
}

/// Linear fields are carried exactly by isoparametric cells: the three components of
/// u = A x + c, to 1e-9 of the field's size, on every node of the fine mesh; the nodes lie in
/// or on their coarse cells (curved edges: |ξ|∞ − 1 ≤ 1e-2).
#[test]
fn a_linear_field_is_carried_exactly() {
    let u = |x: [f64; 3]| {
        [
            1e-3 + 0.2 * x[0] - 0.1 * x[1] + 0.3 * x[2],
            -0.05 * x[0] + 0.4 * x[1] + 0.1 * x[2],
            0.2 * x[0] + 0.1 * x[1] - 0.6 * x[2] - 2e-3,
        ]
    };
    for (coarse, fine) in pairs() {
        let t = Transfer::between(&coarse, &fine).unwrap();
        assert_eq!(t.len(), fine.nodes.len());
        let field: Vec<f64> = coarse.nodes.iter().flat_map(|&x| u(x)).collect();
        let out = t.apply(&field, 3).unwrap();
        let scale = field.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        for (j, &x) in fine.nodes.iter().enumerate() {
            for k in 0..3 {
                let e = (out[3 * j + k] - u(x)[k]).abs();
                assert!(e <= 1e-9 * scale, "node {j} component {k}: error {e}");
            }
        }
        assert!(t.outside() <= 1e-2, "outside by {}", t.outside());
    }
}

/// Each fine crack node is interpolated in a coarse cell on its own side of the crack (the
/// cell's centroid above the crack plane z = H for the upper face, below it for the lower),
/// and a field that jumps across the crack (1 on the coarse cells above z = H, 0 below, the
/// bonded interface's nodes belonging to both taking 1) gives the upper face 1 and the lower
/// face's inner nodes 0.
#[test]
fn crack_faces_take_their_own_side() {
    for (coarse, fine) in pairs() {
        let t = Transfer::between(&coarse, &fine).unwrap();
        let z = |m: &Mesh, c: usize| {
            m.cells[c].nodes.iter().map(|&n| m.nodes[n][2]).sum::<f64>()
                / m.cells[c].nodes.len() as f64
        };
        let plane = fine.nodes[fine.node_sets[CRACK_UPPER][0]][2];
        let mut above = vec![0.0; coarse.nodes.len()];
        for (c, cell) in coarse.cells.iter().enumerate() {
            if z(&coarse, c) > plane {
                for &n in &cell.nodes {
                    above[n] = 1.0;
                }
            }
        }
        let jump = t.apply(&above, 1).unwrap();
        let (up, low) = (&fine.node_sets[CRACK_UPPER], &fine.node_sets[CRACK_LOWER]);
        assert!(!up.is_empty() && up.len() == low.len());
        for (&a, &b) in up.iter().zip(low) {
            assert!(z(&coarse, t.cell(a)) > plane, "upper node {a}");
            assert!(z(&coarse, t.cell(b)) < plane, "lower node {b}");
            assert!((jump[a] - 1.0).abs() < 1e-12, "upper node {a}: {}", jump[a]);
        }
        // Lower-face nodes whose coarse cell has no node on the bonded interface read 0.
        let bonded = |c: usize| coarse.cells[c].nodes.iter().any(|&n| above[n] == 1.0);
        let inner: Vec<usize> = low
            .iter()
            .copied()
            .filter(|&b| !bonded(t.cell(b)))
            .collect();
        assert!(!inner.is_empty());
        assert!(inner.iter().all(|&b| jump[b].abs() < 1e-12));
    }
}
