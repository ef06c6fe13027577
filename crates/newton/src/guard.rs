//! The inertia guard of path following: a converged increment over which the tangent gained
//! negative pivots is not accepted silently.

use crate::{Bifurcation, IncrementReport, Termination};

/// What the guard says of a converged attempt.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Verdict {
    /// Accept it (the count did not rise, or it rose at an increment the guard accepts: then
    /// the attempt carries its [`Bifurcation`]).
    Accept,
    /// Refuse it and cut back: the count rose over an increment larger than the guard accepts.
    Refuse,
}

/// Tracks the negative pivots of the last accepted state and the increment at which a rise
/// was first seen. A rise from a stable state (no negative pivot) over an increment Δλ is
/// refused (and the step cut back) while Δλ > `fraction`·Δλ_first; at or below that (or when
/// the next cut would go below the smallest step) it is accepted as a real crossing and
/// recorded. A spurious equilibrium a large step jumped to does not survive the smaller steps;
/// a bifurcation does, localised to within `fraction` of the first step. Rises on a path that
/// is already unstable (further bifurcations of a trivial path, which the caller has chosen to
/// follow) are recorded without refusal.
#[derive(Debug, Clone)]
pub(crate) struct InertiaGuard {
    fraction: f64,
    /// Negative pivots at the last accepted state, if known.
    reference: Option<usize>,
    /// The increment at which the pending rise was first seen.
    first: Option<f64>,
}

impl InertiaGuard {
    /// A guard with `fraction` (0 = record rises but never refuse) and the inertia of the
    /// start state if known.
    pub(crate) fn new(fraction: f64, reference: Option<usize>) -> Self {
        Self {
            fraction,
            reference,
            first: None,
        }
    }

    /// Whether it refuses anything.
    pub(crate) fn is_on(&self) -> bool {
        self.fraction > 0.0
    }

    /// Whether it refuses rises but does not know the count at the last accepted state.
    pub(crate) fn needs_reference(&self) -> bool {
        self.is_on() && self.reference.is_none()
    }

    /// Sets the count of the start state when it was not known.
    pub(crate) fn know(&mut self, pivots: Option<usize>) {
        if self.reference.is_none() {
            self.reference = pivots;
        }
    }

    /// Whether a rise is pending (seen, not yet accepted): the step should not grow.
    pub(crate) fn pending(&self) -> bool {
        self.first.is_some()
    }

    /// Judges a converged `attempt` of increment `delta` from load factor `from`; the next
    /// step would be `next` (a refusal is turned into an acceptance when `next` < `min`). A
    /// refused attempt gets [`Termination::InertiaChanged`]; an accepted rise gets its
    /// [`Bifurcation`].
    pub(crate) fn judge(
        &mut self,
        attempt: &mut IncrementReport,
        from: f64,
        delta: f64,
        next: f64,
        min: f64,
    ) -> Verdict {
        let after = attempt.negative_pivots();
        if let (Some(before), Some(after)) = (self.reference, after)
            && after > before
        {
            let first = *self.first.get_or_insert(delta);
            let stable = before == 0;
            if stable && self.is_on() && delta > self.fraction * first * (1.0 + 1e-9) && next >= min
            {
                attempt.termination = Termination::InertiaChanged { before, after };
                return Verdict::Refuse;
            }
            attempt.bifurcation = Some(Bifurcation {
                from,
                before,
                after,
            });
            self.first = None;
        }
        if after.is_some() {
            self.reference = after;
        }
        Verdict::Accept
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::IterationRecord;

    /// A converged attempt at `lambda` whose last factorisation had `pivots` negative pivots.
    fn converged(lambda: f64, pivots: usize) -> IncrementReport {
        IncrementReport {
            lambda,
            initial_residual: 1.0,
            tolerance: 1e-4,
            iterations: vec![IterationRecord {
                residual: 1e-5,
                step: 1.0,
                increment: 1e-3,
                negative_pivots: Some(pivots),
                bfgs_pairs: 0,
            }],
            termination: Termination::Converged,
            bifurcation: None,
        }
    }

    #[test]
    fn a_rise_is_refused_until_the_step_is_a_quarter_of_the_first() {
        let mut guard = InertiaGuard::new(0.25, Some(0));
        let mut a = converged(1.0, 2);
        assert_eq!(guard.judge(&mut a, 0.0, 1.0, 0.5, 1e-4), Verdict::Refuse);
        assert_eq!(
            a.termination,
            Termination::InertiaChanged {
                before: 0,
                after: 2
            }
        );
        assert!(guard.pending());
        let mut a = converged(0.5, 1);
        assert_eq!(guard.judge(&mut a, 0.0, 0.5, 0.25, 1e-4), Verdict::Refuse);
        let mut a = converged(0.25, 0);
        assert_eq!(guard.judge(&mut a, 0.0, 0.25, 0.125, 1e-4), Verdict::Accept);
        assert!(a.bifurcation.is_none() && guard.pending());
        let mut a = converged(0.5, 1);
        assert_eq!(
            guard.judge(&mut a, 0.25, 0.25, 0.125, 1e-4),
            Verdict::Accept
        );
        assert_eq!(
            a.bifurcation,
            Some(Bifurcation {
                from: 0.25,
                before: 0,
                after: 1
            })
        );
        assert!(!guard.pending());
        // On the now unstable path a further rise is recorded, not refused.
        let mut a = converged(1.5, 3);
        assert_eq!(guard.judge(&mut a, 0.5, 1.0, 0.5, 1e-4), Verdict::Accept);
        assert_eq!(a.bifurcation.map(|b| (b.before, b.after)), Some((1, 3)));
    }

    #[test]
    fn no_refusal_below_the_smallest_step_off_or_without_a_reference() {
        let mut a = converged(1.0, 1);
        let mut guard = InertiaGuard::new(0.25, Some(0));
        assert_eq!(guard.judge(&mut a, 0.0, 1.0, 1e-5, 1e-4), Verdict::Accept);
        assert!(a.bifurcation.is_some());
        let mut a = converged(1.0, 1);
        let mut off = InertiaGuard::new(0.0, Some(0));
        assert!(!off.needs_reference());
        assert_eq!(off.judge(&mut a, 0.0, 1.0, 0.5, 1e-4), Verdict::Accept);
        assert!(a.bifurcation.is_some());
        let mut a = converged(1.0, 1);
        let mut blind = InertiaGuard::new(0.25, None);
        assert!(blind.needs_reference());
        assert_eq!(blind.judge(&mut a, 0.0, 1.0, 0.5, 1e-4), Verdict::Accept);
        assert!(a.bifurcation.is_none());
        // It knows the count from then on.
        assert!(!blind.needs_reference());
    }
}
