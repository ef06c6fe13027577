//! `Scene`: a serde/TOML description of one delamination analysis (docs/SCENES.md).
//!
//! Lengths are written in mm and moduli in GPa, the unit in each field's name (`a_mm`,
//! `e11_gpa`); everything is converted to SI when the model is built. Unknown fields are
//! errors, so a typo is caught rather than silently ignored.

use crate::Error;
use nonlin3d_element::ElementKind;
use nonlin3d_laminate::{Orthotropic, PlyStack, ShearCoupling, Stiffness, materials};
use serde::{Deserialize, Serialize};

mod analysis;
pub use analysis::{
    AnalysisOptions, ForceKinematics, NewtonName, PathName, RuleName, SolverName, StartName,
};
mod contact;
pub(crate) use contact::check as check_contact;
pub use contact::{ContactModeName, ContactOptions, CrackFacesName, DEFAULT_TOLERANCE_MM};
mod loads;
pub use loads::{CriterionSpec, Loads};
mod substructure;
pub use substructure::{PartitionName, SubstructureOptions};

/// The thesis's reference case (§4.3, §5.1) on the default mesh (no mesh knobs: the
/// front-resolving `nonlin3d_mesh::DEFAULT_MESH`): the scene `nonlin3d run` runs without
/// arguments.
pub const DEFAULT_SCENE: &str = include_str!("../examples/scenes/reference_circle_30mm.toml");

/// The thesis's reference case on the thesis's own mesh (`slices = 8`, the other knobs the
/// thesis's reference mesh), as its Fig. 5.1.3 was drawn.
pub const THESIS_SCENE: &str = include_str!("../examples/scenes/fig_5_1_3_circle_30mm.toml");

/// One analysis: geometry, material, mesh, loads, options.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// A line for reports.
    pub title: String,
    /// The delamination model.
    pub geometry: Geometry,
    /// The material.
    pub material: MaterialSpec,
    /// Ply-level modelling of the sublaminate (and base plies below it), chapter 7.
    #[serde(default)]
    pub layup: Option<Layup>,
    /// Mesh controls (defaults per geometry).
    #[serde(default)]
    pub mesh: MeshControls,
    /// Applied strains or transverse loads.
    pub loads: Loads,
    /// Solution options.
    #[serde(default)]
    pub analysis: AnalysisOptions,
    /// A growth criterion to evaluate along the front (optional).
    #[serde(default)]
    pub criterion: Option<CriterionSpec>,
    /// Substructuring (thesis §2.6, §4.5): which cells are condensed into a superelement.
    #[serde(default)]
    pub substructure: SubstructureOptions,
    /// Crack-face contact (default: `auto`).
    #[serde(default)]
    pub contact: ContactOptions,
}

/// Planform of an embedded or edge delamination.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Shape {
    /// Ellipse (circle when a = b), conformal map eq. 3.1.1.
    #[default]
    Ellipse,
    /// Rectangle 2a × 2b (Fig. 3.1.3).
    Rectangle,
}

/// The delamination model (thesis Fig. 3.2.1–3.2.3 and §4.1). `a_mm` is the semi-axis along
/// x (the load direction), `b_mm` along y; `h_mm` the sublaminate, `base_mm` the base laminate
/// (H), `w_mm` the quarter model's size W.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum Geometry {
    /// Embedded delamination, quarter model (u = 0 on x = 0, v = 0 on y = 0, w = 0 on z = 0).
    Embedded {
        /// Planform.
        #[serde(default)]
        shape: Shape,
        /// Semi-axis along x, mm.
        a_mm: f64,
        /// Semi-axis along y, mm.
        b_mm: f64,
        /// Sublaminate thickness h, mm.
        h_mm: f64,
        /// Base laminate thickness H, mm.
        base_mm: f64,
        /// Quarter-model size W, mm.
        w_mm: f64,
    },
    /// Edge delamination (§5.5): as embedded, with y = 0 a free edge.
    Edge {
        /// Planform.
        #[serde(default)]
        shape: Shape,
        /// Semi-axis along x, mm.
        a_mm: f64,
        /// Depth from the edge along y, mm.
        b_mm: f64,
        /// Sublaminate thickness h, mm.
        h_mm: f64,
        /// Base laminate thickness H, mm.
        base_mm: f64,
        /// Model size W, mm.
        w_mm: f64,
    },
    /// The thin-film model of §5.3: the sublaminate of the embedded model alone, its lower
    /// face outside the delamination moved with the base laminate's uniform strain (the base
    /// taken as rigid against the sublaminate); the fields as for `embedded` (H places the
    /// delamination plane z = H and gives the base's through-thickness displacement there).
    ThinFilm {
        /// Planform.
        #[serde(default)]
        shape: Shape,
        /// Semi-axis along x, mm.
        a_mm: f64,
        /// Semi-axis along y, mm.
        b_mm: f64,
        /// Sublaminate thickness h, mm.
        h_mm: f64,
        /// Base laminate thickness H, mm.
        base_mm: f64,
        /// Quarter-model size W, mm.
        w_mm: f64,
    },
    /// Through-width delamination (Fig. 3.2.3), plane strain.
    ThroughWidth {
        /// Half-length a (delaminated for 0 ≤ x < a), mm.
        a_mm: f64,
        /// Model length L along x, mm.
        length_mm: f64,
        /// Width along y, mm.
        width_mm: f64,
        /// Sublaminate thickness h, mm.
        h_mm: f64,
        /// Base laminate thickness H, mm.
        base_mm: f64,
    },
    /// The transversely loaded plate of §4.1: a circular debond of radius a under a central
    /// transverse load.
    Plate {
        /// Debond radius a, mm.
        a_mm: f64,
        /// Plate (sublaminate) thickness h, mm.
        h_mm: f64,
        /// Base thickness H, mm.
        base_mm: f64,
        /// Quarter-model size W, mm.
        w_mm: f64,
    },
}

impl Geometry {
    /// The named lengths of the geometry (mm), as written in the scene.
    pub fn lengths_mm(&self) -> Vec<(&'static str, f64)> {
        match *self {
            Self::Embedded {
                a_mm,
                b_mm,
                h_mm,
                base_mm,
                w_mm,
                ..
            }
            | Self::Edge {
                a_mm,
                b_mm,
                h_mm,
                base_mm,
                w_mm,
                ..
            }
            | Self::ThinFilm {
                a_mm,
                b_mm,
                h_mm,
                base_mm,
                w_mm,
                ..
            } => vec![
                ("a_mm", a_mm),
                ("b_mm", b_mm),
                ("h_mm", h_mm),
                ("base_mm", base_mm),
                ("w_mm", w_mm),
            ],
            Self::ThroughWidth {
                a_mm,
                length_mm,
                width_mm,
                h_mm,
                base_mm,
            } => vec![
                ("a_mm", a_mm),
                ("length_mm", length_mm),
                ("width_mm", width_mm),
                ("h_mm", h_mm),
                ("base_mm", base_mm),
            ],
            Self::Plate {
                a_mm,
                h_mm,
                base_mm,
                w_mm,
            } => vec![
                ("a_mm", a_mm),
                ("h_mm", h_mm),
                ("base_mm", base_mm),
                ("w_mm", w_mm),
            ],
        }
    }

    /// The base laminate thickness H, mm.
    pub fn base_mm(&self) -> f64 {
        match *self {
            Self::Embedded { base_mm, .. }
            | Self::Edge { base_mm, .. }
            | Self::ThinFilm { base_mm, .. }
            | Self::ThroughWidth { base_mm, .. }
            | Self::Plate { base_mm, .. } => base_mm,
        }
    }
}

/// Homogenisation of the material into one effective solid.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Homogenize {
    /// Use the material as given (ply axes = global axes).
    #[default]
    None,
    /// The homogeneous quasi-isotropic laminate of chapter 5: eq. 2.9.1, the volume average of
    /// (±45/0/90)s plies of this material.
    QuasiIsotropic,
}

/// The material (constants in GPa).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum MaterialSpec {
    /// A material of the thesis's Table 1 or a metal: `generic-graphite-epoxy`, `im7-8551-7`,
    /// `steel`, `aluminium`.
    Named {
        /// Its name.
        name: String,
        /// Homogenisation.
        #[serde(default)]
        homogenize: Homogenize,
    },
    /// Isotropic: E (GPa), ν.
    Isotropic {
        /// Young's modulus, GPa.
        e_gpa: f64,
        /// Poisson ratio.
        nu: f64,
    },
    /// Orthotropic engineering constants in ply axes.
    Orthotropic {
        /// E11, GPa.
        e11_gpa: f64,
        /// E22, GPa.
        e22_gpa: f64,
        /// E33, GPa.
        e33_gpa: f64,
        /// ν12.
        nu12: f64,
        /// ν13.
        nu13: f64,
        /// ν23.
        nu23: f64,
        /// G12, GPa.
        g12_gpa: f64,
        /// G13, GPa.
        g13_gpa: f64,
        /// G23, GPa.
        g23_gpa: f64,
        /// Homogenisation.
        #[serde(default)]
        homogenize: Homogenize,
    },
}

/// Ply-level layers: one element per ply in the sublaminate and in `base_below`; the rest of
/// the base homogeneous quasi-isotropic (eq. 2.9.1) of the same ply material.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Layup {
    /// Ply thickness, mm.
    pub ply_mm: f64,
    /// Sublaminate ply angles (degrees), from the delamination plane up.
    pub sublaminate: Vec<f64>,
    /// Base ply angles modelled ply by ply, from the delamination plane down.
    #[serde(default)]
    pub base_below: Vec<f64>,
}

/// Mesh controls; unset fields take the generator's defaults (thesis reference mesh).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct MeshControls {
    /// `hex20` (default) or `hex8`.
    #[serde(default)]
    pub element: Option<ElementName>,
    /// Slices through the 90° sweep (even), embedded/edge/plate.
    #[serde(default)]
    pub slices: Option<usize>,
    /// Elements between the centre and the front (along x for through-width). Default: 4 for
    /// a ≤ b, 4·⌈a/b⌉ for a delamination longer along the load than across it
    /// (`EmbeddedParams::radial_inside_for`); through-width: 10.
    #[serde(default)]
    pub inside: Option<usize>,
    /// Elements between the front and the boundary.
    #[serde(default)]
    pub outside: Option<usize>,
    /// Size of the element next to the front over the one farthest inside (< 1 refines).
    #[serde(default)]
    pub front_grading: Option<f64>,
    /// Element size at the delamination front, mm (embedded, edge: issue 25's front-resolving
    /// grading): the rings either side of the front and the layers either side of the
    /// delamination plane start at this size and grow geometrically away from it, so the cells
    /// at the front are square in the radial–thickness plane; `front_grading` is then unused.
    #[serde(default)]
    pub front_element_mm: Option<f64>,
    /// `[inside, outside]`: the rings behind and ahead of the front that carry three times the
    /// slices (embedded, edge: issue 25's refinement along the front only), joined to the rest
    /// by a conformal transition ring on each side. Unset: every ring has `slices` arcs.
    #[serde(default)]
    pub front_band: Option<[usize; 2]>,
    /// `[inside, outside]`: the rings behind and ahead of the front that keep `sub_layers` and
    /// `base_layers` (embedded, edge: issue 25's refinement through the thickness near the
    /// front only); the rest of the model takes every other thickness station (both counts
    /// even), joined by a conformal 1 → 2 transition ring on each side. Unset: the same layers
    /// everywhere.
    #[serde(default)]
    pub layer_band: Option<[usize; 2]>,
    /// Elements through the sublaminate.
    #[serde(default)]
    pub sub_layers: Option<usize>,
    /// Elements through the base.
    #[serde(default)]
    pub base_layers: Option<usize>,
    /// Elements across the width (through-width only).
    #[serde(default)]
    pub across: Option<usize>,
    /// The map that turns the circular mesh into an elliptic one (elliptic embedded and edge
    /// delaminations): `modified` (default, eq. 3.1.2 with r = 0.9·min(a, b)) or `conformal`
    /// (eq. 3.1.1, to reproduce the thesis's Fig. 3.1.2b; its inner cells degrade with the
    /// aspect ratio).
    #[serde(default)]
    pub elliptic_map: Option<MapName>,
    /// Hex20 mid-edge nodes on the mesh's curves (embedded and edge delaminations): `true` puts
    /// every ring's mid-edge nodes on the ring as the planform map draws it, so the front's
    /// nodes all lie on the ellipse and VCCT measures the widths along the curved edges;
    /// `false` (default) keeps them at the midpoints of their corners, as the thesis does
    /// (§3.1: straight edges, the front the polygon through its corners).
    #[serde(default)]
    pub curved_edges: Option<bool>,
    /// The discretisation-error estimate reported with every G (docs/ACCURACY.md §3):
    /// `companion` (default: the same levels on a coarser companion mesh — in-plane counts
    /// halved, the sublaminate layers kept where there are two or more — about 12–30 % of the
    /// run's CPU) or `off`.
    #[serde(default)]
    pub error_estimate: Option<ErrorEstimateName>,
    /// Target relative error of G at the front (e.g. 0.02): picks the front-resolving mesh
    /// from a measured table (docs/MESH.md, "Accuracy"); knobs given beside it override the
    /// table's, field by field; a warning when the estimate exceeds it.
    #[serde(default)]
    pub accuracy: Option<f64>,
}

impl MeshControls {
    /// Whether any knob that shapes the mesh or picks it is given (the counts, gradings,
    /// bands, `across`, `accuracy`; not `element` or `error_estimate`): without one an
    /// embedded or edge scene runs the default mesh (`nonlin3d_mesh::DEFAULT_MESH`), a strip
    /// the default strip mesh (`ThroughWidthParams::with_default_mesh`; docs/MESH.md).
    pub fn gives_mesh_knobs(&self) -> bool {
        let counts = [
            self.slices,
            self.inside,
            self.outside,
            self.across,
            self.sub_layers,
            self.base_layers,
        ];
        counts.iter().any(Option::is_some)
            || self.front_grading.is_some()
            || self.front_element_mm.is_some()
            || self.front_band.is_some()
            || self.layer_band.is_some()
            || self.accuracy.is_some()
    }
}

/// `[mesh] error_estimate` names.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum ErrorEstimateName {
    /// No estimate.
    Off,
    /// a·max(|G(M) − G(M/2)|, 0.2·|ΔG_T at the G_T max|) per point and mode (a = 0.5 or
    /// 1.2 by what the companion coarsens: docs/ACCURACY.md §3).
    #[default]
    Companion,
}

/// Elliptic map names in scenes (thesis §3.1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MapName {
    /// Eq. 3.1.2 with r = 0.9·min(a, b).
    Modified,
    /// Eq. 3.1.1.
    Conformal,
}

/// Element names in scenes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ElementName {
    /// 20-node brick.
    Hex20,
    /// 8-node brick.
    Hex8,
}

impl ElementName {
    /// The element kind.
    pub fn kind(self) -> ElementKind {
        match self {
            Self::Hex20 => ElementKind::Hex20,
            Self::Hex8 => ElementKind::Hex8,
        }
    }
}

impl Scene {
    /// Parses a TOML scene; errors name the line and field.
    pub fn from_toml(text: &str) -> Result<Self, Error> {
        let s: Self = toml::from_str(text).map_err(|e| Error::Scene(e.to_string()))?;
        s.validate()?;
        Ok(s)
    }

    /// The TOML text of this scene.
    pub fn to_toml(&self) -> Result<String, Error> {
        toml::to_string_pretty(self).map_err(|e| Error::Scene(e.to_string()))
    }

    /// The thesis's reference case on the thesis's mesh ([`THESIS_SCENE`]).
    pub fn thesis_reference() -> Result<Self, Error> {
        Self::from_toml(THESIS_SCENE)
    }

    /// The reference case on the default mesh ([`DEFAULT_SCENE`]): what `nonlin3d run`
    /// runs without a scene.
    pub fn reference() -> Result<Self, Error> {
        Self::from_toml(DEFAULT_SCENE)
    }

    /// The material's ply-axis constants (before homogenisation), and whether it is to be
    /// homogenised quasi-isotropically.
    pub fn ply_material(&self) -> Result<(Orthotropic, Homogenize), Error> {
        let gpa = 1e9;
        Ok(match &self.material {
            MaterialSpec::Named { name, homogenize } => {
                let m = match name.as_str() {
                    "generic-graphite-epoxy" => materials::generic_graphite_epoxy(),
                    "im7-8551-7" => materials::im7_8551_7(),
                    "steel" => materials::steel(),
                    "aluminium" | "aluminum" => materials::aluminium(),
                    other => {
                        return Err(Error::Scene(format!(
                            "material.name = '{other}': one of generic-graphite-epoxy, \
                             im7-8551-7, steel, aluminium"
                        )));
                    }
                };
                (m, *homogenize)
            }
            MaterialSpec::Isotropic { e_gpa, nu } => {
                (Orthotropic::isotropic(e_gpa * gpa, *nu), Homogenize::None)
            }
            MaterialSpec::Orthotropic {
                e11_gpa,
                e22_gpa,
                e33_gpa,
                nu12,
                nu13,
                nu23,
                g12_gpa,
                g13_gpa,
                g23_gpa,
                homogenize,
            } => (
                Orthotropic {
                    e11: e11_gpa * gpa,
                    e22: e22_gpa * gpa,
                    e33: e33_gpa * gpa,
                    nu12: *nu12,
                    nu13: *nu13,
                    nu23: *nu23,
                    g12: g12_gpa * gpa,
                    g13: g13_gpa * gpa,
                    g23: g23_gpa * gpa,
                },
                *homogenize,
            ),
        })
    }

    /// Materials indexed as the mesh's cells use them: `[homogeneous]` without a layup;
    /// `[homogenised base, ply material]` with one (the mesh generator's convention).
    pub fn stiffnesses(&self) -> Result<Vec<Stiffness>, Error> {
        let (ply, homogenize) = self.ply_material()?;
        let qi = || -> Result<Stiffness, Error> {
            Ok(PlyStack::quasi_isotropic(ply, 1.0)?.average_stiffness(ShearCoupling::Exact)?)
        };
        Ok(match (&self.layup, homogenize) {
            (None, Homogenize::None) => vec![ply.stiffness()?],
            (None, Homogenize::QuasiIsotropic) => vec![qi()?],
            (Some(_), _) => vec![qi()?, ply.stiffness()?],
        })
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn the_default_scene_parses_and_round_trips() {
        let s = Scene::thesis_reference().unwrap();
        let again = Scene::from_toml(&s.to_toml().unwrap()).unwrap();
        assert_eq!(s, again);
        assert_eq!(s.loads.strains.len(), 5);
        assert_eq!(s.stiffnesses().unwrap().len(), 1);
    }

    #[test]
    fn mistakes_are_named() {
        let s = DEFAULT_SCENE.replace("a_mm", "aa_mm");
        let e = Scene::from_toml(&s).unwrap_err().to_string();
        assert!(e.contains("aa_mm"), "{e}");
        let s = DEFAULT_SCENE.replace("h_mm = 0.4", "h_mm = -0.4");
        let e = Scene::from_toml(&s).unwrap_err().to_string();
        assert!(e.contains("geometry.h_mm"), "{e}");
        let s = DEFAULT_SCENE.replace("generic-graphite-epoxy", "unobtainium");
        let e = Scene::from_toml(&s)
            .unwrap()
            .stiffnesses()
            .unwrap_err()
            .to_string();
        assert!(e.contains("unobtainium"), "{e}");
    }
}
