//! A's lower triangle in the factor's numbering, made once per analysis (issue 20).
//!
//! faer's `factorize_numeric_ldlt` / `_llt` first copy A through the fill-reducing order,
//! P A Pᵀ (a transpose-and-scatter of every stored entry into scratch: 5–7 % of a scene run's
//! CPU), then call the supernodal kernel on its lower triangle or the simplicial one on its
//! upper triangle. The copy's pattern and the place each value lands depend only on A's
//! pattern and the order, so they are found once, with the gather map g (value k of the copy
//! is A's value g[k]); each factorisation fills the values through g and calls the kernel
//! directly, as the split's halves do (`split/half.rs`). The map is faer's own copy applied to
//! the value positions (its `permute_self_adjoint_to_unsorted`), so the kernel reads the same
//! entries in the same order and gives the same bits (the simplicial kernel's row reach, and
//! so its sums, follow the copy's unsorted order).

use crate::{SolverError, SymmetricPattern};
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::ldlt::factor::{LdltError, LdltRegularization};
use faer::linalg::cholesky::llt::factor::{LltError, LltRegularization};
use faer::sparse::linalg::cholesky::{
    SymbolicCholesky, SymbolicCholeskyRaw, simplicial, supernodal,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat, SymbolicSparseColMatRef};
use faer::{Par, Side};

/// P A Pᵀ's pattern as faer's numeric kernels read it, and where its values come from in A.
#[derive(Debug)]
pub(super) struct Permuted {
    /// The copy's pattern, each column's rows in the order faer's copy scatters them
    /// (unsorted).
    pattern: SymbolicSparseColMat<usize>,
    /// Value k of the copy is A's value `gather[k]`.
    gather: Vec<usize>,
    /// Factor position → DOF (the order's forward array).
    forward: Vec<usize>,
    /// The f64 copy's values, kept between f64 factorisations.
    values: Vec<f64>,
}

/// The side of P A Pᵀ faer's kernel on `symbolic` reads: the upper triangle (simplicial) or
/// the lower one (supernodal), as `factorize_numeric_ldlt` passes it.
fn kernel_side(symbolic: &SymbolicCholesky<usize>) -> Side {
    match symbolic.raw() {
        SymbolicCholeskyRaw::Simplicial(_) => Side::Upper,
        SymbolicCholeskyRaw::Supernodal(_) => Side::Lower,
    }
}

/// Scratch of the numeric kernel alone (no room for a permuted copy), LDLᵀ or LLᵀ, in
/// precision `T`.
pub(super) fn kernel_scratch<T: faer::traits::ComplexField>(
    symbolic: &SymbolicCholesky<usize>,
    ldlt: bool,
    par: Par,
) -> StackReq {
    match (symbolic.raw(), ldlt) {
        (SymbolicCholeskyRaw::Simplicial(_), _) => {
            simplicial::factorize_simplicial_numeric_ldlt_scratch::<usize, T>(symbolic.nrows())
        }
        (SymbolicCholeskyRaw::Supernodal(s), true) => {
            supernodal::factorize_supernodal_numeric_ldlt_scratch::<usize, T>(
                s,
                par,
                Default::default(),
            )
        }
        (SymbolicCholeskyRaw::Supernodal(s), false) => {
            supernodal::factorize_supernodal_numeric_llt_scratch::<usize, T>(
                s,
                par,
                Default::default(),
            )
        }
    }
}

/// Bytes a [`Permuted`] of a pattern with `nnz` stored entries and `n` columns keeps.
pub(super) fn bytes(n: usize, nnz: usize) -> usize {
    let word = std::mem::size_of::<usize>();
    (3usize.saturating_mul(nnz).saturating_add(2 * n + 1)).saturating_mul(word)
}

impl Permuted {
    /// The copy's pattern and gather map for `pattern` (lower triangle) in `symbolic`'s order.
    pub(super) fn new(
        pattern: &SymmetricPattern,
        symbolic: &SymbolicCholesky<usize>,
    ) -> Result<Self, SolverError> {
        let n = pattern.n();
        let nnz = pattern.nnz_lower();
        let identity: Vec<usize>;
        let (fwd, inv) = match symbolic.perm() {
            Some(p) => p.arrays(),
            None => {
                identity = (0..n).collect();
                (identity.as_slice(), identity.as_slice())
            }
        };
        let perm = faer::perm::PermRef::new_checked(fwd, inv, n);
        let too_big = || SolverError::OutOfMemory {
            what: "the permuted matrix's pattern",
            bytes: bytes(n, nnz),
        };
        // Value positions as f64 are exact below 2⁵³ entries.
        let positions: Vec<f64> = (0..nnz).map(|k| k as f64).collect();
        let mut new_values = crate::budget::try_zeros(nnz, "the permuted matrix's values")?;
        let mut col_ptr = vec![0usize; n + 1];
        let mut row_idx = vec![0usize; nnz];
        let mut buffer = MemBuffer::try_new(StackReq::new::<usize>(n)).map_err(|_| too_big())?;
        let sym =
            SymbolicSparseColMatRef::new_checked(n, n, pattern.col_ptr(), None, pattern.row_idx());
        let copy = faer::sparse::utils::permute_self_adjoint_to_unsorted(
            &mut new_values,
            &mut col_ptr,
            &mut row_idx,
            SparseColMatRef::new(sym, &positions),
            perm,
            Side::Lower,
            kernel_side(symbolic),
            MemStack::new(&mut buffer),
        );
        let len = copy.val().len();
        drop(positions);
        // The copy's values become the gather map in their own allocation (f64 and usize have
        // the same layout: `collect` reuses it), so the analysis holds at most three words per
        // entry, as each factorisation does.
        new_values.truncate(len);
        let gather: Vec<usize> = new_values.into_iter().map(|v| v as usize).collect();
        Ok(Self {
            pattern: SymbolicSparseColMat::new_unsorted_checked(n, n, col_ptr, None, row_idx),
            gather,
            forward: fwd.to_vec(),
            values: Vec::new(),
        })
    }

    /// Factor position → DOF.
    pub(super) fn forward(&self) -> &[usize] {
        &self.forward
    }

    /// The copy's values from A's `a`, rounded to `T`, into `out`.
    fn fill<T: Narrow>(&self, a: &[f64], out: &mut Vec<T>) {
        out.clear();
        out.extend(self.gather.iter().map(|&g| T::narrow(a[g])));
    }

    fn matrix<'a, T>(&'a self, values: &'a [T]) -> SparseColMatRef<'a, usize, T> {
        SparseColMatRef::new(self.pattern.as_ref(), values)
    }

    /// faer's LDLᵀ kernel on P A Pᵀ (A's values `a`) into `l` (f64).
    pub(super) fn ldlt_f64(
        &mut self,
        symbolic: &SymbolicCholesky<usize>,
        a: &[f64],
        l: &mut [f64],
        par: Par,
        stack: &mut MemStack,
    ) -> Result<(), LdltError> {
        let mut values = std::mem::take(&mut self.values);
        self.fill(a, &mut values);
        let done = ldlt_kernel(symbolic, self.matrix(&values), l, par, stack);
        self.values = values;
        done
    }

    /// faer's LDLᵀ kernel on P A Pᵀ rounded to f32 into `l` (the values made and freed here).
    pub(super) fn ldlt_f32(
        &self,
        symbolic: &SymbolicCholesky<usize>,
        a: &[f64],
        l: &mut [f32],
        par: Par,
        stack: &mut MemStack,
    ) -> Result<(), LdltError> {
        let mut values = Vec::new();
        self.fill(a, &mut values);
        ldlt_kernel(symbolic, self.matrix(&values), l, par, stack)
    }

    /// faer's LLᵀ kernel on P A Pᵀ into `l` (f64).
    pub(super) fn llt_f64(
        &mut self,
        symbolic: &SymbolicCholesky<usize>,
        a: &[f64],
        l: &mut [f64],
        par: Par,
        stack: &mut MemStack,
    ) -> Result<(), LltError> {
        let mut values = std::mem::take(&mut self.values);
        self.fill(a, &mut values);
        let m = self.matrix(&values);
        let done = match symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => simplicial::factorize_simplicial_numeric_llt(
                l,
                m,
                LltRegularization::default(),
                s,
                stack,
            ),
            SymbolicCholeskyRaw::Supernodal(s) => supernodal::factorize_supernodal_numeric_llt(
                l,
                m,
                LltRegularization::default(),
                s,
                par,
                stack,
                Default::default(),
            ),
        };
        self.values = values;
        done.map(|_| ())
    }
}

/// The precisions the copy is made in.
trait Narrow: Copy {
    fn narrow(v: f64) -> Self;
}

impl Narrow for f64 {
    fn narrow(v: f64) -> Self {
        v
    }
}

impl Narrow for f32 {
    fn narrow(v: f64) -> Self {
        v as f32
    }
}

/// faer's simplicial or supernodal LDLᵀ kernel on the copy `m`.
fn ldlt_kernel<T: faer::traits::ComplexField>(
    symbolic: &SymbolicCholesky<usize>,
    m: SparseColMatRef<'_, usize, T>,
    l: &mut [T],
    par: Par,
    stack: &mut MemStack,
) -> Result<(), LdltError> {
    match symbolic.raw() {
        SymbolicCholeskyRaw::Simplicial(s) => simplicial::factorize_simplicial_numeric_ldlt(
            l,
            m,
            LdltRegularization::default(),
            s,
            stack,
        ),
        SymbolicCholeskyRaw::Supernodal(s) => supernodal::factorize_supernodal_numeric_ldlt(
            l,
            m,
            LdltRegularization::default(),
            s,
            par,
            stack,
            Default::default(),
        ),
    }
    .map(|_| ())
}
