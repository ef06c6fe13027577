//! The column sweeps of a split half's triangular solves (`half.rs`), one supernode at a time.
//! A direction solve reads the whole factor twice and does two flops per value read, so its
//! speed is the memory's. These read each value of a supernode's interior columns once, in
//! memory order within a column, with the right-hand side (the supernode's rows, a few kB) in
//! cache; the vector code is chosen once per supernode, not per column.
//!
//! The order of every operation is fixed by the code, not by the vector width: products are
//! rounded before they are added (no fused multiply–add), and the dot products sum in
//! [`GROUPS`] × [`LANES`] lanes whatever the width. The bits are the same on every x86-64 CPU
//! (AVX-512, AVX2 or neither).

/// Lanes of a group of the backward sweep's dot products: one 512-bit vector of f32.
pub(in crate::faer_backend) const LANES: usize = 16;

/// Groups of [`LANES`] accumulators: whole blocks of `LANES` products go to the groups in turn,
/// so that four independent sums keep the memory busy (one sum alone waits on its adds).
pub(in crate::faer_backend) const GROUPS: usize = 4;

/// Forward and backward substitution over a supernode's columns, in f32 or f64. `values` is
/// the supernode's column-major block of `rows` rows (its diagonal block, then the rows below),
/// `y` its rows' values; only the first `m` columns are swept.
pub(in crate::faer_backend) trait Sweep: Copy + Sized {
    /// For c = 0, …, m − 1: y[c+1..] ← y[c+1..] − L[c+1.., c]·y[c] (unit lower L).
    fn forward(values: &[Self], rows: usize, m: usize, y: &mut [Self]);
    /// For c = m − 1, …, 0: y[c] ← y[c] − L[c+1.., c]·y[c+1..], in two passes that each read
    /// memory forward within a column. First the rows below the swept columns (r ≥ m, whose
    /// values are known), c = 0, …, m − 1 in memory order: y[c] ← y[c] − Σ_{r≥m} L[r,c] y[r].
    /// Then the triangle, c = m − 1, …, 0: y[c] ← y[c] − Σ_{c<r<m} L[r,c] y[r]. Each sum:
    /// block q of [`LANES`] products (whole blocks only) added lane by lane into group
    /// q mod [`GROUPS`], the groups summed as (g₀ + g₁) + (g₂ + g₃), the lanes of that in
    /// halves (k + LANES/2 into k, and so on), then the products past the last whole block,
    /// summed in order, added last.
    fn backward(values: &[Self], rows: usize, m: usize, y: &mut [Self]);
}

macro_rules! sweep {
    ($t:ty, $lanes:ident) => {
        impl Sweep for $t {
            fn forward(values: &[$t], rows: usize, m: usize, y: &mut [$t]) {
                #[inline(always)]
                fn body(values: &[$t], rows: usize, m: usize, y: &mut [$t]) {
                    for c in 0..m {
                        let (head, tail) = y[..rows].split_at_mut(c + 1);
                        let s = head[c];
                        let column = &values[c * rows + c + 1..(c + 1) * rows];
                        for (yi, &l) in tail.iter_mut().zip(column) {
                            *yi -= l * s;
                        }
                    }
                }
                #[cfg(target_arch = "x86_64")]
                {
                    #[target_feature(enable = "avx512f")]
                    fn wide(values: &[$t], rows: usize, m: usize, y: &mut [$t]) {
                        body(values, rows, m, y)
                    }
                    #[target_feature(enable = "avx2")]
                    fn narrow(values: &[$t], rows: usize, m: usize, y: &mut [$t]) {
                        body(values, rows, m, y)
                    }
                    if std::arch::is_x86_feature_detected!("avx512f") {
                        // SAFETY: the CPU has AVX-512F (checked above).
                        return unsafe { wide(values, rows, m, y) };
                    }
                    if std::arch::is_x86_feature_detected!("avx2") {
                        // SAFETY: the CPU has AVX2 (checked above).
                        return unsafe { narrow(values, rows, m, y) };
                    }
                }
                body(values, rows, m, y)
            }

            fn backward(values: &[$t], rows: usize, m: usize, y: &mut [$t]) {
                /// The lanes halved into lane 0, then the products past the whole blocks.
                #[inline(always)]
                fn finish(mut acc: [$t; LANES], column: &[$t], known: &[$t], whole: usize) -> $t {
                    let mut half = LANES / 2;
                    while half > 0 {
                        for k in 0..half {
                            acc[k] += acc[k + half];
                        }
                        half /= 2;
                    }
                    let mut tail = 0.0 as $t;
                    for (&l, &x) in column[whole..].iter().zip(&known[whole..]) {
                        tail += l * x;
                    }
                    acc[0] + tail
                }
                #[inline(always)]
                fn body(
                    values: &[$t],
                    rows: usize,
                    m: usize,
                    y: &mut [$t],
                    groups: impl Fn(&[$t], &[$t]) -> [[$t; LANES]; GROUPS],
                ) {
                    let reduce = |g: [[$t; LANES]; GROUPS]| {
                        let mut acc = [0.0 as $t; LANES];
                        for k in 0..LANES {
                            acc[k] = (g[0][k] + g[1][k]) + (g[2][k] + g[3][k]);
                        }
                        acc
                    };
                    let below = rows - m;
                    let whole = below - below % LANES;
                    for c in 0..m {
                        let column = &values[c * rows + m..(c + 1) * rows];
                        let known = &y[m..rows];
                        let g = groups(&column[..whole], &known[..whole]);
                        y[c] -= finish(reduce(g), column, known, whole);
                    }
                    for c in (0..m).rev() {
                        let column = &values[c * rows + c + 1..c * rows + m];
                        let known = &y[c + 1..m];
                        let whole = column.len() - column.len() % LANES;
                        let g = groups(&column[..whole], &known[..whole]);
                        y[c] -= finish(reduce(g), column, known, whole);
                    }
                }
                #[cfg(target_arch = "x86_64")]
                {
                    #[target_feature(enable = "avx512f")]
                    fn wide(values: &[$t], rows: usize, m: usize, y: &mut [$t]) {
                        // Closures inside inherit AVX-512F.
                        body(values, rows, m, y, |a, b| lanes::$lanes::avx512(a, b))
                    }
                    #[target_feature(enable = "avx2")]
                    fn narrow(values: &[$t], rows: usize, m: usize, y: &mut [$t]) {
                        // Closures inside inherit AVX2.
                        body(values, rows, m, y, |a, b| lanes::$lanes::avx2(a, b))
                    }
                    if std::arch::is_x86_feature_detected!("avx512f") {
                        // SAFETY: the CPU has AVX-512F (checked above).
                        return unsafe { wide(values, rows, m, y) };
                    }
                    if std::arch::is_x86_feature_detected!("avx2") {
                        // SAFETY: the CPU has AVX2 (checked above).
                        return unsafe { narrow(values, rows, m, y) };
                    }
                }
                body(values, rows, m, y, lanes::$lanes::portable)
            }
        }
    };
}

sweep!(f32, f32s);
sweep!(f64, f64s);

/// The [`GROUPS`] × [`LANES`] partial sums of a dot product over whole blocks (a.len() =
/// b.len(), a multiple of [`LANES`]): block q's products are added lane by lane into group
/// q mod GROUPS, each product rounded before it is added.
mod lanes {
    use super::{GROUPS, LANES};

    macro_rules! portable {
        ($t:ty) => {
            #[inline(always)]
            pub(in super::super) fn portable(a: &[$t], b: &[$t]) -> [[$t; LANES]; GROUPS] {
                let mut acc = [[0.0 as $t; LANES]; GROUPS];
                let blocks = a.chunks_exact(LANES).zip(b.chunks_exact(LANES));
                for (q, (x, y)) in blocks.enumerate() {
                    let g = &mut acc[q % GROUPS];
                    for k in 0..LANES {
                        g[k] += x[k] * y[k];
                    }
                }
                acc
            }
        };
    }

    /// Adds block after block into the groups in turn, `$blk(q)` being block q's products:
    /// whole rounds of GROUPS blocks, then the rest (fewer than GROUPS) into the first groups.
    /// The accumulators are named variables, not an array indexed at run time, so that they
    /// stay in registers.
    macro_rules! rounds {
        ($n:expr, $zero:expr, $add:expr, $blk:expr) => {{
            let (mut g0, mut g1, mut g2, mut g3) = ($zero, $zero, $zero, $zero);
            let mut q = 0;
            while q + GROUPS <= $n {
                g0 = $add(g0, $blk(q));
                g1 = $add(g1, $blk(q + 1));
                g2 = $add(g2, $blk(q + 2));
                g3 = $add(g3, $blk(q + 3));
                q += GROUPS;
            }
            if q < $n {
                g0 = $add(g0, $blk(q));
            }
            if q + 1 < $n {
                g1 = $add(g1, $blk(q + 1));
            }
            if q + 2 < $n {
                g2 = $add(g2, $blk(q + 2));
            }
            [g0, g1, g2, g3]
        }};
    }

    pub(super) mod f32s {
        use super::{GROUPS, LANES};
        #[cfg(target_arch = "x86_64")]
        use std::arch::x86_64::*;
        portable!(f32);

        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx512f")]
        pub(in super::super) fn avx512(a: &[f32], b: &[f32]) -> [[f32; LANES]; GROUPS] {
            let n = a.len().min(b.len()) / LANES;
            let (pa, pb) = (a.as_ptr(), b.as_ptr());
            // SAFETY: block q (16 f32 from 16q) lies inside both slices: q < n.
            let blk = |q: usize| unsafe {
                _mm512_mul_ps(
                    _mm512_loadu_ps(pa.add(q * LANES)),
                    _mm512_loadu_ps(pb.add(q * LANES)),
                )
            };
            let add = |g: __m512, p: __m512| _mm512_add_ps(g, p);
            let g = rounds!(n, _mm512_setzero_ps(), add, blk);
            let mut out = [[0.0f32; LANES]; GROUPS];
            for (o, v) in out.iter_mut().zip(g) {
                // SAFETY: `o` holds 16 f32.
                unsafe { _mm512_storeu_ps(o.as_mut_ptr(), v) };
            }
            out
        }

        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2")]
        pub(in super::super) fn avx2(a: &[f32], b: &[f32]) -> [[f32; LANES]; GROUPS] {
            let n = a.len().min(b.len()) / LANES;
            let (pa, pb) = (a.as_ptr(), b.as_ptr());
            // SAFETY: block q (16 f32 from 16q) lies inside both slices: q < n.
            let blk = |q: usize| unsafe {
                let (x, y) = (pa.add(q * LANES), pb.add(q * LANES));
                [
                    _mm256_mul_ps(_mm256_loadu_ps(x), _mm256_loadu_ps(y)),
                    _mm256_mul_ps(_mm256_loadu_ps(x.add(8)), _mm256_loadu_ps(y.add(8))),
                ]
            };
            let add = |g: [__m256; 2], p: [__m256; 2]| {
                [_mm256_add_ps(g[0], p[0]), _mm256_add_ps(g[1], p[1])]
            };
            let g = rounds!(n, [_mm256_setzero_ps(); 2], add, blk);
            let mut out = [[0.0f32; LANES]; GROUPS];
            for (o, v) in out.iter_mut().zip(g) {
                // SAFETY: `o` holds 16 f32, 8 from 0 and 8 from 8.
                unsafe {
                    _mm256_storeu_ps(o.as_mut_ptr(), v[0]);
                    _mm256_storeu_ps(o.as_mut_ptr().add(8), v[1]);
                }
            }
            out
        }
    }

    pub(super) mod f64s {
        use super::{GROUPS, LANES};
        #[cfg(target_arch = "x86_64")]
        use std::arch::x86_64::*;
        portable!(f64);

        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx512f")]
        pub(in super::super) fn avx512(a: &[f64], b: &[f64]) -> [[f64; LANES]; GROUPS] {
            let n = a.len().min(b.len()) / LANES;
            let (pa, pb) = (a.as_ptr(), b.as_ptr());
            // SAFETY: block q (16 f64 from 16q) lies inside both slices: q < n.
            let blk = |q: usize| unsafe {
                let (x, y) = (pa.add(q * LANES), pb.add(q * LANES));
                [
                    _mm512_mul_pd(_mm512_loadu_pd(x), _mm512_loadu_pd(y)),
                    _mm512_mul_pd(_mm512_loadu_pd(x.add(8)), _mm512_loadu_pd(y.add(8))),
                ]
            };
            let add = |g: [__m512d; 2], p: [__m512d; 2]| {
                [_mm512_add_pd(g[0], p[0]), _mm512_add_pd(g[1], p[1])]
            };
            let g = rounds!(n, [_mm512_setzero_pd(); 2], add, blk);
            let mut out = [[0.0f64; LANES]; GROUPS];
            for (o, v) in out.iter_mut().zip(g) {
                // SAFETY: `o` holds 16 f64, 8 from 0 and 8 from 8.
                unsafe {
                    _mm512_storeu_pd(o.as_mut_ptr(), v[0]);
                    _mm512_storeu_pd(o.as_mut_ptr().add(8), v[1]);
                }
            }
            out
        }

        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2")]
        pub(in super::super) fn avx2(a: &[f64], b: &[f64]) -> [[f64; LANES]; GROUPS] {
            let n = a.len().min(b.len()) / LANES;
            let (pa, pb) = (a.as_ptr(), b.as_ptr());
            // SAFETY: block q (16 f64 from 16q) lies inside both slices: q < n.
            let blk = |q: usize| unsafe {
                let (x, y) = (pa.add(q * LANES), pb.add(q * LANES));
                [0, 4, 8, 12]
                    .map(|o| _mm256_mul_pd(_mm256_loadu_pd(x.add(o)), _mm256_loadu_pd(y.add(o))))
            };
            let add =
                |g: [__m256d; 4], p: [__m256d; 4]| [0, 1, 2, 3].map(|h| _mm256_add_pd(g[h], p[h]));
            let g = rounds!(n, [_mm256_setzero_pd(); 4], add, blk);
            let mut out = [[0.0f64; LANES]; GROUPS];
            for (o, v) in out.iter_mut().zip(g) {
                for (h, s) in v.into_iter().enumerate() {
                    // SAFETY: `o` holds 16 f64, 4 from 4h.
                    unsafe { _mm256_storeu_pd(o.as_mut_ptr().add(4 * h), s) };
                }
            }
            out
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A supernode block with `rows` rows and `m` swept columns, and a right-hand side.
    fn block(rows: usize, m: usize) -> (Vec<f64>, Vec<f64>) {
        let values = (0..rows * m)
            .map(|i| ((i * 37) % 101) as f64 / 512.0 - 0.09)
            .collect();
        let y = (0..rows)
            .map(|i| ((i * 53) % 97) as f64 / 8.0 - 5.0)
            .collect();
        (values, y)
    }

    /// The sweeps against dense substitution: forward then backward is L⁻ᵀ applied to L⁻¹'s
    /// result on the swept columns (the rows below only feed the backward sweep).
    #[test]
    fn the_sweeps_are_substitution_by_columns() {
        for (rows, m) in [(1, 1), (5, 3), (40, 17), (70, 33)] {
            let (values, y0) = block(rows, m);
            let l = |i: usize, c: usize| values[c * rows + i];
            let mut y = y0.clone();
            f64::forward(&values, rows, m, &mut y);
            let mut expected = y0.clone();
            for c in 0..m {
                for i in c + 1..rows {
                    expected[i] -= l(i, c) * expected[c];
                }
            }
            for (a, b) in y.iter().zip(&expected) {
                assert!(
                    (a - b).abs() <= 1e-12 * (1.0 + b.abs()),
                    "forward {rows}×{m}"
                );
            }
            let mut x = y0.clone();
            f64::backward(&values, rows, m, &mut x);
            let mut expected = y0.clone();
            for c in (0..m).rev() {
                let s: f64 = (c + 1..rows).map(|i| l(i, c) * expected[i]).sum();
                expected[c] -= s;
            }
            for (a, b) in x.iter().zip(&expected) {
                assert!(
                    (a - b).abs() <= 1e-12 * (1.0 + b.abs()),
                    "backward {rows}×{m}"
                );
            }
        }
    }

    /// The vector code and the portable loops give the same bits, in f32 and f64, on every
    /// vector width this CPU has (the rest of the sweeps is shared code).
    #[test]
    fn the_vector_code_gives_the_portable_bits() {
        let (a, b) = block(211, 1);
        let a = &a[..208];
        let b = &b[..208];
        let a32: Vec<f32> = a.iter().map(|&v| v as f32).collect();
        let b32: Vec<f32> = b.iter().map(|&v| v as f32).collect();
        let groups = lanes::f64s::portable(a, b);
        let groups32 = lanes::f32s::portable(&a32, &b32);
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx512f") {
                // SAFETY: the CPU has AVX-512F (checked above).
                unsafe {
                    assert_eq!(lanes::f64s::avx512(a, b), groups);
                    assert_eq!(lanes::f32s::avx512(&a32, &b32), groups32);
                }
            }
            if std::arch::is_x86_feature_detected!("avx2") {
                // SAFETY: the CPU has AVX2 (checked above).
                unsafe {
                    assert_eq!(lanes::f64s::avx2(a, b), groups);
                    assert_eq!(lanes::f32s::avx2(&a32, &b32), groups32);
                }
            }
        }
        // The groups take blocks in turn: 13 blocks of 16, so groups 0 holds blocks 0, 4, 8, 12.
        let lane3: f64 = [0, 4, 8, 12]
            .iter()
            .fold(0.0, |s, q| s + a[16 * q + 3] * b[16 * q + 3]);
        assert_eq!(groups[0][3], lane3);
    }
}
