//! The profile (skyline, envelope) LDLᵀ solver of the thesis (§2.4: "vectorized versions of
//! banded and profile equation solvers", ref. 35), written for speed.
//!
//! Storage: row i of the permuted lower triangle holds columns first(i) … i contiguously, the
//! diagonal last (the envelope; the Jennings scheme by rows). Crout factorisation, row by row:
//!
//! c_ij = a_ij − Σ_{k = max(f_i, f_j)}^{j−1} L_jk c_ik,   L_ij = c_ij / d_j,   d_i = a_ii − Σ_j L_ij c_ij
//!
//! Each Σ is an inner product of two contiguous row segments: the "column-oriented inner
//! products" of the thesis's solver, here SIMD dot products compiled for AVX2 + FMA when the
//! CPU has them. No pivoting: the inertia (count of d_i < 0) is exact by Sylvester's law
//! whenever the factorisation exists; a pivot |d_i| ≤ tolerance·|a_ii| is an error.

use crate::budget::{MemoryBudget, Need, current_budget, try_filled, try_room, try_zeros};
use crate::ordering::first_columns;
use crate::{
    Analysis, Factorization, LinearSolver, Permutation, SolverError, SymmetricMatrix,
    SymmetricPattern, envelope_stats, reverse_cuthill_mckee,
};
use std::sync::Arc;

/// Default relative pivot tolerance: |d_i| ≤ 1e-12·|a_ii| is a zero pivot. A stiffness with a
/// rigid-body mode left unsupported produces d_i of 1e-16 … 1e-13 of a_ii (round-off of an
/// exact zero); a genuine pivot of a stiffness with condition number κ is ≳ a_ii/κ, and
/// laminate models stay below κ ≈ 1e11.
pub const DEFAULT_PIVOT_TOLERANCE: f64 = 1e-12;

/// Whether pivot `d` counts as zero against the diagonal scale |a_ii|: not finite, or
/// |d| ≤ tolerance·|a_ii|.
pub(crate) fn is_zero_pivot(d: f64, tolerance: f64, scale: f64) -> bool {
    !d.is_finite() || d.abs() <= tolerance * scale
}

/// Default cap on envelope entries, 3·2²⁷ (3 GiB of f64), kept as the upper bound the
/// benchmarks and callers rely on; whether an envelope fits in memory is the memory budget's
/// call ([`crate::budget`]), which knows the machine, checked as well.
pub const DEFAULT_MAX_ENTRIES: usize = 3 << 27;

/// How the profile solver orders the equations.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub enum ProfileOrdering {
    /// Reverse Cuthill–McKee (the default).
    #[default]
    ReverseCuthillMckee,
    /// The caller's numbering.
    Natural,
    /// A given permutation.
    Given(Permutation),
}

/// The profile LDLᵀ solver. See the module documentation.
#[derive(Debug, Clone)]
pub struct ProfileLdlt {
    /// Relative zero-pivot tolerance.
    pub tolerance: f64,
    /// Envelope size cap (entries), on top of the memory budget.
    pub max_entries: usize,
    /// Bytes the envelope, its workspace and the matrix may take; `None`: the process-wide
    /// budget ([`crate::set_memory_budget`]), if any.
    pub memory_budget: Option<MemoryBudget>,
    /// Equation ordering used by [`analyze`](LinearSolver::analyze).
    pub ordering: ProfileOrdering,
    pattern: Option<Arc<SymmetricPattern>>,
    perm: Permutation,
    first: Vec<usize>,
    start: Vec<usize>,
    map: Vec<usize>,
    flops: f64,
    env: Vec<f64>,
    dinv: Vec<f64>,
    scale: Vec<f64>,
    factored: bool,
    work: Vec<f64>,
}

impl Default for ProfileLdlt {
    fn default() -> Self {
        Self::new()
    }
}

impl ProfileLdlt {
    /// A solver with the default tolerance, memory cap and RCM ordering.
    pub fn new() -> Self {
        Self {
            tolerance: DEFAULT_PIVOT_TOLERANCE,
            max_entries: DEFAULT_MAX_ENTRIES,
            memory_budget: None,
            ordering: ProfileOrdering::default(),
            pattern: None,
            perm: Permutation::identity(0),
            first: Vec::new(),
            start: Vec::new(),
            map: Vec::new(),
            flops: 0.0,
            env: Vec::new(),
            dinv: Vec::new(),
            scale: Vec::new(),
            factored: false,
            work: Vec::new(),
        }
    }

    /// The same solver with another ordering.
    pub fn with_ordering(mut self, ordering: ProfileOrdering) -> Self {
        self.ordering = ordering;
        self
    }

    /// The pivots d_i in factorisation order (after a successful factorisation).
    pub fn pivots(&self) -> Vec<f64> {
        (0..self.first.len())
            .map(|i| self.env[self.start[i] + i - self.first[i]])
            .collect()
    }
}

impl LinearSolver for ProfileLdlt {
    fn name(&self) -> &'static str {
        "profile LDLᵀ"
    }

    fn analyze(&mut self, pattern: &Arc<SymmetricPattern>) -> Result<Analysis, SolverError> {
        let n = pattern.n();
        let perm = match &self.ordering {
            ProfileOrdering::ReverseCuthillMckee => reverse_cuthill_mckee(pattern),
            ProfileOrdering::Natural => Permutation::identity(n),
            ProfileOrdering::Given(p) => {
                if p.len() != n {
                    return Err(SolverError::DimensionMismatch {
                        what: "permutation",
                        expected: n,
                        got: p.len(),
                    });
                }
                p.clone()
            }
        };
        let first = first_columns(pattern, &perm);
        let mut start = Vec::new();
        try_room(&mut start, n + 1, "the envelope's row starts")?;
        let mut total = 0usize;
        for (i, &f) in first.iter().enumerate() {
            start.push(total);
            total = total.saturating_add(i - f + 1);
        }
        start.push(total);
        if total > self.max_entries {
            return Err(SolverError::TooLarge {
                what: "profile envelope",
                entries: total,
                limit: self.max_entries,
            });
        }
        let f64s = |k: usize| k.saturating_mul(std::mem::size_of::<f64>());
        let nnz = pattern.nnz_lower();
        // Whatever an earlier analysis holds goes first: the new envelope may need the room.
        self.env = Vec::new();
        self.map = Vec::new();
        self.pattern = None;
        self.factored = false;
        Need {
            what: "profile LDLᵀ envelope",
            entries: total,
            factor_bytes: f64s(total),
            // The value map, and five n-vectors (first, start, 1/d, scale, work).
            workspace_bytes: f64s(nnz).saturating_add(f64s(5 * n)),
            matrix_bytes: f64s(nnz),
        }
        .check(current_budget(self.memory_budget.as_ref()))?;
        // Position of each stored pattern entry in the envelope.
        let inv = perm.inverse();
        let mut map = Vec::new();
        try_room(&mut map, nnz, "the envelope's value map")?;
        for j in 0..n {
            for &i in pattern.column(j) {
                let (a, b) = (inv[i], inv[j]);
                let (row, col) = if a >= b { (a, b) } else { (b, a) };
                map.push(start[row] + col - first[row]);
            }
        }
        // Flops of one numeric factorisation: 2 per multiply-add of the inner products, plus the
        // scaling and the diagonal update (3 per off-diagonal entry).
        let mut flops = 0.0;
        for i in 0..n {
            for j in first[i]..i {
                flops += 2.0 * (j - first[i].max(first[j])) as f64 + 3.0;
            }
        }
        let stats = envelope_stats(pattern, &perm);
        self.env = try_zeros(total, "the profile envelope")?;
        self.dinv = try_filled(n, 0.0, "the pivots")?;
        self.scale = try_filled(n, 0.0, "the pivot scales")?;
        self.work = try_filled(n, 0.0, "the solve vector")?;
        self.pattern = Some(pattern.clone());
        self.perm = perm;
        self.first = first;
        self.start = start;
        self.map = map;
        self.flops = flops;
        Ok(Analysis {
            factor_entries: total,
            lower_nonzeros: total,
            flops,
            bandwidth: Some(stats.bandwidth),
            profile: Some(stats.profile),
            ordering: match self.ordering {
                ProfileOrdering::ReverseCuthillMckee => "RCM",
                ProfileOrdering::Natural => "natural",
                ProfileOrdering::Given(_) => "given",
            },
            tree: None,
        })
    }

    fn factorize(&mut self, a: &SymmetricMatrix) -> Result<Factorization, SolverError> {
        let pattern = self
            .pattern
            .as_ref()
            .ok_or(SolverError::NotReady("factorize called before analyze"))?;
        a.check_for(pattern)?;
        self.factored = false;
        self.env.fill(0.0);
        for (&p, &v) in self.map.iter().zip(a.values()) {
            self.env[p] += v;
        }
        let inv = self.perm.inverse();
        for (old, d) in a.diagonal().into_iter().enumerate() {
            self.scale[inv[old]] = d.abs();
        }
        let negative = run_factor(self)?;
        self.factored = true;
        Ok(Factorization {
            negative_pivots: negative,
            factor_entries: self.env.len(),
            flops: self.flops,
        })
    }

    fn solve_in_place(&mut self, b: &mut [f64], nrhs: usize) -> Result<(), SolverError> {
        if !self.factored {
            return Err(SolverError::NotReady(
                "solve called before a successful factorize",
            ));
        }
        let n = self.first.len();
        if b.len() != n * nrhs {
            return Err(SolverError::DimensionMismatch {
                what: "right-hand sides",
                expected: n * nrhs,
                got: b.len(),
            });
        }
        for (c, col) in b.chunks_exact_mut(n.max(1)).enumerate().take(nrhs) {
            if let Some(i) = col.iter().position(|v| !v.is_finite()) {
                return Err(SolverError::NonFinite {
                    row: i,
                    col: c,
                    value: col[i],
                });
            }
            for (y, &old) in self.work.iter_mut().zip(self.perm.forward()) {
                *y = col[old];
            }
            run_solve(self);
            for (&y, &old) in self.work.iter().zip(self.perm.forward()) {
                col[old] = y;
            }
        }
        Ok(())
    }
}

/// Σ a_k b_k with eight independent accumulators (vectorises to two 4-wide FMA chains).
#[inline(always)]
fn dot<const FMA: bool>(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut acc = [0.0f64; 8];
    let (ca, cb) = (a.chunks_exact(8), b.chunks_exact(8));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for l in 0..8 {
            acc[l] = if FMA {
                x[l].mul_add(y[l], acc[l])
            } else {
                acc[l] + x[l] * y[l]
            };
        }
    }
    let mut s = ((acc[0] + acc[4]) + (acc[1] + acc[5])) + ((acc[2] + acc[6]) + (acc[3] + acc[7]));
    for (x, y) in ra.iter().zip(rb) {
        s += x * y;
    }
    s
}

/// y −= α·x.
#[inline(always)]
fn axpy_neg<const FMA: bool>(alpha: f64, x: &[f64], y: &mut [f64]) {
    for (yi, xi) in y.iter_mut().zip(x) {
        *yi = if FMA {
            (-alpha).mul_add(*xi, *yi)
        } else {
            *yi - alpha * xi
        };
    }
}

fn run_factor(s: &mut ProfileLdlt) -> Result<usize, SolverError> {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma") {
        // SAFETY: the AVX2 and FMA instruction sets were detected on this CPU just above.
        return unsafe { factor_avx2(s) };
    }
    factor::<false>(s)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn factor_avx2(s: &mut ProfileLdlt) -> Result<usize, SolverError> {
    factor::<true>(s)
}

/// Rows per block of the blocked Crout factorisation: each earlier row is read once per block
/// and applied to all its rows. Measured on Hex20 matrices of 11 k–54 k DOF (docs/PERFORMANCE.md):
/// 16 rows 12–14 GFLOP/s, 32 rows 15, 64 rows 19–20, 128 rows 18–19; 64 it is.
const BLOCK_ROWS: usize = 64;

/// Σ_k x_k·y_r,k for four rows y_r at once: x is loaded once for four FMAs (5 loads per 4
/// FMAs instead of 8). Every y_r must be at least as long as x.
#[inline(always)]
fn dot4<const FMA: bool>(x: &[f64], y: [&[f64]; 4]) -> [f64; 4] {
    let n = x.len();
    let y = [&y[0][..n], &y[1][..n], &y[2][..n], &y[3][..n]];
    #[cfg(target_arch = "x86_64")]
    if FMA {
        use std::arch::x86_64::*;
        // SAFETY: FMA is set only in code compiled with avx2+fma after runtime detection; all
        // accesses are at k..k + 4 ≤ n within slices of length n.
        unsafe {
            let mut a = [_mm256_setzero_pd(); 4];
            let mut k = 0;
            while k + 4 <= n {
                let xv = _mm256_loadu_pd(x.as_ptr().add(k));
                for r in 0..4 {
                    a[r] = _mm256_fmadd_pd(xv, _mm256_loadu_pd(y[r].as_ptr().add(k)), a[r]);
                }
                k += 4;
            }
            let mut out = [0.0; 4];
            for r in 0..4 {
                let mut lanes = [0.0; 4];
                _mm256_storeu_pd(lanes.as_mut_ptr(), a[r]);
                out[r] = (lanes[0] + lanes[1]) + (lanes[2] + lanes[3]);
                for kk in k..n {
                    out[r] += x[kk] * y[r][kk];
                }
            }
            return out;
        }
    }
    let mut out = [0.0; 4];
    for r in 0..4 {
        out[r] = dot::<false>(x, y[r]);
    }
    out
}

/// Two rows x₀, x₁ against four rows y_r: the y loads (the L2-resident block rows) are shared
/// by two FMAs each, 6 loads per 8 FMAs. All slices at least as long as x₀; x₁ likewise.
#[inline(always)]
fn dot2x4<const FMA: bool>(x0: &[f64], x1: &[f64], y: [&[f64]; 4]) -> ([f64; 4], [f64; 4]) {
    let n = x0.len();
    let x1 = &x1[..n];
    let y = [&y[0][..n], &y[1][..n], &y[2][..n], &y[3][..n]];
    #[cfg(target_arch = "x86_64")]
    if FMA {
        use std::arch::x86_64::*;
        // SAFETY: as in `dot4`.
        unsafe {
            let mut a = [_mm256_setzero_pd(); 4];
            let mut b = [_mm256_setzero_pd(); 4];
            let mut k = 0;
            while k + 4 <= n {
                let u = _mm256_loadu_pd(x0.as_ptr().add(k));
                let v = _mm256_loadu_pd(x1.as_ptr().add(k));
                for r in 0..4 {
                    let yv = _mm256_loadu_pd(y[r].as_ptr().add(k));
                    a[r] = _mm256_fmadd_pd(u, yv, a[r]);
                    b[r] = _mm256_fmadd_pd(v, yv, b[r]);
                }
                k += 4;
            }
            let (mut oa, mut ob) = ([0.0; 4], [0.0; 4]);
            for r in 0..4 {
                let (mut la, mut lb) = ([0.0; 4], [0.0; 4]);
                _mm256_storeu_pd(la.as_mut_ptr(), a[r]);
                _mm256_storeu_pd(lb.as_mut_ptr(), b[r]);
                oa[r] = (la[0] + la[1]) + (la[2] + la[3]);
                ob[r] = (lb[0] + lb[1]) + (lb[2] + lb[3]);
                for kk in k..n {
                    oa[r] += x0[kk] * y[r][kk];
                    ob[r] += x1[kk] * y[r][kk];
                }
            }
            return (oa, ob);
        }
    }
    (dot4::<false>(x0, y), dot4::<false>(x1, y))
}

/// The blocked Crout LDLᵀ of the envelope (module documentation).
///
/// Rows are processed in blocks of [`BLOCK_ROWS`]. Phase 1 applies every finished row j above
/// the block to all block rows whose envelope reaches j, four rows per pass of row j
/// ([`dot4`]): each c_ij with j above the block is complete after it. Phase 2 finishes the block
/// row by row as the unblocked algorithm does. The arithmetic is the same sums in the same order
/// per entry as the row-by-row algorithm, only the loop order over (i, j) changes.
#[inline(always)]
fn factor<const FMA: bool>(s: &mut ProfileLdlt) -> Result<usize, SolverError> {
    let n = s.first.len();
    let (first, start) = (&s.first, &s.start);
    let mut negative = 0;
    let mut order: Vec<usize> = Vec::with_capacity(BLOCK_ROWS);
    let mut i0 = 0;
    while i0 < n {
        let i1 = (i0 + BLOCK_ROWS).min(n);
        let base = start[i0];
        let (done, rest) = s.env.split_at_mut(base);
        let blk = &mut rest[..start[i1] - base];
        // Phase 1: block rows sorted by their first column, so the rows active for a given j
        // form a prefix and rows grouped in fours have similar envelopes.
        order.clear();
        order.extend(i0..i1);
        order.sort_by_key(|&i| first[i]);
        let fb = first[order[0]];
        let mut active = 0;
        let mut j = fb;
        while j < i0 {
            while active < order.len() && first[order[active]] <= j {
                active += 1;
            }
            let fj = first[j];
            let lj = &done[start[j]..start[j] + (j - fj)];
            // Two finished rows at a time when both are above the block and row j + 1 has
            // off-diagonal entries (a row whose envelope starts at its diagonal updates nothing).
            let pair = j + 1 < i0 && first[j + 1] <= j;
            let (fj1, lj1) = if pair {
                let f = first[j + 1];
                (f, &done[start[j + 1]..start[j + 1] + (j + 1 - f)])
            } else {
                (fj, lj)
            };
            let mut g = 0;
            while g + 4 <= active {
                let rows = [order[g], order[g + 1], order[g + 2], order[g + 3]];
                let offs = rows.map(|i| start[i] - base);
                // Common range [kc, j) for every row and both j's; per-row heads before it.
                let kc = rows
                    .iter()
                    .map(|&i| first[i])
                    .chain([fj, fj1])
                    .fold(0, usize::max)
                    .min(j);
                let seg = |r: usize, from: usize, to: usize| -> &[f64] {
                    let i = rows[r];
                    &blk[offs[r] + (from - first[i])..offs[r] + (to - first[i])]
                };
                let ys = [seg(0, kc, j), seg(1, kc, j), seg(2, kc, j), seg(3, kc, j)];
                let (mut d0, mut d1) = if pair {
                    dot2x4::<FMA>(&lj[kc - fj..], &lj1[kc - fj1..], ys)
                } else {
                    (dot4::<FMA>(&lj[kc - fj..], ys), [0.0; 4])
                };
                for r in 0..4 {
                    let i = rows[r];
                    let k0 = first[i].max(fj);
                    if k0 < kc {
                        d0[r] += dot::<FMA>(&lj[k0 - fj..kc - fj], seg(r, k0, kc));
                    }
                    if pair {
                        let k1 = first[i].max(fj1);
                        if k1 < kc {
                            d1[r] += dot::<FMA>(&lj1[k1 - fj1..kc - fj1], seg(r, k1, kc));
                        }
                    }
                }
                for r in 0..4 {
                    let (i, off) = (rows[r], offs[r]);
                    let cij = blk[off + (j - first[i])] - d0[r];
                    blk[off + (j - first[i])] = cij;
                    if pair {
                        // c_i,j+1 also needs the k = j term L_{j+1,j}·c_ij, now that c_ij is final.
                        let kj = if first[i].max(fj1) <= j {
                            lj1[j - fj1] * cij
                        } else {
                            0.0
                        };
                        blk[off + (j + 1 - first[i])] -= d1[r] + kj;
                    }
                }
                g += 4;
            }
            for &i in &order[g..active] {
                let off = start[i] - base;
                for (jj, fjj, ljj) in
                    [(j, fj, lj), (j + 1, fj1, lj1)]
                        .into_iter()
                        .take(if pair { 2 } else { 1 })
                {
                    let k0 = first[i].max(fjj);
                    if k0 < jj {
                        let d = dot::<FMA>(
                            &ljj[k0 - fjj..],
                            &blk[off + (k0 - first[i])..off + (jj - first[i])],
                        );
                        blk[off + (jj - first[i])] -= d;
                    }
                }
            }
            // Rows that become active at j + 1 (first = j + 1) have nothing to take from j + 1.
            j += if pair { 2 } else { 1 };
        }
        // Phase 2: the block's own rows, row by row.
        for i in i0..i1 {
            let (fi, len) = (first[i], i - first[i]);
            let (prev, cur) = blk.split_at_mut(start[i] - base);
            let row = &mut cur[..=len];
            for j in fi.max(i0)..i {
                let fj = first[j];
                let k0 = fi.max(fj);
                if k0 < j {
                    let oj = start[j] - base;
                    let d = dot::<FMA>(&prev[oj + (k0 - fj)..oj + (j - fj)], &row[k0 - fi..j - fi]);
                    row[j - fi] -= d;
                }
            }
            // L_ij = c_ij / d_j and d_i = a_ii − Σ_j L_ij c_ij.
            let mut d = row[len];
            for (c, &dj_inv) in row[..len].iter_mut().zip(&s.dinv[fi..i]) {
                let l = *c * dj_inv;
                d -= l * *c;
                *c = l;
            }
            if is_zero_pivot(d, s.tolerance, s.scale[i]) {
                return Err(SolverError::ZeroPivot {
                    equation: i,
                    dof: s.perm.forward()[i],
                    pivot: d,
                    diagonal: s.scale[i],
                });
            }
            row[len] = d;
            s.dinv[i] = 1.0 / d;
            if d < 0.0 {
                negative += 1;
            }
        }
        i0 = i1;
    }
    Ok(negative)
}

fn run_solve(s: &mut ProfileLdlt) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma") {
        // SAFETY: the AVX2 and FMA instruction sets were detected on this CPU just above.
        unsafe { solve_avx2(s) };
        return;
    }
    solve::<false>(s)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn solve_avx2(s: &mut ProfileLdlt) {
    solve::<true>(s)
}

/// L y = b (inner products along rows), y ← D⁻¹ y, Lᵀ x = y (AXPYs along rows), on `work`.
#[inline(always)]
fn solve<const FMA: bool>(s: &mut ProfileLdlt) {
    let n = s.first.len();
    let y = &mut s.work;
    for i in 0..n {
        let (fi, si) = (s.first[i], s.start[i]);
        let d = dot::<FMA>(&s.env[si..si + i - fi], &y[fi..i]);
        y[i] -= d;
    }
    for (yi, dinv) in y.iter_mut().zip(&s.dinv) {
        *yi *= dinv;
    }
    for i in (0..n).rev() {
        let (fi, si) = (s.first[i], s.start[i]);
        let xi = y[i];
        let (head, _) = y.split_at_mut(i);
        axpy_neg::<FMA>(xi, &s.env[si..si + i - fi], &mut head[fi..]);
    }
}
