//! A warning for levels whose crack faces pass through each other (thesis §2.7): without
//! contact there, G at those points is not physical, and the sublaminate may have buckled into
//! the base, which makes G at the open points beside them wrong too (a 30 × 60 mm ellipse with
//! `crack_faces = "off"` gave G_T = 10 963 J/m² at an open point between overlapped ones, where
//! contact gives 104 J/m²).

use super::{Faces, LevelResult};

/// One warning per level with overlapped front points: how many, where (S range, mm), the
/// largest G_T among them and their neighbours, and what to do.
pub(crate) fn overlap_warnings(levels: &[LevelResult], what: &str) -> Vec<String> {
    let mut out = Vec::new();
    for l in levels {
        let overlapped: Vec<usize> = (0..l.front.len())
            .filter(|&k| l.front[k].faces == Faces::Overlapped)
            .collect();
        let (Some(&first), Some(&last)) = (overlapped.first(), overlapped.last()) else {
            continue;
        };
        // The overlapped points and the points beside them.
        let near = (first.saturating_sub(1)..=(last + 1).min(l.front.len() - 1))
            .map(|k| l.front[k].g_t)
            .fold(f64::NEG_INFINITY, f64::max);
        out.push(format!(
            "level at {what} {}: the crack faces pass through each other at {} of {} front \
             points (S = {:.2} to {:.2} mm; largest G_T there and beside them {:.4e} J/m²): G \
             there is not physical without crack-face contact, and a sublaminate that buckled \
             into the base makes G beside them wrong too — model contact with [contact] \
             crack_faces = \"auto\"",
            l.value,
            overlapped.len(),
            l.front.len(),
            l.front[first].s_mm,
            l.front[last].s_mm,
            near
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use nonlin3d_vcct::FrontRelease;

    fn point(s_mm: f64, g_t: f64, opening: f64) -> FrontRelease {
        FrontRelease {
            node: 0,
            s: s_mm * 1e-3,
            theta_deg: 0.0,
            x: 0.0,
            y: 0.0,
            delta_a: 1e-3,
            area: 1e-6,
            g_i: g_t,
            g_ii: 0.0,
            g_iii: 0.0,
            g_t,
            opening,
        }
    }

    #[test]
    fn overlapped_points_are_warned_with_their_neighbours_largest_g() {
        let open = [point(0.0, 100.0, 1e-4), point(5.0, 90.0, 1e-4)];
        let mixed = [
            point(0.0, 100.0, 1e-4),
            point(5.0, 200.0, -1e-5),
            point(10.0, 10_963.0, 1e-4),
            point(15.0, 800.0, -1e-5),
            point(20.0, 50.0, 1e-4),
        ];
        let levels = [
            LevelResult::new(-0.001, 0.1, 0.1, &[], &open, vec![]),
            LevelResult::new(-0.004, 1.0, 1.0, &[], &mixed, vec![]),
        ];
        let w = overlap_warnings(&levels, "strain");
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(w[0].starts_with("level at strain -0.004:"), "{}", w[0]);
        assert!(
            w[0].contains("at 2 of 5 front points (S = 5.00 to 15.00 mm"),
            "{}",
            w[0]
        );
        assert!(w[0].contains("1.0963e4 J/m²"), "{}", w[0]);
        assert!(w[0].contains("crack_faces = \"auto\""), "{}", w[0]);
    }
}
