//! Tree-level parallelism for [`FaerSolver`]'s LDLᵀ (issue 20). The nested-dissection order's
//! top separator s (ours reports it; METIS's is found from the order, `top.rs`) splits A into
//! two independent halves,
//!
//! A = [A₁₁ 0 A₁ₛ; 0 A₂₂ A₂ₛ; Aₛ₁ Aₛ₂ Aₛₛ],
//!
//! and each half is factored on one thread with the separator appended, Mᵢ = [Aᵢᵢ Aᵢₛ; Aₛᵢ Aₛₛ],
//! by faer's supernodal loop stopped before the separator (`partial.rs`): its interior columns
//! are factored, its separator block is updated by them and read as
//! S′ᵢ = Aₛₛ − Aₛᵢ Aᵢᵢ⁻¹ Aᵢₛ (a Schur complement of a principal submatrix of A: positive
//! definite when A is). The separator's Schur complement S = S′₁ + S′₂ − Aₛₛ is then factored
//! densely (f64). The pivots are those of the unsplit LDLᵀ in the same order (A₁₁'s,
//! A₂₂'s, then S's), so the inertia is their sum (Haynsworth). Solves: forward through each
//! half (its rows of the separator collect −Aₛᵢ Aᵢᵢ⁻¹ bᵢ), S xₛ = bₛ − Σ Aₛᵢ Aᵢᵢ⁻¹ bᵢ, back
//! through each half. Each half is one sequential faer call (or loop) and the halves meet in
//! a fixed order, so the bits do not depend on the thread count.
//!
//! The halves are stored in f64, or in f32 for mixed precision (`mixed.rs` refines the split
//! solve in f64 and decides the fallbacks; the halves' sweeps run in their factor's precision,
//! S's in f64).

use super::factor_diagonal;
use super::pivots::{Attempt, PivotRule, negative_pivots};
use crate::{Factorization, SolverError, SymmetricMatrix, SymmetricPattern};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::ldlt::factor::{LdltError, LdltRegularization};
use faer::sparse::SymbolicSparseColMatRef;
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
    factorize_symbolic_cholesky, supernodal,
};
use faer::{Conj, Mat, MatMut, Par, Side};

mod half;
use half::Half;
mod schur;
pub use schur::{SchurComplement, SchurOutcome};
mod partial;
mod sweep;
use sweep::Sweep;
mod top;
pub(super) use top::top_split;

/// A half's factor values, in the precision last used.
#[derive(Default)]
pub(super) enum Stored {
    #[default]
    Empty,
    Double(Vec<f64>),
    Single(Vec<f32>),
}

/// The precisions a half can be factored in.
pub(super) trait Real:
    faer::traits::ComplexField
    + faer::traits::Conjugate<Canonical = Self>
    + Copy
    + Into<f64>
    + std::ops::AddAssign
    + std::ops::SubAssign
    + std::ops::DivAssign
    + std::ops::MulAssign
    + std::ops::Div<Output = Self>
    + Sweep
    + Send
    + Sync
    + 'static
{
    /// Rounded to this precision.
    fn narrow(v: f64) -> Self;
    /// `stored` as a factor of this precision with `len` entries (the other one freed first).
    fn slot(stored: &mut Stored, len: usize) -> Result<&mut Vec<Self>, SolverError>;
    /// The factor `stored` holds in this precision (empty if another).
    fn view(stored: &Stored) -> &[Self];
}

impl Real for f64 {
    fn narrow(v: f64) -> Self {
        v
    }
    fn slot(stored: &mut Stored, len: usize) -> Result<&mut Vec<Self>, SolverError> {
        if !matches!(stored, Stored::Double(v) if v.len() == len) {
            *stored = Stored::Empty;
            *stored = Stored::Double(crate::budget::try_zeros(len, "a split half's factor")?);
        }
        match stored {
            Stored::Double(v) => Ok(v),
            _ => unreachable!("just stored"),
        }
    }
    fn view(stored: &Stored) -> &[Self] {
        match stored {
            Stored::Double(v) => v,
            _ => &[],
        }
    }
}

impl Real for f32 {
    fn narrow(v: f64) -> Self {
        v as f32
    }
    fn slot(stored: &mut Stored, len: usize) -> Result<&mut Vec<Self>, SolverError> {
        if !matches!(stored, Stored::Single(v) if v.len() == len) {
            *stored = Stored::Empty;
            *stored = Stored::Single(super::mixed::try_zeros_f32(len)?);
        }
        match stored {
            Stored::Single(v) => Ok(v),
            _ => unreachable!("just stored"),
        }
    }
    fn view(stored: &Stored) -> &[Self] {
        match stored {
            Stored::Single(v) => v,
            _ => &[],
        }
    }
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
    /// CPU seconds of the last factorisation's halves (each on its thread), then the join's
    /// wall seconds (S's assembly and dense LDLᵀ).
    times: [f64; 3],
}

/// CPU seconds this thread has run (Linux's `/proc/thread-self/schedstat`; NaN elsewhere):
/// a half's own work, whatever else shares the cores.
fn thread_cpu_seconds() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|t| t.split_whitespace().next()?.parse::<f64>().ok())
        .map_or(f64::NAN, |ns| ns * 1e-9)
}

/// `f()` and the CPU seconds this thread spent in it.
fn timed<R>(f: impl FnOnce() -> R) -> (R, f64) {
    let start = thread_cpu_seconds();
    let r = f();
    (r, thread_cpu_seconds() - start)
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
            let mut dofs = forward[range.clone()].to_vec();
            let interior = dofs.len();
            dofs.extend_from_slice(&sep);
            Half::new(pattern, dofs, interior, range.start)
        };
        // The two halves' patterns and symbolic factors are independent: side by side when
        // the pool has a free thread (the same structures either way).
        let (h0, h1) = rayon::join(|| half(0..n0), || half(n0..n0 + n1));
        let halves = [h0?, h1?];
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
            times: [f64::NAN; 3],
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

    /// Σc² over the column counts of each half's interior columns (the separator's are updated,
    /// not eliminated) and ns³/3 for S: the work of the two threads and of the join.
    pub(super) fn work(&self) -> [f64; 3] {
        let ns = self.sep.len() as f64;
        let interior = |h: &Half| -> f64 {
            super::column_counts(&h.symbolic)[..h.interior]
                .iter()
                .map(|&c| (c * c) as f64)
                .sum()
        };
        [
            interior(&self.halves[0]),
            interior(&self.halves[1]),
            ns.powi(3) / 3.0,
        ]
    }

    /// CPU seconds of each half of the last factorisation and the join's wall seconds.
    pub(super) fn times(&self) -> [f64; 3] {
        self.times
    }

    /// Entries of the two half factors and S.
    pub(super) fn factor_entries(&self) -> usize {
        self.halves
            .iter()
            .map(|h| h.symbolic.len_val())
            .sum::<usize>()
            + self.sep.len().pow(2)
    }

    pub(super) fn is_factored(&self) -> bool {
        self.factored
    }

    /// Factors `a`: the halves in precision `T` on `par`'s threads (one each, their dense
    /// kernels on `kernel`'s, so that a thread the shorter half leaves free takes tiles of the
    /// longer one's), S in f64 on `kernel`'s, pivots judged by `rule`. `Ok(Err(reason))` when
    /// an f32 pivot is in doubt: the caller takes another path.
    pub(super) fn factorize<T: Real>(
        &mut self,
        a: &SymmetricMatrix,
        par: Par,
        kernel: Par,
        rule: PivotRule,
        flops: f64,
    ) -> Attempt<Factorization> {
        self.factored = false;
        let diag = a.diagonal();
        let values = a.values();
        let [h0, h1] = &mut self.halves;
        let mut half0 = || timed(|| h0.factorize::<T>(values, &diag, rule, kernel));
        let mut half1 = || timed(|| h1.factorize::<T>(values, &diag, rule, kernel));
        let ((r0, t0), (r1, t1)) = if par.degree() > 1 {
            rayon::join(half0, half1)
        } else {
            (half0(), half1())
        };
        let join = std::time::Instant::now();
        let (o0, o1) = match (r0?, r1?) {
            (Ok(o0), Ok(o1)) => (o0, o1),
            (Err(w), _) | (_, Err(w)) => return Ok(Err(w)),
        };
        // S = (S′₁ + S′₂) − Aₛₛ on the lower triangle, in this order, read from the halves'
        // separator columns.
        let ns = self.sep.len();
        for j in 0..ns {
            for i in j..ns {
                self.s[(i, j)] = 0.0;
            }
        }
        h0.add_separator_block::<T>(self.s.as_mut());
        h1.add_separator_block::<T>(self.s.as_mut());
        for &(p, i, j) in &self.sep_entries {
            self.s[(i, j)] -= values[p];
        }
        let info = faer::linalg::cholesky::ldlt::factor::cholesky_in_place(
            self.s.as_mut(),
            LdltRegularization::default(),
            kernel,
            MemStack::new(&mut self.s_buffer),
            Default::default(),
        );
        let first = self.n - ns;
        if let Err(LdltError::ZeroPivot { index }) = info {
            let dof = self.sep[index];
            return match rule {
                PivotRule::Single { .. } => Ok(Err("f32 elimination met a zero pivot")),
                PivotRule::Double { .. } => Err(SolverError::ZeroPivot {
                    equation: first + index,
                    dof,
                    pivot: 0.0,
                    diagonal: diag[dof].abs(),
                }),
            };
        }
        let pivots = (0..ns).map(|k| self.s[(k, k)]);
        let negative = match negative_pivots(pivots, first, |k| self.sep[k], &diag, rule)? {
            Ok(count) => count + o0 + o1,
            Err(reason) => return Ok(Err(reason)),
        };
        self.factored = true;
        self.times = [t0, t1, join.elapsed().as_secs_f64()];
        Ok(Ok(Factorization {
            negative_pivots: negative,
            factor_entries: self.factor_entries(),
            flops,
        }))
    }

    /// Overwrites `b` (one column of n values) with A⁻¹b: the halves' sweeps in their
    /// factor's precision (b scaled by a power of two near ‖b‖∞, so f32 neither overflows
    /// nor underflows and f64 is not rounded by it), S's in f64.
    pub(super) fn solve_column(&mut self, b: &mut [f64], par: Par) {
        match self.halves[0].l {
            Stored::Single(_) => self.solve_in::<f32>(b, par),
            _ => self.solve_in::<f64>(b, par),
        }
    }

    fn solve_in<T: Real>(&mut self, b: &mut [f64], par: Par) {
        let norm = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        if norm == 0.0 {
            return;
        }
        let scale = 2f64.powi(norm.log2().round() as i32);
        let [h0, h1] = &self.halves;
        let forward = |h: &Half| {
            let mut z = vec![T::narrow(0.0); h.dofs.len()];
            for (zk, &d) in z.iter_mut().zip(&h.dofs[..h.interior]) {
                *zk = T::narrow(b[d] / scale);
            }
            h.forward(T::view(&h.l), &mut z);
            z
        };
        let (mut z0, mut z1) = if par.degree() > 1 {
            rayon::join(|| forward(h0), || forward(h1))
        } else {
            (forward(h0), forward(h1))
        };
        let ns = self.sep.len();
        let mut xs: Vec<f64> = (0..ns)
            .map(|k| {
                b[self.sep[k]] / scale + z0[h0.interior + k].into() + z1[h1.interior + k].into()
            })
            .collect();
        faer::linalg::cholesky::ldlt::solve::solve_in_place_with_conj(
            self.s.as_ref(),
            self.s.as_ref().diagonal(),
            Conj::No,
            MatMut::from_column_major_slice_mut(&mut xs, ns, 1),
            Par::Seq,
            MemStack::new(&mut self.s_buffer),
        );
        let backward = |h: &Half, z: &mut Vec<T>| {
            for (zk, &x) in z[h.interior..].iter_mut().zip(&xs) {
                *zk = T::narrow(x);
            }
            h.backward(T::view(&h.l), z);
        };
        if par.degree() > 1 {
            rayon::join(|| backward(h0, &mut z0), || backward(h1, &mut z1));
        } else {
            backward(h0, &mut z0);
            backward(h1, &mut z1);
        }
        for (h, z) in [(h0, &z0), (h1, &z1)] {
            for (&d, &zk) in h.dofs[..h.interior].iter().zip(z.iter()) {
                b[d] = zk.into() * scale;
            }
        }
        for (&d, &x) in self.sep.iter().zip(&xs) {
            b[d] = x * scale;
        }
    }
}

impl super::FaerSolver {
    /// The f64 split factorisation, or the unsplit one when the split cannot be trusted.
    pub(super) fn factorize_split(
        &mut self,
        a: &SymmetricMatrix,
    ) -> Result<Factorization, SolverError> {
        let kernel = self.kernel_par(a.n());
        let Some(split) = self.split_state.as_mut() else {
            return self.factorize_double(a);
        };
        let rule = PivotRule::Double {
            tolerance: self.tolerance,
        };
        match split.factorize::<f64>(a, self.par, kernel, rule, self.flops)? {
            Ok(f) => {
                // The unsplit factor, if a fallback made one, is not needed now.
                self.l_values = Vec::new();
                self.split_fallback = None;
                self.factored = true;
                Ok(f)
            }
            Err(reason) => {
                self.split_fallback = Some(reason);
                self.factorize_double(a)
            }
        }
    }

    /// The split solve of each column of `b` (n × nrhs), if the split holds the active
    /// factor; `false` (b untouched) otherwise.
    pub(super) fn solve_split(&mut self, b: &mut [f64], nrhs: usize) -> bool {
        let Some(split) = self.split_state.as_mut().filter(|s| s.is_factored()) else {
            return false;
        };
        let n = b.len() / nrhs.max(1);
        for col in b.chunks_mut(n.max(1)) {
            split.solve_column(col, self.par);
        }
        true
    }

    /// (interior DOFs of half 0, of half 1, separator DOFs) of the split the last analysis
    /// made; `None` when it did not split.
    pub fn split_sizes(&self) -> Option<(usize, usize, usize)> {
        self.split_state.as_ref().map(Split::sizes)
    }

    /// [Σc² of half 0's factor, of half 1's, nₛ³/3 of S] of the split the last analysis
    /// made (`Split::work`); `None` when it did not split.
    pub fn split_work(&self) -> Option<[f64; 3]> {
        self.split_state.as_ref().map(Split::work)
    }

    /// [CPU s of half 0, of half 1, wall s of the join (S)] of the last split factorisation:
    /// on free cores the split takes max(half 0, half 1) + join (`None` when not split).
    pub fn split_times(&self) -> Option<[f64; 3]> {
        self.split_state.as_ref().map(Split::times)
    }

    /// Why the last split factorisation fell back to the unsplit factor, if one did.
    pub fn split_fallback(&self) -> Option<&'static str> {
        self.split_fallback
    }
}
