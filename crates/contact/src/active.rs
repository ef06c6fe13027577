//! The active-set update of the thesis's contact loop (§2.7, Fig. 2.7.2) as a pure function:
//! gaps and contact forces of the last solution in, the change of the set out.
//!
//! An inactive pair whose gap is below −tol_g (overlap) is added; an active pair whose contact
//! force is below −tol_f (tensile: the faces pull on each other) is released. The driver passes
//! the recovered forces f̂ = T f (`recover`), whose sign is that of the pressure on linear and
//! quadratic faces alike, and the gaps in the same basis, g̃ = T⁻ᵀ g, so that f̂·g̃ = f·g: the
//! test is the one complementarity f̂ ≥ 0, g̃ ≥ 0, f̂·g̃ = 0 (docs/THEORY.md, "One basis for
//! closing and release"), which a closed pair meets by its tie g̃_i = 0 and an open pair by
//! f̂_i = 0. An added pair is
//! inactive and a released one active, so no pair is both. The thesis alternates the two checks
//! (overlap first, then tension, each after a solution); here both are read from the same
//! solution, which needs no more passes when the set is right and fewer when it is not.

/// How far past zero a gap or a force may be before the set changes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tolerances {
    /// Overlap allowed before a pair is added (m, ≥ 0).
    pub gap: f64,
    /// Tension allowed before a pair is released (N, ≥ 0).
    pub force: f64,
}

/// A change of the active set: pair indices, ascending.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Change {
    /// Pairs that close (overlap beyond the gap tolerance).
    pub added: Vec<usize>,
    /// Pairs that open (tensile beyond the force tolerance).
    pub released: Vec<usize>,
}

impl Change {
    /// Whether the set stays as it is.
    pub fn is_empty(&self) -> bool {
        self.added.is_empty() && self.released.is_empty()
    }

    /// Applies the change to `active` (one flag per pair).
    pub fn apply(&self, active: &mut [bool]) {
        for &i in &self.added {
            active[i] = true;
        }
        for &i in &self.released {
            active[i] = false;
        }
    }
}

/// The change of the active set `active` given the gaps (m, g = n·(x_up − x_low)) and contact
/// forces (N, compressive positive; zero at inactive pairs) of a solution with that set:
/// added = {i inactive: g_i < −tol_g}, released = {i active: p_i < −tol_f}. Pairs are read
/// index by index, each on its own data (the result does not depend on their order); `gaps`,
/// `forces` and `active` have one entry per pair (extra entries are ignored). A NaN neither
/// adds nor releases.
pub fn update(gaps: &[f64], forces: &[f64], active: &[bool], tol: Tolerances) -> Change {
    let mut change = Change::default();
    for (i, ((&g, &p), &on)) in gaps.iter().zip(forces).zip(active).enumerate() {
        if !on && g < -tol.gap {
            change.added.push(i);
        } else if on && p < -tol.force {
            change.released.push(i);
        }
    }
    change
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    const TOL: Tolerances = Tolerances {
        gap: 1e-9,
        force: 1e-6,
    };

    /// A state of `n` pairs: gap, force and whether active, each from a range that straddles
    /// the tolerances.
    fn state() -> impl Strategy<Value = Vec<(f64, f64, bool)>> {
        prop::collection::vec((-1e-8..1e-8f64, -1e-5..1e-5f64, any::<bool>()), 0..40)
    }

    fn split(s: &[(f64, f64, bool)]) -> (Vec<f64>, Vec<f64>, Vec<bool>) {
        (
            s.iter().map(|x| x.0).collect(),
            s.iter().map(|x| x.1).collect(),
            s.iter().map(|x| x.2).collect(),
        )
    }

    proptest! {
        /// No pair is both added and released; added pairs were inactive and overlap, released
        /// ones were active and tensile.
        #[test]
        fn no_pair_is_added_and_released(s in state()) {
            let (g, p, a) = split(&s);
            let c = update(&g, &p, &a, TOL);
            prop_assert!(c.added.iter().all(|i| !c.released.contains(i)));
            prop_assert!(c.added.iter().all(|&i| !a[i] && g[i] < -TOL.gap));
            prop_assert!(c.released.iter().all(|&i| a[i] && p[i] < -TOL.force));
        }

        /// A set that satisfies the conditions (inactive pairs open within the tolerance,
        /// active pairs compressive within it) is a fixed point: the change is empty and
        /// applying it changes nothing.
        #[test]
        fn a_stable_set_is_a_fixed_point(s in state()) {
            let (mut g, mut p, a) = split(&s);
            for i in 0..a.len() {
                if a[i] {
                    p[i] = p[i].max(-TOL.force);
                } else {
                    g[i] = g[i].max(-TOL.gap);
                }
            }
            let c = update(&g, &p, &a, TOL);
            prop_assert!(c.is_empty());
            let mut b = a.clone();
            c.apply(&mut b);
            prop_assert_eq!(b, a);
        }

        /// Reordering the pairs reorders the change: the same pairs are added and released.
        #[test]
        fn the_change_does_not_depend_on_the_order(s in state(), seed in any::<u64>()) {
            let n = s.len();
            // A permutation from the seed (sort by a hash of the index).
            let mut order: Vec<usize> = (0..n).collect();
            order.sort_by_key(|&i| (i as u64 ^ seed).wrapping_mul(0x9E37_79B9_7F4A_7C15));
            let shuffled: Vec<_> = order.iter().map(|&i| s[i]).collect();
            let (g, p, a) = split(&s);
            let (gs, ps, as_) = split(&shuffled);
            let c = update(&g, &p, &a, TOL);
            let cs = update(&gs, &ps, &as_, TOL);
            let back = |v: &[usize]| {
                let mut w: Vec<usize> = v.iter().map(|&j| order[j]).collect();
                w.sort_unstable();
                w
            };
            prop_assert_eq!(back(&cs.added), c.added);
            prop_assert_eq!(back(&cs.released), c.released);
        }
    }

    proptest! {
        /// Larger tolerances change a subset of what smaller ones change: a pair added with
        /// tolerances (a, b) is added with any (a′ ≤ a, b′ ≤ b), and so is a released one.
        #[test]
        fn larger_tolerances_change_less(s in state(), k in 1.0..10.0f64) {
            let (g, p, a) = split(&s);
            let wide = Tolerances { gap: k * TOL.gap, force: k * TOL.force };
            let (c, w) = (update(&g, &p, &a, TOL), update(&g, &p, &a, wide));
            prop_assert!(w.added.iter().all(|i| c.added.contains(i)));
            prop_assert!(w.released.iter().all(|i| c.released.contains(i)));
        }

        /// One complementarity: a state with f̂ ≥ 0, g̃ ≥ 0 and f̂_i g̃_i = 0 at every pair, the
        /// set being the pairs with g̃_i = 0 and f̂_i > 0 (a closed pair at zero force may be
        /// either), is a fixed point whatever the sizes of f̂ and g̃.
        #[test]
        fn a_complementary_state_is_a_fixed_point(
            s in prop::collection::vec((0.0..1e3f64, any::<bool>()), 0..40)
        ) {
            let g: Vec<f64> = s.iter().map(|&(x, c)| if c { 0.0 } else { x * 1e-6 }).collect();
            let p: Vec<f64> = s.iter().map(|&(x, c)| if c { x } else { 0.0 }).collect();
            let a: Vec<bool> = s.iter().map(|&(_, c)| c).collect();
            prop_assert!(update(&g, &p, &a, TOL).is_empty());
            let exact = Tolerances { gap: 0.0, force: 0.0 };
            prop_assert!(update(&g, &p, &a, exact).is_empty());
        }
    }

    /// Concrete: an open inactive pair stays, an overlapping one is added, a compressive active
    /// pair stays, a tensile one is released, values within the tolerances change nothing.
    #[test]
    fn overlap_adds_and_tension_releases() {
        let g = [1e-3, -1e-3, 0.0, 0.0, -0.5e-9, 0.0];
        let p = [0.0, 0.0, 5.0, -5.0, 0.0, -0.5e-6];
        let a = [false, false, true, true, false, true];
        let c = update(&g, &p, &a, TOL);
        assert_eq!(c.added, [1]);
        assert_eq!(c.released, [3]);
    }
}
