//! The finite element model of a scene: its mesh, front, materials and boundary-condition
//! family, as [`build_model`] makes it and the results keep it for output;
//! and the model's supports, load and perturbation force (thesis §3.2), held here once for
//! both the analysis's constraints ([`crate::analysis::constraints`]) and the exported deck's
//! `*BOUNDARY` and `*CLOAD` lines ([`crate::export`]).

use crate::error::Error;
use crate::scene::{Geometry, MapName, Scene, Shape};
use nonlin3d_laminate::Stiffness;
use nonlin3d_mesh::names::{BONDED, CENTER_TOP, CRACK_LOWER, X0, X1, Y_HOLD, Y0, Y1, Z0};
use nonlin3d_mesh::{
    EllipticMap, EmbeddedParams, Front, FrontBand, Imperfection, LayerBand, Mesh, MidEdges,
    PlyLayout, ThroughWidthParams, embedded_delamination_with_front, through_width_delamination,
};

/// Which boundary conditions a model gets (thesis §3.2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ModelKind {
    /// u = 0 on x = 0, v = 0 on y = 0, w = 0 on z = 0, u = W·ε on x = W.
    Embedded,
    /// As embedded, y = 0 free (one node fixed in y against the rigid motion).
    Edge,
    /// As embedded plus v = 0 on y = W (plane strain).
    ThroughWidth,
    /// u = 0 on x = 0, v = 0 on y = 0, w = 0 on z = 0; the central transverse load.
    Plate,
    /// The thin-film model (§5.3): the sublaminate alone; u = 0 on x = 0, v = 0 on y = 0,
    /// u = W·ε on x = W, and its lower face outside the delamination (with the lower crack
    /// face kept for VCCT's openings) moved with the base laminate's uniform strain.
    ThinFilm {
        /// S12/S11 of the base material: ε_y = (S12/S11)·ε under uniaxial stress.
        nu_y: f64,
        /// S13/S11 of the base material: ε_z = (S13/S11)·ε.
        nu_z: f64,
    },
}

/// The finite element model of a scene.
#[derive(Debug, Clone)]
pub struct Model {
    /// The mesh (SI units).
    pub mesh: Mesh,
    /// The delamination front.
    pub front: Front,
    /// Materials as indexed by the cells.
    pub materials: Vec<Stiffness>,
    /// Integration rule of every cell (the scene's `analysis.integration`).
    pub rule: nonlin3d_element::IntegrationRule,
    /// Boundary-condition family.
    pub kind: ModelKind,
    /// x of the loaded end (u = x_end·ε there), m.
    pub x_end: f64,
    /// Sublaminate thickness h, m.
    pub h: f64,
    /// Smallest in-plane semi-dimension of the delamination (for the perturbation size), m:
    /// min(a, b) embedded and edge, the radius for the plate, the half-length a through the
    /// width.
    pub a_min: f64,
    /// The front's planform as a curve (for the thesis's partition, §3.2).
    pub front_shape: nonlin3d_mesh::FrontShape,
}

/// Builds the mesh and front of a scene (with its imperfection, if any): the embedded
/// generator for embedded, edge and plate models (thesis §3.1), the strip for through-width;
/// `[mesh] accuracy` or the default mesh resolved to knobs first.
pub fn build_model(scene: &Scene) -> Result<Model, Error> {
    scene.validate()?;
    // `[mesh] accuracy` (the knobs its table picks, under the scene's own) or, without knobs,
    // the default mesh (docs/MESH.md).
    let (resolved, _) = crate::analysis::estimate::resolve_mesh(scene)?;
    let scene = &resolved;
    // Nodes and cells estimated from the scene before anything is allocated.
    crate::budget::check_mesh(scene, &crate::budget::limit())?;
    let materials = scene.stiffnesses()?;
    let (mut mesh, front, model_kind, x_end, h, a_min, front_shape) = match &scene.geometry {
        Geometry::Embedded {
            shape,
            a_mm,
            b_mm,
            h_mm,
            base_mm,
            w_mm,
        }
        | Geometry::Edge {
            shape,
            a_mm,
            b_mm,
            h_mm,
            base_mm,
            w_mm,
        } => {
            let p = embedded_params(scene, *shape, *a_mm, *b_mm, *h_mm, *base_mm, *w_mm);
            let (m, f) = embedded_delamination_with_front(&p)?;
            let k = if matches!(scene.geometry, Geometry::Edge { .. }) {
                ModelKind::Edge
            } else {
                ModelKind::Embedded
            };
            (m, f, k, p.w, p.h, p.a.min(p.b), p.front_shape())
        }
        Geometry::ThinFilm {
            shape,
            a_mm,
            b_mm,
            h_mm,
            base_mm,
            w_mm,
        } => {
            let p = embedded_params(scene, *shape, *a_mm, *b_mm, *h_mm, *base_mm, *w_mm);
            let (m, f) = thin_film::cut(embedded_delamination_with_front(&p)?)?;
            let k = thin_film::kind(&materials)?;
            (m, f, k, p.w, p.h, p.a.min(p.b), p.front_shape())
        }
        Geometry::Plate {
            a_mm,
            h_mm,
            base_mm,
            w_mm,
        } => {
            let p = embedded_params(scene, Shape::Ellipse, *a_mm, *a_mm, *h_mm, *base_mm, *w_mm);
            let (m, f) = embedded_delamination_with_front(&p)?;
            (m, f, ModelKind::Plate, p.w, p.h, p.a, p.front_shape())
        }
        Geometry::ThroughWidth {
            a_mm,
            length_mm,
            width_mm,
            h_mm,
            base_mm,
        } => {
            let p = through_width_params(scene, *a_mm, *length_mm, *width_mm, *h_mm, *base_mm)?;
            let (m, f) = through_width_delamination(&p)?;
            let shape = p.front_shape();
            (m, f, ModelKind::ThroughWidth, p.length, p.h, p.a, shape)
        }
    };
    if let Some((shape, amp)) = imperfection(scene) {
        let base = scene.geometry.base_mm() * MM;
        mesh.apply_imperfection(base, CRACK_LOWER, shape, amp)?;
    }
    Ok(Model {
        mesh,
        front,
        materials,
        rule: scene.analysis.integration.rule(),
        kind: model_kind,
        x_end,
        h,
        a_min,
        front_shape,
    })
}

mod thin_film;

/// A millimetre in metres (scenes are in mm, models in SI).
const MM: f64 = 1e-3;

/// The scene's element kind (Hex20 unless it names one).
fn element_kind(scene: &Scene) -> nonlin3d_element::ElementKind {
    scene
        .mesh
        .element
        .map_or(nonlin3d_element::ElementKind::Hex20, |e| e.kind())
}

/// The embedded generator's parameters for a planform `shape` with semi-axes a, b, the
/// sublaminate h on the base H, in a quarter model of size W (all in mm): the scene's mesh
/// controls over the thesis's reference mesh; eq. 3.1.2's modified map for an ellipse unless
/// the scene asks for the conformal map of eq. 3.1.1.
pub(crate) fn embedded_params(
    scene: &Scene,
    shape: Shape,
    a: f64,
    b: f64,
    h: f64,
    base: f64,
    w: f64,
) -> EmbeddedParams {
    let (c, mm) = (&scene.mesh, MM);
    let d = EmbeddedParams::thesis_reference();
    let plies = scene.layup.as_ref().map(|l| PlyLayout {
        ply_thickness: l.ply_mm * mm,
        sublaminate: l.sublaminate.clone(),
        base_below: l.base_below.clone(),
    });
    EmbeddedParams {
        kind: element_kind(scene),
        a: a * mm,
        b: b * mm,
        h: h * mm,
        base: base * mm,
        w: w * mm,
        slices: c.slices.unwrap_or(d.slices),
        radial_inside: c
            .inside
            .unwrap_or_else(|| EmbeddedParams::radial_inside_for(a, b)),
        radial_outside: c.outside.unwrap_or(d.radial_outside),
        front_grading: c.front_grading.unwrap_or(d.front_grading),
        front_element: c.front_element_mm.map(|e| e * mm).or(d.front_element),
        front_band: c
            .front_band
            .map(|[inside, outside]| FrontBand { inside, outside })
            .or(d.front_band),
        layer_band: c
            .layer_band
            .map(|[inside, outside]| LayerBand { inside, outside })
            .or(d.layer_band),
        sub_layers: c.sub_layers.unwrap_or(d.sub_layers),
        base_layers: c.base_layers.unwrap_or(d.base_layers),
        map: match shape {
            Shape::Ellipse => match c.elliptic_map {
                Some(MapName::Conformal) => EllipticMap::Conformal,
                Some(MapName::Modified) | None => EllipticMap::modified_for(a * mm, b * mm),
            },
            Shape::Rectangle => EllipticMap::Rectangle,
        },
        plies,
        mid_edges: if c.curved_edges == Some(true) {
            MidEdges::Mapped
        } else {
            MidEdges::Chords
        },
        ..d
    }
}

/// The through-width generator's parameters for a delamination of half-length a in a strip of
/// length L and width W, the sublaminate h on the base H (all in mm): the scene's mesh
/// controls over the generator's example mesh. No ply-level layers (refused, naming the field).
pub(crate) fn through_width_params(
    scene: &Scene,
    a_mm: f64,
    length_mm: f64,
    width_mm: f64,
    h_mm: f64,
    base_mm: f64,
) -> Result<ThroughWidthParams, Error> {
    if scene.layup.is_some() {
        return Err(Error::Scene(
            "layup: ply-level layers are available for embedded, edge and plate models only".into(),
        ));
    }
    let (c, mm) = (&scene.mesh, MM);
    let geometry = ThroughWidthParams {
        kind: element_kind(scene),
        a: a_mm * mm,
        length: length_mm * mm,
        width: width_mm * mm,
        h: h_mm * mm,
        base: base_mm * mm,
        ..ThroughWidthParams::example()
    };
    // The knobs not given from the generator's example (a scene without any has the default
    // strip mesh's knobs by now: src/analysis_estimate.rs, `resolve_mesh`).
    let d = ThroughWidthParams::example();
    Ok(ThroughWidthParams {
        inside: c.inside.unwrap_or(d.inside),
        outside: c.outside.unwrap_or(d.outside),
        front_grading: c.front_grading.unwrap_or(d.front_grading),
        across: c.across.unwrap_or(d.across),
        sub_layers: c.sub_layers.unwrap_or(d.sub_layers),
        base_layers: c.base_layers.unwrap_or(d.base_layers),
        ..geometry
    })
}

/// The scene's initial imperfection of the crack's lower face, if any: its shape over the
/// delamination and its amplitude, m.
fn imperfection(scene: &Scene) -> Option<(Imperfection, f64)> {
    let amp = scene.loads.imperfection_mm * MM;
    if amp == 0.0 {
        return None;
    }
    let mm = MM;
    let shape = match &scene.geometry {
        Geometry::Embedded { a_mm, b_mm, .. }
        | Geometry::Edge { a_mm, b_mm, .. }
        | Geometry::ThinFilm { a_mm, b_mm, .. } => Imperfection::Cosine {
            a: a_mm * mm,
            b: b_mm * mm,
        },
        Geometry::ThroughWidth { a_mm, .. } => Imperfection::Strip { a: a_mm * mm },
        Geometry::Plate { a_mm, .. } => Imperfection::Cosine {
            a: a_mm * mm,
            b: a_mm * mm,
        },
    };
    Some((shape, amp))
}

/// A displacement component of a node.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Axis {
    /// u, along x (the loading direction).
    X,
    /// v, along y.
    Y,
    /// w, along z (through the thickness).
    Z,
}

impl Axis {
    /// The component's offset in a node's DOFs: 0, 1, 2 (the global DOF is 3·node + offset);
    /// a deck numbers it one higher.
    pub fn offset(self) -> usize {
        match self {
            Self::X => 0,
            Self::Y => 1,
            Self::Z => 2,
        }
    }
}

/// The nodes a support acts on.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Nodes {
    /// Every node of the mesh's node set of this name (one of [`nonlin3d_mesh::names`]).
    Set(&'static str),
    /// One node (0-based mesh index) the model picks, named `set` where a deck needs a set.
    Node {
        /// The set name in an exported deck.
        set: &'static str,
        /// The node.
        node: usize,
    },
}

/// What a support prescribes on its component.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Value {
    /// Held at zero throughout.
    Zero,
    /// The end displacement u = length·ε, ε the applied strain (load factor × the scene's
    /// largest strain): the loaded end of §3.2, length = W the box's extent in x, m.
    Strain {
        /// The lever of the strain, m.
        length: f64,
    },
    /// The base laminate's uniform strain at each node (the thin-film model, §5.3): the
    /// component = ratio·ε·(the node's coordinate along it), ratio 1 along x, S12/S11 along y
    /// and S13/S11 along z (uniaxial stress σ_x in the base, S its compliance).
    Uniform {
        /// ε along the component over the applied ε.
        ratio: f64,
    },
}

impl Value {
    /// The value at node position `x` (m) on component `axis` at the applied strain `strain`.
    pub fn at(self, axis: Axis, x: [f64; 3], strain: f64) -> f64 {
        match self {
            Self::Zero => 0.0,
            Self::Strain { length } => length * strain,
            Self::Uniform { ratio } => ratio * x[axis.offset()] * strain,
        }
    }
}

/// One support of a model: a component of some nodes held at zero or prescribed.
#[derive(Debug, Clone, PartialEq)]
pub struct Support {
    /// Which nodes.
    pub nodes: Nodes,
    /// Which component.
    pub axis: Axis,
    /// Its value.
    pub value: Value,
}

/// The plate's applied load (§4.1): a fraction of the scene's transverse load P in +z, split
/// equally over the nodes of a set (the quarter model carries P/4 at its centre).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CentralLoad {
    /// The node set that carries it.
    pub set: &'static str,
    /// The model's share of P (1/4 on the quarter model).
    pub fraction: f64,
}

impl Model {
    /// The supports of the model (thesis §3.2), in the order they are applied: u = 0 on x = 0,
    /// w = 0 on z = 0 (the mid-plane), then by [`ModelKind`]:
    /// - embedded, plate: v = 0 on y = 0;
    /// - edge: y = 0 free; v = 0 on the one node of x = W, z = 0 with the largest y (far from
    ///   the delamination), against the rigid motion in y;
    /// - through-width: v = 0 on y = 0 and on y = W (plane strain);
    ///
    /// - thin-film: v = 0 on y = 0, no z = 0 (there is no base);
    ///
    /// then, except on the plate, u = x_end·ε on x = W; and last, on the thin film, the
    /// bonded face (`bonded`: z = H outside the delamination, and the lower crack face) moved
    /// with the base: u = ε·x, v = (S12/S11)·ε·y, w = (S13/S11)·ε·z.
    pub fn supports(&self) -> Result<Vec<Support>, Error> {
        let set = |name, axis| Support {
            nodes: Nodes::Set(name),
            axis,
            value: Value::Zero,
        };
        let mut s = vec![set(X0, Axis::X), set(Z0, Axis::Z)];
        match self.kind {
            ModelKind::Edge => s.push(Support {
                nodes: Nodes::Node {
                    set: Y_HOLD,
                    node: self.y_hold()?,
                },
                axis: Axis::Y,
                value: Value::Zero,
            }),
            ModelKind::ThroughWidth => s.extend([set(Y0, Axis::Y), set(Y1, Axis::Y)]),
            ModelKind::Embedded | ModelKind::Plate => s.push(set(Y0, Axis::Y)),
            ModelKind::ThinFilm { .. } => {
                // No base, so no z = 0: the bonded face carries the base's motion instead
                // (last, so it wins where it meets x = 0, y = 0 or x = W; the values agree).
                s.retain(|s| s.nodes != Nodes::Set(Z0));
                s.push(set(Y0, Axis::Y));
            }
        }
        if self.kind != ModelKind::Plate {
            s.push(Support {
                nodes: Nodes::Set(X1),
                axis: Axis::X,
                value: Value::Strain { length: self.x_end },
            });
        }
        if let ModelKind::ThinFilm { nu_y, nu_z } = self.kind {
            for (axis, ratio) in [(Axis::X, 1.0), (Axis::Y, nu_y), (Axis::Z, nu_z)] {
                s.push(Support {
                    nodes: Nodes::Set(BONDED),
                    axis,
                    value: Value::Uniform { ratio },
                });
            }
        }
        Ok(s)
    }

    /// The applied load besides prescribed displacements: the plate's P/4 on `center_top`;
    /// none for the strain-driven models.
    pub fn central_load(&self) -> Option<CentralLoad> {
        (self.kind == ModelKind::Plate).then_some(CentralLoad {
            set: CENTER_TOP,
            fraction: 0.25,
        })
    }

    /// The nodes of the node set `name`.
    pub fn node_set(&self, name: &str) -> Result<&[usize], Error> {
        self.mesh
            .node_sets
            .get(name)
            .map(Vec::as_slice)
            .ok_or_else(|| Error::MissingSet {
                kind: "node",
                name: name.into(),
            })
    }

    /// The nodes a support acts on.
    pub fn nodes_of<'a>(&'a self, nodes: &'a Nodes) -> Result<&'a [usize], Error> {
        match nodes {
            Nodes::Set(name) => self.node_set(name),
            Nodes::Node { node, .. } => Ok(std::slice::from_ref(node)),
        }
    }

    /// The edge model's y-holder: the node of x = W on z = 0 with the largest y.
    fn y_hold(&self) -> Result<usize, Error> {
        let x = &self.mesh.nodes;
        self.node_set(X1)?
            .iter()
            .copied()
            .filter(|&n| x[n][2] == 0.0)
            .max_by(|&a, &b| x[a][1].total_cmp(&x[b][1]))
            .ok_or(Error::NoNodeAt {
                what: "x = W, z = 0 to hold the edge model in y",
            })
    }
}

/// The perturbation force on the model (N): the scene's, or one that deflects the sublaminate,
/// clamped at the front, by w = h/4 in the linear range.
///
/// - Embedded, edge: the clamped circular plate under a central load, eq. 4.1.1 inverted,
///   P = (h/4)·E·h³/(0.217·a²) with E = 1/S11 of the sublaminate material and a the smaller
///   semi-axis; the quarter model carries P/4.
/// - Through-width: the clamped–clamped beam of length ℓ = 2a under a central load,
///   w = P·ℓ³/(192·E·I), I = W·h³/12 over the width W, E = 1/(S11 − S12²/S22) the plane-strain
///   modulus (ε_y = 0, σ_z = 0); the half model (x ≥ 0) carries P/2, so
///   P/2 = 96·E·I·(h/4)/ℓ³ = 2·E·W·h⁴/ℓ³.
pub fn perturbation_force(scene: &Scene, model: &Model) -> Result<f64, Error> {
    if let Some(p) = scene.loads.perturbation_n {
        return Ok(p);
    }
    let index = model
        .materials
        .len()
        .checked_sub(1)
        .ok_or(Error::NoMaterial)?;
    let s = model.materials[index]
        .matrix()
        .try_inverse()
        .ok_or(Error::SingularMaterial { index })?;
    let h = model.h;
    if model.kind == ModelKind::ThroughWidth {
        let e = 1.0 / (s[(0, 0)] - s[(0, 1)] * s[(0, 1)] / s[(1, 1)]);
        let (lo, hi) = model
            .mesh
            .nodes
            .iter()
            .fold((f64::MAX, f64::MIN), |(lo, hi), x| {
                (lo.min(x[1]), hi.max(x[1]))
            });
        let (width, span) = (hi - lo, 2.0 * model.a_min);
        return Ok(2.0 * e * width * h.powi(4) / span.powi(3));
    }
    let e = 1.0 / s[(0, 0)];
    Ok(0.25 * (0.25 * h) * e * h.powi(3) / (0.217 * model.a_min * model.a_min))
}

/// The perturbation as nodal forces: `force` split equally over the `center_top` nodes, in +z
/// (out of the base). Empty for a zero force, and then the set is not needed.
pub fn perturbation_loads(model: &Model, force: f64) -> Result<Vec<(usize, f64)>, Error> {
    if force == 0.0 {
        return Ok(Vec::new());
    }
    let nodes = model.node_set(CENTER_TOP)?;
    let share = force / nodes.len() as f64;
    Ok(nodes.iter().map(|&n| (3 * n + 2, share)).collect())
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    fn edge() -> Model {
        let text = include_str!("../examples/scenes/fig_5_5_1_edge_semicircle_15mm.toml");
        build_model(&Scene::from_toml(text).unwrap()).unwrap()
    }

    /// The edge model's y = 0 is free: v is held on one node only, on x = W and z = 0 at the
    /// largest y (the corner far from the delamination), and no support names `y0`.
    #[test]
    fn edge_model_holds_one_node_in_y() {
        let model = edge();
        let supports = model.supports().unwrap();
        let in_y: Vec<&Support> = supports.iter().filter(|s| s.axis == Axis::Y).collect();
        assert_eq!(in_y.len(), 1);
        assert!(
            matches!(in_y[0].nodes, Nodes::Node { set: Y_HOLD, .. }),
            "{:?}",
            in_y[0]
        );
        let node = model.nodes_of(&in_y[0].nodes).unwrap()[0];
        let x = &model.mesh.nodes;
        let y_max = x.iter().map(|p| p[1]).fold(f64::MIN, f64::max);
        assert_eq!((x[node][0], x[node][2]), (model.x_end, 0.0));
        // On the box side y = W: the generator's coordinates there come from W through a few
        // operations (round-off of a few ulps, ~1e-17 m at W = 50 mm), so 1e-12·W bounds it.
        assert!((x[node][1] - y_max).abs() <= 1e-12 * y_max, "{:?}", x[node]);
        assert!(supports.iter().all(|s| s.nodes != Nodes::Set(Y0)));
    }

    /// `[mesh] layer_band` reaches the generator (fewer nodes than the same mesh without it:
    /// mesh R of docs/ACCURACY.md §2c), and the companion scene of the error estimate, which
    /// keeps two sublaminate layers, halves the band and still meshes.
    #[test]
    fn the_layer_band_reaches_the_mesh_and_its_companion_halves_it() {
        let text = include_str!("../examples/scenes/fig_5_1_3_circle_30mm.toml");
        let mut scene = Scene::from_toml(text).unwrap();
        let m = &mut scene.mesh;
        (m.slices, m.inside, m.outside) = (Some(6), Some(7), Some(6));
        (m.sub_layers, m.base_layers) = (Some(2), Some(2));
        (m.front_element_mm, m.front_band) = (Some(0.3), Some([5, 3]));
        let plain = build_model(&scene).unwrap().mesh.nodes.len();
        scene.mesh.layer_band = Some([3, 2]);
        let banded = build_model(&scene).unwrap().mesh.nodes.len();
        assert!(banded < plain, "{banded} against {plain} nodes");
        // Two sublaminate layers resolve the split: the companion keeps them (and two base
        // layers), so the layer band survives, halved ([3, 2] → [2, 1]), and still meshes.
        let companion = crate::analysis::estimate::companion_scene(&scene, 1).unwrap();
        assert_eq!(companion.mesh.layer_band, Some([2, 1]));
        assert!(build_model(&companion).is_ok());
    }

    /// A model without the set a support needs says which set, in words.
    #[test]
    fn a_missing_set_is_named() {
        let mut model = edge();
        model.mesh.node_sets.remove(X1);
        let e = model.supports().unwrap_err().to_string();
        assert_eq!(e, "the model has no node set 'x1'");
    }
}
