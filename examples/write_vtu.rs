//! Writes a graded Hex20 box with a displacement field and a cell field as VTU, and a two-step
//! PVD series, into the directory given as the first argument (default `target/vtu-example`).
//! CI reads the result back with meshio (`tests/meshio_check.py`).

use nonlin3d::element::ElementKind;
use nonlin3d::mesh::vtu::{Field, write_pvd, write_vtu};
use nonlin3d::mesh::{BoxParams, structured_box};
use std::path::PathBuf;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = PathBuf::from(
        std::env::args()
            .nth(1)
            .unwrap_or_else(|| "target/vtu-example".into()),
    );
    std::fs::create_dir_all(&dir)?;
    let mut p = BoxParams::new(ElementKind::Hex20, [4, 3, 2], [4e-3, 3e-3, 0.5e-3]);
    p.grading = [0.5, 1.0, 1.0];
    let mesh = structured_box(&p)?;
    let mut steps = Vec::new();
    for (step, scale) in [1.0, 2.0].into_iter().enumerate() {
        // u = scale·(1e-3·x, 2e-3·y, −0.1·x²): a known field the reader can check.
        let u: Vec<f64> = mesh
            .nodes
            .iter()
            .flat_map(|x| {
                [
                    scale * 1e-3 * x[0],
                    scale * 2e-3 * x[1],
                    -scale * 0.1 * x[0] * x[0],
                ]
            })
            .collect();
        let sxx: Vec<f64> = (0..mesh.cells.len())
            .map(|c| scale * (c as f64) * 1e6)
            .collect();
        let name = format!("box_{step}.vtu");
        write_vtu(
            &dir.join(&name),
            &mesh,
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
        )?;
        steps.push((scale, name));
    }
    write_pvd(&dir.join("box.pvd"), &steps)?;
    println!(
        "{} nodes, {} cells written to {}",
        mesh.nodes.len(),
        mesh.cells.len(),
        dir.display()
    );
    Ok(())
}
