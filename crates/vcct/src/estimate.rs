//! The discretisation error of G along the front, from the same level solved on a companion
//! mesh (issue 25; the measured reliability is in docs/ACCURACY.md §3).
//!
//! With G(M) the release rates on the run's mesh M and G(M/2) on the companion (the mesh
//! crate's `coarsened()`: in-plane counts halved; the through-thickness mesh at the front kept
//! where M resolves the mode split, coarsened with the rest where it does not), the estimate
//! at each front point of M, per mode k, is
//!
//! δG_k(S) = a · max( |G_k(M; S) − G_k(M/2; S)|, c·|G_T(M; S*) − G_T(M/2; S*)| ),
//!
//! with S* the point of M where G_T is largest among the points whose faces are open (an
//! overlapped point's G is not physical). The first term is Richardson's estimate with a
//! fixed order: the error of M is (G(M) − G(M/2))/(2^p − 1), a = 1/(2^p − 1). The order is
//! not read from the point: a third, cheaper mesh M/4 (2 slices) is far from asymptotic, and
//! the orders observed on M/4, M/2, M bracketed 79–85 of 86 points measured with the same
//! worst ratio (22.9), against 86 of 86 with the fixed factors. The factor is set instead
//! by what the companion coarsens ([`Rule`], measured in docs/ACCURACY.md §3): where it keeps the
//! mode split and halves the in-plane counts only, a = 0.5 (p = 1.58; the converged families'
//! orders are 0.9 … 2.9 by point and mode); where it halves everything, the split of one
//! sublaminate layer converges at p ≈ 0.9 (edge delamination, G_II at S = 0: the difference 24.1
//! J/m² against a true error 25.9), a = 1.2 (p = 0.87); where the mesh has a front band and six or
//! more slices and the companion keeps the rings outside the band (the default mesh), a = 0.4
//! and c = 1 (docs/ACCURACY.md §3b). The second term is a floor relative to the
//! largest error along the front: where G is small, the difference of two meshes can cross zero by
//! accident, and an error there matters against G_T max, not
//! against the local G.
//!
//! Where the companion has a coarser companion of its own (M/4, the nested iteration's) and
//! the rule was measured with it ([`Rule::coarser`]), the estimate is at least
//! b·|G_k(M/2) − G_k(M/4)| ([`coarser`]): just past buckling the error of the default mesh is
//! its buckling strain's, which its companion shares but M/4 (its rings halved) does not
//! (docs/ACCURACY.md §3d).
//!
//! The two fronts have different points; they are matched by their position along the front
//! (S over the front's length, 0 … 1): the run's G is interpolated linearly to the companion's
//! points, where the difference is taken, and the differences are interpolated back to the
//! run's points (the run's front is the finer: interpolating it costs less accuracy than
//! interpolating the companion's).

use crate::VcctError;
use nonlin3d_mesh::CompanionKind;

/// The estimate's factors: δG_k = `scale`·max(|ΔG_k|, `floor`·|ΔG_T(S*)|), and where the
/// companion has a coarser companion of its own at least `coarser`·|G_k(M/2) − G_k(M/4)|
/// (module docs, [`coarser`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rule {
    /// a = 1/(2^p − 1): Richardson's factor for the companion's assumed order p.
    pub scale: f64,
    /// c: the error at any point is at least c times the difference of G_T at its peak.
    pub floor: f64,
    /// b: the factor of the two companions' difference, where there is a coarser companion;
    /// `None`: that term is not used (not measured for this kind of companion).
    pub coarser: Option<f64>,
}

impl Rule {
    /// A companion that keeps the run's mode split (its sublaminate layers, front element and
    /// base layers at the front) and halves the in-plane counts: a = 0.5 (p = 1.58), c = 0.2.
    /// Measured (docs/ACCURACY.md §3) on 28 points of the split-resolving meshes (circle
    /// 8, 7, 7, 2, 3, e = 0.2 and band meshes I, Q, R; edge 8, 7, 7, 2, 3): a ≥ 0.45 brackets
    /// every point (0.4 misses mesh I's G_II at S = 0: 2.4 against 2.7 J/m²); at a = 0.5
    /// the estimate is 1.55× the true error at the median, 4.1× at worst (Q, G_I at S = 0),
    /// where the plain difference (a = 1) was 3.1× and 8.2×.
    pub const SPLIT_KEPT: Self = Self {
        scale: 0.5,
        floor: 0.2,
        coarser: None,
    };

    /// A companion that halves every count (one sublaminate layer, through-width strips):
    /// a = 1.2 (p = 0.87), c = 0.2. The tightest point measured needs a ≥ 1.08 (edge, default
    /// mesh, G_II at S = 0: difference 24.1 J/m², true error 25.9), and c ≥ 0.16 at a = 1.2
    /// (edge, e = 0.4 mm, G_I at S = 0: true error 4.1 against a difference of G_T at the
    /// peak of 21.5); a = 1.2 keeps a margin of 11 % on the first.
    pub const ALL_HALVED: Self = Self {
        scale: 1.2,
        floor: 0.2,
        coarser: None,
    };

    /// A companion of a mesh with a front band that keeps the split and the rings outside the
    /// band, and halves the slices, the band's rings and the base layers
    /// ([`CompanionKind::FarFieldKept`]): a = 0.4 (p = 1.81), c = 1 — every point's error is
    /// taken at least as large as the change of G_T at its peak. Measured (docs/ACCURACY.md
    /// §3b) on the default mesh against the converged families of the circle, the b/a = 2
    /// ellipse and the edge delamination at ε = −0.003, −0.004, −0.005: 77 of 78 points
    /// bracketed (the miss: the ellipse's G_I at S = 0 at −0.005, 6.14 against 6.19 J/m², a
    /// reference uncertain by 3.7), 2.95× too pessimistic at worst, 1.8× at the median. Near
    /// buckling (ε = −0.002 on the circle, G_T max 11.8 J/m²) it under-estimates G at S = 0
    /// up to 2.9× (±0.18 against 0.53 J/m²): the error there is the buckling strain's, which
    /// a companion with the same far field shares. With c = 0.2 the ellipse's G_I at S = 0 is
    /// missed at every level (its difference crosses zero); a = 0.35 misses a second point,
    /// 0.45 is above 3× at −0.003. With the band's rings curved (§3c): 78 of 78 bracketed,
    /// 2.92× at worst; near buckling the same four points missed, by up to 3.1× (±0.14
    /// against 0.43 J/m²) without the coarser companion's term; b = 0.27 (p ≈ 1.3 in
    /// b = 1/(2^p·(2^p − 1))) brackets all 114 points at ε = −0.002 … −0.005 (the smallest
    /// ratio 1.12, at −0.002; 0.25 leaves 1.04, 0.22 misses one), at most 2.92× too pessimistic
    /// from −0.003 on and 3.55× at −0.002 (the edge's G_T at S = 0, 1.13 against 0.23 J/m²):
    /// docs/ACCURACY.md §3d.
    pub const FAR_FIELD_KEPT: Self = Self {
        scale: 0.4,
        floor: 1.0,
        coarser: Some(0.27),
    };

    /// The rule for a companion of this kind.
    pub fn for_companion(kind: CompanionKind) -> Self {
        match kind {
            CompanionKind::FarFieldKept => Self::FAR_FIELD_KEPT,
            CompanionKind::SplitKept => Self::SPLIT_KEPT,
            CompanionKind::AllHalved => Self::ALL_HALVED,
        }
    }
}

/// G per mode at one front point, J/m² (or their errors).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Modes {
    /// G_I.
    pub g_i: f64,
    /// G_II.
    pub g_ii: f64,
    /// G_III.
    pub g_iii: f64,
    /// G_T.
    pub g_t: f64,
}

impl Modes {
    /// The four values in order I, II, III, T.
    fn array(self) -> [f64; 4] {
        [self.g_i, self.g_ii, self.g_iii, self.g_t]
    }

    /// From the four values in order I, II, III, T.
    fn from_array(v: [f64; 4]) -> Self {
        Self {
            g_i: v[0],
            g_ii: v[1],
            g_iii: v[2],
            g_t: v[3],
        }
    }

    /// The largest of the four (an error's worst mode).
    pub fn max(self) -> f64 {
        self.array().into_iter().fold(0.0, f64::max)
    }

    /// Mode by mode the larger of the two (two estimates of one error).
    pub fn larger(self, other: Self) -> Self {
        let (a, b) = (self.array(), other.array());
        Self::from_array(std::array::from_fn(|m| a[m].max(b[m])))
    }
}

/// G along one front: each point's position along the front (S over the front's length,
/// increasing from 0 to 1) and G there.
#[derive(Debug, Clone, Copy)]
pub struct FrontG<'a> {
    /// Positions, increasing.
    pub at: &'a [f64],
    /// G at each position.
    pub g: &'a [Modes],
    /// Whether each point's faces are open (its G physical); `None`: all are. The floor's
    /// G_T max is taken over the open points (over all when none is open).
    pub open: Option<&'a [bool]>,
}

impl FrontG<'_> {
    /// Checks lengths and order, naming `which` front.
    fn check(&self, which: &str) -> Result<(), VcctError> {
        let bad = |reason: String| {
            Err(VcctError::Estimate {
                reason: format!("the {which} front: {reason}"),
            })
        };
        if self.at.len() != self.g.len() || self.at.is_empty() {
            return bad(format!(
                "{} positions for {} G values (need as many, at least one)",
                self.at.len(),
                self.g.len()
            ));
        }
        if let Some(open) = self.open
            && open.len() != self.at.len()
        {
            return bad(format!(
                "{} open/overlapped flags for {} points",
                open.len(),
                self.at.len()
            ));
        }
        if let Some(k) = self.at.windows(2).position(|w| w[1] < w[0]) {
            return bad(format!(
                "positions must increase along the front; point {} is at {} after {}",
                k + 1,
                self.at[k + 1],
                self.at[k]
            ));
        }
        let values = self.g.iter().flat_map(|g| g.array());
        if self
            .at
            .iter()
            .copied()
            .chain(values)
            .any(|v| !v.is_finite())
        {
            return bad("a position or G is not finite".into());
        }
        Ok(())
    }

    /// G linearly interpolated at position `s` (held constant beyond the ends).
    pub fn at_position(&self, s: f64) -> Modes {
        let n = self.at.len();
        let k = self.at.partition_point(|&a| a <= s);
        if k == 0 {
            return self.g[0];
        }
        if k == n {
            return self.g[n - 1];
        }
        let (a0, a1) = (self.at[k - 1], self.at[k]);
        let w = if a1 > a0 { (s - a0) / (a1 - a0) } else { 0.0 };
        let (g0, g1) = (self.g[k - 1].array(), self.g[k].array());
        Modes::from_array(std::array::from_fn(|m| g0[m] + w * (g1[m] - g0[m])))
    }
}

/// The error estimate at each point of `run` (the run's mesh M) from `companion` (the same
/// level on M/2): δG_k = a·max(|G_k(M) − G_k(M/2)|, c·|ΔG_T at the G_T max of M over its
/// open points|) with a, c the `rule`'s, the differences taken at the companion's points and
/// interpolated back (module docs).
pub fn companion(
    run: FrontG<'_>,
    companion: FrontG<'_>,
    rule: Rule,
) -> Result<Vec<Modes>, VcctError> {
    run.check("run's")?;
    companion.check("companion's")?;
    let Rule { scale, floor, .. } = rule;
    if !(floor.is_finite() && floor >= 0.0 && scale.is_finite() && scale > 0.0) {
        return Err(VcctError::Estimate {
            reason: format!(
                "the factors must be finite, the scale {scale} > 0 and the floor {floor} ≥ 0"
            ),
        });
    }
    // |G(M) − G(M/2)| at the companion's points.
    let diffs = differences(&run, &companion);
    let diff = FrontG {
        at: companion.at,
        g: &diffs,
        open: None,
    };
    let is_open = |k: usize| run.open.is_none_or(|o| o[k]);
    let any_open = (0..run.at.len()).any(is_open);
    let peak = (0..run.at.len())
        .filter(|&k| !any_open || is_open(k))
        .max_by(|&a, &b| run.g[a].g_t.total_cmp(&run.g[b].g_t))
        .map_or(0.0, |k| diff.at_position(run.at[k]).g_t);
    Ok(run
        .at
        .iter()
        .map(|&s| {
            let d = diff.at_position(s).array();
            Modes::from_array(d.map(|v| scale * v.max(floor * peak)))
        })
        .collect())
}

/// The second term of the estimate where the companion has a coarser companion of its own
/// (the nested iteration's, src/analysis_seed.rs): at each of the run's positions `run_at`,
/// δG_k = b·|G_k(M/2) − G_k(M/4)|, the companion's G interpolated to the coarser one's points,
/// the differences interpolated back (as in [`companion`]). Just past buckling the run's
/// error is its buckling strain's, which a companion that keeps the rings outside the front
/// band shares (docs/ACCURACY.md §3b) but one that halves them does not: the difference of the
/// two companions sees it where the first term cannot. b = 1/(2^p·(2^p − 1)) for an order p
/// (the run's error from that of its companion's companion); [`Rule::coarser`] gives it.
pub fn coarser(
    run_at: &[f64],
    companion: FrontG<'_>,
    coarser: FrontG<'_>,
    scale: f64,
) -> Result<Vec<Modes>, VcctError> {
    companion.check("companion's")?;
    coarser.check("coarser companion's")?;
    if !(scale.is_finite() && scale > 0.0) {
        return Err(VcctError::Estimate {
            reason: format!("the coarser companion's factor must be finite and > 0: {scale}"),
        });
    }
    let diffs = differences(&companion, &coarser);
    let diff = FrontG {
        at: coarser.at,
        g: &diffs,
        open: None,
    };
    Ok(run_at
        .iter()
        .map(|&s| Modes::from_array(diff.at_position(s).array().map(|v| scale * v)))
        .collect())
}

/// |G(fine) − G(coarse)| per mode at the coarse front's points, the fine front's G
/// interpolated there (module docs: the finer front is the one interpolated).
fn differences(fine: &FrontG<'_>, coarse: &FrontG<'_>) -> Vec<Modes> {
    coarse
        .at
        .iter()
        .zip(coarse.g)
        .map(|(&s, gc)| {
            let (f, c) = (fine.at_position(s).array(), gc.array());
            Modes::from_array(std::array::from_fn(|m| (f[m] - c[m]).abs()))
        })
        .collect()
}

#[cfg(test)]
mod tests;
