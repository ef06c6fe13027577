//! The companion meshes of the discretisation-error estimate (issue 25): the same model with
//! every element count halved and the front element doubled, so that the G of a run can be
//! compared with the G of the same level on a mesh twice as coarse (Richardson's h and 2h).

use super::{EmbeddedParams, FrontBand, LayerBand, ThroughWidthParams};

/// ⌈n/2⌉, at least 1: a count halved.
fn half(n: usize) -> usize {
    n.div_ceil(2).max(1)
}

impl EmbeddedParams {
    /// The companion mesh twice as coarse: slices, rings, band rings and layers halved
    /// (rounded up; slices to the even count ≥ 2, the generator's rule), the front element
    /// size doubled. Ply-level layers keep one element per ply (a ply cannot be coarsened),
    /// and a band that no longer fits inside the halved rings loses its extra rings (it is
    /// dropped when none is left). A doubled front element that would no longer fit between
    /// the core and the front falls back to the thesis grading (`None`).
    pub fn coarsened(&self) -> Self {
        let slices = (self.slices / 2).max(2);
        let slices = slices + slices % 2;
        let (inside, outside) = (half(self.radial_inside), half(self.radial_outside));
        let front_band = self.front_band.and_then(|b| {
            let band = FrontBand {
                inside: half(b.inside).min(inside.saturating_sub(1)),
                outside: half(b.outside).min(outside.saturating_sub(1)),
            };
            (band.inside >= 1 && band.outside >= 1).then_some(band)
        });
        let (sub, base) = (half(self.sub_layers), half(self.base_layers));
        // The layer band halved, kept while the halved counts stay even and it fits.
        let layer_band = self.layer_band.and_then(|b| {
            let band = LayerBand {
                inside: half(b.inside),
                outside: half(b.outside),
            };
            let clash =
                front_band.is_some_and(|f| f.inside == band.inside || f.outside == band.outside);
            let fits = band.inside < inside && band.outside < outside && !clash;
            (fits && sub % 2 == 0 && base % 2 == 0).then_some(band)
        });
        let room = self.a.min(self.b) * (1.0 - self.core_fraction);
        Self {
            slices,
            radial_inside: inside,
            radial_outside: outside,
            front_element: self.front_element.map(|e| 2.0 * e).filter(|e| *e < room),
            front_band,
            layer_band,
            sub_layers: sub,
            base_layers: base,
            ..self.clone()
        }
    }
}

impl ThroughWidthParams {
    /// The companion strip twice as coarse: elements along x inside and outside, through the
    /// sublaminate and the base halved (rounded up, at least one); the width keeps its
    /// elements (plane strain: G does not vary across it).
    pub fn coarsened(&self) -> Self {
        Self {
            inside: half(self.inside),
            outside: half(self.outside),
            sub_layers: half(self.sub_layers),
            base_layers: half(self.base_layers),
            ..self.clone()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_reference_mesh_halves_to_the_thesis_coarse_mesh() {
        // 8, 4, 5, 1, 3 → 4, 2, 3, 1, 2 (the companion of docs/ACCURACY.md §3).
        let c = EmbeddedParams::thesis_reference().coarsened();
        assert_eq!(
            (
                c.slices,
                c.radial_inside,
                c.radial_outside,
                c.sub_layers,
                c.base_layers
            ),
            (4, 2, 3, 1, 2)
        );
        assert_eq!(c.front_element, None);
        // Twice: 2, 1, 2, 1, 1; never below the generator's minimum.
        let cc = c.coarsened().coarsened();
        assert_eq!((cc.slices, cc.radial_inside, cc.sub_layers), (2, 1, 1));
    }

    #[test]
    fn the_front_element_doubles_and_the_band_shrinks_with_the_rings() {
        let p = EmbeddedParams {
            slices: 6,
            radial_inside: 7,
            radial_outside: 6,
            sub_layers: 2,
            base_layers: 2,
            front_element: Some(0.3e-3),
            front_band: Some(FrontBand {
                inside: 5,
                outside: 3,
            }),
            ..EmbeddedParams::thesis_reference()
        };
        let c = p.coarsened();
        // 6 slices → 3 → 4 (even); 7, 6 rings → 4, 3; band 5 + 3 → 3 + 2, inside the rings.
        assert_eq!((c.slices, c.radial_inside, c.radial_outside), (4, 4, 3));
        assert_eq!(
            c.front_band,
            Some(FrontBand {
                inside: 3,
                outside: 2
            })
        );
        assert!((c.front_element.unwrap_or(0.0) - 0.6e-3).abs() < 1e-15);
        assert!(super::super::embedded_delamination(&c).is_ok());
        // A band that cannot stay inside one ring is dropped.
        let thin = EmbeddedParams {
            radial_inside: 2,
            ..p.clone()
        };
        assert_eq!(thin.coarsened().front_band, None);
    }

    #[test]
    fn the_strip_halves_along_x_and_through_the_thickness() {
        let c = ThroughWidthParams::example().coarsened();
        assert_eq!(
            (c.inside, c.outside, c.sub_layers, c.base_layers, c.across),
            (5, 3, 1, 2, 1)
        );
    }
}
