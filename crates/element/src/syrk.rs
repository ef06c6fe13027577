//! K_L = Σ_θ (T^{sα} T^{sβ})^θ (thesis eq. 2.3.3, 2.4.2.5): the stacked-T symmetric rank-k
//! update that dominates the tangent's cost, register-blocked for SIMD.
//!
//! The thesis did this with one VPS-32 inner product per stiffness term over vectors of
//! length NSTR·NG. Here a 4×8 block of K is held in registers while the rows of T stream by,
//! so every loaded T entry feeds 4 or 8 fused multiply-adds.

use crate::prefetch::Prefetch;

/// Rows of K per register block.
const MR: usize = 4;
/// Columns of K per register block (two AVX2 vectors).
const NR: usize = 8;

/// Computes the lower triangle of K = TᵀT, where T has `rows` rows of stride `p` (p ≥ n, a
/// multiple of [`NR`], padding columns zero), and hands each entry (a, b), b ≤ a, to `store`.
/// With `FMA` (the caller runs with AVX2 + FMA enabled) each block uses the intrinsic
/// micro-kernel; otherwise the portable one. The hints of `ahead` are issued evenly, a few after
/// each block, so their misses overlap the arithmetic.
#[inline(always)]
pub(crate) fn syrk_lower<const FMA: bool>(
    t: &[f64],
    rows: usize,
    p: usize,
    n: usize,
    ahead: Prefetch<'_>,
    mut store: impl FnMut(usize, usize, f64),
) {
    debug_assert!(p.is_multiple_of(NR) && p >= n && t.len() >= rows * p);
    let per_block = if ahead.is_empty() {
        0
    } else {
        ahead.len().div_ceil(blocks(n))
    };
    let mut hinted = 0;
    let mut a0 = 0;
    while a0 < n {
        let mut b0 = 0;
        while b0 < n && b0 < a0 + MR {
            let acc = if FMA {
                block_fast(t, rows, p, a0, b0)
            } else {
                block_portable(t, rows, p, a0, b0)
            };
            for (i, acc_row) in acc.iter().enumerate() {
                let a = a0 + i;
                if a >= n {
                    break;
                }
                let end = (b0 + NR).min(a + 1).min(n);
                for b in b0..end {
                    store(a, b, acc_row[b - b0]);
                }
            }
            b0 += NR;
            if hinted < ahead.len() {
                ahead.issue(hinted, hinted + per_block);
                hinted += per_block;
            }
        }
        a0 += MR;
    }
}

/// Number of register blocks [`syrk_lower`] computes for an n × n lower triangle.
fn blocks(n: usize) -> usize {
    (0..n)
        .step_by(MR)
        .map(|a0| (a0 + MR).min(n).div_ceil(NR))
        .sum()
}

/// One MR×NR block of TᵀT: Σ_rows T[row][a0 + i]·T[row][b0 + j], plain Rust.
#[inline(always)]
fn block_portable(t: &[f64], rows: usize, p: usize, a0: usize, b0: usize) -> [[f64; NR]; MR] {
    let mut acc = [[0.0f64; NR]; MR];
    for row in t.chunks_exact(p).take(rows) {
        // a0 + MR ≤ p and b0 + NR ≤ p because p is a multiple of NR ≥ n and a0, b0 < n are
        // multiples of MR and NR; the `else` arms never run.
        let (Some(av), Some(bv)) = (row[a0..].first_chunk::<MR>(), row[b0..].first_chunk::<NR>())
        else {
            break;
        };
        for i in 0..MR {
            for j in 0..NR {
                acc[i][j] += av[i] * bv[j];
            }
        }
    }
    acc
}

/// The same block with AVX2 FMA intrinsics: 8 accumulators in registers, per row two loads,
/// four broadcasts and eight fused multiply-adds.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn block_fast(t: &[f64], rows: usize, p: usize, a0: usize, b0: usize) -> [[f64; NR]; MR] {
    use std::arch::x86_64::{
        __m256d, _mm256_fmadd_pd, _mm256_loadu_pd, _mm256_set1_pd, _mm256_setzero_pd,
        _mm256_storeu_pd,
    };
    // SAFETY (whole function): only called from code compiled with `avx2,fma` enabled after
    // runtime detection (`kernel::dispatch`); every pointer comes from a reference to an array
    // of at least 4 (loads) or exactly NR (stores) f64.
    unsafe {
        let mut c: [[__m256d; 2]; MR] = [[_mm256_setzero_pd(); 2]; MR];
        for row in t.chunks_exact(p).take(rows) {
            let (Some(av), Some(bv)) =
                (row[a0..].first_chunk::<MR>(), row[b0..].first_chunk::<NR>())
            else {
                break;
            };
            let lo = _mm256_loadu_pd(bv.as_ptr());
            let hi = _mm256_loadu_pd(bv[4..].as_ptr());
            for i in 0..MR {
                let a = _mm256_set1_pd(av[i]);
                c[i][0] = _mm256_fmadd_pd(a, lo, c[i][0]);
                c[i][1] = _mm256_fmadd_pd(a, hi, c[i][1]);
            }
        }
        let mut acc = [[0.0f64; NR]; MR];
        for i in 0..MR {
            _mm256_storeu_pd(acc[i].as_mut_ptr(), c[i][0]);
            _mm256_storeu_pd(acc[i][4..].as_mut_ptr(), c[i][1]);
        }
        acc
    }
}

#[cfg(not(target_arch = "x86_64"))]
#[inline(always)]
fn block_fast(t: &[f64], rows: usize, p: usize, a0: usize, b0: usize) -> [[f64; NR]; MR] {
    block_portable(t, rows, p, a0, b0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[target_feature(enable = "avx2,fma")]
    fn syrk_avx2(t: &[f64], rows: usize, p: usize, n: usize, k: &mut [f64]) {
        syrk_lower::<true>(t, rows, p, n, Prefetch::NONE, |a, b, v| k[a * n + b] = v);
    }

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
            syrk_lower::<false>(&t, rows, p, n, Prefetch::NONE, |a, b, v| k[a * n + b] = v);
            let mut k2 = vec![f64::NAN; n * n];
            if std::arch::is_x86_feature_detected!("avx2")
                && std::arch::is_x86_feature_detected!("fma")
            {
                // SAFETY: features detected just above.
                unsafe { syrk_avx2(&t, rows, p, n, &mut k2) };
                for a in 0..n {
                    for b in 0..=a {
                        let d = (k2[a * n + b] - k[a * n + b]).abs();
                        assert!(d <= 1e-12 * k[a * n + b].abs().max(1.0), "avx2 {a},{b}");
                    }
                }
            }
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
