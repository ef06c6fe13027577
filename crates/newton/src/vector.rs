//! The two vector reductions the iterations share: the residual norm and the dot product.

/// ‖v‖∞, NaN if any entry is: the residual norm of the convergence tests and line searches.
pub(crate) fn norm_inf(v: &[f64]) -> f64 {
    v.iter().fold(
        0.0f64,
        |a, x| if x.is_nan() { f64::NAN } else { a.max(x.abs()) },
    )
}

/// aᵀb, summed in index order (the same bits on any thread count).
pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}
