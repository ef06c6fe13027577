//! A split half's LDLᵀ stopped at the separator: faer's left-looking supernodal loop over
//! Mᵢ = [Aᵢᵢ Aᵢₛ; Aₛᵢ Aₛₛ] (its columns in elimination order, the separator last), with the
//! separator's columns updated but not factored. Their panels then hold the half's Schur
//! complement
//!
//! S′ᵢ = Aₛₛ − Lₛᵢ Dᵢ Lₛᵢᵀ = Aₛₛ − Aₛᵢ Aᵢᵢ⁻¹ Aᵢₛ,
//!
//! read directly. A whole factorisation of Mᵢ would also factor the separator block and
//! rebuild S′ᵢ = Lₛₛ Dₛ Lₛₛᵀ from it: 2·nₛ³/3 multiply–adds a half for nothing, and a rounding
//! of S′ᵢ the direct reading does not have.
//!
//! Supernode s (columns b..e, rows Rₛ = b..e then its pattern) is assembled from Mᵢ's columns
//! b..e, then each descendant d (a supernode before s with rows in b..e) subtracts
//! L_{Rₛ,d} D_d L_{b..e,d}ᵀ over its factored columns, by the same fused product faer's own
//! loop calls (each tile of the product subtracted through the row and column maps while it
//! is in registers). An interior supernode is then factored (F₁₁ = L₁₁ D L₁₁ᵀ, L₂₁ = F₂₁ L₁₁⁻ᵀ
//! D⁻¹: faer's dense kernels). A supernode that reaches the separator (b < nᵢ < e) factors its
//! interior columns and updates its own separator columns with them; its later columns, and
//! the separator's supernodes, stay unfactored. The factor's values sit where faer puts them,
//! so the sweeps and the pivots read them as before. Every sum runs in a fixed order
//! (supernodes and descendants in increasing order, faer's dense kernels), so the bits do not
//! depend on the thread count.

use super::Real;
use faer::dyn_stack::MemStack;
use faer::linalg::cholesky::ldlt::factor::{LdltError, LdltRegularization};
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::linalg::cholesky::supernodal::SymbolicSupernodalCholesky;
use faer::{Accum, Mat, MatMut, MatRef, Par};

/// For each supernode s, the supernodes before it that have rows among its columns (its
/// descendants in the update sense), in increasing order: faer's row-major structure.
pub(super) struct Descendants {
    ptr: Vec<usize>,
    list: Vec<usize>,
}

impl Descendants {
    pub(super) fn new(sn: &SymbolicSupernodalCholesky<usize>) -> Self {
        let count = sn.n_supernodes();
        let mut owner = vec![0usize; sn.nrows()];
        for s in 0..count {
            owner[sn.supernode_begin()[s]..sn.supernode_end()[s]].fill(s);
        }
        // (s, d) pairs for d in increasing order: a pattern is sorted, so its owners are too.
        let mut pairs = Vec::new();
        for d in 0..count {
            let mut last = usize::MAX;
            for &r in sn.supernode(d).pattern() {
                let s = owner[r];
                if s != last {
                    pairs.push((s, d));
                    last = s;
                }
            }
        }
        let mut ptr = vec![0usize; count + 1];
        for &(s, _) in &pairs {
            ptr[s + 1] += 1;
        }
        for s in 0..count {
            ptr[s + 1] += ptr[s];
        }
        let mut next = ptr.clone();
        let mut list = vec![0usize; pairs.len()];
        for &(s, d) in &pairs {
            list[next[s]] = d;
            next[s] += 1;
        }
        Self { ptr, list }
    }

    fn of(&self, s: usize) -> &[usize] {
        &self.list[self.ptr[s]..self.ptr[s + 1]]
    }
}

/// Mᵢ's lower triangle in the half's numbering: column pointers and rows, and for each entry
/// its position in A's values (`usize::MAX`: a structural zero), read straight from A.
pub(super) struct Lower<'a> {
    pub(super) col_ptr: &'a [usize],
    pub(super) rows: &'a [usize],
    pub(super) gather: &'a [usize],
    pub(super) a: &'a [f64],
}

/// Factors the first `interior` columns of `m` on faer's supernodal structure `sn` into `l`
/// (faer's layout; the separator's columns are left holding S′ᵢ, which
/// [`add_separator_block`] reads). `Err(index)`: the pivot of interior column `index` was zero.
pub(super) fn factorize<T: Real>(
    sn: &SymbolicSupernodalCholesky<usize>,
    descendants: &Descendants,
    m: Lower<'_>,
    interior: usize,
    l: &mut [T],
    par: Par,
    stack: &mut MemStack,
) -> Result<(), usize> {
    let zero = T::narrow(0.0);
    let col_ptr_val = sn.col_ptr_for_val();
    // A row below a supernode's columns → its position in the supernode's rows.
    let mut global_to_local = vec![usize::MAX; sn.nrows()];
    let (mut rows_at, mut cols_at) = (Vec::new(), Vec::new());
    for s in 0..sn.n_supernodes() {
        let (b, e) = (sn.supernode_begin()[s], sn.supernode_end()[s]);
        let pattern = sn.supernode(s).pattern();
        let w = e - b;
        let rows = w + pattern.len();
        for (k, &r) in pattern.iter().enumerate() {
            global_to_local[r] = w + k;
        }
        let (head, tail) = l.split_at_mut(col_ptr_val[s]);
        let panel = &mut tail[..col_ptr_val[s + 1] - col_ptr_val[s]];
        panel.fill(zero);
        for j in b..e {
            let column = &mut panel[(j - b) * rows..(j - b + 1) * rows];
            for k in m.col_ptr[j]..m.col_ptr[j + 1] {
                let i = m.rows[k];
                let at = if i >= e { global_to_local[i] } else { i - b };
                let g = m.gather[k];
                column[at] += T::narrow(if g == usize::MAX { 0.0 } else { m.a[g] });
            }
        }
        let mut front = MatMut::from_column_major_slice_mut(&mut *panel, rows, w);
        for &d in descendants.of(s) {
            let bd = sn.supernode_begin()[d];
            let wd = sn.supernode_end()[d] - bd;
            // Only a descendant's factored columns update (those before the separator).
            let md = wd.min(interior.saturating_sub(bd));
            if md == 0 {
                continue;
            }
            let d_pattern = sn.supernode(d).pattern();
            let ld = MatRef::from_column_major_slice(
                &head[col_ptr_val[d]..col_ptr_val[d + 1]],
                wd + d_pattern.len(),
                wd,
            );
            let start = d_pattern.partition_point(|&r| r < b);
            let mid = d_pattern[start..].partition_point(|&r| r < e);
            // Each row's place in the supernode's rows, and the columns it reaches.
            rows_at.clear();
            rows_at.extend(
                d_pattern[start..]
                    .iter()
                    .map(|&r| if r >= e { global_to_local[r] } else { r - b }),
            );
            cols_at.clear();
            cols_at.extend(d_pattern[start..start + mid].iter().map(|&r| r - b));
            let lhs = ld.subrows(wd + start, rows_at.len()).subcols(0, md);
            subtract_update(
                front.rb_mut(),
                &rows_at,
                &cols_at,
                lhs,
                ld.subrows(0, md).subcols(0, md),
                par,
            );
        }
        if b < interior {
            factor_columns(front, w.min(interior - b), par, stack).map_err(|index| {
                for &r in pattern {
                    global_to_local[r] = usize::MAX;
                }
                b + index
            })?;
        }
        for &r in pattern {
            global_to_local[r] = usize::MAX;
        }
    }
    Ok(())
}

/// Factors the first `elim` columns of a supernode's assembled and updated panel `front` (its
/// rows × its width): F₁₁ = L₁₁ D L₁₁ᵀ, L₂₁ = F₂₁ L₁₁⁻ᵀ D⁻¹, as faer's loop does. When the
/// supernode reaches the separator (`elim` < width), its separator columns are updated with
/// the factored ones, F[elim.., elim..] −= L₂₁ D L₂₁[..width − elim]ᵀ, and left unfactored.
/// `Err(k)`: the pivot of column k was zero.
fn factor_columns<T: Real>(
    front: MatMut<'_, T>,
    elim: usize,
    par: Par,
    stack: &mut MemStack,
) -> Result<(), usize> {
    let (rows, w) = (front.nrows(), front.ncols());
    let zero = T::narrow(0.0);
    let (mut left, right) = front.split_at_col_mut(elim);
    let (mut l11, mut l21) = left.rb_mut().split_at_row_mut(elim);
    if let Err(LdltError::ZeroPivot { index }) =
        faer::linalg::cholesky::ldlt::factor::cholesky_in_place(
            l11.rb_mut(),
            LdltRegularization::default(),
            par,
            stack,
            Default::default(),
        )
    {
        return Err(index);
    }
    for j in 0..elim {
        for i in 0..j {
            l11[(i, j)] = zero;
        }
    }
    faer::linalg::triangular_solve::solve_unit_lower_triangular_in_place(
        l11.rb(),
        l21.rb_mut().transpose_mut(),
        par,
    );
    // X = L₂₁ D, kept when the supernode's own separator columns need it.
    let x = (elim < w).then(|| l21.rb().to_owned());
    for j in 0..elim {
        let inv = T::narrow(1.0) / l11[(j, j)];
        for i in 0..rows - elim {
            l21[(i, j)] *= inv;
        }
    }
    if let Some(x) = x {
        faer::linalg::matmul::matmul(
            right.subrows_mut(elim, rows - elim),
            Accum::Add,
            x.as_ref(),
            l21.rb().subrows(0, w - elim).transpose(),
            T::narrow(-1.0),
            par,
        );
    }
    Ok(())
}

/// front[rows_at[i], cols_at[j]] −= Σₖ lhs[i, k] D_k lhs[j, k] for i ≥ j: a descendant's update
/// of a supernode (lhs: the descendant's factored columns on its rows from the supernode's
/// first column down, the first `cols_at.len()` of them inside the supernode's columns; D on
/// `top`'s diagonal). On x86-64 with AVX2 and FMA this is faer's own fused kernel
/// (`private_gemm_x86`, which faer's supernodal loop calls the same way), elsewhere a dense
/// product and a scatter.
fn subtract_update<T: Real>(
    front: MatMut<'_, T>,
    rows_at: &[usize],
    cols_at: &[usize],
    lhs: MatRef<'_, T>,
    top: MatRef<'_, T>,
    par: Par,
) {
    let (below, mid, depth) = (rows_at.len(), cols_at.len(), lhs.ncols());
    if below == 0 || mid == 0 {
        return;
    }
    // The kernel writes through these maps: every place must lie inside the panel.
    assert!(
        rows_at.iter().all(|&r| r < front.nrows()) && cols_at.iter().all(|&c| c < front.ncols()),
        "a descendant's update reaches outside its supernode's panel"
    );
    // faer's threshold for handing a product to more than one thread.
    let par = if below * mid * depth > 32 * 32 * 32 {
        par
    } else {
        Par::Seq
    };
    #[cfg(target_arch = "x86_64")]
    {
        use private_gemm_x86::{Accum as Beta, DType, DstKind, IType, InstrSet, gemm};
        let instr = if std::arch::is_x86_feature_detected!("avx512f") {
            Some(InstrSet::Avx512)
        } else if std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("fma")
        {
            Some(InstrSet::Avx256)
        } else {
            None
        };
        if let Some(instr) = instr {
            let dtype = if size_of::<T>() == 4 {
                DType::F32
            } else {
                DType::F64
            };
            let diag = top.diagonal().column_vector();
            let rhs = lhs.subrows(0, mid).transpose();
            let alpha = T::narrow(-1.0);
            // SAFETY: every pointer and stride comes from a live faer view of the right shape:
            // `front` (checked above to hold every mapped row and column), `lhs` below × depth,
            // its first `mid` rows transposed (depth × mid), and `top`'s depth diagonal entries;
            // the maps are usize (U64 on x86-64) of lengths below and mid, as faer's own call
            // passes them. `T` is f32 or f64 (`Real`), told apart by its size.
            unsafe {
                gemm(
                    dtype,
                    IType::U64,
                    instr,
                    below,
                    mid,
                    depth,
                    front.as_ptr_mut() as _,
                    front.row_stride(),
                    front.col_stride(),
                    rows_at.as_ptr() as _,
                    cols_at.as_ptr() as _,
                    DstKind::Lower,
                    Beta::Add,
                    lhs.as_ptr() as _,
                    lhs.row_stride(),
                    lhs.col_stride(),
                    false,
                    diag.as_ptr() as _,
                    diag.row_stride(),
                    rhs.as_ptr() as _,
                    rhs.row_stride(),
                    rhs.col_stride(),
                    false,
                    &raw const alpha as _,
                    par.degree(),
                );
            }
            return;
        }
    }
    subtract_update_dense(front, rows_at, cols_at, lhs, top, par);
}

/// [`subtract_update`] without the fused kernel: P = lhs D lhs[..mid]ᵀ densely, then its lower
/// part subtracted through the maps.
fn subtract_update_dense<T: Real>(
    mut front: MatMut<'_, T>,
    rows_at: &[usize],
    cols_at: &[usize],
    lhs: MatRef<'_, T>,
    top: MatRef<'_, T>,
    par: Par,
) {
    let (below, mid, depth) = (rows_at.len(), cols_at.len(), lhs.ncols());
    let mut scaled = lhs.subrows(0, mid).to_owned();
    for k in 0..depth {
        let dk = top[(k, k)];
        for j in 0..mid {
            scaled[(j, k)] *= dk;
        }
    }
    let mut product = Mat::<T>::zeros(below, mid);
    faer::linalg::matmul::matmul(
        product.as_mut(),
        Accum::Replace,
        lhs,
        scaled.as_ref().transpose(),
        T::narrow(1.0),
        par,
    );
    for (j, &c) in cols_at.iter().enumerate() {
        for (i, &r) in rows_at.iter().enumerate().skip(j) {
            front[(r, c)] -= product[(i, j)];
        }
    }
}

/// out += S′ᵢ on the lower triangle (ns × ns, f64), S′ᵢ read from the separator's unfactored
/// columns after [`factorize`] (an entry outside every supernode's rows is a structural zero
/// and adds nothing).
pub(super) fn add_separator_block<T: Real>(
    sn: &SymbolicSupernodalCholesky<usize>,
    l: &[T],
    interior: usize,
    mut out: MatMut<'_, f64>,
) {
    for s in 0..sn.n_supernodes() {
        let (b, e) = (sn.supernode_begin()[s], sn.supernode_end()[s]);
        if e <= interior {
            continue;
        }
        let pattern = sn.supernode(s).pattern();
        let w = e - b;
        let rows = w + pattern.len();
        let panel = &l[sn.col_ptr_for_val()[s]..sn.col_ptr_for_val()[s + 1]];
        for c in b.max(interior)..e {
            let column = &panel[(c - b) * rows..(c - b + 1) * rows];
            let row_of = (b..e).chain(pattern.iter().copied());
            for (r, &v) in row_of.zip(column).skip(c - b) {
                out[(r - interior, c - interior)] += v.into();
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{subtract_update, subtract_update_dense};
    use faer::{Mat, Par};

    /// The fused kernel (this CPU's) and the dense product with a scatter subtract the same
    /// update, entry by entry to rounding (2.8e-12: 2e-13 of the largest sum possible, 7
    /// products of at most 2), and only below the diagonal of the mapped block: a descendant
    /// of depth 7 updating 5 columns of a 12-row, 6-column panel, rows mapped out of order
    /// below the first five.
    #[test]
    fn the_fused_and_the_dense_update_agree() {
        let mut rng = nonlin3d_testkit::Lcg::new(7);
        let (rows, w, depth) = (12, 6, 7);
        let rows_at = [0usize, 2, 3, 4, 5, 11, 7, 9, 6];
        let cols_at = [0usize, 2, 3, 4, 5];
        let lhs = Mat::<f64>::from_fn(rows_at.len(), depth, |_, _| rng.uniform(-1.0, 1.0));
        let top = Mat::<f64>::from_fn(depth, depth, |_, _| rng.uniform(0.5, 2.0));
        let start = Mat::<f64>::from_fn(rows, w, |_, _| rng.uniform(-1.0, 1.0));
        let (mut fused, mut dense) = (start.clone(), start.clone());
        subtract_update(
            fused.as_mut(),
            &rows_at,
            &cols_at,
            lhs.as_ref(),
            top.as_ref(),
            Par::Seq,
        );
        subtract_update_dense(
            dense.as_mut(),
            &rows_at,
            &cols_at,
            lhs.as_ref(),
            top.as_ref(),
            Par::Seq,
        );
        for j in 0..w {
            for i in 0..rows {
                let (f, d) = (fused[(i, j)], dense[(i, j)]);
                assert!(
                    (f - d).abs() <= 1e-13 * depth as f64 * 4.0,
                    "({i}, {j}): {f} vs {d}"
                );
            }
        }
        // The mapped lower part changed, by Σₖ lhs[a,k] D_k lhs[b,k]; the rest did not.
        for (b, &c) in cols_at.iter().enumerate() {
            for (a, &r) in rows_at.iter().enumerate() {
                let expected = start[(r, c)]
                    - if a >= b {
                        (0..depth)
                            .map(|k| lhs[(a, k)] * top[(k, k)] * lhs[(b, k)])
                            .sum::<f64>()
                    } else {
                        0.0
                    };
                assert!(
                    (dense[(r, c)] - expected).abs() <= 1e-13 * 28.0,
                    "({r}, {c})"
                );
            }
        }
        assert_eq!(dense[(1, 0)], start[(1, 0)]);
        assert_eq!(fused[(10, 4)], start[(10, 4)]);
    }
}
