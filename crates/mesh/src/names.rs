//! Names of the node and cell sets that the generators make and the analysis looks up.
//!
//! One place for each name, so a generator and the code that reads its sets cannot drift apart.
//! The box sets (`x0` … `z1`) are the nodes (and faces) on each end of the box along an axis;
//! the delamination generators (thesis §3.1–3.2) add the sets of the crack faces and the front.

/// Nodes (and faces) on x = 0: the loaded end held in x (thesis §3.2: u = 0).
pub const X0: &str = "x0";
/// Nodes (and faces) on x = W: the end where u = W·ε is prescribed.
pub const X1: &str = "x1";
/// Nodes (and faces) on y = 0: a symmetry plane (v = 0) except in edge models.
pub const Y0: &str = "y0";
/// Nodes (and faces) on y = W.
pub const Y1: &str = "y1";
/// Nodes (and faces) on z = 0: the laminate's mid-plane, w = 0 by symmetry.
pub const Z0: &str = "z0";
/// Nodes (and faces) on the top surface.
pub const Z1: &str = "z1";
/// Every cell of a structured box.
pub const ALL: &str = "all";
/// The top node(s) of the sublaminate at the delamination's centre, where the perturbation
/// load that triggers local buckling is applied (thesis §3.3).
pub const CENTER_TOP: &str = "center_top";
/// Nodes of the upper crack face (the sublaminate's underside), paired by index with
/// [`CRACK_LOWER`].
pub const CRACK_UPPER: &str = "crack_upper";
/// Nodes of the lower crack face (the base's top), paired by index with [`CRACK_UPPER`].
pub const CRACK_LOWER: &str = "crack_lower";
/// Nodes on the delamination front.
pub const FRONT: &str = "front";
/// Nodes of the bonded interface outside the front (sublaminate and base share them).
pub const BONDED: &str = "bonded";
/// Cells of the base laminate.
pub const BASE: &str = "base";
/// Cells of the sublaminate above the delamination.
pub const SUBLAMINATE: &str = "sublaminate";
/// The one node that holds an edge model in y (on x = W, z = 0, at the largest y), as a set of
/// an exported deck: the generators make no such set.
pub const Y_HOLD: &str = "vfix";

/// The set names of the box ends along axis `axis` (0 = x, 1 = y, 2 = z): (low end, high end).
pub const fn box_ends(axis: usize) -> (&'static str, &'static str) {
    match axis {
        0 => (X0, X1),
        1 => (Y0, Y1),
        _ => (Z0, Z1),
    }
}
