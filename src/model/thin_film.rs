//! The thin-film model of thesis §5.3 cut from the embedded model: the sublaminate's cells,
//! their nodes, and the lower crack face's nodes (no cell holds them; they are prescribed with
//! the base's motion and give VCCT the lower face's displacement behind the front, §2.8).

use super::ModelKind;
use crate::error::Error;
use nonlin3d_laminate::Stiffness;
use nonlin3d_mesh::names::{BASE, BONDED, CRACK_LOWER, CRACK_UPPER, SUBLAMINATE, Z0};
use nonlin3d_mesh::{Front, Mesh};

/// The sublaminate of the embedded model (`full`, with its front) alone, renumbered: node set
/// `bonded` = the nodes on z = H that are not on the upper crack face (the bonded lower face,
/// the front line, and the kept lower crack face), `crack_lower` kept (as isolated nodes),
/// `z0` and `base` dropped; the front's nodes and cells renumbered.
pub(super) fn cut((full, front): (Mesh, Front)) -> Result<(Mesh, Front), Error> {
    let set = |name: &str| full.node_sets.get(name).cloned().unwrap_or_default();
    let cells = full.cell_sets.get(SUBLAMINATE).cloned().unwrap_or_default();
    let (mut mesh, mut node_map) = full.extract(&cells)?;
    // The lower crack face joins as isolated nodes after the sublaminate's.
    let lower = set(CRACK_LOWER);
    for &n in &lower {
        if node_map[n].is_none() {
            node_map[n] = Some(mesh.nodes.len());
            mesh.nodes.push(full.nodes[n]);
        }
    }
    let renumber = |n: usize| -> Result<usize, Error> {
        node_map[n].ok_or(Error::NoNodeAt {
            what: "a VCCT node of the front in the thin-film model",
        })
    };
    let mut cell_map = vec![None; full.cells.len()];
    for (new, &c) in cells.iter().enumerate() {
        cell_map[c] = Some(new);
    }
    let lower: Vec<usize> = lower
        .iter()
        .map(|&n| renumber(n))
        .collect::<Result<_, _>>()?;
    mesh.node_sets.insert(CRACK_LOWER.into(), lower);
    mesh.node_sets.remove(Z0);
    mesh.cell_sets.remove(BASE);
    // z = H: the front's nodes are at the plane exactly (shared by both faces).
    let plane = front
        .points
        .first()
        .map(|p| full.nodes[p.c][2])
        .ok_or(Error::NoNodeAt {
            what: "a delamination front to cut the thin-film model at",
        })?;
    let upper: std::collections::HashSet<usize> = mesh
        .node_sets
        .get(CRACK_UPPER)
        .into_iter()
        .flatten()
        .copied()
        .collect();
    let tol = 1e-9 * plane.abs().max(1e-3);
    let bonded = (0..mesh.nodes.len())
        .filter(|&n| (mesh.nodes[n][2] - plane).abs() < tol && !upper.contains(&n))
        .collect();
    mesh.node_sets.insert(BONDED.into(), bonded);
    let mut front = front;
    for p in &mut front.points {
        p.c = renumber(p.c)?;
        p.a_upper = renumber(p.a_upper)?;
        p.a_lower = renumber(p.a_lower)?;
        p.b_upper = p.b_upper.map(renumber).transpose()?;
        p.b_lower = p.b_lower.map(renumber).transpose()?;
        p.d = p.d.map(renumber).transpose()?;
        p.cells_above = p.cells_above.iter().filter_map(|&c| cell_map[c]).collect();
    }
    Ok((mesh, front))
}

/// The thin-film kind with the base's Poisson ratios under uniaxial stress σ_x (the base
/// laminate free in y and z, §5.3): ε_y/ε_x = S12/S11 and ε_z/ε_x = S13/S11, S = C⁻¹ of the
/// base material (material 0: the homogeneous laminate, or the homogenised base of a layup).
pub(super) fn kind(materials: &[Stiffness]) -> Result<ModelKind, Error> {
    let base = materials.first().ok_or(Error::NoMaterial)?;
    let s = base
        .matrix()
        .try_inverse()
        .ok_or(Error::SingularMaterial { index: 0 })?;
    Ok(ModelKind::ThinFilm {
        nu_y: s[(0, 1)] / s[(0, 0)],
        nu_z: s[(0, 2)] / s[(0, 0)],
    })
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use crate::model::{Axis, Nodes, Value, build_model};
    use crate::scene::Scene;
    use nonlin3d_mesh::names::{BONDED, CRACK_LOWER, CRACK_UPPER, Z0};

    fn scene() -> Scene {
        let text = include_str!("../../examples/scenes/thin_film_circle_30mm.toml");
        Scene::from_toml(text).unwrap()
    }

    /// The cut keeps the sublaminate's cells; every front node VCCT pairs lies in the cut
    /// mesh at the full mesh's position, the lower face's nodes on the bonded set, and the
    /// base's uniaxial Poisson ratios of the quasi-isotropic laminate lie in (0, 0.5).
    #[test]
    fn the_cut_keeps_the_front_and_bonds_the_lower_face() {
        let thin = build_model(&scene()).unwrap();
        let mut full_scene = scene();
        let text = full_scene
            .to_toml()
            .unwrap()
            .replace("thin-film", "embedded");
        full_scene = Scene::from_toml(&text).unwrap();
        let full = build_model(&full_scene).unwrap();
        let sub = full.mesh.cell_sets["sublaminate"].len();
        assert_eq!(thin.mesh.cells.len(), sub);
        assert_eq!(thin.front.points.len(), full.front.points.len());
        for (t, f) in thin.front.points.iter().zip(&full.front.points) {
            for (a, b) in [(t.c, f.c), (t.a_upper, f.a_upper), (t.a_lower, f.a_lower)] {
                assert_eq!(thin.mesh.nodes[a], full.mesh.nodes[b]);
            }
            assert_eq!(t.cells_above.len(), f.cells_above.len());
        }
        let bonded = &thin.mesh.node_sets[BONDED];
        assert!(
            thin.mesh.node_sets[CRACK_LOWER]
                .iter()
                .all(|n| bonded.contains(n))
        );
        assert!(
            thin.mesh.node_sets[CRACK_UPPER]
                .iter()
                .all(|n| !bonded.contains(n))
        );
        assert!(!thin.mesh.node_sets.contains_key(Z0));
        let supports = thin.supports().unwrap();
        let ratios: Vec<f64> = supports
            .iter()
            .filter(|s| s.nodes == Nodes::Set(BONDED))
            .map(|s| match s.value {
                Value::Uniform { ratio } => ratio,
                _ => f64::NAN,
            })
            .collect();
        assert_eq!(ratios.len(), 3);
        assert_eq!(ratios[0], 1.0);
        // The ratios are S12/S11 = −ν_xy and S13/S11 = −ν_xz of the laminate: negative.
        assert!(ratios[1] < 0.0 && ratios[1] > -0.5, "{ratios:?}");
        assert!(ratios[2] < 0.0 && ratios[2] > -0.5, "{ratios:?}");
        let held_z = supports.iter().filter(|s| s.axis == Axis::Z).count();
        assert_eq!(held_z, 1);
    }
}
