//! Central finite differences, to check a derivative against the function it derives from.
//!
//! With step s the central difference (f(x + s·e_j) − f(x − s·e_j)) / 2s has truncation error
//! O(s²·f‴) and round-off O(ε·|f|/s); a caller picks s from the scale of x (s ≈ 1e-6…1e-7 of it
//! for smooth functions in double precision) and states the tolerance that follows.

/// ∂f_i/∂x_j by central differences with step `step`, as columns: `result[j][i]`.
pub fn central_jacobian(
    mut f: impl FnMut(&[f64]) -> Vec<f64>,
    x: &[f64],
    step: f64,
) -> Vec<Vec<f64>> {
    let mut probe = x.to_vec();
    (0..x.len())
        .map(|j| {
            probe[j] = x[j] + step;
            let plus = f(&probe);
            probe[j] = x[j] - step;
            let minus = f(&probe);
            probe[j] = x[j];
            plus.iter()
                .zip(&minus)
                .map(|(p, m)| (p - m) / (2.0 * step))
                .collect()
        })
        .collect()
}

/// ∂f/∂x_j of a scalar function by central differences with step `step`.
pub fn central_gradient(mut f: impl FnMut(&[f64]) -> f64, x: &[f64], step: f64) -> Vec<f64> {
    central_jacobian(|y| vec![f(y)], x, step)
        .into_iter()
        .map(|column| column[0])
        .collect()
}

/// The largest |a − b| over two equally long sequences, and the largest |b| (to state a
/// mismatch relative to the size of the reference).
pub fn max_mismatch(a: &[f64], b: &[f64]) -> (f64, f64) {
    assert_eq!(a.len(), b.len(), "lengths differ");
    a.iter().zip(b).fold((0.0f64, 0.0f64), |(d, s), (x, y)| {
        (d.max((x - y).abs()), s.max(y.abs()))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A cubic's central difference is exact up to s²·|f‴|/6 = 1e-12·1 and round-off.
    #[test]
    fn the_jacobian_of_a_polynomial_map() {
        let f = |x: &[f64]| vec![x[0] * x[0] * x[1], x[1].powi(3)];
        let x = [1.5, -0.5];
        let j = central_jacobian(f, &x, 1e-6);
        let exact = [[2.0 * x[0] * x[1], 0.0], [x[0] * x[0], 3.0 * x[1] * x[1]]];
        for (c, e) in j.iter().zip(&exact) {
            let (d, s) = max_mismatch(c, e);
            assert!(d <= 1e-8 * s.max(1.0), "{c:?} vs {e:?}");
        }
        let g = central_gradient(|x| x[0].sin() + x[1], &x, 1e-6);
        assert!((g[0] - x[0].cos()).abs() < 1e-9 && (g[1] - 1.0).abs() < 1e-9);
    }
}
