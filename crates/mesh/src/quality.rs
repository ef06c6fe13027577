//! Per-cell quality: minimum scaled Jacobian and aspect ratio.

use crate::model::kind_name;
use crate::{Mesh, MeshError};
use nonlin3d_element::{HEX20_EDGES, gauss_1d};

/// Quality of one cell.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CellQuality {
    /// min over the nodes and the 3×3×3 Gauss points of det J / (|∂x/∂ξ| |∂x/∂η| |∂x/∂ζ|):
    /// 1 for a rectangular box, ≤ 0 for an inverted cell.
    pub min_scaled_jacobian: f64,
    /// Where the minimum sits (reference coordinates).
    pub at: [f64; 3],
    /// Longest over shortest of the 12 corner-to-corner edges.
    pub aspect_ratio: f64,
}

/// Quality of every cell of a validated mesh.
pub fn quality(mesh: &Mesh) -> Result<Vec<CellQuality>, MeshError> {
    mesh.validate()?;
    let (g, _) = gauss_1d(3).ok_or(MeshError::Parameter {
        name: "quadrature",
        reason: "3-point rule missing".into(),
    })?;
    let mut points: Vec<[f64; 3]> = Vec::new();
    for &a in g {
        for &b in g {
            for &c in g {
                points.push([a, b, c]);
            }
        }
    }
    let mut out = Vec::with_capacity(mesh.cells.len());
    let mut dn = vec![[0.0; 3]; 20];
    for (c, cell) in mesh.cells.iter().enumerate() {
        let x = mesh.cell_coordinates(c);
        let mut best = (f64::INFINITY, [0.0; 3]);
        for &p in points.iter().chain(cell.kind.reference_nodes()) {
            let dn = &mut dn[..cell.kind.nodes()];
            cell.kind.shape_gradients(p, dn);
            let mut j = [[0.0; 3]; 3];
            for (d, xm) in dn.iter().zip(&x) {
                for r in 0..3 {
                    for k in 0..3 {
                        j[r][k] += d[r] * xm[k];
                    }
                }
            }
            let det = j[0][0] * (j[1][1] * j[2][2] - j[1][2] * j[2][1])
                - j[0][1] * (j[1][0] * j[2][2] - j[1][2] * j[2][0])
                + j[0][2] * (j[1][0] * j[2][1] - j[1][1] * j[2][0]);
            let norms: f64 = j
                .iter()
                .map(|row| (row[0] * row[0] + row[1] * row[1] + row[2] * row[2]).sqrt())
                .product();
            let s = if norms > 0.0 {
                det / norms
            } else {
                f64::NEG_INFINITY
            };
            if s < best.0 {
                best = (s, p);
            }
        }
        let lengths: Vec<f64> = HEX20_EDGES
            .iter()
            .map(|&(a, b)| {
                let (p, q) = (x[a], x[b]);
                ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
            })
            .collect();
        let (lo, hi) = lengths
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(lo, hi), &l| {
                (lo.min(l), hi.max(l))
            });
        out.push(CellQuality {
            min_scaled_jacobian: best.0,
            at: best.1,
            aspect_ratio: if lo > 0.0 { hi / lo } else { f64::INFINITY },
        });
    }
    Ok(out)
}

impl Mesh {
    /// An error naming the first cell whose Jacobian is not positive everywhere.
    pub fn check_geometry(&self) -> Result<(), MeshError> {
        for (cell, q) in quality(self)?.iter().enumerate() {
            if q.min_scaled_jacobian.is_nan() || q.min_scaled_jacobian <= 0.0 {
                let x = self.cell_coordinates(cell);
                let det = self.cells[cell]
                    .kind
                    .jacobian_determinant(q.at, &x)
                    .map_err(|_| MeshError::NodeCount {
                        cell,
                        kind: kind_name(self.cells[cell].kind),
                        expected: self.cells[cell].kind.nodes(),
                        got: x.len(),
                    })?;
                return Err(MeshError::Inverted {
                    cell,
                    xi: q.at,
                    det,
                });
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{BoxParams, structured_box};
    use nonlin3d_element::ElementKind;

    #[test]
    fn box_cells_are_perfect_and_aspect_is_measured() {
        let m = structured_box(&BoxParams::new(
            ElementKind::Hex20,
            [2, 1, 1],
            [4e-3, 1e-3, 0.25e-3],
        ))
        .unwrap();
        for q in quality(&m).unwrap() {
            assert!((q.min_scaled_jacobian - 1.0).abs() < 1e-12);
            assert!((q.aspect_ratio - 8.0).abs() < 1e-12);
        }
        assert!(m.check_geometry().is_ok());
    }

    #[test]
    fn an_inverted_cell_is_named() {
        let mut m = structured_box(&BoxParams::new(
            ElementKind::Hex8,
            [2, 1, 1],
            [2.0, 1.0, 1.0],
        ))
        .unwrap();
        // Push node 6 of cell 1 (corner (+,+,+)) through the cell.
        let n = m.cells[1].nodes[6];
        m.nodes[n] = [0.0, -1.0, -1.0];
        let q = quality(&m).unwrap();
        assert!(q[1].min_scaled_jacobian < 0.0);
        assert!(matches!(
            m.check_geometry(),
            Err(MeshError::Inverted { cell: 1, .. })
        ));
    }
}
