//! Parameters of the embedded delamination model (thesis §3.1–3.2, chapter 7 ply layers).

use super::EllipticMap;
use crate::MeshError;
use crate::generators::grading::graded_to_last;
use crate::generators::{graded_coordinates, graded_from_first};
use nonlin3d_element::ElementKind;

/// Parameters of [`embedded_delamination`](crate::embedded_delamination) (SI units).
#[derive(Debug, Clone, PartialEq)]
pub struct EmbeddedParams {
    /// Hex20 (the thesis's) or Hex8.
    pub kind: ElementKind,
    /// Delamination semi-axis along x (load direction), m.
    pub a: f64,
    /// Delamination semi-axis along y, m.
    pub b: f64,
    /// Sublaminate thickness h, m.
    pub h: f64,
    /// Base laminate thickness H, m.
    pub base: f64,
    /// Half-width W of the square specimen (quarter model 0 ≤ x, y ≤ W), m.
    pub w: f64,
    /// Arcs per quarter ring (thesis: 4, 8, 12); even.
    pub slices: usize,
    /// Radial elements between the core and the front.
    pub radial_inside: usize,
    /// Radial elements between the front and the square boundary.
    pub radial_outside: usize,
    /// Inside the delamination: the element next to the front over the one farthest from it
    /// (< 1 refines towards the front). Outside, the first element is as long as the last one
    /// inside (the single-solution VCCT pairs them, §2.8) and the sizes grow geometrically.
    pub front_grading: f64,
    /// Front-resolving grading (issue 25): the element size at the front, m. `Some(e)`: the
    /// ring behind the front and the one ahead are e wide (the inside rings grow geometrically
    /// towards the centre and `front_grading` is not used), the sublaminate layers grow
    /// geometrically from e at z = H upwards and the base layers from e at z = H downwards
    /// (`base_grading` not used), so the cells at the front are e × e in the radial–thickness
    /// plane, where the VCCT's forces and openings (§2.8) are taken. A count too small to
    /// reach e (n·e < length) gives uniform elements. `None`: the thesis's grading (§3.1).
    pub front_element: Option<f64>,
    /// Refinement along the front only (issue 25): `Some(band)` gives the `band.inside` rings
    /// behind the front and the `band.outside` rings ahead of it [`FrontBand::FACTOR`]·`slices`
    /// arcs, joined to the `slices`-arc rings on either side by one conformal transition ring
    /// (each coarse arc split into three, four quadrilaterals: no hanging node). `None`: every
    /// ring has `slices` arcs (§3.1).
    pub front_band: Option<FrontBand>,
    /// Refinement through the thickness near the front only (issue 25): `Some(band)` keeps
    /// `sub_layers` and `base_layers` in the `band.inside` rings behind the front and the
    /// `band.outside` rings ahead of it, and puts half as many (every other thickness station)
    /// everywhere else, joined by one conformal 1 → 2 transition ring on each side (a quad
    /// template in the radial–thickness plane swept along the slices: no hanging node).
    /// `None`: the same layers everywhere (§3.2).
    pub layer_band: Option<LayerBand>,
    /// Core (first ring) radius as a fraction of the front circle's radius min(a, b).
    pub core_fraction: f64,
    /// Rings out to `transition`·min(a, b) (radii of the circular mesh, whose front circle has
    /// radius min(a, b)) take the planform map; beyond they blend into the square.
    pub transition: f64,
    /// Elements through the sublaminate.
    pub sub_layers: usize,
    /// Elements through the base laminate (graded towards z = H).
    pub base_layers: usize,
    /// Ratio of the base element at z = H to the one at z = 0.
    pub base_grading: f64,
    /// The elliptic map (or the rectangular planform).
    pub map: EllipticMap,
    /// Ply-level modelling (chapter 7); `None`: homogeneous layers, material 0.
    pub plies: Option<PlyLayout>,
    /// How the centre (the axis r = 0) is meshed.
    pub centre: Centre,
    /// Where the Hex20 mid-edge nodes sit: on the chords (the thesis's re-centring) or on the
    /// mapped curves (issue 25).
    pub mid_edges: MidEdges,
}

/// Where the Hex20 mid-edge nodes of the swept section sit (thesis §3.1, issue 25).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum MidEdges {
    /// At the midpoints of their corners (§3.1: "the coordinates of the midside nodes are
    /// recalculated as the average of the coordinates of the adjacent corner nodes"): every
    /// edge is straight, the front is the polygon through its corner nodes, and VCCT's width is
    /// the chord between the midside nodes (eq. 2.8.1).
    #[default]
    Chords,
    /// On the mesh's own curves: each mid-edge node at the planform map of the midpoint in the
    /// circular mesh (an arc's mid-angle on its ring, a slice line's mid-radius), so every ring
    /// is a quadratic curve through the map, the front's nodes all lie on the ellipse, and
    /// VCCT's width is the length along the quadratic edges from midside node to midside node.
    /// Edges of the joining cells (core to first ring, the bands' transitions to their
    /// interior vertices) stay straight.
    Mapped,
}

/// A band of rings around the front with [`FrontBand::FACTOR`] times the slices (issue 25).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrontBand {
    /// Rings behind the front with the fine slices (≥ 1, < `radial_inside`: one more ring is
    /// the transition).
    pub inside: usize,
    /// Rings ahead of the front with the fine slices (≥ 1, < `radial_outside`).
    pub outside: usize,
}

impl FrontBand {
    /// The band's arcs per coarse arc: the conformal quadrilateral transition splits an edge
    /// into three (two edges need no interior vertex pattern that quadrilaterals can close).
    pub const FACTOR: usize = 3;
}

/// The rings around the front that keep the full `sub_layers` and `base_layers` (issue 25);
/// the rest of the model has half as many.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LayerBand {
    /// Rings behind the front with the full layers (≥ 1, < `radial_inside`: one more ring is
    /// the 1 → 2 transition; not the front band's own count, whose next ring is its in-plane
    /// transition).
    pub inside: usize,
    /// Rings ahead of the front with the full layers (≥ 1, < `radial_outside`, not the front
    /// band's count).
    pub outside: usize,
}

/// The centre of the swept section.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Centre {
    /// A square core of (slices/2)² cells and one joining ring (the default): no degenerate cell.
    #[default]
    OGrid,
    /// The thesis's construction (§3.1): the first ring of cells reaches the axis, whose nodes
    /// are moved onto an arc of radius 1e-9 m; those cells are nearly triangular.
    ThesisArc,
}

/// Ply-level layers (chapter 7): one element through each ply of the sublaminate and of the
/// base plies just below the delamination; the rest of the base as homogenised layers.
/// Cells in plies get material 1 and their ply angle; homogenised cells material 0, angle 0.
#[derive(Debug, Clone, PartialEq)]
pub struct PlyLayout {
    /// Ply thickness, m.
    pub ply_thickness: f64,
    /// Sublaminate ply angles (degrees), bottom (at z = H) to top; their count × thickness
    /// must equal h.
    pub sublaminate: Vec<f64>,
    /// Base ply angles modelled ply by ply, from z = H downwards.
    pub base_below: Vec<f64>,
}

impl EmbeddedParams {
    /// Radial elements inside the front for semi-axes a (along the load) and b: the reference
    /// mesh's 4 times ⌈a/b⌉. The rings are laid out on the circle of radius min(a, b) and
    /// stretched along the long axis; when that is the load direction (a > b) the sublaminate
    /// buckles in about a/b half-waves along it, which 4 rings resolve badly: onset +11.8 % at
    /// a/b = 3 with 4, +0.9 % with 12 (docs/VALIDATION.md). For a ≤ b the mode varies slowly
    /// along the stretched direction and 4 suffice (−0.5 % at a/b = 1/3).
    pub fn radial_inside_for(a: f64, b: f64) -> usize {
        let ratio = if a > 0.0 && b > 0.0 && (a / b).is_finite() {
            a / b
        } else {
            1.0
        };
        4 * (ratio - 1e-9).ceil().clamp(1.0, 64.0) as usize
    }

    /// The thesis's reference case (§4.3, §5.1): 30 mm circular delamination (a = b = 15 mm),
    /// h = 0.4 mm, H = 4 mm, W = 50 mm, Hex20, 8 slices, refined like Table 2's model 4
    /// (2 085 nodes, 336 cells); here 2 263 nodes, 384 cells. 4 and 12 slices give Table 2's
    /// model 3 and 5 sizes (docs/MESH.md).
    pub fn thesis_reference() -> Self {
        Self {
            kind: ElementKind::Hex20,
            a: 15e-3,
            b: 15e-3,
            h: 0.4e-3,
            base: 4e-3,
            w: 50e-3,
            slices: 8,
            radial_inside: 4,
            radial_outside: 5,
            front_grading: 0.25,
            front_element: None,
            front_band: None,
            layer_band: None,
            core_fraction: 0.3,
            transition: 1.4,
            sub_layers: 1,
            base_layers: 3,
            base_grading: 0.25,
            map: EllipticMap::Conformal,
            plies: None,
            centre: Centre::OGrid,
            mid_edges: MidEdges::Chords,
        }
    }

    /// The parameters' checks (thesis §3.1–3.2): positive finite sizes, an even number of
    /// slices, at least one element per count, a core inside the front circle, the transition
    /// ring inside the square, eq. 3.1.2's r within the front circle, and the ply layout.
    pub(super) fn check(&self) -> Result<(), MeshError> {
        let bad = |name: &'static str, reason: String| Err(MeshError::Parameter { name, reason });
        for (name, v) in [
            ("a", self.a),
            ("b", self.b),
            ("h", self.h),
            ("base", self.base),
            ("w", self.w),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return bad(name, format!("{v} must be positive and finite"));
            }
        }
        if self.slices < 2 || self.slices % 2 == 1 {
            return bad("slices", format!("{} must be even and ≥ 2", self.slices));
        }
        for (name, n) in [
            ("radial_inside", self.radial_inside),
            ("radial_outside", self.radial_outside),
            ("sub_layers", self.sub_layers),
            ("base_layers", self.base_layers),
        ] {
            if n == 0 {
                return bad(name, "at least one element".into());
            }
        }
        if let Some(e) = self.front_element
            && !(e.is_finite() && e > 0.0 && e < self.a.min(self.b) * (1.0 - self.core_fraction))
        {
            return bad(
                "front_element",
                format!(
                    "{e} m must be positive and shorter than the distance from the core to the \
                     front, {} m",
                    self.a.min(self.b) * (1.0 - self.core_fraction)
                ),
            );
        }
        if let Some(band) = self.front_band
            && !(band.inside >= 1
                && band.outside >= 1
                && band.inside < self.radial_inside
                && band.outside < self.radial_outside)
        {
            return bad(
                "front_band",
                format!(
                    "{} rings inside and {} outside: each at least 1 and below radial_inside = {} \
                     and radial_outside = {} (one more ring on each side joins the band to the \
                     coarse rings)",
                    band.inside, band.outside, self.radial_inside, self.radial_outside
                ),
            );
        }
        self.check_layer_band()?;
        if !(self.core_fraction > 0.0 && self.core_fraction < 1.0) {
            return bad(
                "core_fraction",
                format!("{} must lie in (0, 1)", self.core_fraction),
            );
        }
        let big = self.a.max(self.b);
        if !(self.transition >= 1.0 && self.transition * big < self.w) {
            return bad(
                "transition",
                format!(
                    "need 1 ≤ transition and transition·max(a, b) < W ({} · {big} vs {})",
                    self.transition, self.w
                ),
            );
        }
        // Eq. 3.1.2 reaches the ellipse only where F = 1, so r must not exceed the front
        // circle's radius min(a, b); a larger r would leave the front off the ellipse.
        let short = self.a.min(self.b);
        if let EllipticMap::Modified { r } = self.map
            && !(r.is_finite() && r > 0.0 && r <= short)
        {
            return bad(
                "map.r",
                format!(
                    "{r} m must be positive and at most min(a, b) = {short} m, the radius of \
                     the front circle that eq. 3.1.2 maps onto the ellipse"
                ),
            );
        }
        match &self.plies {
            Some(pl) => pl.check(self.h, self.base),
            None => Ok(()),
        }
    }

    /// The layer band's checks (issue 25): rings as the front band's (≥ 1, below the ring
    /// counts), its transition rings not the front band's (one ring cannot carry both
    /// templates), even layer counts (the far field takes every other station), no ply layers
    /// (one element per ply cannot be halved).
    fn check_layer_band(&self) -> Result<(), MeshError> {
        let Some(lb) = self.layer_band else {
            return Ok(());
        };
        let bad = |reason: String| {
            Err(MeshError::Parameter {
                name: "layer_band",
                reason: format!(
                    "{} rings inside and {} outside: {reason}",
                    lb.inside, lb.outside
                ),
            })
        };
        if !(lb.inside >= 1
            && lb.outside >= 1
            && lb.inside < self.radial_inside
            && lb.outside < self.radial_outside)
        {
            return bad(format!(
                "each at least 1 and below radial_inside = {} and radial_outside = {} (one more \
                 ring on each side is the 1 → 2 transition)",
                self.radial_inside, self.radial_outside
            ));
        }
        if let Some(fb) = self.front_band
            && (fb.inside == lb.inside || fb.outside == lb.outside)
        {
            return bad(format!(
                "the front band's counts are {} and {}: its transition rings would also be the \
                 layers' (choose a layer band narrower or wider than the front band on each side)",
                fb.inside, fb.outside
            ));
        }
        if self.sub_layers % 2 == 1 || self.base_layers % 2 == 1 {
            return bad(format!(
                "sub_layers = {} and base_layers = {} must be even (half as many away from the \
                 front)",
                self.sub_layers, self.base_layers
            ));
        }
        if self.plies.is_some() {
            return bad("ply-level layers keep one element per ply everywhere".into());
        }
        Ok(())
    }

    /// Whether radial station m0 (index into the radial stations, `front` the front circle's)
    /// carries the full layers: always without a layer band; inside it otherwise (issue 25).
    pub(super) fn full_layers_at(&self, m0: usize, front: usize) -> bool {
        match self.layer_band {
            Some(lb) => m0 + lb.inside >= front && m0 <= front + lb.outside,
            None => true,
        }
    }

    /// z stations and, per layer between them, (material, ply angle); and the index of z = H.
    pub(super) fn layers(&self) -> Result<Layers, MeshError> {
        let Some(pl) = &self.plies else {
            let (zb, zs) = match self.front_element {
                Some(e) => (
                    graded_to_last(self.base_layers, self.base, e)?,
                    graded_from_first(
                        self.sub_layers,
                        self.h,
                        e.min(self.h / self.sub_layers as f64),
                    )?,
                ),
                None => (
                    graded_coordinates(self.base_layers, self.base, self.base_grading)?,
                    graded_coordinates(self.sub_layers, self.h, 1.0)?,
                ),
            };
            let mut z = zb.clone();
            z.extend(zs.iter().skip(1).map(|d| self.base + d));
            let layers = vec![(0, 0.0); z.len() - 1];
            return Ok((z, layers, self.base_layers));
        };
        let t = pl.ply_thickness;
        let homog = self.base - pl.base_below.len() as f64 * t;
        let mut z = graded_coordinates(self.base_layers, homog, self.base_grading)?;
        let mut layers = vec![(0, 0.0); self.base_layers];
        for (k, &angle) in pl.base_below.iter().rev().enumerate() {
            z.push(homog + (k + 1) as f64 * t);
            layers.push((1, angle));
        }
        if let Some(last) = z.last_mut() {
            *last = self.base;
        }
        let zh = z.len() - 1;
        for (k, &angle) in pl.sublaminate.iter().enumerate() {
            z.push(self.base + (k + 1) as f64 * t);
            layers.push((1, angle));
        }
        Ok((z, layers, zh))
    }
}

impl PlyLayout {
    /// The layout's checks (chapter 7): a positive ply thickness, sublaminate plies that fill
    /// h, base plies that leave some homogenised base below them, finite angles.
    fn check(&self, h: f64, base: f64) -> Result<(), MeshError> {
        let bad = |name: &'static str, reason: String| Err(MeshError::Parameter { name, reason });
        let t = self.ply_thickness;
        if !(t.is_finite() && t > 0.0) || self.sublaminate.is_empty() {
            return bad(
                "plies",
                "positive ply thickness and at least one sublaminate ply".into(),
            );
        }
        if ((self.sublaminate.len() as f64 * t) - h).abs() > 1e-9 * h {
            return bad(
                "plies",
                format!("{} plies × {t} m ≠ h = {} m", self.sublaminate.len(), h),
            );
        }
        if self.base_below.len() as f64 * t >= base {
            return bad("plies", "base plies leave no homogenised base".into());
        }
        if self
            .sublaminate
            .iter()
            .chain(&self.base_below)
            .any(|a| !a.is_finite())
        {
            return bad("plies", "ply angles must be finite".into());
        }
        Ok(())
    }
}

/// Thickness stations, (material, ply angle) of each layer, index of z = H.
pub(super) type Layers = (Vec<f64>, Vec<(usize, f64)>, usize);

#[cfg(test)]
mod tests {
    use super::*;

    /// Each broken ply layout is refused under the name `plies`, and the reference layout of
    /// four 0.1 mm plies in h = 0.4 mm passes.
    #[test]
    fn ply_layouts_that_do_not_fit_are_named() {
        let p = EmbeddedParams::thesis_reference();
        let good = PlyLayout {
            ply_thickness: 0.1e-3,
            sublaminate: vec![0.0, 90.0, 90.0, 0.0],
            base_below: vec![45.0],
        };
        assert!(good.check(p.h, p.base).is_ok());
        let broken = [
            PlyLayout {
                ply_thickness: 0.0,
                ..good.clone()
            },
            PlyLayout {
                sublaminate: vec![0.0, 90.0, 0.0],
                ..good.clone()
            },
            PlyLayout {
                base_below: vec![0.0; 40],
                ..good.clone()
            },
            PlyLayout {
                base_below: vec![f64::NAN],
                ..good.clone()
            },
        ];
        for layout in broken {
            let err = layout.check(p.h, p.base).unwrap_err();
            assert!(
                matches!(err, MeshError::Parameter { name: "plies", .. }),
                "{layout:?}: {err}"
            );
        }
    }
}
