//! Tree-level parallelism for [`FaerSolver`]'s LDLᵀ (issue 20). The nested-dissection order's
//! top separator s splits A into two independent halves,
//!
//! A = [A₁₁ 0 A₁ₛ; 0 A₂₂ A₂ₛ; Aₛ₁ Aₛ₂ Aₛₛ],
//!
//! and each half is factored by faer on one thread with the separator appended:
//! Mᵢ = [Aᵢᵢ Aᵢₛ; Aₛᵢ Aₛₛ] = Lᵢ Dᵢ Lᵢᵀ, whose trailing block gives back
//! Lₛₛ Dₛ Lₛₛᵀ = S′ᵢ = Aₛₛ − Aₛᵢ Aᵢᵢ⁻¹ Aᵢₛ (a Schur complement of a principal submatrix of A:
//! positive definite when A is). The separator's Schur complement S = S′₁ + S′₂ − Aₛₛ is then
//! factored densely. The pivots are those of the unsplit LDLᵀ in the same order (A₁₁'s, A₂₂'s,
//! then S's), so the inertia is their sum (Haynsworth). Solves: forward through each half
//! (its rows of the separator collect −Aₛᵢ Aᵢᵢ⁻¹ bᵢ), S xₛ = bₛ − Σ Aₛᵢ Aᵢᵢ⁻¹ bᵢ, back through
//! each half. Each half is one sequential faer call (or loop) and the halves meet in a fixed
//! order, so the bits do not depend on the thread count.

use super::factor_diagonal;
use crate::{Factorization, SolverError, SymmetricMatrix, SymmetricPattern};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::ldlt::factor::{LdltError, LdltRegularization};
use faer::linalg::matmul::triangular::BlockStructure;
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
    factorize_symbolic_cholesky, supernodal,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Accum, Conj, Mat, MatMut, Par, Side};

/// One half with the separator appended, in its own numbering: interior DOFs (in the
/// nested-dissection order), then the separator's.
struct Half {
    /// Local index → DOF of A.
    dofs: Vec<usize>,
    /// Interior DOFs (the first `interior` local indices).
    interior: usize,
    pattern: SymmetricPattern,
    /// Local value k is A's value `gather[k]`.
    gather: Vec<usize>,
    symbolic: SymbolicCholesky<usize>,
    values: Vec<f64>,
    l: Vec<f64>,
    buffer: MemBuffer,
}

/// What a half's factorisation found.
struct HalfOutcome {
    /// Negative interior pivots.
    negative: usize,
    /// S′ᵢ, lower triangle (ns × ns).
    schur: Mat<f64>,
}

/// The split factor: two halves and the dense separator block.
pub(super) struct Split {
    n: usize,
    /// Separator DOFs, in order.
    sep: Vec<usize>,
    halves: [Half; 2],
    /// A's value index of each lower entry (i ≥ j) of Aₛₛ, with its dense position (i, j).
    sep_entries: Vec<(usize, usize, usize)>,
    /// S's LDLᵀ: unit L strictly below the diagonal, D on it.
    s: Mat<f64>,
    s_buffer: MemBuffer,
    factored: bool,
}

impl Split {
    /// The split of `pattern` by the top separator of its nested-dissection order `forward`
    /// (side 0: `forward[..n0]`, side 1: the next `n1`, separator: the rest). `None` when a
    /// side or the separator is empty, or an entry couples the two sides.
    pub(super) fn analyze(
        pattern: &SymmetricPattern,
        forward: &[usize],
        (n0, n1): (usize, usize),
    ) -> Result<Option<Self>, SolverError> {
        let n = pattern.n();
        if n0 == 0 || n1 == 0 || n0 + n1 >= n {
            return Ok(None);
        }
        let mut side = vec![2u8; n];
        for &d in &forward[..n0] {
            side[d] = 0;
        }
        for &d in &forward[n0..n0 + n1] {
            side[d] = 1;
        }
        for j in 0..n {
            if pattern.column(j).iter().any(|&i| side[i] + side[j] == 1) {
                return Ok(None);
            }
        }
        let sep = forward[n0 + n1..].to_vec();
        let ns = sep.len();
        let half = |range: std::ops::Range<usize>| {
            let mut dofs = forward[range].to_vec();
            let interior = dofs.len();
            dofs.extend_from_slice(&sep);
            Half::new(pattern, dofs, interior)
        };
        let halves = [half(0..n0)?, half(n0..n0 + n1)?];
        let mut local = vec![usize::MAX; n];
        for (k, &d) in sep.iter().enumerate() {
            local[d] = k;
        }
        let mut sep_entries = Vec::new();
        for (k, &j) in sep.iter().enumerate() {
            let start = pattern.col_ptr()[j];
            for (p, &i) in pattern.column(j).iter().enumerate() {
                if local[i] != usize::MAX {
                    let (r, c) = (local[i].max(k), local[i].min(k));
                    sep_entries.push((start + p, r, c));
                }
            }
        }
        let s_buffer = MemBuffer::try_new(
            faer::linalg::cholesky::ldlt::factor::cholesky_in_place_scratch::<f64>(
                ns,
                Par::Seq,
                Default::default(),
            ),
        )
        .map_err(|_| SolverError::OutOfMemory {
            what: "the separator's workspace",
            bytes: ns * 8,
        })?;
        Ok(Some(Self {
            n,
            sep,
            halves,
            sep_entries,
            s: Mat::zeros(ns, ns),
            s_buffer,
            factored: false,
        }))
    }

    /// Separator size and the interior sizes of the halves.
    pub(super) fn sizes(&self) -> (usize, usize, usize) {
        (
            self.halves[0].interior,
            self.halves[1].interior,
            self.sep.len(),
        )
    }

    /// Entries of the two half factors and S.
    pub(super) fn factor_entries(&self) -> usize {
        self.halves.iter().map(|h| h.l.len()).sum::<usize>() + self.sep.len().pow(2)
    }

    pub(super) fn is_factored(&self) -> bool {
        self.factored
    }

    /// Factors `a`: the halves on `par`'s threads (one each), S on `par`. `Ok(Err(reason))`
    /// when a half's trailing block (which the unsplit factor never forms) meets a pivot too
    /// small to trust: the caller factors unsplit.
    pub(super) fn factorize(
        &mut self,
        a: &SymmetricMatrix,
        par: Par,
        tolerance: f64,
        flops: f64,
    ) -> Result<Result<Factorization, &'static str>, SolverError> {
        self.factored = false;
        let diag = a.diagonal();
        let values = a.values();
        let [h0, h1] = &mut self.halves;
        let (r0, r1) = if par.degree() > 1 {
            rayon::join(
                || h0.factorize(values, &diag, tolerance),
                || h1.factorize(values, &diag, tolerance),
            )
        } else {
            (
                h0.factorize(values, &diag, tolerance),
                h1.factorize(values, &diag, tolerance),
            )
        };
        let (o0, o1) = match (r0?, r1?) {
            (Ok(o0), Ok(o1)) => (o0, o1),
            (Err(w), _) | (_, Err(w)) => return Ok(Err(w)),
        };
        // S = (S′₁ + S′₂) − Aₛₛ on the lower triangle, in this order.
        let ns = self.sep.len();
        for j in 0..ns {
            for i in j..ns {
                self.s[(i, j)] = o0.schur[(i, j)] + o1.schur[(i, j)];
            }
        }
        for &(p, i, j) in &self.sep_entries {
            self.s[(i, j)] -= values[p];
        }
        drop((o0.schur, o1.schur));
        let info = faer::linalg::cholesky::ldlt::factor::cholesky_in_place(
            self.s.as_mut(),
            LdltRegularization::default(),
            par,
            MemStack::new(&mut self.s_buffer),
            Default::default(),
        );
        let mut negative = o0.negative + o1.negative;
        for k in 0..ns {
            let d = self.s[(k, k)];
            let dof = self.sep[k];
            let equation = self.n - ns + k;
            let failed = matches!(info, Err(LdltError::ZeroPivot { index }) if index == k);
            if failed || crate::profile::is_zero_pivot(d, tolerance, diag[dof].abs()) {
                return Err(SolverError::ZeroPivot {
                    equation,
                    dof,
                    pivot: if failed { 0.0 } else { d },
                    diagonal: diag[dof].abs(),
                });
            }
            if d < 0.0 {
                negative += 1;
            }
        }
        self.factored = true;
        Ok(Ok(Factorization {
            negative_pivots: negative,
            factor_entries: self.factor_entries(),
            flops,
        }))
    }

    /// Overwrites `b` (one column of n values) with A⁻¹b.
    pub(super) fn solve_column(&mut self, b: &mut [f64], par: Par) {
        let [h0, h1] = &self.halves;
        let forward = |h: &Half| {
            let mut z = vec![0.0; h.dofs.len()];
            for (zk, &d) in z.iter_mut().zip(&h.dofs[..h.interior]) {
                *zk = b[d];
            }
            h.forward(&mut z);
            z
        };
        let (mut z0, mut z1) = if par.degree() > 1 {
            rayon::join(|| forward(h0), || forward(h1))
        } else {
            (forward(h0), forward(h1))
        };
        let ns = self.sep.len();
        let mut xs: Vec<f64> = (0..ns)
            .map(|k| b[self.sep[k]] + z0[h0.interior + k] + z1[h1.interior + k])
            .collect();
        faer::linalg::cholesky::ldlt::solve::solve_in_place_with_conj(
            self.s.as_ref(),
            self.s.as_ref().diagonal(),
            Conj::No,
            MatMut::from_column_major_slice_mut(&mut xs, ns, 1),
            Par::Seq,
            MemStack::new(&mut self.s_buffer),
        );
        let backward = |h: &Half, z: &mut Vec<f64>| {
            z[h.interior..].copy_from_slice(&xs);
            h.backward(z);
        };
        if par.degree() > 1 {
            rayon::join(|| backward(h0, &mut z0), || backward(h1, &mut z1));
        } else {
            backward(h0, &mut z0);
            backward(h1, &mut z1);
        }
        for (h, z) in [(h0, &z0), (h1, &z1)] {
            for (&d, &zk) in h.dofs[..h.interior].iter().zip(z.iter()) {
                b[d] = zk;
            }
        }
        for (&d, &x) in self.sep.iter().zip(&xs) {
            b[d] = x;
        }
    }
}

impl Half {
    /// The pattern of A on `dofs` (renumbered), its gather map and faer's supernodal symbolic
    /// factor in that order.
    fn new(a: &SymmetricPattern, dofs: Vec<usize>, interior: usize) -> Result<Self, SolverError> {
        let n = a.n();
        let m = dofs.len();
        let mut local = vec![usize::MAX; n];
        for (k, &d) in dofs.iter().enumerate() {
            local[d] = k;
        }
        let mut columns: Vec<Vec<usize>> = vec![Vec::new(); m];
        for j in 0..n {
            if local[j] == usize::MAX {
                continue;
            }
            for &i in a.column(j) {
                if local[i] != usize::MAX {
                    let (r, c) = (local[i].max(local[j]), local[i].min(local[j]));
                    columns[c].push(r);
                }
            }
        }
        let pattern = SymmetricPattern::from_lower_columns(m, &columns)?;
        drop(columns);
        let mut gather = vec![usize::MAX; pattern.nnz_lower()];
        for j in 0..n {
            if local[j] == usize::MAX {
                continue;
            }
            let start = a.col_ptr()[j];
            for (p, &i) in a.column(j).iter().enumerate() {
                if local[i] != usize::MAX {
                    let (r, c) = (local[i].max(local[j]), local[i].min(local[j]));
                    if let Some(q) = pattern.position(r, c) {
                        gather[q] = start + p;
                    }
                }
            }
        }
        let sym =
            SymbolicSparseColMatRef::new_checked(m, m, pattern.col_ptr(), None, pattern.row_idx());
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
            ..Default::default()
        };
        // The identity as a custom order: faer's `Identity` reads the pattern as its upper
        // triangle, a custom order transposes the lower one first.
        let id: Vec<usize> = (0..m).collect();
        let order = SymmetricOrdering::Custom(faer::perm::PermRef::new_checked(&id, &id, m));
        let symbolic = factorize_symbolic_cholesky(sym, Side::Lower, order, params)
            .map_err(|e| SolverError::Faer(format!("split half, symbolic: {e:?}")))?;
        let req = symbolic
            .factorize_numeric_ldlt_scratch::<f64>(Par::Seq, Default::default())
            .or(symbolic.solve_in_place_scratch::<f64>(1, Par::Seq));
        let buffer = MemBuffer::try_new(req).map_err(|_| SolverError::OutOfMemory {
            what: "a split half's workspace",
            bytes: req.size_bytes(),
        })?;
        let l = crate::budget::try_zeros(symbolic.len_val(), "a split half's factor")?;
        let values = vec![0.0; pattern.nnz_lower()];
        Ok(Self {
            dofs,
            interior,
            pattern,
            gather,
            symbolic,
            values,
            l,
            buffer,
        })
    }

    fn supernodal(&self) -> &supernodal::SymbolicSupernodalCholesky<usize> {
        match self.symbolic.raw() {
            SymbolicCholeskyRaw::Supernodal(s) => s,
            SymbolicCholeskyRaw::Simplicial(_) => unreachable!("split halves are supernodal"),
        }
    }

    /// Factors Mᵢ (one thread), checks the interior pivots against A's diagonal and returns
    /// S′ᵢ = Lₛₛ Dₛ Lₛₛᵀ.
    fn factorize(
        &mut self,
        a: &[f64],
        diag: &[f64],
        tolerance: f64,
    ) -> Result<Result<HalfOutcome, &'static str>, SolverError> {
        for (v, &g) in self.values.iter_mut().zip(&self.gather) {
            *v = if g == usize::MAX { 0.0 } else { a[g] };
        }
        let m = self.dofs.len();
        let sym = SymbolicSparseColMatRef::new_checked(
            m,
            m,
            self.pattern.col_ptr(),
            None,
            self.pattern.row_idx(),
        );
        let mat = SparseColMatRef::new(sym, &self.values);
        let done = self.symbolic.factorize_numeric_ldlt(
            &mut self.l,
            mat,
            Side::Lower,
            LdltRegularization::default(),
            Par::Seq,
            MemStack::new(&mut self.buffer),
            Default::default(),
        );
        if let Err(LdltError::ZeroPivot { index }) = done {
            if index < self.interior {
                let dof = self.dofs[index];
                return Err(SolverError::ZeroPivot {
                    equation: index,
                    dof,
                    pivot: 0.0,
                    diagonal: diag[dof].abs(),
                });
            }
            return Ok(Err("a split half's separator block met a zero pivot"));
        }
        let d = factor_diagonal(&self.symbolic, &self.l);
        let mut negative = 0;
        for (k, &dk) in d.iter().enumerate() {
            let dof = self.dofs[k];
            let scale = diag[dof].abs();
            if k >= self.interior {
                // S′ᵢ's own pivots: not A's; a small one only makes the rebuild inexact.
                if crate::profile::is_zero_pivot(dk, 1e-8, scale) {
                    return Ok(Err("a split half's separator pivot is too small"));
                }
                continue;
            }
            if crate::profile::is_zero_pivot(dk, tolerance, scale) {
                return Err(SolverError::ZeroPivot {
                    equation: k,
                    dof,
                    pivot: dk,
                    diagonal: scale,
                });
            }
            if dk < 0.0 {
                negative += 1;
            }
        }
        Ok(Ok(HalfOutcome {
            negative,
            schur: self.trailing_schur(&d),
        }))
    }

    /// S′ᵢ = Lₛₛ Dₛ Lₛₛᵀ from the factor's separator columns (lower triangle).
    fn trailing_schur(&self, d: &[f64]) -> Mat<f64> {
        let ni = self.interior;
        let ns = self.dofs.len() - ni;
        let sn = self.supernodal();
        let f = supernodal::SupernodalLdltRef::new(sn, &self.l);
        // W = Lₛₛ Dₛ (lower), L = Lₛₛ.
        let mut lss = Mat::<f64>::zeros(ns, ns);
        for k in 0..sn.n_supernodes() {
            let (b, e) = (sn.supernode_begin()[k], sn.supernode_end()[k]);
            if e <= ni {
                continue;
            }
            let s = f.supernode(k);
            let val = s.val();
            let w = e - b;
            for c in b.max(ni)..e {
                let col = c - b;
                let lc = c - ni;
                lss[(lc, lc)] = 1.0;
                for r in col + 1..w {
                    lss[(b + r - ni, lc)] = val[(r, col)];
                }
                for (t, &row) in s.pattern().iter().enumerate() {
                    lss[(row - ni, lc)] = val[(w + t, col)];
                }
            }
        }
        let mut wd = lss.clone();
        for j in 0..ns {
            let dj = d[ni + j];
            for i in j..ns {
                wd[(i, j)] *= dj;
            }
        }
        let mut out = Mat::<f64>::zeros(ns, ns);
        faer::linalg::matmul::triangular::matmul(
            out.as_mut(),
            BlockStructure::TriangularLower,
            Accum::Replace,
            wd.as_ref(),
            BlockStructure::TriangularLower,
            lss.as_ref().transpose(),
            BlockStructure::UnitTriangularUpper,
            1.0,
            Par::Seq,
        );
        out
    }

    /// z ← D⁻¹L⁻¹z over the interior columns; the separator rows of z collect −Lₛᵢ y
    /// (= −Aₛᵢ Aᵢᵢ⁻¹ bᵢ when z's separator rows start at zero).
    fn forward(&self, z: &mut [f64]) {
        let ni = self.interior;
        let sn = self.supernodal();
        let f = supernodal::SupernodalLdltRef::new(sn, &self.l);
        for k in 0..sn.n_supernodes() {
            let (b, e) = (sn.supernode_begin()[k], sn.supernode_end()[k]);
            if b >= ni {
                break;
            }
            let s = f.supernode(k);
            let val = s.val();
            let w = e - b;
            for c in b..e.min(ni) {
                let col = c - b;
                let y = z[c];
                if y == 0.0 {
                    continue;
                }
                let v = val.col(col);
                for r in col + 1..w {
                    z[b + r] -= v[r] * y;
                }
                for (t, &row) in s.pattern().iter().enumerate() {
                    z[row] -= v[w + t] * y;
                }
            }
            for c in b..e.min(ni) {
                z[c] /= val[(c - b, c - b)];
            }
        }
    }

    /// z ← L⁻ᵀz over the interior columns, the separator rows of z holding xₛ.
    fn backward(&self, z: &mut [f64]) {
        let ni = self.interior;
        let sn = self.supernodal();
        let f = supernodal::SupernodalLdltRef::new(sn, &self.l);
        for k in (0..sn.n_supernodes()).rev() {
            let (b, e) = (sn.supernode_begin()[k], sn.supernode_end()[k]);
            if b >= ni {
                continue;
            }
            let s = f.supernode(k);
            let val = s.val();
            let w = e - b;
            for c in (b..e.min(ni)).rev() {
                let col = c - b;
                let v = val.col(col);
                let mut acc = z[c];
                for r in col + 1..w {
                    acc -= v[r] * z[b + r];
                }
                for (t, &row) in s.pattern().iter().enumerate() {
                    acc -= v[w + t] * z[row];
                }
                z[c] = acc;
            }
        }
    }
}

impl super::FaerSolver {
    /// The split factorisation, or the unsplit one when the split cannot be trusted.
    pub(super) fn factorize_split(
        &mut self,
        a: &SymmetricMatrix,
    ) -> Result<Factorization, SolverError> {
        let Some(pattern) = &self.pattern else {
            return Err(SolverError::NotReady("factorize called before analyze"));
        };
        a.check_for(pattern)?;
        self.factored = false;
        let Some(split) = self.split_state.as_mut() else {
            return self.factorize_double(a);
        };
        match split.factorize(a, self.par, self.tolerance, self.flops)? {
            Ok(f) => {
                // The unsplit factor, if a fallback made one, is not needed now.
                self.l_values = Vec::new();
                self.factored = true;
                Ok(f)
            }
            Err(reason) => {
                self.split_fallback = Some(reason);
                self.factorize_double(a)
            }
        }
    }

    /// (interior DOFs of half 0, of half 1, separator DOFs) of the split the last analysis
    /// made; `None` when it did not split.
    pub fn split_sizes(&self) -> Option<(usize, usize, usize)> {
        self.split_state.as_ref().map(Split::sizes)
    }

    /// Why the last split factorisation fell back to the unsplit factor, if one did.
    pub fn split_fallback(&self) -> Option<&'static str> {
        self.split_fallback
    }
}
