//! Which candidate pairs the contact system's pattern couples ([`Reserve`]): all of them once,
//! or a reserve grown around the closed pairs as the set spreads. A reserved pair couples the
//! two crack faces in the pattern whether it is closed or not, so the fewer reserved, the less
//! fill; a pair closing outside the reserve costs a new pattern and a new symbolic analysis.

use super::{Contact, Mode, Reserve};
use crate::tie::candidate_tie;
use crate::{ContactError, Pair};
use nonlin3d_assembly::{SystemBuilder, Tie};
use nonlin3d_newton::StructuralProblem;

impl Contact {
    /// Reserves the couplings of the pairs in the reserve ([`Reserve`]: every candidate pair,
    /// or none yet) in the system to be built: both whole nodes of each pair and, for a
    /// mid-edge pair, of the pairs at its edge's ends. The reserve grows with the one problem
    /// the sets are installed in: a problem built from this contact before it grew lacks what
    /// it grew by (installing such a set there fails with `AssemblyError::Unreserved`).
    pub fn reserve(&self, builder: SystemBuilder) -> SystemBuilder {
        builder.reserve_ties(&self.candidate_ties(&self.reserved))
    }

    /// Whether each pair's couplings are reserved in the pattern.
    pub fn reserved(&self) -> &[bool] {
        &self.reserved
    }

    /// The candidate ties of the flagged pairs ([`candidate_tie`]).
    fn candidate_ties(&self, which: &[bool]) -> Vec<Tie> {
        let pairs = self.faces.pairs();
        (0..pairs.len())
            .filter(|&i| which[i])
            .map(|i| {
                let ends: Vec<Pair> = self.faces.ends(i).iter().map(|&c| pairs[c]).collect();
                candidate_tie(pairs[i], &ends)
            })
            .collect()
    }

    /// Grows the reserve ([`Reserve::Grow`]) when `active` closes a pair outside it, at the
    /// state `u`: the pairs within `rings` of a closed pair and those whose gap g is at most
    /// `gap_share` × max(largest gap, 0) are reserved too, and the problem's pattern is built
    /// again ([`System::reserve_ties`](nonlin3d_assembly::System::reserve_ties)). Nothing
    /// happens when every closed pair is reserved, or in [`Mode::External`].
    pub(super) fn grow_reserve(
        &mut self,
        problem: &mut StructuralProblem,
        u: &[f64],
        active: &[bool],
    ) -> Result<(), ContactError> {
        let Reserve::Grow { rings, gap_share } = self.settings.reserve else {
            return Ok(());
        };
        let outside = active.iter().zip(&self.reserved).any(|(&a, &r)| a && !r);
        if !outside || self.settings.mode == Mode::External {
            return Ok(());
        }
        let mut wanted = self.faces.within(active, rings);
        if gap_share > 0.0 {
            let gaps = self.faces.gaps(u, &self.faces.normals(u)?);
            let near = gap_share * gaps.iter().fold(0.0f64, |m, &g| m.max(g));
            for (w, &g) in wanted.iter_mut().zip(&gaps) {
                *w |= g <= near;
            }
        }
        let new: Vec<bool> = wanted
            .iter()
            .zip(&self.reserved)
            .map(|(&w, &r)| w && !r)
            .collect();
        problem
            .system_mut()
            .reserve_ties(&self.candidate_ties(&new))?;
        for (r, n) in self.reserved.iter_mut().zip(new) {
            *r |= n;
        }
        Ok(())
    }
}
