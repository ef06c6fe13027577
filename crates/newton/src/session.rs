//! A linear solver, its tangent and the kept-tangent cache carried over several path calls
//! (the levels of a sweep): the symbolic analysis is done once, and with `keep_tangent` a call
//! starts from the last factorisation instead of a new one.

use crate::{NewtonError, NonlinearProblem, TangentCache};
use nonlin3d_solver::{Analysis, LinearSolver, MixedStats, SolverKind, SymmetricMatrix};
use std::sync::Arc;

/// What [`PathSolver::start_tangent`] found.
#[derive(Debug)]
pub(crate) enum StartTangent {
    /// The factorisation kept from the increment that reached the state (its residual is
    /// within that increment's tolerance).
    Kept,
    /// A factorisation made at the state, with the residual there.
    Made(Vec<f64>),
    /// The tangent at the state is singular: nothing is factorised.
    Singular,
}

/// A solver analysed for a problem's sparsity pattern, with the tangent it factors and the
/// [`TangentCache`] that says whether (and how old) its factorisation is. Made once per
/// problem and handed to [`follow_path_with`](crate::follow_path_with) level after level; the
/// stability test of a converged state ([`PathSolver::inertia_at`]) leaves its factorisation
/// as the next level's kept tangent.
pub struct PathSolver {
    kind: SolverKind,
    pub(crate) solver: Box<dyn LinearSolver>,
    pub(crate) k: SymmetricMatrix,
    pub(crate) cache: TangentCache,
    /// The last accepted state this session saw (empty: none): its factorisation, when the
    /// cache vouches for one, serves as the tangent there (the predictor's), and `pivots` is
    /// its inertia.
    pub(crate) state: Vec<f64>,
    /// Negative pivots at `state` (from the last factorisation of the increment that reached
    /// it, or one made there).
    pub(crate) pivots: Option<usize>,
    /// Symbolic analyses made over the session's life (1 from [`PathSolver::new`], one more
    /// each time [`fit`](Self::fit) had to make it anew).
    analyses: usize,
    /// What the last symbolic analysis found (`None` while a deferred session waits).
    analysis: Option<Analysis>,
    /// What mixed precision did in the solvers [`fit`](Self::fit) replaced (a new pattern).
    replaced: Option<MixedStats>,
}

impl PathSolver {
    /// A solver of `kind`, analysed for `problem`'s pattern; nothing factorised yet.
    pub fn new(problem: &dyn NonlinearProblem, kind: SolverKind) -> Result<Self, NewtonError> {
        let pattern = problem.pattern();
        let mut solver = kind.build();
        let analysis = solver.analyze(&pattern)?;
        Ok(Self {
            kind,
            solver,
            k: SymmetricMatrix::zeros(pattern),
            cache: TangentCache::new(),
            state: Vec::new(),
            pivots: None,
            analyses: 1,
            analysis: Some(analysis),
            replaced: None,
        })
    }

    /// A solver of `kind` for `problem`'s pattern whose symbolic analysis (ordering, symbolic
    /// factor, the split's halves) waits for the first call that factorises: a session that
    /// may never be used (a sweep whose levels all start in another system, the contact
    /// loop's) costs no analysis. An analysis error (e.g. the factor refused by the memory
    /// budget) then comes from that first call.
    pub fn deferred(problem: &dyn NonlinearProblem, kind: SolverKind) -> Self {
        Self {
            kind,
            solver: kind.build(),
            k: SymmetricMatrix::zeros(problem.pattern()),
            cache: TangentCache::new(),
            state: Vec::new(),
            pivots: None,
            analyses: 0,
            analysis: None,
            replaced: None,
        }
    }

    /// What the solver's mixed precision did over the session's life, every analysis
    /// included (f32 factorisations, f64 fall-backs, refinement steps, the last backward
    /// error); `None` for an f64 solver.
    pub fn mixed_stats(&self) -> Option<MixedStats> {
        match (self.replaced, self.solver.mixed_stats()) {
            (Some(before), Some(now)) => Some(before.then(now)),
            (before, now) => now.or(before),
        }
    }

    /// Symbolic analyses this session made (1 unless the pattern or the solver kind changed
    /// under it): a change of constraints within the pattern (a replaced tie group, a
    /// released DOF) costs none.
    pub fn analyses(&self) -> usize {
        self.analyses
    }

    /// What the last symbolic analysis found: the ordering, the factor's entries and flops,
    /// its supernode tree (`None` while a [`deferred`](Self::deferred) session waits).
    pub fn analysis(&self) -> Option<Analysis> {
        self.analysis
    }

    /// Newton at the fixed load factor λ from `u` (updated in place, also when not
    /// converged) with this session's solver and tangent: no new analysis. For a re-solve
    /// after the constraints changed at a converged state (a contact active set); the kept
    /// factorisation is forgotten first, since it was made under the old constraints.
    pub fn solve_at(
        &mut self,
        problem: &mut dyn NonlinearProblem,
        u: &mut [f64],
        lambda: f64,
        settings: &crate::NewtonSettings,
    ) -> Result<crate::IncrementReport, NewtonError> {
        self.fit(problem, settings.solver)?;
        self.cache.invalidate();
        let report = crate::solve_increment_with(
            problem,
            u,
            lambda,
            settings,
            &mut *self.solver,
            &mut self.k,
            &mut self.cache,
        )?;
        if report.converged() {
            self.accept(u, report.negative_pivots());
        } else {
            self.cache.invalidate();
        }
        Ok(report)
    }

    /// The solver kind.
    pub fn kind(&self) -> SolverKind {
        self.kind
    }

    /// Made anew (analysis included) if `problem`'s pattern is not the one this solver was
    /// analysed for, or if `kind` differs; a pattern of the same size after an analysis is
    /// taken as grown from it and analysed with the last analysis's choices
    /// ([`LinearSolver::reanalyze`]).
    pub(crate) fn fit(
        &mut self,
        problem: &dyn NonlinearProblem,
        kind: SolverKind,
    ) -> Result<(), NewtonError> {
        let pattern = problem.pattern();
        let same = Arc::ptr_eq(self.k.pattern(), &pattern) || **self.k.pattern() == *pattern;
        let grown = kind == self.kind && self.analysis.is_some() && pattern.n() == self.k.n();
        if !same && grown {
            // The same equations with more couplings (a contact reserve that grew): the
            // solver's own choices again (`LinearSolver::reanalyze`), a fresh start otherwise.
            let replaced = self.mixed_stats();
            self.analysis = None;
            self.k = SymmetricMatrix::zeros(pattern.clone());
            self.cache = TangentCache::new();
            self.state.clear();
            self.pivots = None;
            self.analysis = Some(self.solver.reanalyze(&pattern)?);
            self.analyses += 1;
            self.replaced = replaced;
        } else if kind != self.kind || !same {
            let analyses = self.analyses;
            let replaced = self.mixed_stats();
            *self = Self::new(problem, kind)?;
            self.analyses = analyses + 1;
            self.replaced = replaced;
        } else if self.analysis.is_none() {
            self.analysis = Some(self.solver.analyze(&pattern)?);
            self.analyses += 1;
        }
        Ok(())
    }

    /// Negative pivots of the tangent at (u, λ) (`u` taken as it is), from one assembly and one
    /// factorisation: the stability test of a converged state (thesis §3.2: past a
    /// bifurcation the trivial path has K_T with negative eigenvalues). The factorisation is
    /// kept as a fresh tangent (no BFGS pairs) for the next call with `keep_tangent`.
    pub fn inertia_at(
        &mut self,
        problem: &mut dyn NonlinearProblem,
        u: &[f64],
        lambda: f64,
    ) -> Result<usize, NewtonError> {
        self.fit(problem, self.kind)?;
        self.cache.invalidate();
        let mut r = vec![0.0; problem.n()];
        problem.evaluate(u, lambda, &mut r, Some(&mut self.k))?;
        let pivots = self.solver.factorize(&self.k)?.negative_pivots;
        self.cache = TangentCache::factored_now();
        self.state = u.to_vec();
        self.pivots = Some(pivots);
        Ok(pivots)
    }

    /// Makes sure the solver holds a factorised tangent for the start state `u` of an
    /// increment: the one kept from the increment that reached `u` (the last factorisation of
    /// its Newton iterations, as CalculiX reuses it), else one assembled and factorised at `u`
    /// (which also gives `u`'s inertia and its residual r(u, λ)).
    pub(crate) fn start_tangent(
        &mut self,
        problem: &mut dyn NonlinearProblem,
        u: &[f64],
        lambda: f64,
    ) -> Result<StartTangent, NewtonError> {
        if self.cache.is_factored() && self.state == u {
            return Ok(StartTangent::Kept);
        }
        self.cache.invalidate();
        let mut r = vec![0.0; problem.n()];
        problem.evaluate(u, lambda, &mut r, Some(&mut self.k))?;
        let Ok(f) = self.solver.factorize(&self.k) else {
            return Ok(StartTangent::Singular);
        };
        self.cache = TangentCache::factored_now();
        self.state = u.to_vec();
        self.pivots = Some(f.negative_pivots);
        Ok(StartTangent::Made(r))
    }

    /// Records `u` as the last accepted state, with the negative pivots of the increment that
    /// reached it (None: that increment made no factorisation; the count is kept).
    pub(crate) fn accept(&mut self, u: &[f64], pivots: Option<usize>) {
        self.state.clear();
        self.state.extend_from_slice(u);
        self.pivots = pivots.or(self.pivots);
    }

    /// Negative pivots at `u` if it is the last accepted state this session saw.
    pub(crate) fn pivots_at(&self, u: &[f64]) -> Option<usize> {
        if self.state == u { self.pivots } else { None }
    }

    /// Forgets the factorisation (the next call factors anew).
    pub fn invalidate(&mut self) {
        self.cache.invalidate();
    }

    /// Whether a factorisation is held for the next call.
    pub fn is_factored(&self) -> bool {
        self.cache.is_factored()
    }
}

impl std::fmt::Debug for PathSolver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PathSolver")
            .field("kind", &self.kind)
            .field("n", &self.k.pattern().n())
            .field("factored", &self.cache.is_factored())
            .finish()
    }
}

#[cfg(test)]
mod tests {
    use crate::perturb::tests::compressed;
    use crate::{
        IncrementReport, NewtonSettings, NonlinearProblem, PathSolver, StructuralProblem,
        solve_increment,
    };

    /// The compressed test problem solved at λ = 0.3 from rest through a new session.
    fn solved_at_03(
        settings: &NewtonSettings,
    ) -> (PathSolver, StructuralProblem, Vec<f64>, IncrementReport) {
        let (mut problem, _, _) = compressed();
        let mut session = PathSolver::new(&problem, settings.solver).unwrap();
        let mut u = vec![0.0; problem.n()];
        let report = session
            .solve_at(&mut problem, &mut u, 0.3, settings)
            .unwrap();
        assert!(report.converged());
        (session, problem, u, report)
    }

    /// A Newton solve at a fixed level through the session gives what a fresh solver gives
    /// (the same iterations on the same tangents: bitwise), records the state as accepted,
    /// and analyses nothing more; a session fitted to another pattern counts a second analysis.
    #[test]
    fn a_solve_at_a_level_reuses_the_analysis() {
        let settings = NewtonSettings::default();
        let (mut session, mut problem, u, report) = solved_at_03(&settings);
        assert_eq!(session.analyses(), 1);
        assert_eq!(session.pivots_at(&u), report.negative_pivots());
        let mut fresh = vec![0.0; problem.n()];
        let mut solver = settings.solver.build();
        solver.analyze(&problem.pattern()).unwrap();
        let mut k = nonlin3d_solver::SymmetricMatrix::zeros(problem.pattern());
        let plain = solve_increment(
            &mut problem,
            &mut fresh,
            0.3,
            &settings,
            &mut *solver,
            &mut k,
        )
        .unwrap();
        assert!(fresh == u && plain.iterations == report.iterations);
        // Another pattern: the session is made anew, and counts it.
        let other = crate::problem::tests::bar_problem();
        session.fit(&other, settings.solver).unwrap();
        assert_eq!(session.analyses(), 2);
    }

    /// Mixed precision's counts are the session's, not its last analysis's: a new pattern
    /// (a contact reserve that grew) makes the solver anew, and what the replaced one did is
    /// kept and added to.
    #[test]
    fn mixed_precision_counts_survive_a_new_pattern() {
        let settings = NewtonSettings {
            solver: nonlin3d_solver::SolverKind::FaerLdltMixed(1),
            ..NewtonSettings::default()
        };
        let factorisations = |s: &PathSolver| {
            let m = s.mixed_stats().unwrap();
            (
                m.single_factorizations + m.double_factorizations,
                m.refinement_steps,
            )
        };
        let (mut session, _, _, _) = solved_at_03(&settings);
        let (first, steps) = factorisations(&session);
        assert!(first > 0 && steps > 0);
        // A bar pulled at its free end by a prescribed displacement.
        let (mut other, _, end) = crate::problem::tests::bar();
        other.prescribe_value(end[0], 1e-6).unwrap();
        session.fit(&other, settings.solver).unwrap();
        assert_eq!(session.analyses(), 2);
        assert_eq!(factorisations(&session), (first, steps));
        let mut v = vec![0.0; other.n()];
        session
            .solve_at(&mut other, &mut v, 1.0, &settings)
            .unwrap();
        let (total, more) = factorisations(&session);
        assert!(total > first && more > steps, "{total} after {first}");
    }

    /// A deferred session analyses nothing until a call needs a factorisation, then once, and
    /// gives the eager session's iterates bit for bit.
    #[test]
    fn a_deferred_session_analyses_at_its_first_use_only() {
        let settings = NewtonSettings::default();
        let (mut problem, _, _) = compressed();
        let mut lazy = PathSolver::deferred(&problem, settings.solver);
        assert_eq!(lazy.analyses(), 0);
        assert!(lazy.analysis().is_none());
        assert!(!lazy.is_factored());
        let mut eager = PathSolver::new(&problem, settings.solver).unwrap();
        let (mut a, mut b) = (vec![0.0; problem.n()], vec![0.0; problem.n()]);
        for lambda in [0.3, 0.6] {
            let ra = lazy
                .solve_at(&mut problem, &mut a, lambda, &settings)
                .unwrap();
            let rb = eager
                .solve_at(&mut problem, &mut b, lambda, &settings)
                .unwrap();
            assert!(ra.converged() && ra.iterations == rb.iterations);
            assert!(a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits()));
        }
        assert_eq!(lazy.analyses(), 1);
        // Both sessions report the same analysis once made.
        assert_eq!(lazy.analysis(), eager.analysis());
        assert!(lazy.analysis().is_some_and(|a| a.flops > 0.0));
    }
}
