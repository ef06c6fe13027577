//! Operations along the nodes of one element (vectors of length NS, the thesis's §2.4
//! vectors), with an AVX2 + FMA path used when the kernel runs compiled for it (`FAST`) and a
//! portable path otherwise. NS is 8 or 20, multiples of the 4-lane width; a remainder is
//! handled in scalar code anyway.

/// dst = c₀·g₀ + c₁·g₁ + c₂·g₂ (or dst += … with `ACC`), elementwise along the nodes.
#[inline(always)]
fn lincomb<const NS: usize, const FAST: bool, const ACC: bool>(
    dst: &mut [f64; NS],
    c: [f64; 3],
    g: &[[f64; NS]; 3],
) {
    #[cfg(target_arch = "x86_64")]
    if FAST {
        use std::arch::x86_64::*;
        // SAFETY: FAST is set only in code compiled with avx2+fma after runtime detection;
        // every access is at m..m + 4 ≤ NS inside arrays of length NS.
        unsafe {
            let (c0, c1, c2) = (
                _mm256_set1_pd(c[0]),
                _mm256_set1_pd(c[1]),
                _mm256_set1_pd(c[2]),
            );
            let mut m = 0;
            while m + 4 <= NS {
                let v = _mm256_mul_pd(c0, _mm256_loadu_pd(g[0].as_ptr().add(m)));
                let v = _mm256_fmadd_pd(c1, _mm256_loadu_pd(g[1].as_ptr().add(m)), v);
                let v = _mm256_fmadd_pd(c2, _mm256_loadu_pd(g[2].as_ptr().add(m)), v);
                let v = if ACC {
                    _mm256_add_pd(_mm256_loadu_pd(dst.as_ptr().add(m)), v)
                } else {
                    v
                };
                _mm256_storeu_pd(dst.as_mut_ptr().add(m), v);
                m += 4;
            }
            for m in m..NS {
                let v = c[0] * g[0][m] + c[1] * g[1][m] + c[2] * g[2][m];
                dst[m] = if ACC { dst[m] + v } else { v };
            }
            return;
        }
    }
    for m in 0..NS {
        let v = c[0] * g[0][m] + c[1] * g[1][m] + c[2] * g[2][m];
        dst[m] = if ACC { dst[m] + v } else { v };
    }
}

/// dst = c₀·g₀ + c₁·g₁ + c₂·g₂, elementwise along the nodes.
#[inline(always)]
pub(crate) fn comb3<const NS: usize, const FAST: bool>(
    dst: &mut [f64; NS],
    c: [f64; 3],
    g: &[[f64; NS]; 3],
) {
    lincomb::<NS, FAST, false>(dst, c, g)
}

/// dst += c₀·g₀ + c₁·g₁ + c₂·g₂, elementwise along the nodes.
#[inline(always)]
pub(crate) fn acc3<const NS: usize, const FAST: bool>(
    dst: &mut [f64; NS],
    c: [f64; 3],
    g: &[[f64; NS]; 3],
) {
    lincomb::<NS, FAST, true>(dst, c, g)
}

/// Σ_m a[m]·b[m] along the nodes.
#[inline(always)]
pub(crate) fn dot<const NS: usize, const FAST: bool>(a: &[f64; NS], b: &[f64; NS]) -> f64 {
    #[cfg(target_arch = "x86_64")]
    if FAST {
        use std::arch::x86_64::*;
        // SAFETY: as in `comb3`.
        unsafe {
            let mut acc = _mm256_setzero_pd();
            let mut m = 0;
            while m + 4 <= NS {
                acc = _mm256_fmadd_pd(
                    _mm256_loadu_pd(a.as_ptr().add(m)),
                    _mm256_loadu_pd(b.as_ptr().add(m)),
                    acc,
                );
                m += 4;
            }
            let mut lanes = [0.0; 4];
            _mm256_storeu_pd(lanes.as_mut_ptr(), acc);
            let mut s = (lanes[0] + lanes[1]) + (lanes[2] + lanes[3]);
            for m in m..NS {
                s += a[m] * b[m];
            }
            return s;
        }
    }
    let mut s = 0.0;
    for m in 0..NS {
        s += a[m] * b[m];
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[target_feature(enable = "avx2,fma")]
    fn fast_versions(d: &mut [f64; 20], e: &mut [f64; 20], g: &[[f64; 20]; 3]) -> f64 {
        comb3::<20, true>(d, [0.5, -2.0, 3.0], g);
        acc3::<20, true>(e, [0.5, -2.0, 3.0], g);
        dot::<20, true>(&g[0], &g[1])
    }

    #[test]
    fn fast_and_portable_paths_agree() {
        let mut g = [[0.0; 20]; 3];
        for r in 0..3 {
            for m in 0..20 {
                g[r][m] = ((r * 7 + m * 3) % 11) as f64 - 5.0 + 0.1 * m as f64;
            }
        }
        let (mut d1, mut e1) = ([0.0; 20], [1.0; 20]);
        comb3::<20, false>(&mut d1, [0.5, -2.0, 3.0], &g);
        acc3::<20, false>(&mut e1, [0.5, -2.0, 3.0], &g);
        let s1 = dot::<20, false>(&g[0], &g[1]);
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
        {
            let (mut d2, mut e2) = ([0.0; 20], [1.0; 20]);
            // SAFETY: features detected just above.
            let s2 = unsafe { fast_versions(&mut d2, &mut e2, &g) };
            for m in 0..20 {
                assert!((d1[m] - d2[m]).abs() <= 1e-13 * d1[m].abs().max(1.0));
                assert!((e1[m] - e2[m]).abs() <= 1e-13 * e1[m].abs().max(1.0));
            }
            assert!((s1 - s2).abs() <= 1e-12 * s1.abs().max(1.0));
        }
    }
}
