//! The front descriptor of the embedded delamination (thesis §2.8, Fig. 2.8.1, on the front
//! of §3.1, the ellipse of eq. 3.1.1–3.1.2): for each front node c, the node pairs a/a′ behind
//! it, b/b′ and d (Hex20), and the sublaminate cells touching c and d.

use super::extrusion::Solid;
use super::planform::Section;
use super::{EmbeddedParams, MidEdges};
use crate::MeshError;
use crate::front::{CellsTouching, Front, FrontPoint, FrontWidths, missing_node as missing};
use nonlin3d_element::ElementKind;

/// The §2.8 front descriptor of the §3.1 mesh, from the y axis (q = slices) to the x axis
/// (q = 0): a corner point per slice line and, for Hex20, a mid-edge point between each two.
pub(super) fn descriptor(
    p: &EmbeddedParams,
    s: &Section,
    solid: &Solid,
) -> Result<Front, MeshError> {
    let cells = CellsTouching::new(&solid.mesh, &solid.sub_cells);
    let mut points = Vec::new();
    // The front ring's arcs: `slices`, or the front band's (issue 25).
    let n = s.rings[s.front_ring].len() - 1;
    for q in (0..=n).rev() {
        points.push(corner_point(p.kind, s, solid, &cells, q)?);
        if p.kind == ElementKind::Hex20 && q > 0 {
            points.push(mid_edge_point(s, solid, &cells, q)?);
        }
    }
    let widths = match p.mid_edges {
        MidEdges::Chords => FrontWidths::Chords,
        MidEdges::Mapped => FrontWidths::AlongEdges,
    };
    Ok(Front { points, widths }.finish(&solid.mesh.nodes))
}

/// The corner front point on slice line q (§2.8, Fig. 2.8.1): c on the front ring, a/a′ the
/// upper/lower nodes one ring behind; for Hex20 b/b′ the mid-edge nodes between them and d the
/// mid-edge node one half-element ahead.
fn corner_point(
    kind: ElementKind,
    s: &Section,
    solid: &Solid,
    cells: &CellsTouching,
    q: usize,
) -> Result<FrontPoint, MeshError> {
    let f = s.front_ring;
    let (cf, cb, ca) = (s.rings[f][q], s.rings[f - 1][q], s.rings[f + 1][q]);
    let c = solid.upper(cf).ok_or_else(|| missing("c"))?;
    let au = solid.upper(cb).ok_or_else(|| missing("a"))?;
    let al = solid.lower_or_shared(cb).ok_or_else(|| missing("a′"))?;
    let (b, d) = if kind == ElementKind::Hex20 {
        let bu = solid.midside(c, au).ok_or_else(|| missing("b"))?;
        let bl = solid.midside(c, al).ok_or_else(|| missing("b′"))?;
        let ahead = solid.upper(ca).ok_or_else(|| missing("d"))?;
        let d = solid.midside(c, ahead).ok_or_else(|| missing("d"))?;
        (Some((bu, bl)), Some(d))
    } else {
        (None, None)
    };
    Ok(FrontPoint::new(
        c,
        true,
        (au, al),
        b,
        d,
        cells.touching(c, d),
    ))
}

/// The Hex20 mid-edge front point between slice lines q and q − 1 (§2.8), paired with the
/// mid-edge nodes of the ring behind (upper and lower).
fn mid_edge_point(
    s: &Section,
    solid: &Solid,
    cells: &CellsTouching,
    q: usize,
) -> Result<FrontPoint, MeshError> {
    let (front, behind) = (&s.rings[s.front_ring], &s.rings[s.front_ring - 1]);
    let up = |v: usize| solid.upper(v).ok_or_else(|| missing("c"));
    let low = |v: usize| solid.lower_or_shared(v).ok_or_else(|| missing("a′"));
    let (cf2, cb, cb2) = (front[q - 1], behind[q], behind[q - 1]);
    let cm = solid
        .midside(up(front[q])?, up(cf2)?)
        .ok_or_else(|| missing("mid-edge front"))?;
    let au = solid
        .midside(up(cb)?, up(cb2)?)
        .ok_or_else(|| missing("a (mid-edge)"))?;
    let al = solid
        .midside(low(cb)?, low(cb2)?)
        .ok_or_else(|| missing("a′ (mid-edge)"))?;
    Ok(FrontPoint::new(
        cm,
        false,
        (au, al),
        None,
        None,
        cells.touching(cm, None),
    ))
}
