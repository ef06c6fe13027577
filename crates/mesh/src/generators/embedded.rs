//! The embedded delamination model of thesis Fig. 3.1.1 and Fig. 3.2.1 (§3.1–3.2).
//!
//! Quarter model 0 ≤ x, y ≤ W, base laminate 0 ≤ z ≤ H, sublaminate H ≤ z ≤ H + h, delamination
//! on z = H inside the ellipse (x/a)² + (y/b)² < 1. Built as the thesis builds it, with one
//! change at the axis:
//!
//! 1. A 2-D quarter section: circular rings at radii ρ graded towards the front circle
//!    ρ = r₀ = min(a, b) (the short semi-axis: the maps stretch along the long one), each ring
//!    divided into `slices` arcs; the thesis collapsed the innermost elements onto the axis (nodes
//!    shifted to a 1e-9 m arc, degenerate elements). Here the inside of the first ring is an
//!    O-grid: a square core [0, ρ₀/2]² of (slices/2)² cells and one ring of cells joining its
//!    boundary to the circle ρ₀: no degenerate cell (docs/MESH.md compares the quality).
//! 2. Rings beyond `transition`·r₀ blend linearly into the square boundary x = W or y = W
//!    (Fig. 3.1.1c).
//! 3. The elliptic map (eq. 3.1.1, conformal; or eq. 3.1.2 with parameter r) turns the front
//!    circle of radius r₀ into the ellipse with semi-axes a (x) and b (y), stretching y when
//!    b > a and x when a > b (module `maps`); the rectangular planform stretches it onto a
//!    rectangle (Fig. 3.1.3). The thesis applied the map to every node, which
//!    bends the outer boundary; here the rings are mapped first and the rings beyond the
//!    transition then blend into the square, so the boundary stays the square while the region
//!    around the front keeps the exact map (and its orthogonality).
//! 4. The section is swept through the thickness stations; Hex20 mid-edge nodes sit at the
//!    midpoints of their corners (the thesis's re-centring after the map), or with
//!    [`MidEdges::Mapped`] at the map of the circular mesh's mid-edge points, so the rings are
//!    curved as the map curves them (issue 25).
//! 5. Corner nodes on z = H strictly inside the front are duplicated (lower copy for base cells,
//!    upper for sublaminate cells); mid-edge nodes are keyed by their two corner nodes, so exactly
//!    the mid-edge nodes between duplicated corners, or between a duplicated corner and the
//!    front, are duplicated too. Everything else is shared.
//! 6. The sets (planes, `center_top`, paired crack faces, front, base and sublaminate) and the
//!    front descriptor for VCCT (§2.8).
//!
//! One module per part: `planform` (steps 1–2, the 2-D section), `maps` (step 3, eq. 3.1.1–3.1.2
//! and the rectangle), `extrusion` (steps 4–5), `layers` (the layer band's 1 → 2 template
//! through the thickness, issue 25), `sets` and `front` (step 6), `params` (the parameters and
//! their checks, and the thickness stations).

mod extrusion;
mod front;
mod layers;
mod maps;
mod params;
mod planform;
mod sets;

pub use maps::EllipticMap;
pub use params::{Centre, EmbeddedParams, FrontBand, LayerBand, MidEdges, PlyLayout};

use crate::MeshError;
use crate::front::Front;
use crate::model::Mesh;
use crate::names;

/// The embedded delamination mesh. Node sets: `x0`, `y0`, `z0`, `x1` (x = W), `y1` (y = W),
/// `center_top` (the node at (0, 0, H + h), where the thesis applies its perturbation load),
/// `crack_upper` and `crack_lower` (paired crack-face nodes, same order), `front` (nodes on the
/// delamination front line at z = H). Cell sets: `base`, `sublaminate`, `all`.
pub fn embedded_delamination(p: &EmbeddedParams) -> Result<Mesh, MeshError> {
    embedded_delamination_with_front(p).map(|(mesh, _)| mesh)
}

/// [`embedded_delamination`] together with its [`Front`] descriptor for VCCT: the §3.1
/// planform (eq. 3.1.1–3.1.2) extruded through the thickness (§3.2), its sets, its front (§2.8).
pub fn embedded_delamination_with_front(p: &EmbeddedParams) -> Result<(Mesh, Front), MeshError> {
    p.check()?;
    let section = planform::section(p)?;
    let mut solid = extrusion::extrude(p, &section)?;
    sets::add_node_sets(p, &section, &mut solid);
    let front = front::descriptor(p, &section, &solid)?;
    let mesh = sets::add_cell_sets(solid);
    mesh.validate()?;
    mesh.check_geometry()?;
    Ok((mesh, front))
}

/// The edge delamination of §5.5: the same quarter mesh as [`embedded_delamination_with_front`]
/// (a semicircular or semi-elliptical delamination at the free edge y = 0 of a specimen
/// symmetric about x = 0); the analysis leaves the `y0` set free instead of imposing v = 0.
pub fn edge_delamination(p: &EmbeddedParams) -> Result<(Mesh, Front), MeshError> {
    embedded_delamination_with_front(p)
}

/// The thin-film model of §5.3: only the sublaminate of [`embedded_delamination`]; its lower
/// face outside the delamination (node set `bonded`, z = H) receives the displacements of the
/// base laminate, known in closed form; `crack_upper` is its free lower face inside the
/// delamination; `front`, `x0`, `y0`, `x1`, `y1`, `center_top` as in the full model.
pub fn thin_film(p: &EmbeddedParams) -> Result<Mesh, MeshError> {
    let full = embedded_delamination(p)?;
    let sub = full
        .cell_sets
        .get(names::SUBLAMINATE)
        .cloned()
        .unwrap_or_default();
    let (mut m, _) = full.extract(&sub)?;
    m.node_sets.remove(names::CRACK_LOWER);
    m.node_sets.remove(names::Z0);
    m.cell_sets.remove(names::BASE);
    let free: std::collections::HashSet<usize> = m
        .node_sets
        .get(names::CRACK_UPPER)
        .into_iter()
        .flatten()
        .copied()
        .collect();
    let tol = 1e-9 * p.w;
    let bonded = (0..m.nodes.len())
        .filter(|&n| (m.nodes[n][2] - p.base).abs() < tol && !free.contains(&n))
        .collect();
    m.node_sets.insert(names::BONDED.into(), bonded);
    Ok(m)
}
