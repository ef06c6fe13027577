//! Node positions along an axis: geometric grading (the refinement towards a delamination
//! front, thesis §3.1–3.2) and the doubled grid index of Hex20 mid-edge nodes.

use crate::MeshError;

/// Node positions 0 = x_0 < … < x_n = length with geometric element sizes whose first element
/// is `first` (the common ratio found by bisection). Used to continue a graded side of a
/// delamination front with an element of the same length on the other side: the single-solution
/// VCCT (thesis §2.8) pairs forces one element ahead with openings one element behind and
/// assumes the two are equally long. With one element, or `first` ≥ `length`, the elements are uniform.
pub fn graded_from_first(n: usize, length: f64, first: f64) -> Result<Vec<f64>, MeshError> {
    if !(first.is_finite() && first > 0.0) {
        return Err(MeshError::Parameter {
            name: "first element",
            reason: format!("{first} must be positive and finite"),
        });
    }
    if n <= 1 || first >= length {
        return graded_coordinates(n, length, 1.0);
    }
    // Σ_{k<n} first·q^k = length, increasing in q: bisect on log q.
    let total = |q: f64| (0..n).map(|k| first * q.powi(k as i32)).sum::<f64>();
    let (mut lo, mut hi) = (1e-6_f64, 1e6_f64);
    for _ in 0..200 {
        let mid = (lo * hi).sqrt();
        if total(mid) < length {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let q = (lo * hi).sqrt();
    graded_coordinates(n, length, q.powi(n as i32 - 1))
}

/// Node positions 0 = x_0 < … < x_n = length with geometric element sizes whose LAST element
/// is `last` (at most length/n, so the sizes never shrink away from the end): the mirror image
/// of [`graded_from_first`], for refining towards a front that lies at the end of the axis.
pub fn graded_to_last(n: usize, length: f64, last: f64) -> Result<Vec<f64>, MeshError> {
    let from_end = graded_from_first(n, length, last.min(length / n.max(1) as f64))?;
    let mut x: Vec<f64> = from_end.iter().rev().map(|d| length - d).collect();
    x[0] = 0.0;
    Ok(x)
}

/// Node positions 0 = x_0 < … < x_n = length with geometric element sizes, last/first = `ratio`.
pub fn graded_coordinates(n: usize, length: f64, ratio: f64) -> Result<Vec<f64>, MeshError> {
    if n == 0 {
        return Err(MeshError::Parameter {
            name: "counts",
            reason: "at least one element per axis".into(),
        });
    }
    if !(length.is_finite() && length > 0.0) {
        return Err(MeshError::Parameter {
            name: "size",
            reason: format!("{length} must be positive and finite"),
        });
    }
    if !(ratio.is_finite() && ratio > 0.0) {
        return Err(MeshError::Parameter {
            name: "grading",
            reason: format!("{ratio} must be positive and finite"),
        });
    }
    // Sizes h_k = h_0 q^k with q^(n−1) = ratio.
    let q = if n > 1 {
        ratio.powf(1.0 / (n - 1) as f64)
    } else {
        1.0
    };
    let sizes: Vec<f64> = (0..n).map(|k| q.powi(k as i32)).collect();
    let total: f64 = sizes.iter().sum();
    let mut x = Vec::with_capacity(n + 1);
    let mut acc = 0.0;
    x.push(0.0);
    for s in &sizes {
        acc += s;
        x.push(length * acc / total);
    }
    if let Some(last) = x.last_mut() {
        *last = length;
    }
    Ok(x)
}

/// The doubled grid index of the node at reference coordinates `r` (each −1, 0 or 1) of cell
/// (i, j, k) of a structured grid: 2·i + 1 + r per axis (even: a vertex, odd: a mid-edge node).
pub(crate) fn grid_index(cell: [usize; 3], r: &[f64; 3]) -> [usize; 3] {
    std::array::from_fn(|a| (2 * cell[a] as i64 + 1 + r[a] as i64) as usize)
}

/// Position of doubled grid index `g` along an axis with vertex positions `axis`: even `g` is
/// vertex g/2, odd `g` the midpoint of its element (where Hex20 mid-edge nodes sit).
pub(crate) fn grid_position(axis: &[f64], g: usize) -> f64 {
    if g.is_multiple_of(2) {
        axis[g / 2]
    } else {
        0.5 * (axis[g / 2] + axis[g / 2 + 1])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grading_hits_the_ratio_and_the_length() {
        let x = graded_coordinates(5, 2.0, 0.25).unwrap();
        assert_eq!(x.len(), 6);
        assert_eq!(x[0], 0.0);
        assert_eq!(x[5], 2.0);
        let first = x[1] - x[0];
        let last = x[5] - x[4];
        assert!((last / first - 0.25).abs() < 1e-12);
        assert!(graded_coordinates(0, 1.0, 1.0).is_err());
        assert!(graded_coordinates(3, -1.0, 1.0).is_err());
        assert!(graded_coordinates(3, 1.0, f64::NAN).is_err());
    }

    #[test]
    fn graded_from_first_matches_the_first_element() {
        for (n, len, first) in [(5, 10.0, 0.5), (3, 1.0, 0.6), (8, 75.0, 1.0)] {
            let x = graded_from_first(n, len, first).unwrap();
            assert_eq!(x.len(), n + 1);
            assert!((x[1] - first).abs() < 1e-12 * len);
            assert!((x[n] - len).abs() < 1e-12 * len);
            assert!(x.windows(2).all(|w| w[1] > w[0]));
        }
        assert!(graded_from_first(3, 1.0, 0.0).is_err());
    }

    #[test]
    fn graded_to_last_ends_with_the_last_element_and_never_shrinks_backwards() {
        let x = graded_to_last(6, 10.5, 0.1).unwrap();
        assert_eq!((x[0], x[6]), (0.0, 10.5));
        assert!((x[6] - x[5] - 0.1).abs() < 1e-12);
        assert!(x.windows(3).all(|w| w[2] - w[1] < w[1] - w[0]));
        // A last element longer than length/n gives uniform elements, not ones growing
        // towards the end.
        let u = graded_to_last(4, 1.0, 0.9).unwrap();
        assert!(u.windows(2).all(|w| (w[1] - w[0] - 0.25).abs() < 1e-12));
    }
}
