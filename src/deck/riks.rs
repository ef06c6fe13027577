//! A `*STATIC, RIKS` step (Abaqus): arc-length path following ([`follow_arc_length`],
//! Crisfield 1981/1983) instead of time incrementation. The step's loads and prescribed values
//! are reference values: with λ the load proportionality factor (LPF), each is
//! P = P₀ + λ·(P_ref − P₀), P₀ its value at the start of the step (Abaqus's definition), and
//! λ is an unknown that the path finds, increment by increment, through limit points.
//!
//! Arc lengths are in scaled load–displacement space: the first increment's LPF is
//! Δl_in/l_period; the smallest and largest arc lengths scale the same way. The step ends when
//! |λ| reaches λ_end, when the monitored displacement is crossed, or after `INC=` increments
//! (all normal ends, as in Abaqus). Each converged increment is reported with its LPF, its
//! arc length and its iterations; the output tables' step time is the accumulated arc length
//! (Abaqus's "time" of a Riks step), the LPF is in the summary.

use super::drive::{Converged, newton_settings};
use super::loads::{Frame, History};
use super::{IncrementSummary, StepOptions};
use crate::Error;
use nonlin3d_mesh::{InpModel, RiksData};
use nonlin3d_newton::{ArcLength, NewtonError, SignRule, StructuralProblem, follow_arc_length};

/// The arc-length control of a Riks step: Abaqus's arc lengths over l_period (so the first
/// increment moves λ by Δl_in/l_period), `INC=`, λ_end and the monitored node's DOF; the
/// predictor's sign by [`SignRule::Combined`]; `DIRECT` keeps Δl_in (growth 1, no
/// cutback: the smallest arc is the initial one).
pub(crate) fn arc_control(model: &InpModel, k: usize, riks: &RiksData) -> ArcLength {
    let step = &model.steps[k];
    let scale = riks.period;
    let mut arc = ArcLength {
        initial: riks.initial / scale,
        min: riks.min / scale,
        max: riks.max / scale,
        max_increments: step.max_increments,
        max_lpf: riks.max_lpf,
        monitor: riks
            .monitor
            .map(|(node, dof, value)| (3 * node + usize::from(dof) - 1, value)),
        // Not det K_T's sign alone: a symmetric deck can pass a bifurcation (an eigenvalue
        // crosses zero with no turn of λ), where it would send the path back along itself
        // (Crisfield 1983 notes it); the combined rule takes the direction there.
        sign: SignRule::Combined,
        ..ArcLength::default()
    };
    if riks.direct {
        arc.min = arc.initial;
        arc.growth = 1.0;
        // √(I_d/I) ≥ 1 always, capped by the growth of 1: s stays.
        arc.target_iterations = usize::MAX;
    }
    arc
}

/// Runs Riks step `k` (0-based) from `u` (updated to its end), appending every converged
/// increment to `attempts` (with its LPF and arc length) and calling `on_increment` with it.
#[allow(clippy::too_many_arguments)]
pub(crate) fn run_step(
    model: &InpModel,
    k: usize,
    history: &History,
    frame: Frame,
    problem: &mut StructuralProblem,
    u: &mut Vec<f64>,
    options: &StepOptions,
    riks: &RiksData,
    attempts: &mut Vec<IncrementSummary>,
    on_increment: &mut dyn FnMut(Converged<'_>) -> Result<(), Error>,
) -> Result<(), Error> {
    let step = &model.steps[k];
    let settings = newton_settings(&options.newton, options.newton.line_search, step);
    // λ = 0: the values at the step's start, λ = 1: the step's reference values.
    problem.set_constraints(history.constraints(model, frame, 0.0, frame.period)?)?;
    let arc = arc_control(model, k, riks);
    let mut travelled = 0.0;
    let mut failure: Option<Error> = None;
    let outcome = follow_arc_length(problem, u, 0.0, &settings, &arc, &mut |inc, u, problem| {
        travelled += inc.arc * riks.period;
        attempts.push(IncrementSummary {
            increment: inc.index,
            step_time: travelled,
            total_time: frame.start + travelled,
            iterations: inc.iterations,
            residuals: vec![inc.residual],
            converged: true,
            termination: match inc.cutbacks {
                0 => "converged".into(),
                n => format!("converged after {n} cutbacks of the arc length"),
            },
            negative_pivots: Some(inc.negative_pivots),
            // Full Newton: one a corrector iteration (the predictor's not counted).
            factorisations: inc.iterations,
            lpf: Some(inc.lambda),
            arc_length: Some(inc.arc * riks.period),
            contact: None,
            mixed_precision: None,
        });
        let told = on_increment(Converged {
            increment: inc.index,
            step_time: travelled,
            last: inc.stop.is_some(),
            u,
            problem,
            attempts,
            analysis: None,
        });
        match told {
            Ok(()) => false,
            Err(e) => {
                failure = Some(e);
                true
            }
        }
    });
    if let Some(e) = failure {
        return Err(e);
    }
    match outcome {
        Ok(_) => Ok(()),
        Err(e @ NewtonError::ArcLength { .. }) => Err(Error::Step {
            step: k + 1,
            line: step.line,
            reason: e.to_string(),
        }),
        Err(e) => Err(e.into()),
    }
}
