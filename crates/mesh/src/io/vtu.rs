//! VTU (VTK XML unstructured grid) and PVD (time series) output, readable by ParaView and
//! meshio. Hex8 cells are `VTK_HEXAHEDRON` (12), Hex20 `VTK_QUADRATIC_HEXAHEDRON` (25); both
//! node orders equal nonlin3d's (Abaqus C3D8/C3D20).
//!
//! Every array is inline binary, as VTK's own writers make it uncompressed (`format="binary"`):
//! the base64 encoding of a UInt64 byte count followed by the values' little-endian bytes, in
//! one stream. Exact (the bits of every f64), about 1.8× smaller than shortest round-trip
//! decimal text and several times faster to write: the VTU was a deck's largest output cost
//! (docs/PERFORMANCE.md, "The VTU in binary"). Every cell also carries its `material` (index)
//! and `ply_angle_deg`.

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

/// The base64 alphabet of RFC 4648 (standard, with `=` padding), which VTK's inline binary
/// data uses.
const BASE64: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

/// Appends the base64 encoding of `bytes` (RFC 4648, padded, no line breaks).
fn base64_into(s: &mut String, bytes: &[u8]) {
    s.reserve(bytes.len().div_ceil(3) * 4);
    let mut chunks = bytes.chunks_exact(3);
    for c in &mut chunks {
        let v = (u32::from(c[0]) << 16) | (u32::from(c[1]) << 8) | u32::from(c[2]);
        for shift in [18, 12, 6, 0] {
            s.push(char::from(BASE64[(v >> shift) as usize & 63]));
        }
    }
    let rest = chunks.remainder();
    if !rest.is_empty() {
        let v = (u32::from(rest[0]) << 16) | rest.get(1).map_or(0, |&b| u32::from(b) << 8);
        s.push(char::from(BASE64[(v >> 18) as usize & 63]));
        s.push(char::from(BASE64[(v >> 12) as usize & 63]));
        s.push(if rest.len() == 2 {
            char::from(BASE64[(v >> 6) as usize & 63])
        } else {
            '='
        });
        s.push('=');
    }
}

/// One `DataArray` of `vtk_type` (`Float64`, `Int64`, `Int32`, `UInt8`) in inline binary:
/// base64 of the UInt64 byte count (the VTKFile's `header_type`) followed by the
/// little-endian values that `values` appends, encoded as one stream (the values are written
/// once, behind room for the count).
fn binary_array(
    s: &mut String,
    vtk_type: &str,
    name: &str,
    components: usize,
    values: impl FnOnce(&mut Vec<u8>),
) {
    let _ = write!(
        s,
        "        <DataArray type=\"{vtk_type}\" Name=\"{name}\" NumberOfComponents=\"{components}\" format=\"binary\">\n          "
    );
    let mut all = vec![0u8; 8];
    values(&mut all);
    let count = (all.len() - 8) as u64;
    all[..8].copy_from_slice(&count.to_le_bytes());
    base64_into(s, &all);
    s.push_str("\n        </DataArray>\n");
}

/// A Float64 array of `components` values per point or cell, bit for bit.
fn data_array(s: &mut String, name: &str, components: usize, values: impl Iterator<Item = f64>) {
    binary_array(s, "Float64", name, components, |b| {
        b.extend(values.flat_map(f64::to_le_bytes))
    });
}

/// An Int64 array (connectivity, offsets), one component.
fn int64_array(s: &mut String, name: &str, values: impl Iterator<Item = usize>) {
    binary_array(s, "Int64", name, 1, |b| {
        b.extend(values.flat_map(|v| (v as i64).to_le_bytes()))
    });
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
    binary_array(&mut s, "Int32", "material", 1, |b| {
        b.extend(
            mesh.cells
                .iter()
                .flat_map(|c| (c.material as i32).to_le_bytes()),
        )
    });
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
    s.push_str("      </Points>\n      <Cells>\n");
    int64_array(
        &mut s,
        "connectivity",
        mesh.cells.iter().flat_map(|c| c.nodes.iter().copied()),
    );
    int64_array(
        &mut s,
        "offsets",
        mesh.cells.iter().scan(0, |offset, c| {
            *offset += c.nodes.len();
            Some(*offset)
        }),
    );
    binary_array(&mut s, "UInt8", "types", 1, |b| {
        b.extend(mesh.cells.iter().map(|c| match c.kind {
            ElementKind::Hex8 => 12u8,
            ElementKind::Hex20 => 25,
        }))
    });
    s.push_str("      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n");
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
    s.push_str("      </Points>\n      <Cells>\n");
    int64_array(&mut s, "connectivity", segments.iter().flatten().copied());
    int64_array(&mut s, "offsets", (1..=segments.len()).map(|i| 2 * i));
    binary_array(&mut s, "UInt8", "types", 1, |b| {
        b.resize(b.len() + segments.len(), 3)
    });
    s.push_str("      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n");
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
        assert_eq!(array(&s, "types"), [25, 25]);
        assert_eq!(int64s(&array(&s, "offsets")), [20, 40]);
        assert_eq!(f64s(&array(&s, "sxx")), sxx);
        assert_eq!(f64s(&array(&s, "displacement")), u);
        let connectivity = int64s(&array(&s, "connectivity"));
        let expected: Vec<i64> = m
            .cells
            .iter()
            .flat_map(|c| c.nodes.iter().map(|&n| n as i64))
            .collect();
        assert_eq!(connectivity, expected);
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
        assert_eq!(int64s(&array(&line, "connectivity")), [0, 1, 1, 2]);
        assert_eq!(int64s(&array(&line, "offsets")), [2, 4]);
        assert_eq!(array(&line, "types"), [3, 3]);
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

    /// RFC 4648 base64 decoding, padded input.
    fn base64_decode(text: &str) -> Vec<u8> {
        let value = |c: u8| BASE64.iter().position(|&b| b == c).unwrap() as u32;
        let mut out = Vec::new();
        for quad in text.as_bytes().chunks(4) {
            let pad = quad.iter().filter(|&&c| c == b'=').count();
            let v = quad
                .iter()
                .map(|&c| if c == b'=' { 0 } else { value(c) })
                .fold(0u32, |v, d| (v << 6) | d);
            out.extend_from_slice(&v.to_be_bytes()[1..4 - pad]);
        }
        out
    }

    /// The bytes of the inline binary `DataArray` named `name`, read as a VTU reader does: the
    /// base64 stream decoded, the UInt64 byte count checked against what follows it.
    fn array(text: &str, name: &str) -> Vec<u8> {
        let tag = text.find(&format!("Name=\"{name}\"")).unwrap();
        let body = &text[tag..];
        let body = &body[body.find('>').unwrap() + 1..body.find("</DataArray>").unwrap()];
        let bytes = base64_decode(body.trim());
        let count = u64::from_le_bytes(bytes[..8].try_into().unwrap()) as usize;
        assert_eq!(count, bytes.len() - 8, "{name}: header and length");
        bytes[8..].to_vec()
    }

    fn f64s(bytes: &[u8]) -> Vec<f64> {
        bytes
            .chunks(8)
            .map(|b| f64::from_le_bytes(b.try_into().unwrap()))
            .collect()
    }

    fn int64s(bytes: &[u8]) -> Vec<i64> {
        bytes
            .chunks(8)
            .map(|b| i64::from_le_bytes(b.try_into().unwrap()))
            .collect()
    }

    /// Base64 against RFC 4648's test vectors (§10).
    #[test]
    fn base64_is_rfc_4648() {
        for (plain, encoded) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            let mut s = String::new();
            base64_into(&mut s, plain.as_bytes());
            assert_eq!(s, encoded);
            assert_eq!(base64_decode(&s), plain.as_bytes());
        }
    }

    proptest::proptest! {
        /// Every value written reads back to the same bits, whatever the magnitude
        /// (subnormals, ±0, the extremes of f64), and every length of the base64 stream.
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
            let back = f64s(&array(&s, "v"));
            proptest::prop_assert_eq!(back.len(), values.len());
            for (a, b) in back.iter().zip(&values) {
                proptest::prop_assert_eq!(a.to_bits(), b.to_bits());
            }
        }
    }
}
