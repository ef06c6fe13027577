//! Mixed-mode delamination criteria: the failure index along a front and the critical applied
//! strain of a strain sweep.
//!
//! Sources (as Abaqus's VCCT documentation also cites them):
//! - power law: E. M. Wu and R. C. Reuter, "Crack extension in fiberglass reinforced
//!   plastics", T&AM Report 275, University of Illinois, 1965 — (G_I/G_Ic)^α +
//!   (G_II/G_IIc)^β + (G_III/G_IIIc)^β = 1 at onset; J. R. Reeder, "An evaluation of mixed-mode
//!   delamination failure criteria", NASA TM-104210, 1992, compares it with the others;
//! - Benzeggagh–Kenane: M. L. Benzeggagh and M. Kenane, "Measurement of mixed-mode
//!   delamination fracture toughness of unidirectional glass/epoxy composites with mixed-mode
//!   bending apparatus", Composites Science and Technology 56 (1996) 439–449 — G_c = G_Ic +
//!   (G_IIc − G_Ic)·(G_shear/G_T)^η, onset at G_T = G_c.
//!
//! The thesis (§2.8) computes G_I, G_II, G_III along the front and applies no criterion.

use crate::{FrontRelease, VcctError};

/// A mixed-mode criterion; [`MixedMode::index`] is 1 at the onset of growth.
///
/// Negative G_I counts as 0 in every criterion. Points whose faces overlap
/// ([`FrontRelease::open`] false) are not physical without contact and are left out of
/// [`critical_strain`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MixedMode {
    /// Power law: (G_I/G_Ic)^α + (G_II/G_IIc)^β + (G_III/G_IIIc)^β.
    PowerLaw {
        /// Mode I toughness G_Ic, J/m².
        g_ic: f64,
        /// Mode II toughness G_IIc, J/m².
        g_iic: f64,
        /// Mode III toughness G_IIIc, J/m² (often taken = G_IIc).
        g_iiic: f64,
        /// Exponent α on mode I.
        alpha: f64,
        /// Exponent β on the shear modes.
        beta: f64,
    },
    /// Benzeggagh–Kenane (1996): G_c = G_Ic + (G_IIc − G_Ic)·(G_shear/G_T)^η with
    /// G_shear = G_II + G_III; index G_T / G_c.
    BenzeggaghKenane {
        /// Mode I toughness G_Ic, J/m².
        g_ic: f64,
        /// Mode II toughness G_IIc, J/m².
        g_iic: f64,
        /// The B–K exponent η.
        eta: f64,
    },
}

/// Smallest toughness a criterion accepts, J/m² (real interfaces: 10 … 10⁴ J/m²).
pub const MIN_TOUGHNESS: f64 = 1e-3;
/// Largest exponent (α, β, η) a criterion accepts.
pub const MAX_EXPONENT: f64 = 100.0;

impl MixedMode {
    /// Checks that toughnesses and exponents are positive and finite.
    pub fn validate(&self) -> Result<(), VcctError> {
        let vals: &[(&'static str, f64)] = match self {
            Self::PowerLaw {
                g_ic,
                g_iic,
                g_iiic,
                alpha,
                beta,
            } => &[
                ("G_Ic", *g_ic),
                ("G_IIc", *g_iic),
                ("G_IIIc", *g_iiic),
                ("alpha", *alpha),
                ("beta", *beta),
            ],
            Self::BenzeggaghKenane { g_ic, g_iic, eta } => {
                &[("G_Ic", *g_ic), ("G_IIc", *g_iic), ("eta", *eta)]
            }
        };
        for &(name, v) in vals {
            // Toughnesses of real interfaces are 10 … 10⁴ J/m²; the bounds keep every index
            // finite for any finite G (a toughness of 1e-308 made (G/G_c)^β overflow).
            let (lo, hi) = if name.starts_with("G_") {
                (MIN_TOUGHNESS, 1e12)
            } else {
                (1e-3, MAX_EXPONENT)
            };
            if !(v >= lo && v <= hi) {
                return Err(VcctError::Criterion { name, value: v });
            }
        }
        Ok(())
    }

    /// The failure index of one front point (≥ 1: growth predicted). Saturates at f64::MAX
    /// rather than overflow to ∞ for an absurd G (never a non-finite number in the results).
    pub fn index(&self, r: &FrontRelease) -> f64 {
        self.raw_index(r).min(f64::MAX)
    }

    fn raw_index(&self, r: &FrontRelease) -> f64 {
        let g_i = r.g_i.max(0.0);
        let (g_ii, g_iii) = (r.g_ii.abs(), r.g_iii.abs());
        match *self {
            Self::PowerLaw {
                g_ic,
                g_iic,
                g_iiic,
                alpha,
                beta,
            } => (g_i / g_ic).powf(alpha) + (g_ii / g_iic).powf(beta) + (g_iii / g_iiic).powf(beta),
            Self::BenzeggaghKenane { g_ic, g_iic, eta } => {
                let shear = g_ii + g_iii;
                let total = g_i + shear;
                if total <= 0.0 {
                    return 0.0;
                }
                let gc = g_ic + (g_iic - g_ic) * (shear / total).powf(eta);
                total / gc
            }
        }
    }

    /// The mode mix of a front point, (G_II + G_III)/G_T with G_T = G_I + G_II + G_III as
    /// VCCT gives them (0 where G_T = 0): B–K's G_shear/G_T, the front VTU's `mode_mix`.
    pub fn mode_mix(r: &FrontRelease) -> f64 {
        let shear = r.g_ii + r.g_iii;
        let total = r.g_i + shear;
        if total == 0.0 { 0.0 } else { shear / total }
    }

    /// Failure indices along a front.
    pub fn indices(&self, rates: &[FrontRelease]) -> Vec<f64> {
        rates.iter().map(|r| self.index(r)).collect()
    }
}

/// Where and at which applied strain a strain sweep first reaches a failure index of 1.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CriticalStrain {
    /// The applied strain at onset, interpolated — or, when [`CriticalStrain::after`] is set,
    /// the first level whose index is ≥ 1 (the onset lies between the two).
    pub strain: f64,
    /// Set when the onset cannot be interpolated: the level before released nothing (the
    /// sublaminate still flat, index < 1e-6 of the next level's), so G started growing at an
    /// unknown bifurcation strain between the two levels and the √index interpolation, which
    /// assumes growth from the lower level, would place the onset too early. The onset lies in
    /// (after, strain]; levels between them locate it.
    pub after: Option<f64>,
    /// Index of the front point that reaches 1 first (in the sweep's front tables).
    pub point: usize,
    /// Index (in `levels`) of the first level whose largest failure index is ≥ 1.
    pub level: usize,
    /// The failure index of `point` at `level` (≥ 1).
    pub index: f64,
    /// S of that point (m).
    pub s: f64,
}

/// The critical applied strain of a sweep: `levels` are (applied strain, front table) in the
/// order applied (|strain| growing). The largest index over the front's open points (where the
/// faces overlap, G is not physical without contact) is followed from level to
/// level; between the two levels where it first crosses 1, √index is interpolated linearly in
/// strain (G grows with the square of the load where the response is linear, so √index is
/// linear there). `None` if the index stays below 1; the first level if it is already ≥ 1
/// there.
pub fn critical_strain(
    criterion: &MixedMode,
    levels: &[(f64, Vec<FrontRelease>)],
) -> Result<Option<CriticalStrain>, VcctError> {
    criterion.validate()?;
    let peak = |rates: &[FrontRelease]| -> Option<(usize, f64)> {
        rates
            .iter()
            .enumerate()
            .filter(|(_, r)| r.open())
            .map(|(i, r)| (i, criterion.index(r)))
            .max_by(|a, b| a.1.total_cmp(&b.1))
    };
    let mut last: Option<(f64, f64)> = None;
    for (level, (strain, rates)) in levels.iter().enumerate() {
        let Some((i, f)) = peak(rates) else {
            continue;
        };
        if f >= 1.0 {
            let (at, after) = match last {
                None => (*strain, None),
                Some((e0, f0)) if f0 < 1e-6 * f => (*strain, Some(e0)),
                Some((e0, f0)) => {
                    let (r0, r1) = (f0.sqrt(), f.sqrt());
                    (e0 + (strain - e0) * (1.0 - r0) / (r1 - r0), None)
                }
            };
            return Ok(Some(CriticalStrain {
                strain: at,
                after,
                point: i,
                level,
                index: f,
                s: rates[i].s,
            }));
        }
        last = Some((*strain, f));
    }
    Ok(None)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn point(g_i: f64, g_ii: f64, g_iii: f64) -> FrontRelease {
        FrontRelease {
            node: 0,
            s: 0.0,
            theta_deg: 0.0,
            x: 0.0,
            y: 0.0,
            delta_a: 1.0,
            area: 1.0,
            g_i,
            g_ii,
            g_iii,
            g_t: g_i + g_ii + g_iii,
            opening: 1.0,
        }
    }

    #[test]
    fn criteria_reduce_to_the_pure_mode_toughness() {
        let pl = MixedMode::PowerLaw {
            g_ic: 200.0,
            g_iic: 800.0,
            g_iiic: 800.0,
            alpha: 1.0,
            beta: 2.0,
        };
        let bk = MixedMode::BenzeggaghKenane {
            g_ic: 200.0,
            g_iic: 800.0,
            eta: 2.1,
        };
        for c in [pl, bk] {
            assert_relative_eq!(c.index(&point(200.0, 0.0, 0.0)), 1.0, epsilon = 1e-14);
            assert_relative_eq!(c.index(&point(0.0, 800.0, 0.0)), 1.0, epsilon = 1e-14);
            // Overlap (G_I < 0) does not drive growth.
            assert_relative_eq!(c.index(&point(-50.0, 0.0, 0.0)), 0.0);
        }
        // B–K at mode mixity ½: G_c = 200 + 600·0.5^2.1.
        let gc = 200.0 + 600.0 * 0.5_f64.powf(2.1);
        assert_relative_eq!(
            bk.index(&point(100.0, 100.0, 0.0)),
            200.0 / gc,
            epsilon = 1e-14
        );
        assert!(matches!(
            MixedMode::BenzeggaghKenane {
                g_ic: 0.0,
                g_iic: 1.0,
                eta: 1.0
            }
            .validate(),
            Err(VcctError::Criterion { name: "G_Ic", .. })
        ));
    }

    /// Hand computations at a mixed-mode point G = (60, 30, 10) J/m² (G_T = 100, mode mix
    /// (30 + 10)/100 = 0.4) and at (50, 400, 100):
    /// - power law, G_Ic = 200, G_IIc = 800, G_IIIc = 1000, α = 1, β = 2:
    ///   50/200 + (400/800)² + (100/1000)² = 0.25 + 0.25 + 0.01 = 0.51;
    /// - B–K, G_Ic = 200, G_IIc = 800, η = 2: G_c = 200 + 600·0.4² = 296, index 100/296.
    ///
    /// Computed in floating point these agree with the decimal values to a few ulps: 1e-15
    /// relative.
    #[test]
    fn indices_and_mode_mix_match_hand_computations() {
        let pl = MixedMode::PowerLaw {
            g_ic: 200.0,
            g_iic: 800.0,
            g_iiic: 1000.0,
            alpha: 1.0,
            beta: 2.0,
        };
        assert_relative_eq!(
            pl.index(&point(50.0, 400.0, 100.0)),
            0.51,
            max_relative = 1e-15
        );
        let bk = MixedMode::BenzeggaghKenane {
            g_ic: 200.0,
            g_iic: 800.0,
            eta: 2.0,
        };
        let p = point(60.0, 30.0, 10.0);
        assert_relative_eq!(MixedMode::mode_mix(&p), 0.4, max_relative = 1e-15);
        assert_relative_eq!(bk.index(&p), 100.0 / 296.0, max_relative = 1e-15);
        assert_eq!(MixedMode::mode_mix(&point(0.0, 0.0, 0.0)), 0.0);
        // The onset of a sweep of this point scaled by (ε/ε₁)², ε₁ = −0.001: B–K's index is
        // proportional to the scale (the mix is fixed), 0.338 at ε₁ and 1.351 at 2ε₁; √index
        // is linear in ε, so the onset is at ε₁·√(296/100) exactly, at the second level.
        let levels: Vec<(f64, Vec<FrontRelease>)> = [1.0, 2.0]
            .iter()
            .map(|&k| {
                let q = k * k;
                (-0.001 * k, vec![point(60.0 * q, 30.0 * q, 10.0 * q)])
            })
            .collect();
        let hit = critical_strain(&bk, &levels).unwrap().unwrap();
        assert_eq!((hit.level, hit.point), (1, 0));
        assert_relative_eq!(hit.index, 400.0 / 296.0, max_relative = 1e-15);
        assert_relative_eq!(hit.strain, -0.001 * 2.96_f64.sqrt(), max_relative = 1e-14);
    }

    /// G ∝ ε² gives √index ∝ ε: the interpolation recovers the onset exactly.
    #[test]
    fn critical_strain_is_exact_for_quadratic_growth() {
        let c = MixedMode::PowerLaw {
            g_ic: 100.0,
            g_iic: 100.0,
            g_iiic: 100.0,
            alpha: 1.0,
            beta: 1.0,
        };
        // G_I = 100·(ε/ε*)², ε* = −0.0037.
        let star = -0.0037;
        let levels: Vec<(f64, Vec<FrontRelease>)> = (1..=5)
            .map(|k| {
                let e = -0.001 * k as f64;
                let g = 100.0 * (e / star) * (e / star);
                (e, vec![point(0.5 * g, 0.0, 0.0), point(g, 0.0, 0.0)])
            })
            .collect();
        let hit = critical_strain(&c, &levels).unwrap().unwrap();
        assert_relative_eq!(hit.strain, star, epsilon = 1e-15);
        assert_eq!(hit.point, 1);
        assert_eq!(hit.after, None);
        assert!(critical_strain(&c, &levels[..3]).unwrap().is_none());
    }

    /// A flat level (nothing released: below the bifurcation) followed by one past the onset:
    /// the onset is bracketed, not interpolated from the flat level.
    #[test]
    fn an_onset_after_a_flat_level_is_bracketed() {
        let c = MixedMode::PowerLaw {
            g_ic: 100.0,
            g_iic: 100.0,
            g_iiic: 100.0,
            alpha: 1.0,
            beta: 1.0,
        };
        let levels = vec![
            (-0.004, vec![point(1e-25, 0.0, 0.0)]),
            (-0.0065, vec![point(230.0, 0.0, 0.0)]),
        ];
        let hit = critical_strain(&c, &levels).unwrap().unwrap();
        assert_eq!(hit.strain, -0.0065);
        assert_eq!(hit.after, Some(-0.004));
    }

    /// A point whose faces overlap carries no physical G: a large G_I there does not trigger
    /// growth; the open point does, later.
    #[test]
    fn overlapped_points_do_not_trigger_growth() {
        let c = MixedMode::PowerLaw {
            g_ic: 100.0,
            g_iic: 100.0,
            g_iiic: 100.0,
            alpha: 1.0,
            beta: 1.0,
        };
        let overlapped = FrontRelease {
            opening: -1e-6,
            ..point(500.0, 0.0, 0.0)
        };
        let levels = vec![
            (-0.001, vec![overlapped, point(50.0, 0.0, 0.0)]),
            (-0.002, vec![overlapped, point(200.0, 0.0, 0.0)]),
        ];
        let hit = critical_strain(&c, &levels).unwrap().unwrap();
        assert_eq!(hit.point, 1);
        // √index 0.707 → 1.414: crossing 1 at ε = −0.001 − 0.001·(1 − 0.707)/(1.414 − 0.707).
        let (r0, r1) = (0.5_f64.sqrt(), 2.0_f64.sqrt());
        assert_relative_eq!(
            hit.strain,
            -0.001 - 0.001 * (1.0 - r0) / (r1 - r0),
            epsilon = 1e-15
        );
    }
}
