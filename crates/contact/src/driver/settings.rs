//! How the contact loop holds pairs and when it stops (`driver`).

use nonlin3d_assembly::TieGroup;
use nonlin3d_newton::{NewtonSettings, Stepping};

/// How an active pair is held.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Mode {
    /// Two-body contact: the pair is tied, n·(u_up − u_low) = −g₀; the contact force acts on
    /// both faces (Fig. 2.7.1b).
    #[default]
    TwoBody,
    /// The thesis's approximation (Fig. 2.7.1c): the upper node's w is prescribed to the lower
    /// node's current height (re-taken at each pass); the force that holds it is external, the
    /// base does not react it.
    External,
}

/// Which candidate pairs the contact system's pattern holds: the couplings each pair's tie
/// needs (its upper and lower nodes, and for a mid-edge pair those of its edge's end pairs,
/// [`candidate_tie`](crate::candidate_tie)). A pair reserved couples the two crack faces in
/// the pattern whether it is closed or not, so every reserved pair costs fill; a closed pair
/// outside the reserve cannot be held without a new pattern. In [`Mode::External`] a closed
/// pair is a prescribed height, which needs no coupling: nothing is reserved there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Reserve {
    /// Every candidate pair, once, when the system is built: any set fits and no set ever
    /// costs a new pattern or symbolic analysis. Thesis model 6 (334 pairs): 6.42 GFLOP a
    /// factorisation against 4.26 without the crack faces coupled.
    All,
    /// None when the system is built; when a set is installed with a closed pair outside the
    /// reserve, every pair within `rings` rings of lower-face neighbours of a closed pair
    /// ([`CrackFaces::within`](crate::CrackFaces::within)) and every pair whose gap is at most
    /// `gap_share` of the largest gap at that state (where the faces are near each other, the
    /// set spreads as the load grows) are reserved too, and the pattern is built again
    /// ([`System::reserve_ties`](nonlin3d_assembly::System::reserve_ties); the solver analyses
    /// it anew at its next factorisation). The reserve only grows.
    Grow {
        /// Rings of neighbours reserved around the closed pairs.
        rings: usize,
        /// Open pairs with a gap of at most this share of the largest gap are reserved too
        /// (0: none; at a state with no open gap, every pair touching or overlapping).
        gap_share: f64,
    },
}

impl Reserve {
    /// The default: grown, two rings, pairs within a tenth of the largest gap. On thesis model
    /// 6 the contact system's pattern then grows once (the set's first install) and costs
    /// 4.94 GFLOP a factorisation against 6.42 with every pair (docs/PERFORMANCE.md, "The
    /// contact reserve grows").
    pub const DEFAULT: Reserve = Reserve::Grow {
        rings: 2,
        gap_share: 0.1,
    };
}

/// Settings of the contact loop.
#[derive(Debug, Clone, PartialEq)]
pub struct ContactSettings {
    /// Overlap allowed before a pair closes (m). Default 1e-9 m: far above the round-off of
    /// coordinates of centimetre models (1e-18 m), far below the overlaps that matter.
    pub gap_tolerance: f64,
    /// Tension allowed before a pair opens (N); the Newton tolerance of the state
    /// (relative tolerance × force scale, the accuracy of a reaction) when larger. Default 0.
    pub force_tolerance: f64,
    /// Most passes (re-solves) at one level. Default 50.
    pub max_passes: usize,
    /// Most inexact updates at one level (a primal–dual active-set, or semismooth Newton,
    /// step): the re-solve of a pass stops after one Newton iteration and the set is read
    /// again from that iterate, while it keeps changing; only the set that stops changing is
    /// converged, and the loop still ends only on a converged state whose set does not change
    /// (cycles are judged on converged states). After this many, the passes converge each
    /// re-solve (the exact loop of Fig. 2.7.2). 0 = the exact loop only. Default 10.
    pub inexact_passes: usize,
    /// Two-body or the thesis's external force.
    pub mode: Mode,
    /// The tie group of the contact ties. Default `TieGroup(0xC0)`.
    pub group: TieGroup,
    /// Largest load-factor step over which the set may stay unchecked (λ = 1: the largest
    /// level): a longer level is solved as sub-levels of equal steps ≤ this, the loop at each
    /// ([`Contact::sublevels`](crate::Contact::sublevels)). Default 0.25. What it guards since
    /// closing and release are decided in one basis (the set itself no longer depends on the
    /// path: on the 30 mm circle at 4 slices one level to ε = −0.005 with no sub-level closes
    /// the same 12 pairs as steps of 0.001 and 0.0005): the nonlinear problem's other
    /// equilibria. On the 30 mm circle at 5 901 DOF (e = 0.1 mm), ε = −0.004 in one level, the
    /// passes started from the state without contact (overlapping by 0.029 mm) land on another
    /// equilibrium, centre deflection 0.726 mm against the path's 0.674 mm, without
    /// sub-levels; with them on the path's.
    pub max_step: f64,
    /// Which candidate pairs the pattern holds. Default [`Reserve::DEFAULT`].
    pub reserve: Reserve,
}

impl ContactSettings {
    /// How many sub-levels the loop makes of the level `from` → `to`: the fewest equal steps
    /// of at most [`max_step`](Self::max_step) in load factor (at least one).
    pub fn sublevels(&self, from: f64, to: f64) -> usize {
        let steps = ((to - from).abs() / self.max_step * (1.0 - 1e-12)).ceil();
        if steps.is_finite() && steps >= 1.0 {
            steps as usize
        } else {
            1
        }
    }

    /// The end of sub-level `j` (1-based) of `count` over `from` → `to`: `to` itself for the
    /// last, so that the level ends exactly where asked.
    pub fn sublevel_end(from: f64, to: f64, j: usize, count: usize) -> f64 {
        if j >= count {
            to
        } else {
            from + (to - from) * j as f64 / count as f64
        }
    }
}

/// How the loop follows a level: Newton's settings, the path's stepping and the perturbation
/// load offered to its first unstable sub-level ((DOF, force) pairs, N; empty for none; thesis
/// §3.2). Shared by [`Contact::solve_level`](crate::Contact::solve_level) and
/// [`Contact::continue_level`](crate::Contact::continue_level).
#[derive(Debug, Clone, Copy)]
pub struct LevelSettings<'a> {
    /// Newton's settings of every solve.
    pub newton: &'a NewtonSettings,
    /// The path's increments.
    pub stepping: &'a Stepping,
    /// The perturbation offered until a sub-level applies it.
    pub perturbation: &'a [(usize, f64)],
}

impl Default for ContactSettings {
    fn default() -> Self {
        Self {
            gap_tolerance: 1e-9,
            force_tolerance: 0.0,
            max_passes: 50,
            inexact_passes: 10,
            mode: Mode::TwoBody,
            group: TieGroup(0xC0),
            max_step: 0.25,
            reserve: Reserve::DEFAULT,
        }
    }
}
