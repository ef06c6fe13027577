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
//!    midpoints of their corners (the thesis's re-centring after the map).
//! 5. Corner nodes on z = H strictly inside the front are duplicated (lower copy for base cells,
//!    upper for sublaminate cells); mid-edge nodes are keyed by their two corner nodes, so exactly
//!    the mid-edge nodes between duplicated corners, or between a duplicated corner and the
//!    front, are duplicated too. Everything else is shared.

mod maps;
mod params;

pub use maps::EllipticMap;
pub use params::{Centre, EmbeddedParams, PlyLayout};

use crate::MeshError;
use crate::front::{CellsTouching, Front, FrontPoint};
use crate::model::{Cell, Mesh};
use maps::{front_radius, planform, radial_stations};
use nonlin3d_element::ElementKind;
use std::collections::HashMap;

/// The embedded delamination mesh. Node sets: `x0`, `y0`, `z0`, `x1` (x = W), `y1` (y = W),
/// `center_top` (the node at (0, 0, H + h), where the thesis applies its perturbation load),
/// `crack_upper` and `crack_lower` (paired crack-face nodes, same order), `front` (nodes on the
/// delamination front line at z = H). Cell sets: `base`, `sublaminate`, `all`.
pub fn embedded_delamination(p: &EmbeddedParams) -> Result<Mesh, MeshError> {
    embedded_delamination_with_front(p).map(|(mesh, _)| mesh)
}

/// [`embedded_delamination`] together with its [`Front`] descriptor for VCCT.
pub fn embedded_delamination_with_front(p: &EmbeddedParams) -> Result<(Mesh, Front), MeshError> {
    p.check()?;
    let k = p.slices / 2;
    let (rho, front) = radial_stations(p)?;
    let rc = rho[0];
    let angle = |q: usize| std::f64::consts::FRAC_PI_2 * q as f64 / p.slices as f64;
    // --- 2-D vertices: core (k+1)² grid, then rings 1.. with slices+1 nodes each.
    let mut v2: Vec<[f64; 2]> = Vec::new();
    let mut inside: Vec<bool> = Vec::new();
    // Square core [0, c]² with c = ρ₀/2 (its corner at 0.71 ρ₀): a k × k grid; one ring of
    // cells joins its boundary to the first circle ρ₀, so no cell has a near-straight corner.
    let c = 0.5 * rc;
    let mut core_id = vec![vec![0usize; k + 1]; k + 1];
    if p.centre == Centre::OGrid {
        for j in 0..=k {
            for i in 0..=k {
                core_id[j][i] = v2.len();
                v2.push([c * i as f64 / k as f64, c * j as f64 / k as f64]);
                inside.push(true);
            }
        }
    }
    // Node q of the core boundary, counter-clockwise from the x axis: q ≤ k on x = c, q ≥ k on y = c.
    let core_boundary = |q: usize| {
        if q <= k {
            core_id[q][k]
        } else {
            core_id[k][2 * k - q]
        }
    };
    // Ring 0 is the core boundary; ring m ≥ 1 the circle (or blend) at radial station m − 1.
    let mut ring_id = vec![vec![0usize; p.slices + 1]; rho.len() + 1];
    for q in 0..=p.slices {
        ring_id[0][q] = match p.centre {
            Centre::OGrid => core_boundary(q),
            Centre::ThesisArc => {
                // The thesis's axis nodes, spread on an arc of 1e-9 m.
                let phi = angle(q);
                v2.push([1e-9 * phi.cos(), 1e-9 * phi.sin()]);
                inside.push(true);
                v2.len() - 1
            }
        };
    }
    // Ring nodes: the planform map (ellipse or rectangle) of the circle point up to the
    // transition ring; beyond it, points on the straight line from the mapped transition ring to
    // the square boundary, reached on the last ring. Monotone whenever the mapped transition
    // ring lies inside the square, which `check` ensures: it needs transition·max(a, b) < W, and
    // every map sends the ring ρ = t·r₀ (t ≥ 1) inside |x| ≤ t·a, |y| ≤ t·b (eq. 3.1.1 for
    // a ≤ b: semi-axes t·a and √(t²a² + b² − a²) ≤ t·b; mirrored for a > b).
    let wt = p.transition * front_radius(p);
    let to_planform = |x: f64, y: f64| {
        let (u, v) = planform(p.map, p.a, p.b, x, y);
        [u, v]
    };
    for (m0, &r) in rho.iter().enumerate() {
        let m = m0 + 1;
        for q in 0..=p.slices {
            let phi = angle(q);
            let pt = if r <= wt {
                to_planform(r * phi.cos(), r * phi.sin())
            } else {
                // Straight from the mapped transition ring to the square boundary.
                let mapped = to_planform(wt * phi.cos(), wt * phi.sin());
                let beta = (r - wt) / (p.w - wt);
                let sq = if q == p.slices {
                    [0.0, p.w]
                } else if phi <= std::f64::consts::FRAC_PI_4 {
                    [p.w, p.w * phi.tan()]
                } else {
                    [p.w / phi.tan(), p.w]
                };
                [
                    (1.0 - beta) * mapped[0] + beta * sq[0],
                    (1.0 - beta) * mapped[1] + beta * sq[1],
                ]
            };
            ring_id[m][q] = v2.len();
            v2.push(pt);
            inside.push(m0 < front);
        }
    }
    // The core and its joining ring take the planform map too.
    let core_nodes = match p.centre {
        Centre::OGrid => (k + 1) * (k + 1),
        Centre::ThesisArc => p.slices + 1,
    };
    let mapped: Vec<[f64; 2]> = v2
        .iter()
        .enumerate()
        .map(|(v, pt)| {
            if v < core_nodes {
                to_planform(pt[0], pt[1])
            } else {
                *pt
            }
        })
        .collect();
    // 2-D quads (counter-clockwise seen from +z): core, then rings.
    let mut quads: Vec<[usize; 4]> = Vec::new();
    for j in 0..if p.centre == Centre::OGrid { k } else { 0 } {
        for i in 0..k {
            quads.push([
                core_id[j][i],
                core_id[j][i + 1],
                core_id[j + 1][i + 1],
                core_id[j + 1][i],
            ]);
        }
    }
    for m in 0..rho.len() {
        for q in 0..p.slices {
            quads.push([
                ring_id[m][q],
                ring_id[m + 1][q],
                ring_id[m + 1][q + 1],
                ring_id[m][q + 1],
            ]);
        }
    }
    // --- z stations: base graded towards H, sublaminate uniform.
    let (z, layer_props, zh) = p.layers()?;
    // --- 3-D corner nodes: (2-D vertex, z station); lower copies on z = H inside the front.
    let mut mesh = Mesh::default();
    let nv = v2.len();
    let mut corner = vec![vec![0usize; nv]; z.len()];
    let mut lower = vec![usize::MAX; nv];
    for (l, &zl) in z.iter().enumerate() {
        for v in 0..nv {
            corner[l][v] = mesh.nodes.len();
            mesh.nodes.push([mapped[v][0], mapped[v][1], zl]);
            if l == zh && inside[v] {
                lower[v] = mesh.nodes.len();
                mesh.nodes.push([mapped[v][0], mapped[v][1], zl]);
            }
        }
    }
    let node_at = |l: usize, v: usize, below: bool| {
        if l == zh && below && inside[v] {
            lower[v]
        } else {
            corner[l][v]
        }
    };
    // --- cells; mid-edge nodes keyed by their corner pair.
    let mut mid: HashMap<(usize, usize), usize> = HashMap::new();
    let mut base_cells = Vec::new();
    let mut sub_cells = Vec::new();
    for l in 0..z.len() - 1 {
        let below_plane = l < zh; // cells under z = H use the lower copies on it
        for qd in &quads {
            let bottom: Vec<usize> = qd.iter().map(|&v| node_at(l, v, below_plane)).collect();
            let top: Vec<usize> = qd.iter().map(|&v| node_at(l + 1, v, below_plane)).collect();
            let mut nodes: Vec<usize> = bottom.iter().chain(&top).copied().collect();
            if p.kind == ElementKind::Hex20 {
                for &(a, b) in nonlin3d_element::HEX20_EDGES.iter() {
                    let (na, nb) = (nodes[a], nodes[b]);
                    let key = (na.min(nb), na.max(nb));
                    let id = *mid.entry(key).or_insert_with(|| {
                        let (pa, pb) = (mesh.nodes[na], mesh.nodes[nb]);
                        mesh.nodes.push([
                            0.5 * (pa[0] + pb[0]),
                            0.5 * (pa[1] + pb[1]),
                            0.5 * (pa[2] + pb[2]),
                        ]);
                        mesh.nodes.len() - 1
                    });
                    nodes.push(id);
                }
            }
            let c = mesh.cells.len();
            let (material, ply_angle_deg) = layer_props[l];
            mesh.cells.push(Cell {
                kind: p.kind,
                nodes,
                material,
                ply_angle_deg,
            });
            if below_plane {
                base_cells.push(c)
            } else {
                sub_cells.push(c)
            }
        }
    }
    // --- sets.
    let tol = 1e-9 * p.w;
    mesh.add_plane_sets(
        &[
            ("x0", 0, 0.0),
            ("y0", 1, 0.0),
            ("z0", 2, 0.0),
            ("x1", 0, p.w),
            ("y1", 1, p.w),
        ],
        tol,
    );
    mesh.node_sets.insert(
        "center_top".into(),
        // The O-grid has a node on the axis; the thesis's centre the arc node on y = 0.
        vec![
            corner[z.len() - 1][if p.centre == Centre::OGrid {
                core_id[0][0]
            } else {
                ring_id[0][0]
            }],
        ],
    );
    // Crack faces: corner pairs, then mid-edge pairs (key with upper corners ↔ lower corners).
    let (mut up, mut lo) = (Vec::new(), Vec::new());
    for v in 0..nv {
        if inside[v] {
            up.push(corner[zh][v]);
            lo.push(lower[v]);
        }
    }
    if p.kind == ElementKind::Hex20 {
        let upper_of: HashMap<usize, usize> = (0..nv)
            .filter(|&v| inside[v])
            .map(|v| (lower[v], corner[zh][v]))
            .collect();
        let mut pairs: Vec<(usize, usize)> = Vec::new();
        for (&(na, nb), &id) in &mid {
            // A mid-edge node on the lower crack face: both corners on z = H, at least one a
            // lower copy, the other a lower copy or a front node.
            let (la, lb) = (upper_of.get(&na), upper_of.get(&nb));
            if la.is_some() || lb.is_some() {
                let ua = la.copied().unwrap_or(na);
                let ub = lb.copied().unwrap_or(nb);
                if let Some(&uid) = mid.get(&(ua.min(ub), ua.max(ub))) {
                    pairs.push((uid, id));
                }
            }
        }
        pairs.sort_unstable();
        for (u, l) in pairs {
            up.push(u);
            lo.push(l);
        }
    }
    mesh.node_sets.insert("crack_upper".into(), up);
    mesh.node_sets.insert("crack_lower".into(), lo);
    let front_ring = front + 1;
    let mut front_nodes: Vec<usize> = (0..=p.slices)
        .map(|q| corner[zh][ring_id[front_ring][q]])
        .collect();
    if p.kind == ElementKind::Hex20 {
        for q in 0..p.slices {
            let (na, nb) = (
                corner[zh][ring_id[front_ring][q]],
                corner[zh][ring_id[front_ring][q + 1]],
            );
            if let Some(&id) = mid.get(&(na.min(nb), na.max(nb))) {
                front_nodes.push(id);
            }
        }
    }
    mesh.node_sets.insert("front".into(), front_nodes);
    // --- front descriptor, from the y axis (q = slices) to the x axis (q = 0).
    let behind = front_ring - 1;
    let ahead = front_ring + 1;
    let midside = |na: usize, nb: usize| mid.get(&(na.min(nb), na.max(nb))).copied();
    let lower_or = |v: usize| if inside[v] { lower[v] } else { corner[zh][v] };
    let cells_of = CellsTouching::new(&mesh, &sub_cells);
    let touching = |a: usize, b: Option<usize>| cells_of.touching(a, b);
    let mut points = Vec::new();
    let missing = |what: &str| MeshError::Parameter {
        name: "front",
        reason: format!("internal: {what} node not found"),
    };
    for q in (0..=p.slices).rev() {
        let (cf, cb, ca) = (
            ring_id[front_ring][q],
            ring_id[behind][q],
            ring_id[ahead][q],
        );
        let c = corner[zh][cf];
        let (au, al) = (corner[zh][cb], lower_or(cb));
        let (b, d) = if p.kind == ElementKind::Hex20 {
            let bu = midside(c, au).ok_or_else(|| missing("b"))?;
            let bl = midside(c, al).ok_or_else(|| missing("b′"))?;
            (
                Some((bu, bl)),
                Some(midside(c, corner[zh][ca]).ok_or_else(|| missing("d"))?),
            )
        } else {
            (None, None)
        };
        points.push(FrontPoint::new(c, true, (au, al), b, d, touching(c, d)));
        if p.kind == ElementKind::Hex20 && q > 0 {
            // The mid-edge front node between q and q − 1, paired with the mid-edge nodes of the
            // ring behind.
            let (cf2, cb2) = (ring_id[front_ring][q - 1], ring_id[behind][q - 1]);
            let cm = midside(c, corner[zh][cf2]).ok_or_else(|| missing("mid-edge front"))?;
            let au =
                midside(corner[zh][cb], corner[zh][cb2]).ok_or_else(|| missing("a (mid-edge)"))?;
            let al =
                midside(lower_or(cb), lower_or(cb2)).ok_or_else(|| missing("a′ (mid-edge)"))?;
            points.push(FrontPoint::new(
                cm,
                false,
                (au, al),
                None,
                None,
                touching(cm, None),
            ));
        }
    }
    let front_descriptor = Front { points }.finish(&mesh.nodes);
    mesh.cell_sets.insert("base".into(), base_cells);
    mesh.cell_sets.insert("sublaminate".into(), sub_cells);
    mesh.cell_sets
        .insert("all".into(), (0..mesh.cells.len()).collect());
    mesh.validate()?;
    mesh.check_geometry()?;
    Ok((mesh, front_descriptor))
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
        .get("sublaminate")
        .cloned()
        .unwrap_or_default();
    let (mut m, _) = full.extract(&sub)?;
    m.node_sets.remove("crack_lower");
    m.node_sets.remove("z0");
    m.cell_sets.remove("base");
    let free: std::collections::HashSet<usize> = m
        .node_sets
        .get("crack_upper")
        .into_iter()
        .flatten()
        .copied()
        .collect();
    let tol = 1e-9 * p.w;
    let bonded = (0..m.nodes.len())
        .filter(|&n| (m.nodes[n][2] - p.base).abs() < tol && !free.contains(&n))
        .collect();
    m.node_sets.insert("bonded".into(), bonded);
    Ok(m)
}
