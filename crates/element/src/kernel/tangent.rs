//! ESTIF3D's stages (thesis §2.3, eq. 2.3.2–2.3.4, 2.4.2.2–2.4.2.7): the rows of T at one
//! station, the geometric stiffness rows, and K = Σ TᵀT + k^{mn} at the end. Inlined into the
//! kernel (and so compiled with its AVX2/FMA features): the same arithmetic in the same order.

use crate::prefetch::Prefetch;
use crate::simd::{acc3, comb3};
use crate::syrk::syrk_lower;

/// ESTIF3D: T^{sα} = Q_is B_i^α √(|J|W) (eq. 2.3.4, 2.4.2.2–2.4.2.4) for the station's rows
/// s ∈ [lo, hi) into `t` (row stride `p`). B of eq. 2.2.3 is B_i^{mr} = Σ_k β_irk ∂N^m/∂x_k
/// with β_r = rows of F: β_0r = (F_r1, 0, 0), β_1r = (0, F_r2, 0), β_2r = (0, 0, F_r3),
/// β_3r = (F_r2, F_r1, 0), β_4r = (0, F_r3, F_r2), β_5r = (F_r3, 0, F_r1). So T row s,
/// direction r = Σ_k c_srk ∇_k N with c_srk = √w Σ_{i ≥ s} Q_is β_irk: three AXPYs along the
/// nodes; `sw` = √w, `gr` the global gradients ∇N as three runs over the nodes.
#[inline(always)]
pub(super) fn t_rows<const NS: usize, const FMA: bool>(
    t: &mut [f64],
    p: usize,
    (lo, hi): (usize, usize),
    q: &[[f64; 6]; 6],
    f: &[[f64; 3]; 3],
    sw: f64,
    gr: &[[f64; NS]; 3],
) {
    for (sc, trow) in (lo..hi).zip(t.chunks_exact_mut(p)) {
        let mut runs_r = [[0.0; NS]; 3];
        for (r, run) in runs_r.iter_mut().enumerate() {
            let fr_ = &f[r];
            let beta = [
                [fr_[0], 0.0, 0.0],
                [0.0, fr_[1], 0.0],
                [0.0, 0.0, fr_[2]],
                [fr_[1], fr_[0], 0.0],
                [0.0, fr_[2], fr_[1]],
                [fr_[2], 0.0, fr_[0]],
            ];
            let mut cf = [0.0; 3];
            for i in sc..hi {
                for k in 0..3 {
                    cf[k] += q[i][sc] * beta[i][k];
                }
            }
            comb3::<NS, FMA>(run, [sw * cf[0], sw * cf[1], sw * cf[2]], gr);
        }
        // Interleave the three direction runs into node-major DOF order 3m + r.
        for (m, dst) in trow.chunks_exact_mut(3).take(NS).enumerate() {
            dst[0] = runs_r[0][m];
            dst[1] = runs_r[1][m];
            dst[2] = runs_r[2][m];
        }
    }
}

/// Geometric stiffness k^{mn} += Σ_i a_i^{mn} σ̂_i = (∇N^m)ᵀ σ̂ ∇N^n (eq. 2.2.5, 2.4.2.6) at one
/// station, `sh` the weighted stress σ |J| W; whole rows along n, of which only n ≤ m is used
/// (so K stays exactly symmetric).
#[inline(always)]
pub(super) fn geometric_rows<const NS: usize, const FMA: bool>(
    kg: &mut [[f64; NS]; NS],
    sh: &[[f64; 3]; 3],
    gr: &[[f64; NS]; 3],
) {
    for m in 0..NS {
        let gm = [gr[0][m], gr[1][m], gr[2][m]];
        let hm = [
            sh[0][0] * gm[0] + sh[0][1] * gm[1] + sh[0][2] * gm[2],
            sh[1][0] * gm[0] + sh[1][1] * gm[1] + sh[1][2] * gm[2],
            sh[2][0] * gm[0] + sh[2][1] * gm[1] + sh[2][2] * gm[2],
        ];
        acc3::<NS, FMA>(&mut kg[m], hm, gr);
    }
}

/// K = Σ TᵀT over the `rows` rows of `t` (eq. 2.3.2, both triangles written), plus the
/// geometric k^{mn} (when given) on the diagonal of each 3×3 node block (eq. 2.4.2.7), mirrored.
#[inline(always)]
pub(super) fn finish<const NS: usize, const FMA: bool>(
    k: &mut [f64],
    t: &[f64],
    rows: usize,
    p: usize,
    prefetch: Prefetch<'_>,
    kg: Option<&[[f64; NS]; NS]>,
) {
    let nd = 3 * NS;
    syrk_lower::<FMA>(t, rows, p, nd, prefetch, |a, b, v| {
        k[a * nd + b] = v;
        k[b * nd + a] = v;
    });
    if let Some(kg) = kg {
        for m in 0..NS {
            for n in 0..m {
                let kmn = kg[m][n];
                for r in 0..3 {
                    k[(3 * m + r) * nd + 3 * n + r] += kmn;
                    k[(3 * n + r) * nd + 3 * m + r] += kmn;
                }
            }
            for r in 0..3 {
                k[(3 * m + r) * nd + 3 * m + r] += kg[m][m];
            }
        }
    }
}
