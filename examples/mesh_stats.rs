//! Prints size and quality figures of the embedded delamination meshes (recorded in
//! docs/MESH.md) and writes the reference mesh as VTU to the directory given (default
//! `target/mesh-example`).

use nonlin3d::mesh::names;
use nonlin3d::mesh::vtu::write_vtu;
use nonlin3d::mesh::{EllipticMap, EmbeddedParams, embedded_delamination, quality};
use std::path::PathBuf;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = PathBuf::from(
        std::env::args()
            .nth(1)
            .unwrap_or_else(|| "target/mesh-example".into()),
    );
    std::fs::create_dir_all(&dir)?;
    println!(
        "| case | slices | nodes | cells | crack pairs | min scaled Jacobian | max aspect ratio |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|");
    let base = EmbeddedParams::thesis_reference();
    let cases = [
        ("30 mm circle", 15e-3, 15e-3, EllipticMap::Conformal),
        (
            "30 × 60 mm ellipse, eq. 3.1.1",
            15e-3,
            30e-3,
            EllipticMap::Conformal,
        ),
        (
            "30 × 60 mm ellipse, eq. 3.1.2 (r = 14 mm)",
            15e-3,
            30e-3,
            EllipticMap::Modified { r: 14e-3 },
        ),
        ("60 mm circle", 30e-3, 30e-3, EllipticMap::Conformal),
        (
            "25.4 × 50.8 mm rectangle (§5.3)",
            12.7e-3,
            25.4e-3,
            EllipticMap::Rectangle,
        ),
    ];
    // The thesis's own centre (axis nodes on a 1e-9 m arc) for comparison.
    for slices in [4, 8, 12] {
        let p = EmbeddedParams {
            slices,
            centre: nonlin3d::mesh::Centre::ThesisArc,
            ..base.clone()
        };
        match embedded_delamination(&p) {
            Ok(m) => {
                let q = quality(&m)?;
                let min = q
                    .iter()
                    .map(|c| c.min_scaled_jacobian)
                    .fold(f64::INFINITY, f64::min);
                let aspect = q.iter().map(|c| c.aspect_ratio).fold(0.0, f64::max);
                println!(
                    "| 30 mm circle, thesis centre (1e-9 m arc) | {slices} | {} | {} | {} | {min:.3} | {aspect:.1e} |",
                    m.nodes.len(),
                    m.cells.len(),
                    m.node_sets[names::CRACK_UPPER].len()
                );
            }
            Err(e) => {
                println!("| 30 mm circle, thesis centre (1e-9 m arc) | {slices} | {e} | | | | |")
            }
        }
    }
    for (name, a, b, map) in cases {
        for slices in [4, 8, 12] {
            let p = EmbeddedParams {
                a,
                b,
                map,
                slices,
                w: if a.max(b) > 20e-3 { 60e-3 } else { base.w },
                ..base.clone()
            };
            let m = embedded_delamination(&p)?;
            let q = quality(&m)?;
            let min = q
                .iter()
                .map(|c| c.min_scaled_jacobian)
                .fold(f64::INFINITY, f64::min);
            let aspect = q.iter().map(|c| c.aspect_ratio).fold(0.0, f64::max);
            println!(
                "| {name} | {slices} | {} | {} | {} | {min:.3} | {aspect:.1} |",
                m.nodes.len(),
                m.cells.len(),
                m.node_sets[names::CRACK_UPPER].len()
            );
            if slices == 8 && name.starts_with("30 × 60 mm ellipse, eq. 3.1.1") {
                write_vtu(&dir.join("ellipse_30x60.vtu"), &m, &[], &[])?;
            }
            if slices == 8 && name.contains("eq. 3.1.2") {
                write_vtu(&dir.join("ellipse_30x60_modified.vtu"), &m, &[], &[])?;
            }
            if slices == 8 && name.contains("rectangle") {
                write_vtu(&dir.join("rectangle.vtu"), &m, &[], &[])?;
            }
            if slices == 8 && name == "30 mm circle" {
                write_vtu(&dir.join("circle_30.vtu"), &m, &[], &[])?;
            }
        }
    }
    Ok(())
}
