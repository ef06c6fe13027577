//! The finite element model of a scene: its mesh, front, materials and boundary-condition
//! family, as [`crate::analysis::build_model`] makes it and the results keep it for output.

use nonlin3d_laminate::Stiffness;
use nonlin3d_mesh::{Front, Mesh};

/// Which boundary conditions a model gets (thesis §3.2).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ModelKind {
    /// u = 0 on x = 0, v = 0 on y = 0, w = 0 on z = 0, u = W·ε on x = W.
    Embedded,
    /// As embedded, y = 0 free (one node fixed in y against the rigid motion).
    Edge,
    /// As embedded plus v = 0 on y = W (plane strain).
    ThroughWidth,
    /// u = 0 on x = 0, v = 0 on y = 0, w = 0 on z = 0; the central transverse load.
    Plate,
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
}
