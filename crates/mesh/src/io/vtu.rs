//! VTU (VTK XML unstructured grid, ASCII) and PVD (time series) output, readable by ParaView
//! and meshio. Hex8 cells are `VTK_HEXAHEDRON` (12), Hex20 `VTK_QUADRATIC_HEXAHEDRON` (25); both
//! node orders equal nonlin3d's (Abaqus C3D8/C3D20).
//!
//! ASCII with shortest round-trip number formatting: files are larger than binary ones, but exact,
//! diffable and written without a base64/compression dependency. Every cell also carries its
//! `material` (index) and `ply_angle_deg`.

use crate::{Mesh, MeshError};
use nonlin3d_element::ElementKind;
use std::fmt::Write as _;
use std::path::Path;

/// A named array of `components` values per point or per cell.
#[derive(Debug, Clone, Copy)]
pub struct Field<'a> {
    /// Array name as ParaView shows it.
    pub name: &'a str,
    /// Values per point or cell (1 scalar, 3 vector, 6 symmetric tensor in Voigt order).
    pub components: usize,
    /// The values, point (or cell) after point.
    pub values: &'a [f64],
}

fn check(field: &Field<'_>, count: usize, owner: &str) -> Result<(), MeshError> {
    let expected = count * field.components;
    if field.components == 0 || field.values.len() != expected {
        return Err(MeshError::Parameter {
            name: "field",
            reason: format!(
                "{owner} field '{}': expected {expected} values, got {}",
                field.name,
                field.values.len()
            ),
        });
    }
    if let Some(i) = field.values.iter().position(|v| !v.is_finite()) {
        return Err(MeshError::Parameter {
            name: "field",
            reason: format!("{owner} field '{}': value {i} is not finite", field.name),
        });
    }
    if field.name.contains(['"', '<', '>', '&']) {
        return Err(MeshError::Parameter {
            name: "field",
            reason: format!("field name '{}' has XML metacharacters", field.name),
        });
    }
    Ok(())
}

/// A Float64 array, each value in its shortest round-trip decimal form (`ryu`: the digits of
/// Rust's `{:?}`, several times faster; the VTU's largest cost in a deck's output).
fn data_array(s: &mut String, name: &str, components: usize, values: impl Iterator<Item = f64>) {
    let _ = write!(
        s,
        "        <DataArray type=\"Float64\" Name=\"{name}\" NumberOfComponents=\"{components}\" format=\"ascii\">\n          "
    );
    let mut digits = ryu::Buffer::new();
    for (i, v) in values.enumerate() {
        if i > 0 {
            s.push_str(if i % components.max(1) == 0 {
                "\n          "
            } else {
                " "
            });
        }
        s.push_str(digits.format(v));
    }
    s.push_str("\n        </DataArray>\n");
}

/// The mesh with point and cell fields as a VTU document.
pub fn vtu_string(
    mesh: &Mesh,
    point_fields: &[Field<'_>],
    cell_fields: &[Field<'_>],
) -> Result<String, MeshError> {
    mesh.validate()?;
    for f in point_fields {
        check(f, mesh.nodes.len(), "point")?;
    }
    for f in cell_fields {
        check(f, mesh.cells.len(), "cell")?;
    }
    let mut s = String::new();
    s.push_str("<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n  <UnstructuredGrid>\n");
    let _ = writeln!(
        s,
        "    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">",
        mesh.nodes.len(),
        mesh.cells.len()
    );
    s.push_str("      <PointData>\n");
    for f in point_fields {
        data_array(&mut s, f.name, f.components, f.values.iter().copied());
    }
    s.push_str("      </PointData>\n      <CellData>\n");
    let _ = write!(
        s,
        "        <DataArray type=\"Int32\" Name=\"material\" format=\"ascii\">\n          "
    );
    for (i, c) in mesh.cells.iter().enumerate() {
        let _ = write!(s, "{}{}", if i > 0 { " " } else { "" }, c.material);
    }
    s.push_str("\n        </DataArray>\n");
    data_array(
        &mut s,
        "ply_angle_deg",
        1,
        mesh.cells.iter().map(|c| c.ply_angle_deg),
    );
    for f in cell_fields {
        data_array(&mut s, f.name, f.components, f.values.iter().copied());
    }
    s.push_str("      </CellData>\n      <Points>\n");
    data_array(&mut s, "Points", 3, mesh.nodes.iter().flatten().copied());
    s.push_str("      </Points>\n      <Cells>\n        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n");
    for c in &mesh.cells {
        s.push_str("          ");
        for (i, n) in c.nodes.iter().enumerate() {
            let _ = write!(s, "{}{n}", if i > 0 { " " } else { "" });
        }
        s.push('\n');
    }
    s.push_str("        </DataArray>\n        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n          ");
    let mut offset = 0;
    for (i, c) in mesh.cells.iter().enumerate() {
        offset += c.nodes.len();
        let _ = write!(s, "{}{offset}", if i > 0 { " " } else { "" });
    }
    s.push_str("\n        </DataArray>\n        <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n          ");
    for (i, c) in mesh.cells.iter().enumerate() {
        let t = match c.kind {
            ElementKind::Hex8 => 12,
            ElementKind::Hex20 => 25,
        };
        let _ = write!(s, "{}{t}", if i > 0 { " " } else { "" });
    }
    s.push_str(
        "\n        </DataArray>\n      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n",
    );
    Ok(s)
}

/// Points joined by line segments (`VTK_LINE`, 3) with point fields, as a VTU document: e.g. a
/// delamination front through its points in S order. (`VTK_POLY_LINE` would be one cell, but
/// meshio does not read it; segments show the same curve in ParaView.)
pub fn lines_vtu_string(
    points: &[[f64; 3]],
    segments: &[[usize; 2]],
    point_fields: &[Field<'_>],
) -> Result<String, MeshError> {
    if let Some(i) = points.iter().position(|p| !p.iter().all(|v| v.is_finite())) {
        return Err(MeshError::NonFinite {
            what: "point",
            index: i,
        });
    }
    if let Some(s) = segments
        .iter()
        .find(|s| s.iter().any(|&n| n >= points.len()))
    {
        return Err(MeshError::Parameter {
            name: "segment",
            reason: format!("{s:?} names a point past the {} given", points.len()),
        });
    }
    for f in point_fields {
        check(f, points.len(), "point")?;
    }
    let mut s = String::new();
    s.push_str("<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n  <UnstructuredGrid>\n");
    let _ = writeln!(
        s,
        "    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">",
        points.len(),
        segments.len()
    );
    s.push_str("      <PointData>\n");
    for f in point_fields {
        data_array(&mut s, f.name, f.components, f.values.iter().copied());
    }
    s.push_str("      </PointData>\n      <Points>\n");
    data_array(&mut s, "Points", 3, points.iter().flatten().copied());
    s.push_str("      </Points>\n      <Cells>\n        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n          ");
    for (i, [a, b]) in segments.iter().enumerate() {
        let _ = write!(s, "{}{a} {b}", if i > 0 { " " } else { "" });
    }
    s.push_str("\n        </DataArray>\n        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n          ");
    for i in 0..segments.len() {
        let _ = write!(s, "{}{}", if i > 0 { " " } else { "" }, 2 * (i + 1));
    }
    s.push_str("\n        </DataArray>\n        <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n          ");
    for i in 0..segments.len() {
        let _ = write!(s, "{}3", if i > 0 { " " } else { "" });
    }
    s.push_str(
        "\n        </DataArray>\n      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n",
    );
    Ok(s)
}

/// Writes [`vtu_string`] to `path`.
pub fn write_vtu(
    path: &Path,
    mesh: &Mesh,
    point_fields: &[Field<'_>],
    cell_fields: &[Field<'_>],
) -> Result<(), MeshError> {
    let s = vtu_string(mesh, point_fields, cell_fields)?;
    std::fs::write(path, s).map_err(|source| MeshError::Io {
        path: path.display().to_string(),
        source,
    })
}

/// Writes a PVD collection: one (time, VTU file name relative to the PVD) per step, e.g. per
/// applied strain level.
pub fn write_pvd(path: &Path, steps: &[(f64, String)]) -> Result<(), MeshError> {
    let s = pvd_string(steps)?;
    std::fs::write(path, s).map_err(|source| MeshError::Io {
        path: path.display().to_string(),
        source,
    })
}

/// The text of a PVD collection ([`write_pvd`] without the file).
pub fn pvd_string(steps: &[(f64, String)]) -> Result<String, MeshError> {
    let mut s = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"1.0\" byte_order=\"LittleEndian\">\n  <Collection>\n",
    );
    for (t, file) in steps {
        if !t.is_finite() || file.contains(['"', '<', '>', '&']) {
            return Err(MeshError::Parameter {
                name: "pvd step",
                reason: format!("time {t}, file '{file}'"),
            });
        }
        let _ = writeln!(
            s,
            "    <DataSet timestep=\"{t:?}\" group=\"\" part=\"0\" file=\"{file}\"/>"
        );
    }
    s.push_str("  </Collection>\n</VTKFile>\n");
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{BoxParams, structured_box};

    #[test]
    fn vtu_has_the_counts_types_and_values() {
        let m = structured_box(&BoxParams::new(
            ElementKind::Hex20,
            [2, 1, 1],
            [2.0, 1.0, 1.0],
        ))
        .unwrap();
        let u: Vec<f64> = m
            .nodes
            .iter()
            .flat_map(|p| [0.5 * p[0], 0.0, -0.25])
            .collect();
        let sxx: Vec<f64> = (0..m.cells.len()).map(|c| c as f64 + 0.5).collect();
        let s = vtu_string(
            &m,
            &[Field {
                name: "displacement",
                components: 3,
                values: &u,
            }],
            &[Field {
                name: "sxx",
                components: 1,
                values: &sxx,
            }],
        )
        .unwrap();
        assert!(s.contains(&format!(
            "NumberOfPoints=\"{}\" NumberOfCells=\"2\"",
            m.nodes.len()
        )));
        assert!(s.contains("\n          25 25\n"));
        assert!(s.contains("\n          20 40\n"));
        assert!(s.contains("1.5"));
        // Wrong lengths and non-finite values are errors.
        assert!(
            vtu_string(
                &m,
                &[Field {
                    name: "u",
                    components: 3,
                    values: &u[..3]
                }],
                &[]
            )
            .is_err()
        );
        let line = lines_vtu_string(
            &[[0.0; 3], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]],
            &[[0, 1], [1, 2]],
            &[Field {
                name: "g",
                components: 1,
                values: &[1.0, 2.0, 3.0],
            }],
        )
        .unwrap();
        assert!(line.contains("NumberOfPoints=\"3\" NumberOfCells=\"2\""));
        assert!(line.contains("\n          0 1 1 2\n") && line.contains("\n          2 4\n"));
        assert!(lines_vtu_string(&[[0.0; 3]], &[[0, 1]], &[]).is_err());
        let mut bad = sxx.clone();
        bad[1] = f64::NAN;
        assert!(
            vtu_string(
                &m,
                &[],
                &[Field {
                    name: "s",
                    components: 1,
                    values: &bad
                }]
            )
            .is_err()
        );
    }

    /// The values of a `data_array`, read back as a VTU reader does.
    fn read_back(text: &str) -> Vec<f64> {
        let body = &text[text.find('>').unwrap() + 1..text.rfind("</DataArray>").unwrap()];
        body.split_whitespace()
            .map(|w| w.parse().unwrap())
            .collect()
    }

    proptest::proptest! {
        /// Every value written reads back to the same bits: the text is exact whatever the
        /// magnitude (subnormals, ±0, the extremes of f64).
        #[test]
        fn values_read_back_bit_for_bit(
            bits in proptest::collection::vec(proptest::num::u64::ANY, 1..40)
        ) {
            let extremes = [0.0, -0.0, 1.0, 1e-7, 1e16, 123456789.0, f64::MIN_POSITIVE, 5e-324];
            let values: Vec<f64> = bits
                .iter()
                .map(|&b| f64::from_bits(b))
                .filter(|v| v.is_finite())
                .chain(extremes.into_iter().chain([f64::MAX, -f64::MAX]))
                .collect();
            let mut s = String::new();
            data_array(&mut s, "v", 3, values.iter().copied());
            let back = read_back(&s);
            proptest::prop_assert_eq!(back.len(), values.len());
            for (a, b) in back.iter().zip(&values) {
                proptest::prop_assert_eq!(a.to_bits(), b.to_bits());
            }
        }
    }
}
