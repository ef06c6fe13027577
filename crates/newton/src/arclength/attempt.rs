//! One arc-length increment's attempt (Crisfield 1981): the tangent predictor along the
//! previous direction, then corrector iterations on the constraint's quadratic, traced as
//! Newton's load-controlled attempts are.

use super::{Start, Work};
use crate::vector::{dot, norm_inf};
use crate::{IterationRecord, NewtonError, NewtonSettings, NonlinearProblem, residual_tolerance};

/// The converged end of an attempt: state, load factor, the iterations, the initial ‖r‖∞, the
/// tolerance met.
pub(super) type Converged = (Vec<f64>, f64, Vec<IterationRecord>, f64, f64);

/// [`Converged`] without the iterations, which the caller keeps ([`traced_attempt`]).
type Attempted = (Vec<f64>, f64, f64, f64);

/// [`attempt`] in a `tracing` span `attempt` (field `lambda`, the start), ended by an `attempt`
/// event (`lambda` reached or the start, `iterations`, `converged`, `termination`) as Newton's
/// load-controlled attempts report (target [`TRACE_TARGET`](crate::TRACE_TARGET)), so progress
/// bars and logs follow an arc-length path as they follow a load path.
pub(super) fn traced_attempt<P: NonlinearProblem + ?Sized>(
    w: &mut Work<P>,
    from: &Start,
    s: f64,
    (l2, psi2): (f64, f64),
    settings: &NewtonSettings,
) -> Result<Result<Converged, String>, NewtonError> {
    let span = tracing::debug_span!(target: crate::TRACE_TARGET, "attempt", lambda = from.lambda);
    let _entered = span.enter();
    let mut records = Vec::new();
    let outcome = attempt(w, from, s, l2, psi2, settings, &mut records)?;
    let (reached, termination) = match &outcome {
        Ok(done) => (done.1, "converged"),
        Err(why) => (from.lambda, why.as_str()),
    };
    tracing::debug!(
        target: crate::TRACE_TARGET,
        event = "attempt",
        lambda = reached,
        iterations = records.len(),
        converged = outcome.is_ok(),
        termination,
    );
    Ok(outcome.map(|(u, lambda, initial, tolerance)| (u, lambda, records, initial, tolerance)))
}

/// One attempt at an increment of arc length `s` from `from`: the tangent predictor, then
/// corrector iterations on the constraint's quadratic until the residual test of `settings`
/// passes. Ok(Err(why)) when the attempt failed in a way a shorter arc may cure; on success
/// `w.k` holds the tangent at the converged state (the next increment's start).
fn attempt<P: NonlinearProblem + ?Sized>(
    w: &mut Work<P>,
    from: &Start,
    s: f64,
    l2: f64,
    psi2: f64,
    settings: &NewtonSettings,
    records: &mut Vec<IterationRecord>,
) -> Result<Result<Attempted, String>, NewtonError> {
    let t0 = from.rate;
    let dl0 = from.sign * s / (dot(t0, t0) / l2 + psi2).sqrt();
    let mut du: Vec<f64> = t0.iter().map(|t| dl0 * t).collect();
    let mut dl = dl0;
    let mut u: Vec<f64> = from.u.iter().zip(&du).map(|(a, b)| a + b).collect();
    let mut lambda = from.lambda + dl;
    w.problem.prescribe(&mut u, lambda);
    let mut first = None;
    let (mut moved, mut pivots) = (0.0, None);
    for iteration in 0..=settings.max_iterations {
        let scale = w.evaluate(&u, lambda)?;
        let norm = norm_inf(&w.r);
        let tolerance = residual_tolerance(settings, scale)?;
        if iteration > 0 {
            records.push(IterationRecord {
                residual: norm,
                step: 1.0,
                increment: moved,
                negative_pivots: pivots,
                bfgs_pairs: 0,
            });
            tracing::debug!(
                target: crate::TRACE_TARGET,
                event = "iteration",
                lambda,
                iteration,
                residual = norm,
                correction = moved,
                step = 1.0,
                negative_pivots = pivots.map_or(-1, |p| p as i64),
                tolerance,
            );
        }
        if !norm.is_finite() || u.iter().any(|x| !x.is_finite()) {
            return Ok(Err(format!(
                "a residual or displacement became NaN or infinite at iteration {iteration}"
            )));
        }
        let initial = *first.get_or_insert(norm);
        if norm <= tolerance {
            // Converged backwards along the path (the constraint's cylinder meets the path
            // again behind the start: a sharp turn within the arc): refused, so that a
            // shorter arc takes the turn instead of reversing the path.
            let ahead = dot(&du, t0) * dl0 / l2 + psi2 * dl * dl0;
            if ahead < 0.0 {
                return Ok(Err(format!(
                    "the corrector converged behind the predictor (the path turns sharply \
                     within the arc) at iteration {iteration}"
                )));
            }
            return Ok(Ok((u, lambda, initial, tolerance)));
        }
        if norm > 1e8 * initial {
            return Ok(Err(format!(
                "diverged at iteration {iteration} (residual above 1e8 times its initial value)"
            )));
        }
        if iteration == settings.max_iterations {
            break;
        }
        match w.factorize() {
            Ok(p) => pivots = Some(p),
            Err(why) => {
                return Ok(Err(format!(
                    "singular tangent at iteration {iteration}: {why}"
                )));
            }
        }
        let r = std::mem::take(&mut w.r);
        let solved = w.solve(&r);
        w.r = r;
        let dr = match solved {
            Ok(d) => d,
            Err(why) => return Ok(Err(format!("the solve failed: {why}"))),
        };
        let dt = w.rate(&u, lambda)?;
        let Some(dlambda) = root(&du, dl, &dr, &dt, s, l2, psi2) else {
            return Ok(Err(format!(
                "the arc-length constraint has no real root at iteration {}",
                iteration + 1
            )));
        };
        moved = 0.0;
        for (((x, d), a), b) in u.iter_mut().zip(du.iter_mut()).zip(&dr).zip(&dt) {
            let step = a + dlambda * b;
            *x += step;
            *d += step;
            moved = f64::max(moved, step.abs());
        }
        dl += dlambda;
        lambda += dlambda;
        w.problem.prescribe(&mut u, lambda);
    }
    Ok(Err(format!(
        "no convergence within {} iterations",
        settings.max_iterations
    )))
}

/// δλ from the constraint's quadratic a₁δλ² + a₂δλ + a₃ = 0 (Crisfield 1981, eq. 10) for the
/// increment so far (Δu, Δλ) and the iteration's δu_r, δu_t; of two real roots the one whose
/// new increment makes the smaller angle with (Δu, Δλ) (eq. 13). None without a real root.
fn root(du: &[f64], dl: f64, dr: &[f64], dt: &[f64], s: f64, l2: f64, psi2: f64) -> Option<f64> {
    let a: Vec<f64> = du.iter().zip(dr).map(|(x, y)| x + y).collect();
    let a1 = dot(dt, dt) / l2 + psi2;
    let a2 = 2.0 * (dot(&a, dt) / l2 + psi2 * dl);
    let a3 = dot(&a, &a) / l2 + psi2 * dl * dl - s * s;
    let disc = a2 * a2 - 4.0 * a1 * a3;
    if !(a1 > 0.0 && disc >= 0.0) {
        return None;
    }
    // Numerically stable pair of roots.
    let qq = -0.5 * (a2 + a2.signum() * disc.sqrt());
    let roots = if qq == 0.0 {
        [0.0, 0.0]
    } else {
        [qq / a1, a3 / qq]
    };
    // cos of the angle (up to a positive factor): (a + δλ·δu_t)·Δu/ℓ² + ψ²(Δλ + δλ)Δλ.
    let base = dot(&a, du) / l2 + psi2 * dl * dl;
    let slope = dot(dt, du) / l2 + psi2 * dl;
    let cosine = |x: f64| base + x * slope;
    let best = if cosine(roots[0]) >= cosine(roots[1]) {
        roots[0]
    } else {
        roots[1]
    };
    best.is_finite().then_some(best)
}
