//! A scene as an Abaqus/CalculiX deck (`nonlin3d export`): the same mesh, materials, supports,
//! the perturbation step, its removal, and one NLGEOM step per strain (or load) level, so
//! CalculiX can run the analysis unchanged (§3.2 protocol as deck steps).

use crate::Error;
use crate::analysis::{
    Model, ModelKind, build_model, load_factors, perturbation_force, perturbation_loads,
};
use crate::scene::Scene;
use nonlin3d_mesh::inp::{
    InpBoundary, InpCload, InpDeck, InpElastic, InpMaterial, InpStep, inp_string,
};

fn boundary(nset: &str, dof: u8, value: f64) -> InpBoundary {
    InpBoundary {
        nset: nset.into(),
        first: dof,
        last: dof,
        value,
    }
}

/// The deck text of a scene. For each strain level two NLGEOM steps: the strain with the
/// perturbation force on, then the force removed at that strain (CalculiX ramps it to zero
/// within the step); the second step's state is the level's answer. Re-applying the force at
/// every level stands in for nonlin3d's inertia check (which applies it at the first level
/// whose trivial state is unstable): below buckling the removal returns to the flat state,
/// above it the sublaminate stays on the buckled branch. The force is split over the
/// `center_top` nodes as in [`perturbation_loads`] (two nodes on a Hex8 through-width strip
/// with an odd number of elements across). A plate gets one step per load.
/// Hex20 cells become C3D20R under the 2×2×2 rule (CalculiX's reduced rule is the same
/// 2×2×2 Gauss rule) and C3D20 under 3×3×3.
pub fn deck(scene: &Scene) -> Result<String, Error> {
    let model = build_model(scene)?;
    deck_of(scene, &model)
}

/// [`deck`] for an already built model.
pub fn deck_of(scene: &Scene, model: &Model) -> Result<String, Error> {
    let mut mesh = model.mesh.clone();
    let materials: Vec<InpMaterial> = model
        .materials
        .iter()
        .enumerate()
        .map(|(k, s)| InpMaterial {
            name: format!("MAT{k}"),
            elastic: InpElastic::Anisotropic(Box::new(*s)),
        })
        .collect();
    let mut supports = vec![boundary("x0", 1, 0.0), boundary("z0", 3, 0.0)];
    match model.kind {
        ModelKind::Edge => {
            let x1 = mesh.node_sets.get("x1").cloned().unwrap_or_default();
            let corner = x1
                .iter()
                .copied()
                .filter(|&n| mesh.nodes[n][2] == 0.0)
                .max_by(|&a, &b| mesh.nodes[a][1].total_cmp(&mesh.nodes[b][1]))
                .ok_or_else(|| Error::Numerical("no node on x = W, z = 0".into()))?;
            mesh.node_sets.insert("vfix".into(), vec![corner]);
            supports.push(boundary("vfix", 2, 0.0));
        }
        ModelKind::ThroughWidth => {
            supports.push(boundary("y0", 2, 0.0));
            supports.push(boundary("y1", 2, 0.0));
        }
        ModelKind::Embedded | ModelKind::Plate => supports.push(boundary("y0", 2, 0.0)),
    }
    let (factors, reference) = load_factors(scene);
    let inc = scene.analysis.max_increment.min(1.0);
    let step = |boundaries: Vec<InpBoundary>, cloads: Vec<InpCload>| InpStep {
        nlgeom: true,
        increment: inc,
        period: 1.0,
        boundaries,
        cloads,
    };
    // (DOF, force) pairs as CLOADs on node DOF 3, scaled.
    let cloads = |loads: &[(usize, f64)], scale: f64| -> Vec<InpCload> {
        loads
            .iter()
            .map(|&(dof, f)| InpCload {
                node: dof / 3,
                dof: 3,
                value: scale * f,
            })
            .collect()
    };
    let mut steps = Vec::new();
    if model.kind == ModelKind::Plate {
        // The whole plate's load P, a quarter of it on the quarter model's centre node.
        let centre = perturbation_loads(model, 1.0)?;
        for (k, f) in factors.iter().enumerate() {
            let b = if k == 0 { supports.clone() } else { Vec::new() };
            steps.push(step(b, cloads(&centre, 0.25 * f * reference)));
        }
    } else {
        // The perturbation split over the `center_top` nodes; none (and no set needed) for 0.
        let p = perturbation_loads(model, perturbation_force(scene, model)?)?;
        for (k, f) in factors.iter().enumerate() {
            let mut b = if k == 0 { supports.clone() } else { Vec::new() };
            b.push(boundary("x1", 1, model.x_end * f * reference));
            steps.push(step(b, cloads(&p, 1.0)));
            if !p.is_empty() {
                steps.push(step(Vec::new(), cloads(&p, 0.0)));
            }
        }
    }
    let text = inp_string(&InpDeck {
        heading: scene.title.clone(),
        mesh: &mesh,
        materials: &materials,
        steps,
    })?;
    Ok(match scene.analysis.integration {
        crate::scene::RuleName::Gauss2 => text.replace("TYPE=C3D20,", "TYPE=C3D20R,"),
        _ => text,
    })
}
