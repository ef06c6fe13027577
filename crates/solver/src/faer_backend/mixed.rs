//! Mixed precision for [`FaerSolver`] (issue 20): the LDLᵀ factor in f32 (half the memory,
//! dense kernels about twice as fast), each solution refined in f64 (iterative refinement:
//! x ← x + L̃⁻ᵀD̃⁻¹L̃⁻¹(b − A x) with the f32 factor L̃D̃L̃ᵀ ≈ A, the residual in f64; each step
//! multiplies the error by about cond(A)·ε₃₂), and the f64 factor whenever the f32 one is in
//! doubt:
//!
//! - an entry of A does not fit f32, or f32 elimination meets a zero pivot;
//! - a pivot |d̃_k| falls below [`SINGLE_PIVOT_FLOOR`]·|a_kk| (or the floor given): f32 rounding perturbs d_k by
//!   about ε₃₂·|a_kk| times the growth, so the sign of a smaller one is not trusted;
//! - the negative pivot count differs from the previous factorisation's (any precision): the
//!   inertia the path following reads (thesis §3, Sylvester's law) changes only on an f64
//!   factor, and the next f32 factor must agree with it to be used;
//! - refinement stalls (the backward error falls by less than half in a step) or has not
//!   reached the tolerance in [`MAX_REFINEMENT_STEPS`] (cond(A)·ε₃₂ ≳ 0.5), and conjugate
//!   gradients preconditioned by the f32 factor (when all its pivots are positive) do not
//!   reach it in [`MAX_CONJUGATE_GRADIENT_STEPS`] either: A is too ill-conditioned for f32;
//! - f32 was refused for one of the conditioning reasons above before any f32 factor served
//!   since the analysis, or [`REFUSALS_BEFORE_F64`] times in a row: f64 for the next
//!   [`RETRY_F32_AFTER`] factorisations, then f32 is tried once more (the wait doubled each
//!   time the retry is refused, reset when an f32 factor serves).
//!
//! With [`super::FaerSplit::Halves`] the f32 factor is the split one (f32 halves, S in f64)
//! and the same rules hold; the f64 fallback is then the f64 split.

use super::pivots::{Attempt, PivotRule, negative_pivots};
use super::{FaerSolver, factor_diagonal};
use crate::{Factorization, SolverError, SymmetricMatrix};
use faer::dyn_stack::{MemStack, StackReq};
use faer::sparse::linalg::cholesky::{LdltRef, SymbolicCholesky};
use faer::{Conj, MatMut, Par};

mod refine;
pub use refine::{
    MAX_CONJUGATE_GRADIENT_STEPS, MAX_REFINEMENT_STEPS, TRUSTED_SHARE, UNCHECKED_IN_A_ROW,
};
use refine::{System, Target, Trust, solve_column};

/// f32 pivots smaller than this fraction of their diagonal entry send the factorisation to
/// f64 (about 800 ε₃₂: the sign of such a pivot could be rounding's).
pub const SINGLE_PIVOT_FLOOR: f64 = 1e-4;

/// f32 attempts refused in a row for the matrix's conditioning (any reason but a change of
/// the negative pivot count: an entry beyond f32, an f32 zero pivot, a pivot below the floor,
/// refinement stalling) after which the solver factorises in f64 for a while
/// ([`RETRY_F32_AFTER`]): a tangent too ill-conditioned for f32 stays so over a path, and each
/// refused attempt costs an f32 factorisation (and refinement steps) on top of the f64 one
/// (the thin laminate: 1.6–1.7× the f64 cost, docs/PERFORMANCE.md). One refusal after f32
/// has served (a small pivot near a bifurcation) does not give f32 up; a refusal before any
/// f32 factor has served does.
pub const REFUSALS_BEFORE_F64: usize = 2;

/// f64 factorisations after f32 was given up ([`REFUSALS_BEFORE_F64`]) before f32 is tried
/// again; doubled after each retry that is refused, so a tangent that stays too
/// ill-conditioned for f32 (the thin laminate) pays one f32 attempt (about half an f64
/// factorisation) after 8, 16, 32, … f64 ones, and one refused early (a small pivot at the
/// first state past a bifurcation) does not keep a whole run in f64: the 60 mm circle on the
/// default mesh, refused at its first factorisation, factored 68 times in f64 before.
pub const RETRY_F32_AFTER: usize = 8;

/// The reason an f64 factorisation is made while f32 is given up.
const GIVEN_UP: &str = "f32 refused before it served, or twice in a row: f64 for a while";

/// The default refinement target for the normwise backward error
/// ‖b − A x‖∞ / (‖A‖∞‖x‖∞ + ‖b‖∞). The f64 factor gives 2e-19–3e-16 on the bench's Hex20
/// matrices (docs/PERFORMANCE.md); 1e-14 is six orders below Newton's default force tolerance
/// (1e-8 of the largest force), so the iterations see the same residuals.
pub const DEFAULT_REFINEMENT_TOLERANCE: f64 = 1e-14;

/// The precision of [`FaerSolver`]'s factor.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum FaerPrecision {
    /// f64 factor, direct solves (the default).
    #[default]
    Double,
    /// f32 factor, solutions refined in f64 until the normwise backward error is at most
    /// `tolerance`; f64 factor when the f32 one is in doubt (module docs). LDLᵀ only: an
    /// LLᵀ solver ignores it.
    Mixed {
        /// Target of ‖b − A x‖∞ / (‖A‖∞‖x‖∞ + ‖b‖∞).
        tolerance: f64,
        /// f32 pivots below this fraction of their diagonal entry send the factorisation to
        /// f64 (`SINGLE_PIVOT_FLOOR` = 1e-4 by default).
        pivot_floor: f64,
    },
}

impl FaerPrecision {
    /// Mixed precision refined to a normwise backward error of 1e-14 (`DEFAULT_REFINEMENT_TOLERANCE`).
    pub fn mixed() -> Self {
        Self::Mixed {
            tolerance: DEFAULT_REFINEMENT_TOLERANCE,
            pivot_floor: SINGLE_PIVOT_FLOOR,
        }
    }
}

/// What mixed precision did since the last `analyze`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MixedStats {
    /// Factorisations kept in f32.
    pub single_factorizations: usize,
    /// Factorisations done (or redone) in f64.
    pub double_factorizations: usize,
    /// Refinement steps over all solves (one f32 solve and one f64 product each).
    pub refinement_steps: usize,
    /// Of those, the steps of conjugate gradients where refinement stalled.
    pub conjugate_gradient_steps: usize,
    /// f32 solves to a residual bound taken without the f64 product that checks them: the
    /// factor's checked solves met such bounds with room to spare ([`TRUSTED_SHARE`],
    /// [`UNCHECKED_IN_A_ROW`]).
    pub unchecked_solves: usize,
    /// The backward error the last checked solution reached.
    pub last_backward_error: f64,
    /// Why the last f64 factorisation was made, if one was.
    pub last_fallback: Option<&'static str>,
}

impl MixedStats {
    /// These stats followed by `later`'s (another analysis of the same system): the counts
    /// summed, the last backward error and fall-back the later ones (this one's fall-back if
    /// the later made none).
    pub fn then(self, later: MixedStats) -> MixedStats {
        MixedStats {
            single_factorizations: self.single_factorizations + later.single_factorizations,
            double_factorizations: self.double_factorizations + later.double_factorizations,
            refinement_steps: self.refinement_steps + later.refinement_steps,
            conjugate_gradient_steps: self.conjugate_gradient_steps
                + later.conjugate_gradient_steps,
            unchecked_solves: self.unchecked_solves + later.unchecked_solves,
            last_backward_error: later.last_backward_error,
            last_fallback: later.last_fallback.or(self.last_fallback),
        }
    }
}

/// Why an f32 factor whose inertia differs from the last factorisation's is not used (the
/// one refusal that says nothing about the matrix's conditioning).
const PIVOT_COUNT_CHANGED: &str = "the negative pivot count changed";

/// The f32 factor and what refinement needs.
#[derive(Debug, Default)]
pub(super) struct MixedState {
    pub(super) l32: Vec<f32>,
    len: usize,
    /// The last factorised matrix (f64), for residuals and the f64 fallback.
    a: Option<SymmetricMatrix>,
    a_norm: f64,
    /// max |a_ij| of that matrix.
    a_max: f64,
    /// ‖A‖∞'s row sums (kept between factorisations).
    rows: Vec<f64>,
    /// The active factor is the f32 one.
    single: bool,
    last_negative: Option<usize>,
    /// f32 attempts refused for conditioning since the last one kept whose solves converged.
    refused_in_a_row: usize,
    /// Whether an f32 factor has served a converged refinement since the analysis.
    served: bool,
    /// f64 factorisations since f32 was given up or last retried.
    given_up_for: usize,
    /// f64 factorisations to wait before the next retry (0: [`RETRY_F32_AFTER`]).
    wait: usize,
    /// How far the active f32 factor's solves may go unchecked (reset with each factor).
    trust: Trust,
    stats: MixedStats,
}

impl MixedState {
    /// Forgets everything; room for an unsplit f32 factor of `len` entries, now if
    /// `allocate` (else when first needed).
    pub(super) fn reset(&mut self, len: usize, allocate: bool) -> Result<(), SolverError> {
        *self = Self::default();
        self.len = len;
        if allocate {
            self.l32 = try_zeros_f32(len)?;
        }
        Ok(())
    }

    pub(super) fn single_active(&self) -> bool {
        self.single
    }

    /// Counts an f32 attempt refused for conditioning ([`REFUSALS_BEFORE_F64`]): before any f32
    /// factor has served, one is enough.
    fn refuse(&mut self) {
        self.refused_in_a_row = match self.served {
            true => self.refused_in_a_row + 1,
            false => REFUSALS_BEFORE_F64,
        };
    }

    /// While f32 is given up: whether this factorisation retries it (after `first_wait` f64
    /// ones, [`RETRY_F32_AFTER`] by default, the wait doubling at each retry), else counts it
    /// as one more in f64.
    fn retry_now(&mut self, first_wait: usize) -> bool {
        let wait = if self.wait == 0 {
            first_wait
        } else {
            self.wait
        };
        if self.given_up_for < wait {
            self.given_up_for += 1;
            return false;
        }
        self.given_up_for = 0;
        self.wait = 2 * wait;
        true
    }

    /// An f32 factor served: f32 is in use again, and a later give-up waits
    /// [`RETRY_F32_AFTER`] afresh.
    fn served_now(&mut self) {
        self.refused_in_a_row = 0;
        self.served = true;
        self.given_up_for = 0;
        self.wait = 0;
    }
}

/// Scratch of the f32 factorisation and of one f32 solve.
pub(super) fn scratch(symbolic: &SymbolicCholesky<usize>, par: Par) -> StackReq {
    super::permuted::kernel_scratch::<f32>(symbolic, true, par)
        .or(symbolic.solve_in_place_scratch::<f32>(1, par))
}

pub(super) fn try_zeros_f32(len: usize) -> Result<Vec<f32>, SolverError> {
    let mut v = Vec::new();
    v.try_reserve_exact(len)
        .map_err(|_| SolverError::OutOfMemory {
            what: "the f32 faer factor",
            bytes: len.saturating_mul(4),
        })?;
    v.resize(len, 0.0);
    Ok(v)
}

/// One pass over A's values for an f32 factorisation, each read once: copies them into
/// `copy`, sums |a_ij| by row into `rows` for ‖A‖∞ (row i takes column j's |a_ij| in
/// increasing j, then its own column's in increasing row) and finds max |a_ij| (whether A
/// fits f32). Returns (‖A‖∞, max |a_ij|); a NaN or infinite value is
/// [`SolverError::NonFinite`], named as [`SymmetricMatrix::check_finite`] names it.
fn take_values(
    a: &SymmetricMatrix,
    copy: &mut [f64],
    rows: &mut Vec<f64>,
) -> Result<(f64, f64), SolverError> {
    let p = a.pattern();
    rows.clear();
    rows.resize(p.n(), 0.0);
    let (cp, ri, v) = (p.col_ptr(), p.row_idx(), a.values());
    let mut largest = 0.0f64;
    let mut finite = true;
    for j in 0..p.n() {
        let (s, e) = (cp[j], cp[j + 1]);
        // Row j's sum so far, then its own column's values in order (the diagonal first).
        let mut own = rows[j];
        for ((&i, &x), c) in ri[s..e].iter().zip(&v[s..e]).zip(&mut copy[s..e]) {
            *c = x;
            let m = x.abs();
            finite &= m.is_finite();
            largest = largest.max(m);
            own += m;
            if i != j {
                rows[i] += m;
            }
        }
        rows[j] = own;
    }
    if !finite {
        a.check_finite()?;
    }
    Ok((rows.iter().copied().fold(0.0, f64::max), largest))
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |m, x| m.max(x.abs()))
}

impl FaerSolver {
    /// What mixed precision did since the last `analyze`.
    pub fn mixed_stats(&self) -> MixedStats {
        self.mixed.stats
    }

    /// Factorises `a` (pattern already checked) in f32 if it can be trusted (module docs),
    /// else in f64.
    pub(super) fn factorize_mixed(
        &mut self,
        a: &SymmetricMatrix,
    ) -> Result<Factorization, SolverError> {
        self.mixed.single = false;
        if self.mixed.refused_in_a_row >= REFUSALS_BEFORE_F64
            && !self.mixed.retry_now(self.retry_f32_after)
        {
            // f64 for now: no copy of A for refinement is needed.
            a.check_finite()?;
            return self.fall_back(a, GIVEN_UP);
        }
        let mixed = &mut self.mixed;
        let copy = match &mut mixed.a {
            Some(m) if std::sync::Arc::ptr_eq(m.pattern(), a.pattern()) => m,
            slot => slot.insert(SymmetricMatrix::try_zeros(a.pattern().clone())?),
        };
        (mixed.a_norm, mixed.a_max) = take_values(a, copy.values_mut(), &mut mixed.rows)?;
        match self.factorize_single(a)? {
            Ok(f) => Ok(f),
            Err(reason) => {
                if reason != PIVOT_COUNT_CHANGED {
                    self.mixed.refuse();
                }
                self.fall_back(a, reason)
            }
        }
    }

    /// The f64 factor of `a` (split if the analysis split), because of `reason`; frees the
    /// unsplit f32 one first.
    fn fall_back(
        &mut self,
        a: &SymmetricMatrix,
        reason: &'static str,
    ) -> Result<Factorization, SolverError> {
        self.mixed.l32 = Vec::new();
        self.mixed.single = false;
        // The analysis budgeted the f32 factor; the f64 one (twice its size) is checked now,
        // with the f32 one freed and the matrices already counted as in use: an error naming
        // the size and the limit, not an abort in the allocation.
        if self.split_state.is_none() && self.l_values.is_empty() {
            crate::budget::Need {
                what: "faer LDLᵀ factor in f64 (mixed precision's fall-back)",
                entries: self.mixed.len,
                factor_bytes: self.mixed.len.saturating_mul(std::mem::size_of::<f64>()),
                workspace_bytes: 0,
                matrix_bytes: 0,
            }
            .check(crate::budget::current_budget(self.memory_budget.as_ref()))?;
        }
        self.mixed.stats.last_fallback = Some(reason);
        self.mixed.stats.double_factorizations += 1;
        self.mixed.last_negative = None;
        let f = self.factorize_f64(a)?;
        self.mixed.last_negative = Some(f.negative_pivots);
        Ok(f)
    }

    /// The f32 factorisation (split or not) of `a`, read by [`take_values`] just before:
    /// `Ok(Err(reason))` when it cannot be trusted.
    fn factorize_single(&mut self, a: &SymmetricMatrix) -> Attempt<Factorization> {
        if self.mixed.a_max > f64::from(f32::MAX) {
            return Ok(Err("an entry does not fit f32"));
        }
        let rule = PivotRule::Single {
            tolerance: self.tolerance,
            floor: match self.precision {
                FaerPrecision::Mixed { pivot_floor, .. } => pivot_floor,
                FaerPrecision::Double => 0.0,
            },
        };
        let kernel = self.kernel_par(a.n());
        let done = match self.split_state.as_mut() {
            Some(split) => split.factorize::<f32>(a, self.par, kernel, rule, self.flops)?,
            None => self.factorize_single_unsplit(a, rule)?,
        };
        let f = match done {
            Ok(f) => f,
            Err(reason) => return Ok(Err(reason)),
        };
        if self
            .mixed
            .last_negative
            .is_some_and(|last| last != f.negative_pivots)
        {
            return Ok(Err(PIVOT_COUNT_CHANGED));
        }
        // The f64 factor, if a fallback made one, is not needed now.
        self.l_values = Vec::new();
        self.mixed.single = true;
        self.mixed.trust = Trust::default();
        self.mixed.last_negative = Some(f.negative_pivots);
        self.mixed.stats.single_factorizations += 1;
        self.factored = true;
        Ok(Ok(f))
    }

    /// faer's f32 factorisation of the whole of `a`, its pivots judged by `rule`.
    fn factorize_single_unsplit(
        &mut self,
        a: &SymmetricMatrix,
        rule: PivotRule,
    ) -> Attempt<Factorization> {
        if self.mixed.l32.len() != self.mixed.len {
            self.mixed.l32 = try_zeros_f32(self.mixed.len)?;
        }
        let kernel = self.kernel_par(a.n());
        let (Some(pattern), Some(symbolic), Some(buffer)) =
            (&self.pattern, &self.symbolic, &mut self.buffer)
        else {
            return Err(SolverError::NotReady("factorize called before analyze"));
        };
        let permuted = match &mut self.permuted {
            Some(p) => p,
            slot => slot.insert(super::permuted::Permuted::new(pattern, symbolic)?),
        };
        // A rounded to f32 through the order's gather map (rounding and copying commute: the
        // same bits as rounding A, then permuting).
        if permuted
            .ldlt_f32(
                symbolic,
                a.values(),
                &mut self.mixed.l32,
                kernel,
                MemStack::new(buffer),
            )
            .is_err()
        {
            return Ok(Err("f32 elimination met a zero pivot"));
        }
        let perm_fwd = permuted.forward();
        let pivots = factor_diagonal(symbolic, &self.mixed.l32);
        Ok(
            negative_pivots(pivots, 0, |k| perm_fwd[k], &a.diagonal(), rule)?.map(|negative| {
                Factorization {
                    negative_pivots: negative,
                    factor_entries: self.mixed.len,
                    flops: self.flops,
                }
            }),
        )
    }

    /// Solves with the f32 factor and refines each column in f64, to the backward-error
    /// target or, with `residual`, until ‖b − A x‖∞ ≤ `residual` if that comes first; on a
    /// stall, factorises in f64 and solves directly.
    pub(super) fn solve_mixed(
        &mut self,
        b: &mut [f64],
        nrhs: usize,
        residual: Option<f64>,
    ) -> Result<(), SolverError> {
        let original = b.to_vec();
        let n = b.len() / nrhs.max(1);
        let mut stalled = false;
        for col in b.chunks_mut(n.max(1)) {
            if !self.refine(col, residual)? {
                stalled = true;
                break;
            }
        }
        if !stalled {
            self.mixed.served_now();
        } else {
            self.mixed.refuse();
            let Some(a) = self.mixed.a.take() else {
                return Err(SolverError::NotReady("solve called before factorize"));
            };
            let why = match self.mixed.last_negative {
                Some(0) => "refinement and conjugate gradients stalled",
                _ => "refinement stalled",
            };
            let done = self.fall_back(&a, why);
            self.mixed.a = Some(a);
            done?;
            self.factored = true;
            b.copy_from_slice(&original);
            return self.solve_f64(b, nrhs);
        }
        Ok(())
    }

    /// Iterative refinement of one column in place with the f32 factor (split or not);
    /// `false` if it stalled.
    fn refine(&mut self, col: &mut [f64], residual: Option<f64>) -> Result<bool, SolverError> {
        let FaerPrecision::Mixed { tolerance, .. } = self.precision else {
            return Ok(false);
        };
        let target = Target {
            backward_error: tolerance,
            residual: residual.unwrap_or(0.0),
        };
        let Some(a) = &self.mixed.a else {
            return Err(SolverError::NotReady("solve called before factorize"));
        };
        let system = System {
            a,
            a_norm: self.mixed.a_norm,
            target,
            definite: self.mixed.last_negative == Some(0),
        };
        let (par, stats, trust) = (self.par, &mut self.mixed.stats, &mut self.mixed.trust);
        if let Some(split) = self.split_state.as_mut().filter(|s| s.is_factored()) {
            // The split's solve reads its f32 halves into f64 sums: no scaling needed.
            let correct = |r: &mut [f64]| split.solve_column(r, par);
            return solve_column(col, system, stats, trust, correct);
        }
        let (Some(symbolic), Some(buffer)) = (&self.symbolic, &mut self.buffer) else {
            return Err(SolverError::NotReady("solve called before factorize"));
        };
        let factor = LdltRef::<usize, f32>::new(symbolic, &self.mixed.l32);
        let mut c = vec![0.0f32; col.len()];
        let correct = |r: &mut [f64]| {
            // The correction in f32, scaled to ‖r‖∞ = 1 so small residuals do not underflow.
            let scale = max_abs(r);
            for (ci, ri) in c.iter_mut().zip(r.iter()) {
                *ci = (ri / scale) as f32;
            }
            let n = c.len();
            factor.solve_in_place_with_conj(
                Conj::No,
                MatMut::from_column_major_slice_mut(&mut c, n, 1),
                super::SOLVE_PAR,
                MemStack::new(buffer),
            );
            for (ri, ci) in r.iter_mut().zip(&c) {
                *ri = f64::from(*ci) * scale;
            }
        };
        solve_column(col, system, stats, trust, correct)
    }
}

#[cfg(test)]
mod tests;
