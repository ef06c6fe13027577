//! The Pareto front of (time, error) points: the cases no other case beats on both.

/// Whether each point is on the Pareto front of minimising both coordinates: no other point
/// has time ≤ and error ≤ with at least one strictly smaller. Points with a missing or
/// non-finite coordinate are never on it (and do not dominate). Equal points are all on it.
pub fn front(points: &[Option<(f64, f64)>]) -> Vec<bool> {
    let ok = |p: &Option<(f64, f64)>| p.filter(|(t, e)| t.is_finite() && e.is_finite());
    points
        .iter()
        .map(|p| {
            let Some((t, e)) = ok(p) else {
                return false;
            };
            !points
                .iter()
                .filter_map(ok)
                .any(|(t2, e2)| t2 <= t && e2 <= e && (t2 < t || e2 < e))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_front_of_a_hand_made_set() {
        // (time, error): A fast and rough, B dominated by C, C, D slow and exact, E dominated
        // by D, F equal to C, G missing, H with a NaN error.
        let pts = [
            Some((1.0, 0.30)),     // A: fastest
            Some((3.0, 0.20)),     // B: C is as fast and better
            Some((3.0, 0.10)),     // C
            Some((10.0, 0.01)),    // D: most accurate
            Some((12.0, 0.05)),    // E: D is faster and better
            Some((3.0, 0.10)),     // F: the same as C
            None,                  // G
            Some((0.5, f64::NAN)), // H
            Some((2.0, 0.30)),     // I: A is faster at the same error
        ];
        assert_eq!(
            front(&pts),
            [true, false, true, true, false, true, false, false, false]
        );
        assert!(front(&[]).is_empty());
    }
}
