//! faer's sparse Cholesky (supernodal or simplicial, chosen by faer from the flop count) with
//! AMD, nested-dissection or METIS ordering (by default METIS from 10 000 DOF, below the one needing the fewest flops): LLᵀ for positive definite matrices, LDLᵀ for symmetric indefinite ones.
//! Symbolic analysis once per pattern, numeric factorisation many times.

use crate::budget::{MemoryBudget, Need, current_budget, try_zeros};
use crate::{
    Analysis, Factorization, LinearSolver, SolverError, SymmetricMatrix, SymmetricPattern,
};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::SymbolicSparseColMatRef;
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LdltRef, LltRef, SymbolicCholesky, SymbolicCholeskyRaw,
    SymmetricOrdering, factorize_symbolic_cholesky,
};
use faer::{Conj, MatMut, Par, Side};
use std::sync::Arc;

mod choice;
mod counts;
use counts::{column_counts, factor_flops};
mod directions;
mod dispatch;
mod mixed;
mod options;
mod permuted;
mod pivots;
use pivots::{factor_diagonal, pivot_position};
mod split;
pub use directions::FaerDirections;
pub use mixed::{
    FaerPrecision, MAX_CONJUGATE_GRADIENT_STEPS, MAX_REFINEMENT_STEPS, MixedStats, TRUSTED_SHARE,
    UNCHECKED_IN_A_ROW,
};
pub use options::{
    AUTO_METIS_ONLY_DOFS, AUTO_WITHOUT_AMD_DOFS, FaerMode, FaerOrdering, FaerSplit, FaerStructure,
    KEPT_MIXED_FROM_DOFS, KEPT_RETRY_F32_AFTER, KERNEL_THREADS_FROM_DOFS, MIXED_FROM_DOFS,
    SPLIT_FROM_DOFS,
};
pub use split::{SchurComplement, SchurOutcome};

/// faer's sparse Cholesky behind [`LinearSolver`].
pub struct FaerSolver {
    /// LDLᵀ or LLᵀ.
    pub mode: FaerMode,
    /// Simplicial, supernodal, or faer's choice.
    pub structure: FaerStructure,
    /// The fill-reducing ordering.
    pub ordering: FaerOrdering,
    /// Relative zero-pivot tolerance (as [`crate::profile::DEFAULT_PIVOT_TOLERANCE`]).
    pub tolerance: f64,
    /// Threads for the numeric phase (solves are sequential, `SOLVE_PAR`): `Par::Seq` or
    /// `Par::rayon(k)`. The bits do not depend on it: faer's supernodal LDLᵀ visits the supernodes in one fixed order and
    /// passes the threads only to its dense kernels (update products, the diagonal block's
    /// LDLᵀ, triangular solves), which split the *output* into register tiles and give each
    /// tile to one thread; every entry's sum runs over the depth in fixed 512-wide blocks,
    /// whatever the thread count (private-gemm-x86 0.1.22's `kc`). The dense LDLᵀ's blocking
    /// (128, recursion at 64) does not depend on it either. Tested on 1, 2 and 3 threads
    /// (tests/threads.rs); re-check it when faer is upgraded.
    pub par: Par,
    /// faer's own kernels take `par`'s threads only for matrices of at least this many DOFs
    /// (one thread below; [`KERNEL_THREADS_FROM_DOFS`] by default, 0: always `par`). The split's
    /// two halves run side by side whenever `par` has two threads or more.
    pub kernel_threads_from: usize,
    /// Bytes the factor, its workspace and the matrix may take; `None`: the process-wide
    /// budget ([`crate::set_memory_budget`]), if any.
    pub memory_budget: Option<MemoryBudget>,
    /// f64 throughout, or an f32 factor refined in f64 (LDLᵀ only; [`FaerPrecision`]).
    pub precision: FaerPrecision,
    /// With [`FaerPrecision::Mixed`]: f64 for matrices of fewer DOFs than this (0, the
    /// default: mixed at any size; [`MIXED_FROM_DOFS`] for [`crate::SolverKind::FaerLdltAuto`]).
    pub mixed_from_dofs: usize,
    /// With [`FaerPrecision::Mixed`]: f64 factorisations after f32 was given up before f32 is
    /// tried again, doubled at each refused retry (`RETRY_F32_AFTER` = 8 by default;
    /// [`KEPT_RETRY_F32_AFTER`] for [`crate::SolverKind::FaerLdltKept`]).
    pub retry_f32_after: usize,
    /// The analysed matrix is below `mixed_from_dofs`: f64 whatever `precision` says.
    below_mixed: bool,
    /// Tree-level split of the LDLᵀ ([`FaerSplit`]).
    pub split: FaerSplit,
    /// What `solve_direction_in_place` solves with ([`FaerDirections`]).
    pub directions: FaerDirections,
    /// The f32 copy of the last f64 LDLᵀ factor (`FaerDirections::Single`; empty if none).
    directions_l32: Vec<f32>,
    split_state: Option<split::Split>,
    split_fallback: Option<&'static str>,
    pattern: Option<Arc<SymmetricPattern>>,
    symbolic: Option<SymbolicCholesky<usize>>,
    /// The unsplit factorisations' permuted matrix pattern and gather map (made at the first).
    permuted: Option<permuted::Permuted>,
    chosen: Option<FaerOrdering>,
    l_values: Vec<f64>,
    buffer: Option<MemBuffer>,
    factored: bool,
    flops: f64,
    mixed: mixed::MixedState,
}

impl std::fmt::Debug for FaerSolver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FaerSolver")
            .field("mode", &self.mode)
            .field("tolerance", &self.tolerance)
            .field("factored", &self.factored)
            .finish()
    }
}

impl Default for FaerSolver {
    fn default() -> Self {
        Self::new(FaerMode::Ldlt)
    }
}

impl FaerSolver {
    /// A sequential solver in `mode` with the default pivot tolerance.
    pub fn new(mode: FaerMode) -> Self {
        Self {
            mode,
            structure: FaerStructure::Auto,
            ordering: FaerOrdering::default(),
            tolerance: crate::profile::DEFAULT_PIVOT_TOLERANCE,
            par: Par::Seq,
            kernel_threads_from: KERNEL_THREADS_FROM_DOFS,
            memory_budget: None,
            precision: FaerPrecision::Double,
            split: FaerSplit::Auto,
            directions: FaerDirections::Factor,
            directions_l32: Vec::new(),
            split_state: None,
            mixed_from_dofs: 0,
            retry_f32_after: mixed::RETRY_F32_AFTER,
            below_mixed: false,
            split_fallback: None,
            pattern: None,
            symbolic: None,
            permuted: None,
            chosen: None,
            l_values: Vec::new(),
            buffer: None,
            factored: false,
            flops: 0.0,
            mixed: mixed::MixedState::default(),
        }
    }

    /// The same solver running its numeric phase on `threads` rayon threads (1 = sequential).
    pub fn with_threads(mut self, threads: usize) -> Self {
        self.par = if threads <= 1 {
            Par::Seq
        } else {
            Par::rayon(threads)
        };
        self
    }

    /// The threads faer's own kernels take on an `n`-DOF matrix: `par`'s from
    /// [`Self::kernel_threads_from`] DOFs on, one below.
    pub fn kernel_par(&self, n: usize) -> Par {
        if n < self.kernel_threads_from {
            Par::Seq
        } else {
            self.par
        }
    }

    /// The same solver with a forced factor structure.
    pub fn with_structure(mut self, structure: FaerStructure) -> Self {
        self.structure = structure;
        self
    }

    /// The same solver with another fill-reducing ordering.
    pub fn with_ordering(mut self, ordering: FaerOrdering) -> Self {
        self.ordering = ordering;
        self
    }

    /// The ordering the last analysis used (`Amd`, `NestedDissection` or `Metis`; `None` before
    /// `analyze`).
    pub fn chosen_ordering(&self) -> Option<FaerOrdering> {
        self.chosen
    }

    /// Whether the analysed factor is supernodal (`None` before `analyze`).
    pub fn is_supernodal(&self) -> Option<bool> {
        self.symbolic
            .as_ref()
            .map(|s| matches!(s.raw(), SymbolicCholeskyRaw::Supernodal(_)))
    }
}

/// Threads of the triangular solves: one. faer's column-major matrix-vector product (a solve
/// with one right-hand side, blocks of 256² entries and more) splits the *depth* between
/// threads and adds the partial sums, so its bits depend on the thread count; the solve is
/// memory-bound (0.2 s of the 1.4 s factorisation on the 45 k cube), so it stays sequential.
const SOLVE_PAR: Par = Par::Seq;

/// The packing buffer faer's dense matrix product (private-gemm) allocates per thread.
const GEMM_BUFFER_BYTES: usize = 64 << 20;

/// Scratch sizes for numeric factorisation and solves with up to this many right-hand sides
/// at once; larger batches are split.
const RHS_BLOCK: usize = 16;

impl LinearSolver for FaerSolver {
    fn name(&self) -> &'static str {
        match self.mode {
            FaerMode::Ldlt => "faer LDLᵀ",
            FaerMode::Llt => "faer LLᵀ",
        }
    }

    fn analyze(&mut self, pattern: &Arc<SymmetricPattern>) -> Result<Analysis, SolverError> {
        let n = pattern.n();
        self.below_mixed = n < self.mixed_from_dofs;
        let a =
            SymbolicSparseColMatRef::new_checked(n, n, pattern.col_ptr(), None, pattern.row_idx());
        let threshold = match self.structure {
            FaerStructure::Auto => SupernodalThreshold::AUTO,
            FaerStructure::Simplicial => SupernodalThreshold::FORCE_SIMPLICIAL,
            FaerStructure::Supernodal => SupernodalThreshold::FORCE_SUPERNODAL,
        };
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: threshold,
            ..Default::default()
        };
        // Whatever an earlier analysis holds goes first: the new factor may need the room.
        self.symbolic = None;
        self.permuted = None;
        self.buffer = None;
        self.l_values = Vec::new();
        self.directions_l32 = Vec::new();
        self.pattern = None;
        self.factored = false;
        self.chosen = None;
        self.mixed = mixed::MixedState::default();
        self.split_state = None;
        self.split_fallback = None;
        // The orders the split may need: our nested dissection's with its top sides, METIS's
        // alone (its top sides are found from the order after the choice, `split/top.rs`).
        let wants_split = self.mode == FaerMode::Ldlt
            && match self.split {
                FaerSplit::Off => false,
                FaerSplit::Halves => true,
                FaerSplit::Auto => n >= SPLIT_FROM_DOFS,
            };
        let kernel = self.kernel_par(n);
        // Written by the candidates `auto_choice` may make side by side (threads).
        let top = std::sync::Mutex::new(None);
        let metis_order = std::sync::Mutex::new(None);
        let symbolic_for = |ordering: SymmetricOrdering<'_, usize>| {
            factorize_symbolic_cholesky(a, Side::Lower, ordering, params).map_err(|e| match e {
                faer::sparse::FaerError::OutOfMemory => SolverError::OutOfMemory {
                    what: "faer's symbolic analysis",
                    bytes: 2 * std::mem::size_of::<usize>() * (pattern.nnz_lower() + n + 1),
                },
                other => SolverError::Faer(format!("symbolic analysis: {other:?}")),
            })
        };
        let nested = || {
            let (perm, sides) = crate::nested::nested_dissection_top(pattern)?;
            let p = faer::perm::PermRef::new_checked(perm.forward(), perm.inverse(), n);
            *top.lock().unwrap_or_else(|e| e.into_inner()) =
                sides.map(|s| (perm.forward().to_vec(), s));
            symbolic_for(SymmetricOrdering::Custom(p))
        };
        let metis = || {
            let perm = crate::metis_nested_dissection(pattern)?;
            let p = faer::perm::PermRef::new_checked(perm.forward(), perm.inverse(), n);
            if wants_split {
                *metis_order.lock().unwrap_or_else(|e| e.into_inner()) =
                    Some(perm.forward().to_vec());
            }
            symbolic_for(SymmetricOrdering::Custom(p))
        };
        let (symbolic, chosen) = match self.ordering {
            FaerOrdering::Amd => (symbolic_for(SymmetricOrdering::Amd)?, FaerOrdering::Amd),
            FaerOrdering::NestedDissection => (nested()?, FaerOrdering::NestedDissection),
            FaerOrdering::Metis => (metis()?, FaerOrdering::Metis),
            FaerOrdering::Auto => {
                choice::auto_choice(&symbolic_for, &nested, &metis, n < AUTO_WITHOUT_AMD_DOFS, n)?
            }
        };
        let req = permuted::kernel_scratch::<f64>(&symbolic, self.mode == FaerMode::Ldlt, kernel)
            .or(symbolic.solve_in_place_scratch::<f64>(RHS_BLOCK, kernel))
            .or(mixed::scratch(&symbolic, kernel));
        let sides = match chosen {
            FaerOrdering::NestedDissection => top.into_inner().unwrap_or_else(|e| e.into_inner()),
            FaerOrdering::Metis => metis_order
                .into_inner()
                .unwrap_or_else(|e| e.into_inner())
                .and_then(|f| split::top_split(pattern, &f).map(|s| (f, s))),
            _ => None,
        };
        if let (true, Some((forward, sides))) = (wants_split, sides) {
            // The unsplit factor is allocated only if a fallback needs it.
            self.split_state = split::Split::analyze(pattern, &forward, sides)?;
        }
        let len = symbolic.len_val();
        // The factor the first factorisation makes: the split's halves and S (their
        // separator blocks make it larger than the unsplit one: +15 % on the 45 k cube), or
        // the unsplit factor.
        let entries = self
            .split_state
            .as_ref()
            .map_or(len, |s| s.factor_entries());
        let f64s = |k: usize| k.saturating_mul(std::mem::size_of::<f64>());
        let mixed = self.uses_mixed();
        Need {
            what: match self.mode {
                FaerMode::Ldlt => "faer LDLᵀ factor",
                FaerMode::Llt => "faer LLᵀ factor",
            },
            entries,
            // An f32 factor takes half; an f64 one is made only when refinement falls back,
            // after the f32 one is freed.
            // The f32 copy for directions (`FaerDirections::Single`) takes half more.
            factor_bytes: if mixed {
                f64s(entries) / 2
            } else if self.directions == FaerDirections::Single && self.mode == FaerMode::Ldlt {
                f64s(entries) + f64s(entries) / 2
            } else {
                f64s(entries)
            },
            // The scratch, the permuted matrix (pattern, gather map and f64 values, kept
            // between factorisations) and the diagonal each factorisation makes, and the
            // dense kernels' per-thread packing buffer (64 MiB, allocated by faer's gemm on
            // first use, outside our budget's reach: an address-space limit it does not fit
            // aborts the process).
            workspace_bytes: req
                .size_bytes()
                .saturating_add(permuted::bytes(n, pattern.nnz_lower()))
                .saturating_add(f64s(2 * n))
                .saturating_add(GEMM_BUFFER_BYTES.saturating_mul(self.par.degree().max(1)))
                // The split's per-factorisation copies: each half's values, each half's S′ᵢ.
                .saturating_add(self.split_state.as_ref().map_or(0, |s| {
                    f64s(pattern.nnz_lower()).saturating_add(f64s(2 * s.sizes().2.pow(2)))
                })),
            // Mixed: plus the f64 copy of the matrix kept for residuals and its f32 twin.
            matrix_bytes: f64s(pattern.nnz_lower()).saturating_mul(if mixed { 5 } else { 2 }) / 2,
        }
        .check(current_budget(self.memory_budget.as_ref()))
        .inspect_err(|_| self.split_state = None)?;
        let buffer = MemBuffer::try_new(req).map_err(|_| SolverError::OutOfMemory {
            what: "faer's workspace",
            bytes: req.size_bytes(),
        })?;
        let flops = factor_flops(&symbolic);
        let lower_nonzeros = column_counts(&symbolic).iter().sum();
        let tree = counts::tree_work(&symbolic);
        if mixed {
            self.mixed.reset(len, self.split_state.is_none())?;
        } else if self.split_state.is_none() {
            self.l_values = try_zeros(len, "the faer factor")?;
        }
        self.symbolic = Some(symbolic);
        self.chosen = Some(chosen);
        self.buffer = Some(buffer);
        self.pattern = Some(pattern.clone());
        self.factored = false;
        self.flops = flops;
        Ok(Analysis {
            factor_entries: entries,
            lower_nonzeros,
            flops,
            bandwidth: None,
            profile: None,
            ordering: chosen.name(),
            tree,
        })
    }

    /// With [`FaerOrdering::Auto`], the order the last analysis chose (METIS, nested
    /// dissection or AMD) without comparing the others again; `Auto` itself if that order
    /// fails or none was chosen yet.
    fn reanalyze(&mut self, pattern: &Arc<SymmetricPattern>) -> Result<Analysis, SolverError> {
        let auto = self.ordering;
        let (FaerOrdering::Auto, Some(chosen)) = (auto, self.chosen) else {
            return self.analyze(pattern);
        };
        self.ordering = chosen;
        let analysis = self.analyze(pattern);
        self.ordering = auto;
        match analysis {
            Err(SolverError::OutOfMemory { .. }) | Ok(_) => analysis,
            Err(_) => self.analyze(pattern),
        }
    }

    fn factorize(&mut self, a: &SymmetricMatrix) -> Result<Factorization, SolverError> {
        let Some(pattern) = &self.pattern else {
            return Err(SolverError::NotReady("factorize called before analyze"));
        };
        a.check_pattern(pattern)?;
        self.factored = false;
        self.directions_l32.clear();
        if self.uses_mixed() {
            // Checks the values for NaN and infinity in its one pass over them.
            self.factorize_mixed(a)
        } else {
            a.check_finite()?;
            self.factorize_f64(a)
        }
    }

    fn solve_in_place(&mut self, b: &mut [f64], nrhs: usize) -> Result<(), SolverError> {
        self.solve_checked(b, nrhs, None)
    }

    fn solve_to_residual(&mut self, b: &mut [f64], residual: f64) -> Result<(), SolverError> {
        self.solve_checked(b, 1, Some(residual))
    }

    fn solve_direction_in_place(&mut self, b: &mut [f64], nrhs: usize) -> Result<(), SolverError> {
        self.solve_direction(b, nrhs)
    }

    fn mixed_stats(&self) -> Option<MixedStats> {
        self.uses_mixed().then(|| FaerSolver::mixed_stats(self))
    }
}

impl FaerSolver {
    /// `solve_in_place` (`residual` None) or `solve_to_residual`: the right-hand sides
    /// checked, then the mixed solve (refined to the backward-error target or the residual
    /// bound) or the f64 one.
    fn solve_checked(
        &mut self,
        b: &mut [f64],
        nrhs: usize,
        residual: Option<f64>,
    ) -> Result<(), SolverError> {
        self.check_rhs(b, nrhs)?;
        if self.mixed.single_active() {
            self.solve_mixed(b, nrhs, residual)
        } else {
            self.solve_f64(b, nrhs)
        }
    }

    /// The f64 numeric factorisation of `a` into `l_values` (allocated if an f32 factor held
    /// its place), with pivot checks and inertia.
    fn factorize_double(&mut self, a: &SymmetricMatrix) -> Result<Factorization, SolverError> {
        if self.l_values.is_empty() {
            let len = self.symbolic.as_ref().map_or(0, |s| s.len_val());
            self.l_values = try_zeros(len, "the faer factor")?;
        }
        let par = self.kernel_par(a.n());
        let (Some(pattern), Some(symbolic), Some(buffer)) =
            (&self.pattern, &self.symbolic, &mut self.buffer)
        else {
            return Err(SolverError::NotReady("factorize called before analyze"));
        };
        // `a` was checked against the pattern (and for finite values) by `factorize`, the
        // only way here (directly, through the split's fallback or mixed precision's).
        self.factored = false;
        let permuted = match &mut self.permuted {
            Some(p) => p,
            slot => slot.insert(permuted::Permuted::new(pattern, symbolic)?),
        };
        let stack = MemStack::new(buffer);
        let simplicial = matches!(symbolic.raw(), SymbolicCholeskyRaw::Simplicial(_));
        match self.mode {
            FaerMode::Ldlt => permuted
                .ldlt_f64(symbolic, a.values(), &mut self.l_values, par, stack)
                .map_err(|e| match e {
                    faer::linalg::cholesky::ldlt::factor::LdltError::ZeroPivot { index } => {
                        let index = pivot_position(simplicial, index);
                        let dof = permuted.forward().get(index).copied();
                        SolverError::ZeroPivot {
                            equation: index,
                            dof: dof.unwrap_or(index),
                            pivot: 0.0,
                            diagonal: dof.map_or(0.0, |d| a.get(d, d).abs()),
                        }
                    }
                })?,
            FaerMode::Llt => permuted
                .llt_f64(symbolic, a.values(), &mut self.l_values, par, stack)
                .map_err(|e| match e {
                    faer::linalg::cholesky::llt::factor::LltError::NonPositivePivot { index } => {
                        let index = pivot_position(simplicial, index);
                        SolverError::NotPositiveDefinite {
                            equation: index,
                            dof: permuted.forward().get(index).copied().unwrap_or(index),
                        }
                    }
                })?,
        }
        let perm_fwd = permuted.forward();
        // Pivot checks and inertia from the factor's diagonal (D, or L_kk with d_k = L_kk²).
        let llt = self.mode == FaerMode::Llt;
        let pivots = factor_diagonal(symbolic, &self.l_values)
            .into_iter()
            .map(|v| if llt { v * v } else { v });
        let rule = pivots::PivotRule::Double {
            tolerance: self.tolerance,
        };
        let negative = pivots::negative_pivots(pivots, 0, |k| perm_fwd[k], &a.diagonal(), rule)?
            .unwrap_or_else(|_| unreachable!("f64 pivots are errors, not fallbacks"));
        self.factored = true;
        if !self.uses_mixed() {
            self.copy_for_directions()?;
        }
        Ok(Factorization {
            negative_pivots: negative,
            factor_entries: self.l_values.len(),
            flops: self.flops,
        })
    }

    /// The right-hand sides fit the factor and are finite, and a factor is there.
    fn check_rhs(&self, b: &[f64], nrhs: usize) -> Result<(), SolverError> {
        let (true, Some(symbolic)) = (self.factored, &self.symbolic) else {
            return Err(SolverError::NotReady(
                "solve called before a successful factorize",
            ));
        };
        let n = symbolic.nrows();
        if b.len() != n * nrhs {
            return Err(SolverError::DimensionMismatch {
                what: "right-hand sides",
                expected: n * nrhs,
                got: b.len(),
            });
        }
        if let Some(p) = b.iter().position(|v| !v.is_finite()) {
            return Err(SolverError::NonFinite {
                row: p % n.max(1),
                col: p / n.max(1),
                value: b[p],
            });
        }
        Ok(())
    }

    /// Solves with the f64 factor.
    fn solve_double(&mut self, b: &mut [f64], nrhs: usize) -> Result<(), SolverError> {
        let (Some(symbolic), Some(buffer)) = (&self.symbolic, &mut self.buffer) else {
            return Err(SolverError::NotReady("solve called before analyze"));
        };
        let n = symbolic.nrows();
        let _ = nrhs;
        for block in b.chunks_mut((n * RHS_BLOCK).max(1)) {
            let k = block.len() / n.max(1);
            let rhs = MatMut::from_column_major_slice_mut(block, n, k);
            let stack = MemStack::new(buffer);
            match self.mode {
                FaerMode::Ldlt => LdltRef::new(symbolic, &self.l_values).solve_in_place_with_conj(
                    Conj::No,
                    rhs,
                    SOLVE_PAR,
                    stack,
                ),
                FaerMode::Llt => LltRef::new(symbolic, &self.l_values).solve_in_place_with_conj(
                    Conj::No,
                    rhs,
                    SOLVE_PAR,
                    stack,
                ),
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests;
