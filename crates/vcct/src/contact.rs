//! Release rates that respect crack-face contact (thesis §5.4): where the faces one element
//! behind a front point are held together, mode I is zero.
//!
//! With contact the faces behind a closed point do not open, so the opening that mode I pairs
//! with the transmitted force is zero: G_I = 0 and G_T = G_II + G_III. The shear modes keep
//! their products −½ F′·Δu′: the forces F′ come from a solution with the contact constraints
//! (the contact forces are in the equilibrium the cells above satisfy), so they are the
//! contact-consistent ones. The thesis's external-force approximation left G_I "negligibly
//! small" but not zero there (§5.4); exact ties give zero up to round-off, and zero is written.

use crate::FrontRelease;
use nonlin3d_mesh::Front;

/// The state of the faces one element behind a front point.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FaceState {
    /// Apart (opening within the round-off allowance of [`FrontRelease::open`] or positive).
    Open,
    /// Held together by contact: G_I = 0.
    Closed,
    /// Overlapping, without contact holding them (an analysis without contact): G_I is not
    /// physical there.
    Overlap,
}

impl std::fmt::Display for FaceState {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Open => "open",
            Self::Closed => "closed",
            Self::Overlap => "overlap",
        })
    }
}

/// Applies contact to the release rates `rates` of `front` (from
/// [`release_rates`](crate::release_rates), one per corner point, in order): a point whose
/// pair behind it (a_upper, a_lower) is closed (`closed(upper, lower)`, the contact analysis's
/// active set) gets G_I = 0 and G_T = G_II + G_III. Returns the state of each point: closed,
/// else open or overlapping by its opening ([`FrontRelease::open`]). A rate whose node is not a
/// corner of `front` is left alone and reported by its opening.
pub fn respect_contact(
    rates: &mut [FrontRelease],
    front: &Front,
    closed: impl Fn(usize, usize) -> bool,
) -> Vec<FaceState> {
    rates
        .iter_mut()
        .map(|r| {
            let point = front.points.iter().find(|p| p.corner && p.c == r.node);
            if point.is_some_and(|p| closed(p.a_upper, p.a_lower)) {
                r.g_i = 0.0;
                r.g_t = r.g_ii + r.g_iii;
                FaceState::Closed
            } else if r.open() {
                FaceState::Open
            } else {
                FaceState::Overlap
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::release_rates;
    use nonlin3d_element::ElementKind;
    use nonlin3d_mesh::{EmbeddedParams, embedded_delamination_with_front};

    /// On a coarse Hex20 circle with a made-up state (the upper face pressed into the lower by
    /// w = −1 µm behind every point, forces of 1 N in every direction at the front): the points
    /// whose pair behind is closed lose mode I only (G_T = G_II + G_III, the shear modes as
    /// before), the others keep every mode and are reported as overlapping; without contact
    /// every point overlaps.
    #[test]
    fn a_closed_point_has_no_mode_i() {
        let p = EmbeddedParams {
            kind: ElementKind::Hex20,
            slices: 4,
            radial_inside: 2,
            radial_outside: 2,
            ..EmbeddedParams::thesis_reference()
        };
        let (mesh, front) = embedded_delamination_with_front(&p).unwrap();
        let n = 3 * mesh.nodes.len();
        let mut u = vec![0.0; n];
        let mut f = vec![0.0; n];
        for q in &front.points {
            u[3 * q.a_upper + 2] = -1e-6;
            u[3 * q.a_upper] = 2e-6;
            u[3 * q.a_upper + 1] = -3e-6;
            for k in 0..3 {
                f[3 * q.c + k] = 1.0;
            }
        }
        let plain = release_rates(&front, &mesh.nodes, &u, &f).unwrap();
        assert!(plain.iter().all(|r| r.g_i != 0.0 && r.g_ii != 0.0));
        let mut none = plain.clone();
        let states = respect_contact(&mut none, &front, |_, _| false);
        assert_eq!(none, plain);
        assert!(states.iter().all(|&s| s == FaceState::Overlap));
        // Close the pairs behind every other corner point.
        let corners: Vec<_> = front.points.iter().filter(|q| q.corner).collect();
        let shut: Vec<usize> = corners.iter().step_by(2).map(|q| q.a_upper).collect();
        let mut rates = plain.clone();
        let states = respect_contact(&mut rates, &front, |up, _| shut.contains(&up));
        for ((r, before), (q, s)) in rates.iter().zip(&plain).zip(corners.iter().zip(&states)) {
            assert_eq!((r.g_ii, r.g_iii), (before.g_ii, before.g_iii));
            if shut.contains(&q.a_upper) {
                assert_eq!(*s, FaceState::Closed);
                assert_eq!(r.g_i, 0.0);
                assert_eq!(r.g_t, r.g_ii + r.g_iii);
            } else {
                assert_eq!(*s, FaceState::Overlap);
                assert_eq!(r, before);
            }
        }
        assert!(states.contains(&FaceState::Closed) && states.contains(&FaceState::Overlap));
    }
}
