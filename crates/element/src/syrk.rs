//! K_L = Σ_θ (T^{sα} T^{sβ})^θ (thesis eq. 2.3.3, 2.4.2.5): the stacked-T symmetric rank-k
//! update that dominates the tangent's cost, register-blocked for SIMD.
//!
//! The thesis did this with one VPS-32 inner product per stiffness term over vectors of
//! length NSTR·NG. Here a 4×8 block of K is held in registers while the rows of T stream by,
//! so every loaded T entry feeds 4 or 8 fused multiply-adds.

/// Rows of K per register block.
const MR: usize = 4;
/// Columns of K per register block (two AVX2 vectors).
const NR: usize = 8;

/// `c + a·b`, fused when the caller is compiled with FMA.
#[inline(always)]
pub(crate) fn fmadd<const FMA: bool>(a: f64, b: f64, c: f64) -> f64 {
    if FMA { a.mul_add(b, c) } else { a * b + c }
}

/// Writes the lower triangle (and some entries just above the diagonal) of K = TᵀT, where T
/// has `rows` rows of stride `p` (p ≥ n, a multiple of [`NR`], padding columns zero), into the
/// row-major n×n `k`. The strict upper triangle is left for the caller to mirror.
#[inline(always)]
pub(crate) fn syrk_lower<const FMA: bool>(
    t: &[f64],
    rows: usize,
    p: usize,
    n: usize,
    k: &mut [f64],
) {
    debug_assert!(p % NR == 0 && p >= n && t.len() >= rows * p && k.len() >= n * n);
    let mut a0 = 0;
    while a0 < n {
        let mut b0 = 0;
        while b0 < n && b0 < a0 + MR {
            let mut acc = [[0.0f64; NR]; MR];
            for row in t.chunks_exact(p).take(rows) {
                // a0 + MR ≤ p and b0 + NR ≤ p because p is a multiple of NR ≥ n and
                // a0, b0 < n are multiples of MR and NR; the `else` arms never run.
                let Some(av) = row[a0..].first_chunk::<MR>() else {
                    break;
                };
                let Some(bv) = row[b0..].first_chunk::<NR>() else {
                    break;
                };
                for i in 0..MR {
                    for j in 0..NR {
                        acc[i][j] = fmadd::<FMA>(av[i], bv[j], acc[i][j]);
                    }
                }
            }
            for (i, acc_row) in acc.iter().enumerate() {
                let a = a0 + i;
                if a >= n {
                    break;
                }
                let end = (b0 + NR).min(a + 1).min(n);
                if end > b0 {
                    k[a * n + b0..a * n + end].copy_from_slice(&acc_row[..end - b0]);
                }
            }
            b0 += NR;
        }
        a0 += MR;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocked_syrk_equals_naive_product() {
        for (rows, n) in [(48usize, 60usize), (34, 24), (162, 60), (5, 3), (7, 13)] {
            let p = n.div_ceil(NR) * NR;
            let mut t = vec![0.0; rows * p];
            for r in 0..rows {
                for c in 0..n {
                    t[r * p + c] = ((r * 31 + c * 17) % 13) as f64 - 6.0 + 0.25 * c as f64;
                }
            }
            let mut k = vec![f64::NAN; n * n];
            syrk_lower::<false>(&t, rows, p, n, &mut k);
            for a in 0..n {
                for b in 0..=a {
                    let e: f64 = (0..rows).map(|r| t[r * p + a] * t[r * p + b]).sum();
                    assert!(
                        (k[a * n + b] - e).abs() <= 1e-12 * e.abs().max(1.0),
                        "{a},{b}"
                    );
                }
            }
        }
    }
}
