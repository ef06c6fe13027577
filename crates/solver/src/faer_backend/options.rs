//! The options of [`super::FaerSolver`]: factorisation, factor structure, fill-reducing
//! ordering and the tree-level split (the precision is in `mixed.rs`, beside the refinement
//! it controls).

/// Which factorisation faer computes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FaerMode {
    /// LDLᵀ without pivoting: positive definite and indefinite matrices, inertia from D.
    #[default]
    Ldlt,
    /// Cholesky LLᵀ: positive definite only; a non-positive pivot is
    /// [`crate::SolverError::NotPositiveDefinite`].
    Llt,
}

/// Simplicial (column by column) or supernodal (dense blocks) factor structure.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FaerStructure {
    /// faer decides from the flop count (the default): simplicial for small or very sparse
    /// factors, supernodal otherwise.
    #[default]
    Auto,
    /// Always simplicial.
    Simplicial,
    /// Always supernodal.
    Supernodal,
}

/// The fill-reducing ordering of the faer backend.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FaerOrdering {
    /// Approximate minimum degree (faer's port of SuiteSparse AMD) on the DOF graph.
    Amd,
    /// Nested dissection on the node graph ([`crate::nested_dissection`]).
    NestedDissection,
    /// METIS's nested dissection on the node graph ([`crate::metis_nested_dissection`]).
    Metis,
    /// The candidates' symbolic factors compared by flops (Σ c_k² over the column counts),
    /// the fewest kept (ties: AMD, then nested dissection, then METIS). The default. Below
    /// [`AUTO_WITHOUT_AMD_DOFS`] DOFs the candidates are AMD, nested dissection and METIS;
    /// AMD is left out from it on (AMD needed 1.4–2.1× the best one's flops on every
    /// analysis measured from 4 263 DOF up — the scene plates, their contact systems and the
    /// clamped-plate decks — and 1.6–6× on the cubes and laminates from 10 k DOF, so its
    /// analysis was time spent for nothing; neither nested dissection nor METIS was always
    /// the better: docs/PERFORMANCE.md). A METIS failure only removes it from the comparison. From
    /// [`AUTO_METIS_ONLY_DOFS`] DOFs on, METIS alone (nested dissection if METIS fails).
    #[default]
    Auto,
}

impl FaerOrdering {
    /// The name reports use ("AMD", "nested dissection", "METIS"; "auto" before a choice).
    pub fn name(self) -> &'static str {
        match self {
            Self::Amd => "AMD",
            Self::NestedDissection => "nested dissection",
            Self::Metis => "METIS",
            Self::Auto => "auto",
        }
    }
}

/// From this many DOFs on, [`FaerOrdering::Auto`] leaves AMD out of its comparison. Measured
/// on every analysis of the example scenes and the clamped-plate decks (docs/PERFORMANCE.md,
/// "Setup, ParaView, and two separator-stopping factorisations tried"): AMD had the fewest
/// flops in 18 of 21 analyses up to 3 951 DOF (down to 0.53 of the others', the through-width
/// strip) and in none of 14 from 4 263 DOF on (1.4–2.1× the best), where its ordering and
/// symbolic factor cost 9–23 ms an analysis.
pub const AUTO_WITHOUT_AMD_DOFS: usize = 5_000;

/// From this many DOFs on, [`FaerOrdering::Auto`] takes METIS's order without comparing it
/// with our nested dissection's (which it uses only if METIS fails). Measured
/// (docs/PERFORMANCE.md, "METIS alone from 10 000 DOF"): METIS had the fewer flops on every
/// scene mesh from 10 k DOF (by 7–16 % at 13.5–18.4 k DOF, the error-estimate companions'
/// contact systems below 10 k excepted) and on 5 of the 6 bench models (by 1–21 %); our
/// nested dissection won two boxes by 1.7 % and 2.4 %. Its analysis cost 1.6–1.7× METIS's
/// (0.13–0.14 s against 0.08 s at 18 k DOF; in the bench table, loaded, 3.0 against 1.9 s at
/// 45 k DOF).
pub const AUTO_METIS_ONLY_DOFS: usize = 10_000;

/// Whether [`super::FaerSolver`]'s LDLᵀ splits the matrix at the nested-dissection order's top
/// separator and factors the two halves on two threads (tree-level parallelism, `split.rs`).
///
/// The split is a property of the matrix, not of the thread count: a split factor gives the
/// same bits on one thread (the halves one after the other) as on two, so `Auto` decides by
/// size alone and the results stay bitwise identical for any `--threads`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FaerSplit {
    /// One faer factorisation.
    Off,
    /// Split whenever the chosen ordering is nested dissection (ours or METIS's) and its top
    /// level was dissected into halves of at least a fifth of the interior each (LDLᵀ only:
    /// LLᵀ ignores it). In f64 it falls back to the unsplit factor when
    /// a half's separator block meets a pivot below 1e-8 of its diagonal; with
    /// [`FaerPrecision::Mixed`](super::FaerPrecision::Mixed) the halves are f32, the split solve is refined in f64, and
    /// every fallback of mixed precision goes to the f64 split (then to the unsplit factor).
    Halves,
    /// `Halves` from [`SPLIT_FROM_DOFS`] DOFs on, `Off` below (the default). Measured on two
    /// cores (docs/PERFORMANCE.md, "The split by default"): the factorisation's wall time
    /// 0.56× the unsplit one's at 10.7 k DOF, whole runs 0.71–0.92× at 6.8–24 k DOF (scenes
    /// and decks); on one thread the split costs its separator again (each half factors it,
    /// S′ᵢ is rebuilt and S factored), +4–10 % of a run's CPU time.
    #[default]
    Auto,
}

/// From this many DOFs on, [`FaerSplit::Auto`] splits. Below it the runs measured gained
/// nothing from the split (3.4 k DOF: the same wall time on two cores) and the companion
/// meshes of the error estimate (1.8–6.4 k DOF) run beside a main model on the other core.
pub const SPLIT_FROM_DOFS: usize = 5_000;

/// From this many DOFs on, [`crate::SolverKind::FaerLdltAuto`] factorises in f32 (refined in
/// f64, [`super::FaerPrecision::mixed`]); below it in f64. Measured on the committed scenes
/// (docs/PERFORMANCE.md, "Mixed precision from 10 000 DOF"): at 13.5–18.4 k DOF the f32 factor
/// took 0.86–0.92 of the wall time and 0.81–0.88 of the CPU, the same answers; at 6.8 k DOF
/// and below it gained 0–9 % on five scenes and lost 4–10 % on four (thin sublaminates whose
/// first f32 factor is refused, the 3.4 k through-width strip, the 2.8 k thin film).
pub const MIXED_FROM_DOFS: usize = 10_000;

/// From this many DOFs on, [`crate::SolverKind::FaerLdltKept`] factorises in f32: paths that
/// keep a factorisation over many directions (BFGS, modified Newton), each solved to 1 % of
/// the residual (one f32 solve and one f64 product where cond·ε₃₂ ≲ 0.01). Measured on the
/// plate decks of issue 20 (docs/PERFORMANCE.md, "f32 factors for kept tangents"): one
/// thread's CPU 0.76–0.96 of f64's at 4 263 DOF, 0.78–0.86 at 9 117 and 0.78–0.92 at 24 297;
/// the same negative pivots, the centre deflection within 1e-9 of w₀.
pub const KEPT_MIXED_FROM_DOFS: usize = 4_000;

/// [`crate::SolverKind::FaerLdltKept`]'s wait after f32 is given up: the next factorisation
/// tries f32 again (then 2, 4, … as retries are refused). A kept tangent is factorised a few
/// times per path, and the plate's tangent at rest is too ill-conditioned for f32 while every
/// later one (membrane-stiffened) is not: the scenes' wait of `RETRY_F32_AFTER` = 8 kept the
/// 24 k-DOF plate deck in f64 for 8 of its 12 factorisations.
pub const KEPT_RETRY_F32_AFTER: usize = 1;

/// Below this many DOFs faer's own dense kernels run on one thread whatever
/// [`super::FaerSolver::par`] says (the split's halves still take two): two threads inside
/// faer's kernels cost 1.16× the wall time of one at 6 789 DOF, 1.27× at 18 393 DOF and
/// 1.8× at 10 737 DOF (docs/PERFORMANCE.md, "The scene's time" and "The split by default");
/// they pay from about 45 k DOF on. [`super::FaerSolver::kernel_threads_from`] overrides it.
pub const KERNEL_THREADS_FROM_DOFS: usize = 20_000;
