//! The settings of the Newton iteration (thesis §2.1, §4.4): full, modified and quasi-Newton,
//! tolerances, line search, the linear solver.

use nonlin3d_solver::SolverKind;

/// The refactorisation rule of BFGS on a kept tangent, for scenes (`newton = "bfgs"`) and for
/// decks (`solve`, `*STATIC, DIRECT` steps): a new factorisation only when an iteration more
/// than doubles ‖r‖∞. BFGS's pairs learn a stiffening the kept tangent misses, so an iteration
/// that reduces ‖r‖∞ by less than half is no reason to factorise; a residual that doubles is.
/// On the clamped-plate decks of 9 k and 24 k DOF: 12 factorisations and 82 / 81 iterations
/// against 15 and 74 / 73 with a new factorisation whenever ‖r‖∞ fell by less than half (ratio
/// 0.5), 5–15 % less time on one thread (docs/PERFORMANCE.md, "BFGS refactorises only when
/// the residual doubles").
pub const BFGS_REFACTOR_RATIO: f64 = 2.0;

/// Settings of the Newton iteration.
#[derive(Debug, Clone, PartialEq)]
pub struct NewtonSettings {
    /// Iterations per attempt.
    pub max_iterations: usize,
    /// Absolute residual tolerance in force units (N), 0 = none (the default): only when the
    /// user asks for one (the thesis used 1e-4 N, §4.4). Honoured as given: the criterion is
    /// ‖r‖∞ ≤ max(force_tolerance, relative_tolerance·F); a tolerance below what double
    /// precision reaches (1e-14·F, [`REACHABLE`](crate::REACHABLE)) is refused with [`NewtonError::Setting`](crate::NewtonError::Setting).
    pub force_tolerance: f64,
    /// Relative residual tolerance ε_r against the force scale F of the state (largest external
    /// or reaction force, [`NonlinearProblem::evaluate`](crate::NonlinearProblem::evaluate)): converged when ‖r‖∞ ≤ ε_r·F (CalculiX
    /// and Abaqus: r_max ≤ R_n·q̄, R_n = 0.005). Default 1e-8, tight enough for energy release
    /// rates (differences of forces) to ~1e-6 relative. Invariant to the units of force.
    pub relative_tolerance: f64,
    /// Line search: a full step that raises ‖r‖∞ is shortened, on the potential energy's slope
    /// along the step where the direction descends (Crisfield's energy line search), else by
    /// halving until ‖r‖∞ falls.
    pub line_search: bool,
    /// Refactor the tangent every this many iterations: 1 = full Newton, more = modified Newton
    /// (the thesis's §2.1 option). With `keep_tangent` the count runs on across increments.
    pub refactor_every: usize,
    /// Keep the factorised tangent from one increment to the next (modified Newton "for several
    /// increments"): an increment then starts with a residual evaluation only. Only with
    /// [`solve_increment_with`](crate::solve_increment_with) and one [`TangentCache`](crate::TangentCache) over the increments (as
    /// [`follow_path`](crate::follow_path) does).
    pub keep_tangent: bool,
    /// With a tangent older than the current iteration: factor a new one when an iteration
    /// leaves ‖r_new‖∞ > ratio·‖r_old‖∞ (below 1: when it reduced ‖r‖∞ by less than that;
    /// above 1: only when it raised ‖r‖∞ more than that, [`BFGS_REFACTOR_RATIO`]).
    pub refactor_ratio: f64,
    /// Quasi-Newton: at most this many BFGS pairs (s = Δu, y = Δr) update the inverse of the
    /// kept tangent, H = (I − ρ s yᵀ) H (I − ρ y sᵀ) + ρ s sᵀ, ρ = 1/(yᵀs), applied by the
    /// two-loop recursion around the factorised tangent. 0 = plain (modified) Newton. Pairs
    /// are dropped when the tangent is refactored; pairs with yᵀs ≤ 1e-10·‖y‖‖s‖ are skipped.
    pub quasi_newton: usize,
    /// Linear solver.
    pub solver: SolverKind,
    /// Also require the correction ‖Δu‖∞ of the last iteration ≤ displacement_tolerance·‖u‖∞
    /// (0 = residual only, the default).
    pub displacement_tolerance: f64,
    /// CalculiX's I_0: from this iteration on (1-based), an attempt whose residual after the
    /// last two iterations stayed above the one before them (r_{i−1} > r_{i−2} and r_i > r_{i−2},
    /// r_i above the tolerance) stops as [`Termination::Diverging`](crate::Termination::Diverging). 0 = never (the default).
    pub divergence_check_from: usize,
    /// CalculiX's I_R: from this iteration on, the iterations an attempt still needs are
    /// estimated by logarithmic convergence, i + ln(tol/r_i)/ln(r_i/r_{i−1}) (while the
    /// residual falls); an estimate above `max_iterations` stops it as
    /// [`Termination::TooSlow`](crate::Termination::TooSlow). 0 = never (the default).
    pub slow_check_from: usize,
}

impl NewtonSettings {
    /// Full Newton (a tangent factorised every iteration, the defaults otherwise) with this
    /// one's solver and force tolerances: where a kept tangent (modified Newton, BFGS) does
    /// not apply — a level that picks the branch, the contact loop whose constraints change
    /// between passes, a start carried from another mesh.
    pub fn full_newton(&self) -> Self {
        Self {
            solver: self.solver,
            force_tolerance: self.force_tolerance,
            relative_tolerance: self.relative_tolerance,
            ..Self::default()
        }
    }
}

impl Default for NewtonSettings {
    fn default() -> Self {
        Self {
            max_iterations: 25,
            force_tolerance: 0.0,
            relative_tolerance: 1e-8,
            line_search: true,
            refactor_every: 1,
            keep_tangent: false,
            refactor_ratio: 0.5,
            quasi_newton: 0,
            solver: SolverKind::FaerLdlt,
            displacement_tolerance: 0.0,
            divergence_check_from: 0,
            slow_check_from: 0,
        }
    }
}
