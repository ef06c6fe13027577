//! The companion meshes of the discretisation-error estimate (issue 25, docs/ACCURACY.md §3):
//! the same model on a coarser mesh, so that the G of a run can be compared with the G of the
//! same level on the companion (Richardson's h and 2h).
//!
//! What the companion coarsens depends on whether the run's mesh resolves the mode split at
//! the front. With two or more sublaminate layers it does (G_II at S = 0 within 2–6 % of the
//! converged value on the meshes of docs/ACCURACY.md §1, §2b), and the companion keeps what
//! sets the split — the sublaminate layers, the front element e and at least two base layers
//! under it — and halves the rest (slices, rings, band rings): halving two sublaminate layers
//! to one, or two base layers to one, moves G_II at S = 0 by 12–45 % on any mesh, so the
//! difference would measure the companion's split, not the run's error (§3: 9× and 19× too
//! pessimistic on the band meshes Q and R). With one sublaminate layer the split is the
//! mesh's largest error (G_II at S = 0 −12 … −26 %), and only a companion that coarsens it
//! too (e doubled, base layers halved) shows it: every count is halved.
//!
//! A mesh with a front band (the default mesh and the band meshes) resolves the front with the
//! band, and its rings outside the band only carry the far field. Its companion keeps those
//! rings and halves the band's: halving them too changed G at S = 0 by about 7× the mesh's own
//! error on the circle and the edge and cancelled the layers' effect on the ellipse
//! (docs/ACCURACY.md §2f, §3b) — the difference then measured the far field, not the front.

use super::{EmbeddedParams, FrontBand, LayerBand, ThroughWidthParams};

/// ⌈n/2⌉, at least 1: a count halved.
fn half(n: usize) -> usize {
    n.div_ceil(2).max(1)
}

/// What a run's companion mesh coarsens ([`EmbeddedParams::coarsened`]): the error estimate's
/// factors are measured per kind (the vcct crate's `estimate::Rule`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CompanionKind {
    /// One sublaminate layer (or a through-width strip): every count halved, e doubled.
    AllHalved,
    /// Two or more sublaminate layers, no front band or fewer than six slices: the layers at
    /// the front and e kept; slices, rings and base layers halved.
    SplitKept,
    /// Two or more sublaminate layers, a front band and six or more slices: as
    /// [`Self::SplitKept`], with the rings outside the band kept (the band's rings halved).
    FarFieldKept,
}

impl EmbeddedParams {
    /// Whether the mesh resolves the mode split at the front (two or more sublaminate
    /// layers): the companion then keeps the through-thickness mesh at the front (module
    /// docs). Ply-level meshes keep the rule of one layer (their companions not measured).
    pub fn resolves_the_split(&self) -> bool {
        self.sub_layers >= 2 && self.plies.is_none()
    }

    /// What [`Self::coarsened`] keeps, which sets the estimate's factors: the far field where
    /// the mesh resolves the split, has a front band and six or more slices (its companion
    /// four or more: a two-slice companion is far from the asymptotic range — band mesh Q's
    /// was 7× too pessimistic with the far field kept — and with its rings kept the 30 × 60 mm
    /// ellipse's had an inverted cell).
    pub fn companion_kind(&self) -> CompanionKind {
        match (self.resolves_the_split(), self.front_band.is_some()) {
            (true, true) if self.slices >= 6 => CompanionKind::FarFieldKept,
            (true, _) => CompanionKind::SplitKept,
            (false, _) => CompanionKind::AllHalved,
        }
    }

    /// The companion mesh: slices halved (rounded up to the even count ≥ 2, the generator's
    /// rule), band rings halved (rounded up; a band that no longer fits inside the rings loses
    /// its extra rings, and is dropped when none is left) and the rings halved too, except for
    /// a [`CompanionKind::FarFieldKept`] mesh, whose rings are kept. Where the mesh
    /// resolves the split ([`Self::resolves_the_split`]) the sublaminate layers and the front
    /// element are kept and the base layers halved to no fewer than two; otherwise the layers
    /// are halved and the front element doubled (falling back to the thesis grading, `None`,
    /// when it no longer fits between the core and the front). Ply-level layers keep one
    /// element per ply (a ply cannot be coarsened).
    pub fn coarsened(&self) -> Self {
        let slices = (self.slices / 2).max(2);
        let slices = slices + slices % 2;
        let (inside, outside) = match self.companion_kind() {
            CompanionKind::FarFieldKept => (self.radial_inside, self.radial_outside),
            _ => (half(self.radial_inside), half(self.radial_outside)),
        };
        let front_band = self.front_band.and_then(|b| {
            let band = FrontBand {
                inside: half(b.inside).min(inside.saturating_sub(1)),
                outside: half(b.outside).min(outside.saturating_sub(1)),
            };
            (band.inside >= 1 && band.outside >= 1).then_some(band)
        });
        let room = self.a.min(self.b) * (1.0 - self.core_fraction);
        let (sub_layers, base_layers, front_element) = if self.resolves_the_split() {
            (
                self.sub_layers,
                half(self.base_layers).max(2).min(self.base_layers),
                self.front_element,
            )
        } else {
            (
                half(self.sub_layers),
                half(self.base_layers),
                self.front_element.map(|e| 2.0 * e).filter(|e| *e < room),
            )
        };
        // The layer band halved, kept while the halved counts stay even and it fits.
        let layer_band = self.layer_band.and_then(|b| {
            let band = LayerBand {
                inside: half(b.inside),
                outside: half(b.outside),
            };
            let clash =
                front_band.is_some_and(|f| f.inside == band.inside || f.outside == band.outside);
            let fits = band.inside < inside && band.outside < outside && !clash;
            (fits && sub_layers % 2 == 0 && base_layers % 2 == 0).then_some(band)
        });
        Self {
            slices,
            radial_inside: inside,
            radial_outside: outside,
            front_element,
            front_band,
            layer_band,
            sub_layers,
            base_layers,
            ..self.clone()
        }
    }
}

impl EmbeddedParams {
    /// The companion's own companion (nested iteration three meshes deep, the facade's
    /// src/analysis_seed.rs): only the slices halved (rounded up to the even count ≥ 2), the
    /// rings, bands and layers kept, or None when the slices cannot halve. It serves the
    /// companion's levels' starts, not an estimate, so it keeps what sets the buckled branch:
    /// with its rings halved as well ([`Self::coarsened`] twice), the 30 × 60 mm ellipse's
    /// coarser companion landed on another branch at ε = −0.001 and its start was dropped
    /// (docs/PERFORMANCE.md, "Nested companions"). One exception: two slices under the rings of
    /// a kept far field ([`CompanionKind::FarFieldKept`]: 7 + 6 rings on the default mesh)
    /// make inverted cells on the 30 × 60 mm ellipse, so where the slices fall to two the rings
    /// halve too, as long as the front band and the layer band still fit inside them (the
    /// default mesh's chain then ends on the mesh its companion's companion was before).
    pub fn coarsened_along_front(&self) -> Option<Self> {
        let slices = (self.slices / 2).max(2);
        let slices = slices + slices % 2;
        if slices >= self.slices {
            return None;
        }
        let (inside, outside) = (half(self.radial_inside), half(self.radial_outside));
        let fits = |b: Option<(usize, usize)>| b.is_none_or(|(i, o)| i < inside && o < outside);
        let halve = slices == 2
            && self.front_band.is_some()
            && fits(self.front_band.map(|b| (b.inside, b.outside)))
            && fits(self.layer_band.map(|b| (b.inside, b.outside)));
        Some(Self {
            slices,
            radial_inside: if halve { inside } else { self.radial_inside },
            radial_outside: if halve { outside } else { self.radial_outside },
            ..self.clone()
        })
    }
}

impl ThroughWidthParams {
    /// The companion strip twice as coarse: elements along x inside and outside, through the
    /// sublaminate and the base halved (rounded up, at least one); the width keeps its
    /// elements (plane strain: G does not vary across it). The strip's G is nearly pure
    /// mode II (G_I < 1 % of G_T at ε = −0.004), so there is no split to keep: keeping its
    /// sublaminate layers missed the error of the committed scene's mesh (16, 10, 2, 3:
    /// ±1.87 J/m² against a true 1.98 on G_T, docs/ACCURACY.md §3), halving them brackets it.
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
    fn a_mesh_that_resolves_the_split_keeps_its_layers_and_front_element() {
        // Band mesh Q of docs/ACCURACY.md: 4 → 12 slices, 7 + 6 rings, 2 + 2 layers,
        // e = 0.3 mm, band 5 + 3.
        let p = EmbeddedParams {
            slices: 4,
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
        // 4 slices → 2; 7, 6 rings → 4, 3; band 5 + 3 → 3 + 2, inside the rings; the two
        // sublaminate and two base layers and e kept (the old rule gave 1, 1 and 0.6 mm).
        assert_eq!((c.slices, c.radial_inside, c.radial_outside), (2, 4, 3));
        assert_eq!(
            c.front_band,
            Some(FrontBand {
                inside: 3,
                outside: 2
            })
        );
        assert_eq!((c.sub_layers, c.base_layers), (2, 2));
        assert_eq!(c.front_element, Some(0.3e-3));
        assert!(super::super::embedded_delamination(&c).is_ok());
        // More base layers halve, to no fewer than two: 3 → 2, 5 → 3.
        for (base, want) in [(3, 2), (5, 3)] {
            let q = EmbeddedParams {
                base_layers: base,
                ..p.clone()
            };
            assert_eq!(q.coarsened().base_layers, want);
        }
        // A band that cannot stay inside one ring is dropped.
        let thin = EmbeddedParams {
            radial_inside: 2,
            ..p.clone()
        };
        assert_eq!(thin.coarsened().front_band, None);
    }

    #[test]
    fn the_default_meshs_companion_keeps_the_far_field() {
        // Mesh S (docs/MESH.md): 6 → 18 slices in a band of 5 + 3, 7 + 6 rings, 2 + 4
        // layers, e = 0.2 mm, layer band 3 + 2. Its companion keeps the rings outside the
        // band and halves the rest: 4 → 12 slices, band 3 + 2, 7 + 6 rings, 2 + 2 layers,
        // layer band 2 + 1 (7 581 DOF on the reference circle).
        let p = EmbeddedParams::thesis_reference().with_accuracy_row(&super::super::DEFAULT_MESH);
        assert_eq!((p.slices, p.radial_inside, p.radial_outside), (6, 7, 6));
        assert_eq!((p.sub_layers, p.base_layers), (2, 4));
        assert_eq!(p.companion_kind(), CompanionKind::FarFieldKept);
        let c = p.coarsened();
        assert_eq!((c.slices, c.radial_inside, c.radial_outside), (4, 7, 6));
        assert_eq!((c.sub_layers, c.base_layers), (2, 2));
        assert_eq!(c.front_element, Some(0.2e-3));
        assert_eq!(
            (c.front_band, c.layer_band),
            (
                Some(FrontBand {
                    inside: 3,
                    outside: 2
                }),
                Some(LayerBand {
                    inside: 2,
                    outside: 1
                })
            )
        );
        // Its cells are valid on the circle and on the 30 × 60 mm ellipse (b/a = 2); with two
        // slices and the rings kept, the ellipse's are not (why four slices are needed).
        let valid = |q: &EmbeddedParams| {
            super::super::embedded_delamination(q).is_ok_and(|m| crate::quality(&m).is_ok())
        };
        let ellipse = EmbeddedParams {
            b: 2.0 * p.a,
            ..c.clone()
        };
        assert!(valid(&c) && valid(&ellipse));
        let two = EmbeddedParams {
            slices: 2,
            front_element: Some(0.3e-3),
            ..ellipse.clone()
        };
        assert!(!valid(&two));
        // The companion's own companion: two slices, the rings halved with them (the band and
        // the layer band still fit): 2 → 6 slices, 4 + 3 rings, valid on the ellipse.
        let Some(cc) = ellipse.coarsened_along_front() else {
            panic!("4 slices halve");
        };
        assert_eq!((cc.slices, cc.radial_inside, cc.radial_outside), (2, 4, 3));
        assert_eq!((cc.front_band, cc.layer_band), (c.front_band, c.layer_band));
        assert!(valid(&cc));
        // Four slices (band mesh Q) or no band: the rings halve as well.
        let q = EmbeddedParams {
            slices: 4,
            ..p.clone()
        };
        assert_eq!(q.companion_kind(), CompanionKind::SplitKept);
        assert_eq!(
            (q.coarsened().radial_inside, q.coarsened().radial_outside),
            (4, 3)
        );
        let no_band = EmbeddedParams {
            front_band: None,
            layer_band: None,
            ..p.clone()
        };
        assert_eq!(no_band.companion_kind(), CompanionKind::SplitKept);
        assert_eq!(no_band.coarsened().radial_inside, 4);
    }

    #[test]
    fn along_the_front_only_the_slices_halve() {
        // The default mesh's companion: 4 → 12 slices in a band of 3 + 2, 4 + 3 rings.
        let p = EmbeddedParams {
            slices: 4,
            radial_inside: 4,
            radial_outside: 3,
            sub_layers: 2,
            base_layers: 2,
            front_element: Some(0.2e-3),
            front_band: Some(FrontBand {
                inside: 3,
                outside: 2,
            }),
            layer_band: Some(LayerBand {
                inside: 2,
                outside: 1,
            }),
            ..EmbeddedParams::thesis_reference()
        };
        let Some(c) = p.coarsened_along_front() else {
            panic!("4 slices halve");
        };
        assert_eq!(c.slices, 2);
        assert_eq!(
            EmbeddedParams {
                slices: 4,
                ..c.clone()
            },
            p
        );
        assert!(super::super::embedded_delamination(&c).is_ok());
        // 6 → 4 (even), 2 → none.
        let six = EmbeddedParams {
            slices: 6,
            ..p.clone()
        };
        assert_eq!(six.coarsened_along_front().map(|c| c.slices), Some(4));
        assert_eq!(c.coarsened_along_front(), None);
    }

    #[test]
    fn one_sublaminate_layer_coarsens_the_front_element_and_the_base_too() {
        // 8, 5, 5, 1, 2, e = 0.4 mm (row 1 of the accuracy table): the split is its largest
        // error, so the companion coarsens it: 4, 3, 3, 1, 1, e = 0.8 mm.
        let p = EmbeddedParams {
            radial_inside: 5,
            radial_outside: 5,
            base_layers: 2,
            front_element: Some(0.4e-3),
            ..EmbeddedParams::thesis_reference()
        };
        assert!(!p.resolves_the_split());
        let c = p.coarsened();
        assert_eq!(
            (
                c.slices,
                c.radial_inside,
                c.radial_outside,
                c.sub_layers,
                c.base_layers
            ),
            (4, 3, 3, 1, 1)
        );
        assert!((c.front_element.unwrap_or(0.0) - 0.8e-3).abs() < 1e-15);
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
