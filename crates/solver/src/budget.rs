//! The memory a solver may take for its factor and workspace, and fallible allocation.
//!
//! A solver's symbolic analysis knows the exact size of the factor before the numeric phase
//! allocates it (faer: the entries of L from the symbolic Cholesky; the profile solver: the
//! envelope after RCM). [`LinearSolver::analyze`](crate::LinearSolver::analyze) compares
//! factor + workspace + one matrix of values on the pattern (the matrix the caller will
//! factor) with the budget and refuses with [`SolverError::OverBudget`] before allocating;
//! what it then allocates goes through `try_reserve_exact`, so a refusal by the system is
//! [`SolverError::OutOfMemory`], not an abort.
//!
//! The budget is a plain byte count. It comes from the solver's own
//! [`memory_budget`](crate::FaerSolver::memory_budget) field if set, else from the process-wide
//! provider installed with [`set_memory_budget`] (the `nonlin3d` facade installs one that
//! reads the process's limits at the time of each analysis), else there is none.

use crate::SolverError;
use std::sync::{Arc, RwLock};

/// Bytes a solver may allocate, and what sets that number (for messages, e.g. "the
/// address-space limit (RLIMIT_AS) of 1.00 GiB, 380 MiB of it in use").
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MemoryBudget {
    /// Bytes available to the factorisation.
    pub bytes: usize,
    /// The limit it comes from, in words.
    pub limit: String,
}

impl MemoryBudget {
    /// A budget of `bytes` set by `limit`.
    pub fn new(bytes: usize, limit: impl Into<String>) -> Self {
        Self {
            bytes,
            limit: limit.into(),
        }
    }
}

/// A process-wide source of the current budget, asked at every analysis.
pub type BudgetProvider = dyn Fn() -> Option<MemoryBudget> + Send + Sync;

static PROVIDER: RwLock<Option<Arc<BudgetProvider>>> = RwLock::new(None);

/// Installs (or with `None` removes) the process-wide budget provider that solvers without a
/// budget of their own consult at each [`analyze`](crate::LinearSolver::analyze).
pub fn set_memory_budget(provider: Option<Arc<BudgetProvider>>) {
    let mut slot = PROVIDER.write().unwrap_or_else(|e| e.into_inner());
    *slot = provider;
}

/// The budget now: `own` if given, else the process-wide provider's answer.
pub fn current_budget(own: Option<&MemoryBudget>) -> Option<MemoryBudget> {
    if let Some(b) = own {
        return Some(b.clone());
    }
    let provider = PROVIDER.read().unwrap_or_else(|e| e.into_inner()).clone();
    provider.and_then(|p| p())
}

/// Bytes as a reader wants them: "512.0 MiB", "1.25 GiB".
pub fn format_bytes(bytes: u128) -> String {
    const MIB: f64 = 1024.0 * 1024.0;
    let b = bytes as f64;
    if b >= 1024.0 * MIB {
        format!("{:.2} GiB", b / (1024.0 * MIB))
    } else {
        format!("{:.1} MiB", b / MIB)
    }
}

/// What an analysis is about to allocate: the factor, its workspace, and the matrix of values
/// the caller will hand to `factorize`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Need {
    /// Which factor ("faer LDLᵀ factor", "profile envelope").
    pub what: &'static str,
    /// Stored entries of the factor.
    pub entries: usize,
    /// Bytes of the factor's values.
    pub factor_bytes: usize,
    /// Bytes of workspace (scratch, maps, pivots).
    pub workspace_bytes: usize,
    /// Bytes of one matrix of values on the pattern.
    pub matrix_bytes: usize,
}

impl Need {
    /// Everything, in bytes (saturating).
    pub fn total(&self) -> usize {
        self.factor_bytes
            .saturating_add(self.workspace_bytes)
            .saturating_add(self.matrix_bytes)
    }

    /// `Err(OverBudget)` if the total exceeds the budget.
    pub fn check(&self, budget: Option<MemoryBudget>) -> Result<(), SolverError> {
        match budget {
            Some(b) if self.total() > b.bytes => Err(SolverError::OverBudget {
                what: self.what,
                entries: self.entries,
                factor_bytes: self.factor_bytes,
                workspace_bytes: self.workspace_bytes,
                matrix_bytes: self.matrix_bytes,
                budget: b.bytes,
                limit: b.limit,
            }),
            _ => Ok(()),
        }
    }
}

/// `len` copies of `value`, or [`SolverError::OutOfMemory`] naming `what` if the system
/// refuses the memory.
pub(crate) fn try_filled<T: Clone>(
    len: usize,
    value: T,
    what: &'static str,
) -> Result<Vec<T>, SolverError> {
    let mut v = Vec::new();
    v.try_reserve_exact(len)
        .map_err(|_| SolverError::OutOfMemory {
            what,
            bytes: len.saturating_mul(std::mem::size_of::<T>()),
        })?;
    v.resize(len, value);
    Ok(v)
}

/// `len` zeros, or [`SolverError::OutOfMemory`] naming `what`. Zeroed by the allocator (calloc:
/// fresh pages from the system are not written), so the factor's pages are first touched by
/// the factorisation, as with `vec![0.0; len]`; [`try_filled`] would write them all at once
/// (0.5 s for 626 MiB, measured).
pub(crate) fn try_zeros(len: usize, what: &'static str) -> Result<Vec<f64>, SolverError> {
    if len == 0 {
        return Ok(Vec::new());
    }
    let oom = || SolverError::OutOfMemory {
        what,
        bytes: len.saturating_mul(std::mem::size_of::<f64>()),
    };
    let layout = std::alloc::Layout::array::<f64>(len).map_err(|_| oom())?;
    // SAFETY: `layout` has a non-zero size (len > 0); a null return is the allocator's refusal.
    let ptr = unsafe { std::alloc::alloc_zeroed(layout) }.cast::<f64>();
    if ptr.is_null() {
        return Err(oom());
    }
    // SAFETY: `ptr` was allocated by the global allocator with the layout of `len` f64s (the
    // size and alignment `Vec<f64>` uses for capacity `len`), and all-zero bits are 0.0, so
    // all `len` elements are initialised.
    Ok(unsafe { Vec::from_raw_parts(ptr, len, len) })
}

/// Room for `extra` more elements in `v`, or [`SolverError::OutOfMemory`].
pub(crate) fn try_room<T>(
    v: &mut Vec<T>,
    extra: usize,
    what: &'static str,
) -> Result<(), SolverError> {
    v.try_reserve(extra).map_err(|_| SolverError::OutOfMemory {
        what,
        bytes: (v.len().saturating_add(extra)).saturating_mul(std::mem::size_of::<T>()),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{FaerMode, FaerSolver, LinearSolver, ProfileLdlt, SymmetricMatrix};

    #[test]
    fn a_need_over_the_budget_is_refused_with_its_numbers() {
        let need = Need {
            what: "faer LDLᵀ factor",
            entries: 1000,
            factor_bytes: 8000,
            workspace_bytes: 1000,
            matrix_bytes: 800,
        };
        assert_eq!(need.total(), 9800);
        assert!(need.check(None).is_ok());
        assert!(need.check(Some(MemoryBudget::new(9800, "a test"))).is_ok());
        let e = need
            .check(Some(MemoryBudget::new(9799, "a test limit")))
            .unwrap_err();
        assert!(matches!(
            e,
            SolverError::OverBudget {
                entries: 1000,
                budget: 9799,
                ..
            }
        ));
        let text = e.to_string();
        assert!(
            text.contains("1000 entries") && text.contains("a test limit"),
            "{text}"
        );
    }

    /// A box of m³ eight-node cells, one DOF per node, SPD (each cell adds the Laplacian of
    /// its complete graph, plus the identity).
    fn grid(m: usize) -> SymmetricMatrix {
        let id = |i: usize, j: usize, k: usize| (k * (m + 1) + j) * (m + 1) + i;
        let mut lists = Vec::new();
        for k in 0..m {
            for j in 0..m {
                for i in 0..m {
                    let mut l = Vec::new();
                    for c in 0..8 {
                        l.push(id(i + (c & 1), j + ((c >> 1) & 1), k + (c >> 2)));
                    }
                    lists.push(l);
                }
            }
        }
        let n = (m + 1).pow(3);
        let p = Arc::new(crate::SymmetricPattern::from_dof_lists(n, &lists).unwrap());
        let mut a = SymmetricMatrix::zeros(p);
        let mut block = vec![-1.0; 64];
        for c in 0..8 {
            block[c * 8 + c] = 8.0;
        }
        for l in &lists {
            a.scatter_add(l, &block).unwrap();
        }
        for i in 0..n {
            a.add(i, i, 1.0).unwrap();
        }
        a
    }

    /// Makes a solver with the given budget of its own.
    type Make = Box<dyn FnMut(Option<MemoryBudget>) -> Box<dyn LinearSolver>>;

    fn solvers() -> Vec<Make> {
        vec![
            Box::new(|b| {
                let mut s = FaerSolver::new(FaerMode::Ldlt);
                s.memory_budget = b;
                Box::new(s)
            }),
            Box::new(|b| {
                let mut s = ProfileLdlt::new();
                s.memory_budget = b;
                Box::new(s)
            }),
        ]
    }

    /// The refusal comes from the symbolic analysis: its entry count is the factor the
    /// unbudgeted analysis makes, and a budget of exactly the bytes it names lets it through.
    #[test]
    fn analysis_refuses_exactly_above_the_budget() {
        let a = grid(6);
        for mut make in solvers() {
            let free = make(None).analyze(a.pattern()).unwrap().factor_entries;
            let tight = MemoryBudget::new(1, "a 1-byte test budget");
            let e = make(Some(tight)).analyze(a.pattern()).unwrap_err();
            let SolverError::OverBudget {
                entries,
                factor_bytes,
                workspace_bytes,
                matrix_bytes,
                ..
            } = e
            else {
                panic!("{e}");
            };
            assert_eq!(entries, free);
            assert_eq!(factor_bytes, 8 * free);
            assert_eq!(matrix_bytes, 8 * a.pattern().nnz_lower());
            let total = factor_bytes + workspace_bytes + matrix_bytes;
            let mut s = make(Some(MemoryBudget::new(total - 1, "test")));
            assert!(matches!(
                s.analyze(a.pattern()),
                Err(SolverError::OverBudget { .. })
            ));
            let mut s = make(Some(MemoryBudget::new(total, "test")));
            s.analyze(a.pattern()).unwrap();
            s.factorize(&a).unwrap();
            let mut x = vec![1.0; a.n()];
            s.solve_in_place(&mut x, 1).unwrap();
            assert!(x.iter().all(|v| v.is_finite()));
        }
    }

    /// From `SPLIT_FROM_DOFS` on the default factor is the split one, larger than the unsplit
    /// factor by the separator's blocks: the budget counts that factor (and the split's
    /// per-factorisation copies), so a budget of exactly the bytes named lets the analysis and
    /// a factorisation through, one byte less is refused.
    #[test]
    fn a_split_factor_is_budgeted_as_made() {
        let a = grid(17);
        assert!(a.n() >= crate::SPLIT_FROM_DOFS);
        let mut whole = FaerSolver::new(FaerMode::Ldlt);
        whole.split = crate::FaerSplit::Off;
        let unsplit = whole.analyze(a.pattern()).unwrap().factor_entries;
        let mut probe = FaerSolver::new(FaerMode::Ldlt);
        probe.memory_budget = Some(MemoryBudget::new(1, "a 1-byte test budget"));
        let Err(SolverError::OverBudget {
            entries,
            factor_bytes,
            workspace_bytes,
            matrix_bytes,
            ..
        }) = probe.analyze(a.pattern())
        else {
            panic!("not refused");
        };
        let mut free = FaerSolver::new(FaerMode::Ldlt);
        let made = free.analyze(a.pattern()).unwrap().factor_entries;
        assert!(free.split_sizes().is_some(), "{} DOF not split", a.n());
        assert_eq!(entries, made);
        assert!(
            made > unsplit,
            "split {made} against unsplit {unsplit} entries"
        );
        let total = factor_bytes + workspace_bytes + matrix_bytes;
        let mut s = FaerSolver::new(FaerMode::Ldlt);
        s.memory_budget = Some(MemoryBudget::new(total - 1, "test"));
        assert!(matches!(
            s.analyze(a.pattern()),
            Err(SolverError::OverBudget { .. })
        ));
        s.memory_budget = Some(MemoryBudget::new(total, "test"));
        s.analyze(a.pattern()).unwrap();
        s.factorize(&a).unwrap();
        assert!(s.split_sizes().is_some());
    }

    thread_local! {
        static ON: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
    }

    /// Solvers without a budget of their own ask the process-wide provider at each analysis.
    /// The provider answers on this test's thread only, so tests running beside it are
    /// unaffected.
    #[test]
    fn the_process_wide_provider_is_asked_at_each_analysis() {
        set_memory_budget(Some(Arc::new(|| {
            ON.with(|on| on.get())
                .then(|| MemoryBudget::new(1000, "the test provider's limit"))
        })));
        let a = grid(4);
        for mut make in solvers() {
            ON.with(|on| on.set(true));
            let e = make(None).analyze(a.pattern()).unwrap_err();
            assert!(e.to_string().contains("the test provider's limit"), "{e}");
            // The solver's own budget wins over the provider.
            let own = MemoryBudget::new(usize::MAX, "own");
            assert!(make(Some(own)).analyze(a.pattern()).is_ok());
            ON.with(|on| on.set(false));
            assert!(make(None).analyze(a.pattern()).is_ok());
        }
    }

    #[test]
    fn huge_requests_are_errors_not_aborts() {
        let e = try_zeros(usize::MAX / 8, "test zeros").unwrap_err();
        assert!(matches!(
            e,
            SolverError::OutOfMemory {
                what: "test zeros",
                ..
            }
        ));
        // 2⁶⁰ bytes: a valid layout the system cannot give.
        assert!(try_zeros(1 << 57, "test").is_err());
        let z = try_zeros(1000, "test").unwrap();
        assert!(z.len() == 1000 && z.iter().all(|&v| v == 0.0));
        assert!(try_zeros(0, "test").unwrap().is_empty());
        let e = try_filled(usize::MAX / 8, 0.0f64, "test vector").unwrap_err();
        assert!(matches!(
            e,
            SolverError::OutOfMemory {
                what: "test vector",
                ..
            }
        ));
        let mut v = vec![0u8; 4];
        assert!(try_room(&mut v, usize::MAX / 2, "test").is_err());
    }

    #[test]
    fn bytes_read_in_mib_and_gib() {
        assert_eq!(format_bytes(512 << 20), "512.0 MiB");
        assert_eq!(format_bytes(5 << 29), "2.50 GiB");
    }
}
