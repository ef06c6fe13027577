//! One interface over the profile and faer solvers.

use crate::{SolverError, SymmetricMatrix, SymmetricPattern};
use std::sync::Arc;

/// What a symbolic analysis found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Analysis {
    /// Stored entries of the factor (envelope for the profile solver, L for faer).
    pub factor_entries: usize,
    /// Structural nonzeros of L's lower triangle, diagonal included (what PARDISO and CHOLMOD
    /// report; faer's supernodal storage also holds the upper half of each diagonal block and
    /// the zeros of merged supernodes, counted in `factor_entries`).
    pub lower_nonzeros: usize,
    /// Floating-point operations of one numeric factorisation (a multiply-add counts 2).
    pub flops: f64,
    /// Bandwidth after ordering (profile solver).
    pub bandwidth: Option<usize>,
    /// Profile (off-diagonal envelope entries) after ordering (profile solver).
    pub profile: Option<usize>,
    /// The fill-reducing ordering used: "RCM", "AMD", "nested dissection" or "METIS".
    pub ordering: &'static str,
    /// How the factor's work lies on its supernode tree (faer's supernodal factor; `None`
    /// for the profile solver and faer's simplicial factor of small systems).
    pub tree: Option<TreeWork>,
}

/// The work of a supernodal factor's elimination tree: what threads can make of it.
///
/// Tree-level parallelism runs independent subtrees side by side; a supernode waits for its
/// children. Its bound is W / cp ([`TreeWork::parallelism`]): with any number of threads
/// that only do that, a factorisation takes at least cp/W of its one-thread time. Threads
/// inside a supernode's dense blocks (faer's kernels) can beat it only on the wide
/// supernodes at the top of the tree, whose size `largest_supernode_flops` and `widest` show.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TreeWork {
    /// Supernodes (after faer's relaxed merging).
    pub supernodes: usize,
    /// Columns of the widest supernode.
    pub widest: usize,
    /// W: Σ c² over the factor's column counts (as [`Analysis::flops`] for the unsplit
    /// factor).
    pub flops: f64,
    /// cp: the largest Σ of supernode flops along a chain from a leaf to the root.
    pub critical_path_flops: f64,
    /// The flops of the costliest single supernode.
    pub largest_supernode_flops: f64,
}

impl TreeWork {
    /// W / cp: the most that tree-level parallelism can divide a factorisation's time by.
    pub fn parallelism(&self) -> f64 {
        if self.critical_path_flops > 0.0 {
            self.flops / self.critical_path_flops
        } else {
            1.0
        }
    }
}

/// What a numeric factorisation found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Factorization {
    /// Negative pivots = negative eigenvalues of the matrix (Sylvester's law of inertia). For
    /// a tangent stiffness it changes where the equilibrium path bifurcates or turns.
    pub negative_pivots: usize,
    /// Stored entries of the factor.
    pub factor_entries: usize,
    /// Floating-point operations spent.
    pub flops: f64,
}

/// A sparse symmetric direct solver: symbolic analysis once per pattern, numeric factorisation
/// for every new set of values, then any number of solves.
pub trait LinearSolver: Send {
    /// A short name for reports.
    fn name(&self) -> &'static str;
    /// Orders the equations and sets up the factor's structure for `pattern`.
    fn analyze(&mut self, pattern: &Arc<SymmetricPattern>) -> Result<Analysis, SolverError>;
    /// [`analyze`](Self::analyze) for a pattern grown from the one analysed last (the same
    /// equations, a few more couplings: a contact reserve that grew), making the choices the
    /// last analysis made instead of making them again where the solver makes any
    /// ([`crate::FaerOrdering::Auto`]'s comparison of orders). By default `analyze`.
    fn reanalyze(&mut self, pattern: &Arc<SymmetricPattern>) -> Result<Analysis, SolverError> {
        self.analyze(pattern)
    }
    /// Factors `a`, which must be on the analysed pattern; reports the inertia. After an
    /// error (a NaN in `a`, a zero pivot) no earlier factor is to be solved with: factor
    /// again first (`FaerSolver` refuses such solves; Newton's caches drop their tangent).
    fn factorize(&mut self, a: &SymmetricMatrix) -> Result<Factorization, SolverError>;
    /// Overwrites the `nrhs` column-major right-hand sides in `b` (n·nrhs values) with A⁻¹b.
    fn solve_in_place(&mut self, b: &mut [f64], nrhs: usize) -> Result<(), SolverError>;
    /// Overwrites the one right-hand side `b` with a solution x whose residual only has to be
    /// small in `b`'s own units: ‖b − A x‖∞ ≤ `residual` (a Newton correction, judged by the
    /// force it leaves unbalanced against Newton's force tolerance). A solver that refines a
    /// low-precision solution ([`crate::FaerPrecision::Mixed`]) stops there, or at its own
    /// backward-error target if that comes first; by default the exact solve.
    fn solve_to_residual(&mut self, b: &mut [f64], residual: f64) -> Result<(), SolverError> {
        let _ = residual;
        self.solve_in_place(b, 1)
    }
    /// Overwrites `b` with an approximation of A⁻¹b, for solves whose result only has to be
    /// close (a search direction: BFGS's H₀ = K₀⁻¹ on a kept tangent), never for an answer.
    /// By default the exact solve; [`crate::FaerSolver`] with
    /// [`crate::FaerDirections::Single`] uses an f32 copy of its factor (relative error about
    /// cond(A)·6e-8).
    fn solve_direction_in_place(&mut self, b: &mut [f64], nrhs: usize) -> Result<(), SolverError> {
        self.solve_in_place(b, nrhs)
    }
    /// What mixed precision did since the last `analyze` (f32 factorisations kept, f64
    /// fall-backs, refinement steps); `None` for a solver that factorises in f64 only.
    fn mixed_stats(&self) -> Option<crate::MixedStats> {
        None
    }
}

/// The solvers nonlin3d ships, by name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SolverKind {
    /// [`crate::ProfileLdlt`] with reverse Cuthill–McKee.
    Profile,
    /// [`crate::FaerSolver`] LDLᵀ, ordered by AMD or nested dissection (whichever needs fewer
    /// flops, [`crate::FaerOrdering::Auto`]), numeric phase on as many threads as the current
    /// rayon pool has (`--threads N` sets the pool): the default. Measured faster than the
    /// profile solver from about 450 equations on, 2.7× at 11 k and 3–4× at 50–140 k DOF
    /// (docs/PERFORMANCE.md); the profile solver wins only on tiny systems (153 DOF: 3×).
    #[default]
    FaerLdlt,
    /// [`crate::FaerSolver`] LLᵀ (ordering and threads as `FaerLdlt`): positive definite
    /// matrices only.
    FaerLlt,
    /// [`crate::FaerSolver`] LDLᵀ (ordering as `FaerLdlt`), numeric phase on this many rayon
    /// threads (1: sequential): the split's two halves side by side from
    /// [`crate::SPLIT_FROM_DOFS`], faer's own kernels threaded from
    /// [`crate::KERNEL_THREADS_FROM_DOFS`]. The same bits for any thread count: threads split
    /// the output tiles of each dense block, never a sum, and the split is decided by size
    /// (tests/threads.rs, [`crate::FaerSolver::par`]).
    FaerLdltThreads(usize),
    /// [`crate::FaerSolver`] LDLᵀ (ordering as `FaerLdlt`) with an f32 factor refined in f64
    /// ([`crate::FaerPrecision::mixed`]), on this many threads (0: the rayon pool's). About
    /// half the factor time and memory where f32 suffices (45 k cube, 89 k plate); on thin
    /// laminates it falls back to f64 and costs more (docs/PERFORMANCE.md).
    FaerLdltMixed(usize),
    /// `FaerLdltMixed` from [`crate::MIXED_FROM_DOFS`] DOFs on, `FaerLdltThreads` below (this
    /// many threads, 0: the rayon pool's): the default of scenes solved by full Newton, where
    /// each factorisation serves one solve.
    FaerLdltAuto(usize),
    /// `FaerLdltMixed` from [`crate::KEPT_MIXED_FROM_DOFS`] DOFs on, `FaerLdltThreads` below
    /// (this many threads, 0: the rayon pool's), f32 retried at the next factorisation after
    /// it was given up ([`crate::KEPT_RETRY_F32_AFTER`]): for paths that keep a factorisation
    /// over many directions (BFGS, modified Newton; `nonlin3d solve`'s `auto`), where each
    /// direction needs one f32 solve and one f64 product (`nonlin3d_newton::KEPT_FORCING`).
    FaerLdltKept(usize),
}

impl SolverKind {
    /// A boxed solver of this kind with default settings.
    pub fn build(self) -> Box<dyn LinearSolver> {
        match self {
            Self::Profile => Box::new(crate::ProfileLdlt::new()),
            Self::FaerLdlt => Box::new(
                crate::FaerSolver::new(crate::FaerMode::Ldlt)
                    .with_threads(rayon::current_num_threads()),
            ),
            Self::FaerLlt => Box::new(
                crate::FaerSolver::new(crate::FaerMode::Llt)
                    .with_threads(rayon::current_num_threads()),
            ),
            Self::FaerLdltThreads(n) => {
                Box::new(crate::FaerSolver::new(crate::FaerMode::Ldlt).with_threads(n))
            }
            Self::FaerLdltMixed(n) | Self::FaerLdltAuto(n) | Self::FaerLdltKept(n) => {
                let threads = if n == 0 {
                    rayon::current_num_threads()
                } else {
                    n
                };
                let mut s = crate::FaerSolver::new(crate::FaerMode::Ldlt).with_threads(threads);
                s.precision = crate::FaerPrecision::mixed();
                match self {
                    Self::FaerLdltAuto(_) => s.mixed_from_dofs = crate::MIXED_FROM_DOFS,
                    Self::FaerLdltKept(_) => {
                        s.mixed_from_dofs = crate::KEPT_MIXED_FROM_DOFS;
                        s.retry_f32_after = crate::KEPT_RETRY_F32_AFTER;
                    }
                    _ => {}
                }
                Box::new(s)
            }
        }
    }
}

/// Analyse, factor and solve A x = b in one call (for one-off systems).
pub fn solve(
    kind: SolverKind,
    a: &SymmetricMatrix,
    b: &[f64],
) -> Result<(Vec<f64>, Factorization), SolverError> {
    let mut s = kind.build();
    s.analyze(a.pattern())?;
    let f = s.factorize(a)?;
    let mut x = b.to_vec();
    s.solve_in_place(&mut x, 1)?;
    Ok((x, f))
}
