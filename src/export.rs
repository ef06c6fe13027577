//! A scene as an Abaqus/CalculiX deck (`nonlin3d export`): the same mesh, materials, supports,
//! the perturbation step, its removal, and one NLGEOM step per strain (or load) level, so
//! CalculiX can run the analysis unchanged (§3.2 protocol as deck steps).

use crate::Error;
use crate::model::{
    Model, Nodes, Support, Value, build_model, perturbation_force, perturbation_loads,
};
use crate::problem::load_factors;
use crate::scene::{CrackFacesName, Scene};
use nonlin3d_mesh::inp::{
    InpBoundary, InpCload, InpDeck, InpElastic, InpMaterial, InpStep, Penalty, add_crack_surfaces,
    contact_cards, inp_string,
};

/// A support as `*BOUNDARY` lines at load factor `f` of the largest strain `reference`: the
/// set, the component numbered from 1, the value; a support whose value varies from node to
/// node (the thin film's bonded face, [`Value::Uniform`]) one line per node, on the node's
/// own set `<set>_<node id>` that [`deck_of`] adds.
fn boundary(model: &Model, support: &Support, f: f64, reference: f64) -> Vec<InpBoundary> {
    let dof = support.axis.offset() as u8 + 1;
    let line = |nset: String, x: [f64; 3]| InpBoundary {
        nset,
        first: dof,
        last: dof,
        value: support.value.at(support.axis, x, f * reference),
    };
    match (support.nodes.clone(), support.value) {
        (Nodes::Set(name), Value::Uniform { .. }) => model
            .node_set(name)
            .unwrap_or_default()
            .iter()
            .map(|&n| line(node_set_name(name, n), model.mesh.nodes[n]))
            .collect(),
        (Nodes::Set(name) | Nodes::Node { set: name, .. }, _) => {
            vec![line(name.into(), [0.0; 3])]
        }
    }
}

/// The one-node set of node `n` (0-based) of set `set` in a deck (ids are indices + 1).
fn node_set_name(set: &str, n: usize) -> String {
    format!("{set}_{}", n + 1)
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
///
/// With the scene's crack-face contact `on` (thesis §2.7) and a mesh with crack faces, the
/// deck also holds the faces as element surfaces and a frictionless node-to-surface
/// `*CONTACT PAIR` (the upper face's element faces against the lower face's,
/// [`contact_penalty`]), which CalculiX applies in every step. With `auto` (the default) no
/// contact is written: CalculiX's penalty contact acts from the first increment, where
/// `auto` acts only once the faces overlap, and it does not converge on the through-width
/// strip (`fig_3_2_3_through_width.toml`: too many cutbacks at ε = −0.00046 of the first
/// step, with K from 1e14 to 7e15 Pa/m and with `SMALL SLIDING`), which runs without it.
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
    // The supports of `Model::supports`: the held ones in the first step (they stay), the
    // prescribed end displacement in every step; a single node becomes a set of its own.
    let supports = model.supports()?;
    for s in &supports {
        match s.nodes {
            Nodes::Set(name) => {
                let nodes = model.node_set(name)?;
                if matches!(s.value, Value::Uniform { .. }) {
                    for &n in nodes {
                        mesh.node_sets.insert(node_set_name(name, n), vec![n]);
                    }
                }
            }
            Nodes::Node { set, node } => {
                mesh.node_sets.insert(set.into(), vec![node]);
            }
        }
    }
    let (held, driven): (Vec<&Support>, Vec<&Support>) =
        supports.iter().partition(|s| s.value == Value::Zero);
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
    let first = |k: usize| -> Vec<InpBoundary> {
        match k {
            0 => held
                .iter()
                .flat_map(|s| boundary(model, s, 0.0, 0.0))
                .collect(),
            _ => Vec::new(),
        }
    };
    if let Some(load) = model.central_load() {
        // The whole plate's load P, its share (a quarter on the quarter model) split over the
        // set's nodes (one: the centre).
        let nodes = model.node_set(load.set)?;
        let share = 1.0 / nodes.len() as f64;
        let centre: Vec<(usize, f64)> = nodes.iter().map(|&n| (3 * n + 2, share)).collect();
        for (k, f) in factors.iter().enumerate() {
            steps.push(step(
                first(k),
                cloads(&centre, load.fraction * f * reference),
            ));
        }
    } else {
        // The perturbation split over the `center_top` nodes; none (and no set needed) for 0.
        let p = perturbation_loads(model, perturbation_force(scene, model)?)?;
        for (k, f) in factors.iter().enumerate() {
            let mut b = first(k);
            b.extend(
                driven
                    .iter()
                    .flat_map(|s| boundary(model, s, *f, reference)),
            );
            steps.push(step(b, cloads(&p, 1.0)));
            if !p.is_empty() {
                steps.push(step(Vec::new(), cloads(&p, 0.0)));
            }
        }
    }
    let contact = scene.contact.crack_faces == CrackFacesName::On && add_crack_surfaces(&mut mesh)?;
    let mut text = inp_string(&InpDeck {
        heading: scene.title.clone(),
        mesh: &mesh,
        materials: &materials,
        steps,
    })?;
    if contact {
        let cards = contact_cards(&mesh, contact_penalty(model))?;
        let at = text.find("*STEP").unwrap_or(text.len());
        text.insert_str(at, &cards);
    }
    Ok(match scene.analysis.integration {
        crate::scene::RuleName::Gauss2 => text.replace("TYPE=C3D20,", "TYPE=C3D20R,"),
        _ => text,
    })
}

/// CalculiX's penalty for the hard crack-face contact: K = 100·C₃₃/t (Pa/m), with C₃₃ the
/// largest through-thickness stiffness of the materials and t the thinnest cell above the
/// crack (the z extent of the cells holding an upper-face node), so that a contact pressure p
/// closes the faces by p/K, 1 % of what it compresses that cell (p·t/C₃₃); σ∞ = 1e-6·C₃₃ (Pa),
/// the small tension CalculiX's node-to-surface law keeps at large clearances.
pub fn contact_penalty(model: &Model) -> Penalty {
    let c33 = model
        .materials
        .iter()
        .map(|s| s.c()[2][2])
        .fold(0.0, f64::max);
    let mesh = &model.mesh;
    let upper: std::collections::HashSet<usize> = mesh
        .node_sets
        .get(nonlin3d_mesh::names::CRACK_UPPER)
        .map(|s| s.iter().copied().collect())
        .unwrap_or_default();
    let t = mesh
        .cells
        .iter()
        .filter(|c| c.nodes.iter().any(|v| upper.contains(v)))
        .map(|c| {
            let z = c.nodes.iter().map(|&v| mesh.nodes[v][2]);
            z.clone().fold(f64::MIN, f64::max) - z.fold(f64::MAX, f64::min)
        })
        .fold(f64::INFINITY, f64::min);
    let t = if t.is_finite() && t > 0.0 { t } else { model.h };
    Penalty {
        stiffness: 100.0 * c33 / t,
        tension: 1e-6 * c33,
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::problem::constraints;
    use nonlin3d_mesh::{InpModel, NodeRef, read_inp};
    use std::collections::BTreeMap;

    /// The nodes a deck line names, as 0-based indices of the deck's mesh.
    fn nodes(deck: &InpModel, target: &NodeRef) -> Vec<usize> {
        match target {
            NodeRef::Node(n) => vec![*n],
            NodeRef::Set(name) => deck.mesh.node_sets[name].clone(),
        }
    }

    /// The exported deck and the analysis's constraints of one scene agree: in the step of the
    /// largest strain (load factor 1, the constraints' λ = 1) the DOFs the deck holds or
    /// prescribes, with the `*BOUNDARY` lines of every step up to it in force, are the DOFs the
    /// constraints hold or prescribe, with the same values (u = x_end·1·ε_ref both ways, bit for bit
    /// where the deck's 13 digits hold the value); its `*CLOAD`s are the plate's P/4, or the perturbation force.
    fn deck_matches_constraints(toml: &str) {
        let scene = Scene::from_toml(toml).unwrap();
        let model = build_model(&scene).unwrap();
        let (factors, reference) = load_factors(&scene);
        let c = constraints(&model, reference).unwrap();
        let deck = read_inp(&deck_of(&scene, &model).unwrap()).unwrap();
        assert_eq!(deck.mesh.nodes.len(), model.mesh.nodes.len());
        assert!(deck.node_ids.iter().enumerate().all(|(i, &id)| id == i + 1));
        let last = factors.iter().position(|&f| f == 1.0).unwrap();
        // The strain models write two steps per level (perturbation on, then off).
        let per_level = deck.steps.len() / factors.len();
        let upto = per_level * last;
        let mut held = BTreeMap::new();
        let steps = &deck.steps[..=upto];
        let lines = deck
            .initial_boundaries
            .iter()
            .chain(steps.iter().flat_map(|s| &s.boundaries));
        for b in lines {
            for n in nodes(&deck, &b.target) {
                for dof in b.first..=b.last {
                    held.insert(3 * n + dof as usize - 1, b.value);
                }
            }
        }
        let expected: BTreeMap<usize, f64> = c.prescribed().collect();
        assert!(!expected.is_empty());
        // The deck writer prints 13 significant digits: values that are not short decimals
        // (the thin film's u = ε·x at each node) come back within 5e-13 relative of the largest.
        let scale = expected.values().fold(0.0_f64, |m, v| m.max(v.abs()));
        assert!(
            held.keys().eq(expected.keys())
                && held
                    .iter()
                    .zip(&expected)
                    .all(|((_, a), (_, b))| (a - b).abs() <= 1e-12 * scale),
            "{}: {held:?} against {expected:?}",
            scene.title
        );
        let mut loads = BTreeMap::new();
        for l in &deck.steps[upto].cloads {
            for n in nodes(&deck, &l.target) {
                loads.insert(3 * n + l.dof as usize - 1, l.value);
            }
        }
        let expected: BTreeMap<usize, f64> = if model.central_load().is_some() {
            let mut f = vec![0.0; c.n()];
            c.external(1.0, &mut f);
            f.iter()
                .enumerate()
                .filter(|&(_, &v)| v != 0.0)
                .map(|(d, &v)| (d, v))
                .collect()
        } else {
            let force = perturbation_force(&scene, &model).unwrap();
            perturbation_loads(&model, force)
                .unwrap()
                .into_iter()
                .collect()
        };
        assert!(!expected.is_empty());
        assert_eq!(loads, expected, "{}", scene.title);
    }

    /// Embedded (the reference scene on 4 slices, three strains: the largest last).
    #[test]
    fn embedded_deck_matches_constraints() {
        let text = crate::scene::THESIS_SCENE.replace("slices = 8", "slices = 4");
        deck_matches_constraints(&text);
    }

    /// Edge: y = 0 free, the one node that holds it in y written as a set of its own.
    #[test]
    fn edge_deck_matches_constraints() {
        deck_matches_constraints(include_str!(
            "../examples/scenes/fig_5_5_1_edge_semicircle_15mm.toml"
        ));
    }

    /// Through-width: v = 0 on both sides.
    #[test]
    fn through_width_deck_matches_constraints() {
        deck_matches_constraints(include_str!(
            "../examples/scenes/fig_3_2_3_through_width.toml"
        ));
    }

    /// Thin film: no z = 0; every bonded node prescribed on its own set with the base's
    /// displacement there (u = ε·x, v = (S12/S11)·ε·y, w = (S13/S11)·ε·z).
    #[test]
    fn thin_film_deck_matches_constraints() {
        let text = include_str!("../examples/scenes/thin_film_circle_30mm.toml")
            .replace("slices = 8", "slices = 4");
        deck_matches_constraints(&text);
    }

    /// Plate: no prescribed end, the central load instead.
    #[test]
    fn plate_deck_matches_constraints() {
        deck_matches_constraints(include_str!("../examples/scenes/fig_4_1_1_plate.toml"));
    }

    /// Contact `on`: the deck's `*CONTACT PAIR`, read back, pairs every upper crack-face node
    /// with its partner of the mesh's paired sets, and nothing else (the front's nodes, on both
    /// faces, are left out); `auto` and `off` write no contact.
    #[test]
    fn contact_on_writes_the_crack_face_pairs() {
        let text = include_str!("../examples/scenes/fig_5_1_3_circle_30mm_contact.toml")
            .replace("slices = 8", "slices = 4");
        let scene = Scene::from_toml(&text).unwrap();
        let model = build_model(&scene).unwrap();
        let deck = read_inp(&deck_of(&scene, &model).unwrap()).unwrap();
        assert_eq!(deck.contact.len(), 1);
        let read: std::collections::BTreeSet<(usize, usize)> = deck.contact[0]
            .slave
            .iter()
            .copied()
            .zip(deck.contact[0].master.iter().copied())
            .collect();
        let sets = &model.mesh.node_sets;
        let expected: std::collections::BTreeSet<(usize, usize)> = sets["crack_upper"]
            .iter()
            .copied()
            .zip(sets["crack_lower"].iter().copied())
            .collect();
        assert!(!expected.is_empty());
        assert_eq!(read, expected);
        for faces in ["auto", "off"] {
            let other = text.replace(
                "crack_faces = \"on\"",
                &format!("crack_faces = \"{faces}\""),
            );
            assert_ne!(other, text);
            let scene = Scene::from_toml(&other).unwrap();
            let written = deck_of(&scene, &model).unwrap();
            assert!(!written.contains("*CONTACT PAIR"), "{faces}");
        }
    }
}
