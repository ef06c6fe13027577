//! Arc-length path following (Riks 1979; Crisfield 1981, 1983): the load factor λ becomes an
//! unknown and each increment is held to a fixed length of path, so that limit points
//! (snap-through, snap-back) are followed instead of cut back to failure.
//!
//! The unknowns are (u, λ) with r(u, λ) = 0 (eq. 2.1.3) and one more equation, the
//! constraint on the increment from the last converged state (u₀, λ₀):
//!
//! ‖Δu‖²/ℓ² + ψ²·Δλ² = s²,  Δu = u − u₀, Δλ = λ − λ₀ (Crisfield 1981, eq. 6),
//!
//! with ψ = 0 the cylindrical constraint (the default) and ψ > 0 the spherical one. The
//! displacements are scaled by ℓ = ‖du/dλ‖₂ at the start of the path, so that s is measured
//! in units of the load factor ("scaled load–displacement space", as Abaqus's Riks method):
//! the first increment moves λ by [`ArcLength::initial`].
//!
//! Each iteration solves two systems with one factorisation of K_T(u):
//! δu_r = −K_T⁻¹·r and δu_t = K_T⁻¹·q, q = −∂r/∂λ (the reference load, minus K_fc·ū_c for
//! prescribed values u_c = λ·ū_c, whose own rate ū_c is added to δu_t), and takes
//! δu = δu_r + δλ·δu_t with δλ a root of the constraint's quadratic (Crisfield 1981, eq. 10)
//!
//! a₁·δλ² + a₂·δλ + a₃ = 0,  a₁ = δu_t·δu_t/ℓ² + ψ²,
//! a₂ = 2·[(Δu + δu_r)·δu_t/ℓ² + ψ²·Δλ],  a₃ = ‖Δu + δu_r‖²/ℓ² + ψ²·Δλ² − s²,
//!
//! the root whose new increment makes the smaller angle with the current one (the larger
//! (Δu + δu)·Δu/ℓ² + ψ²·(Δλ + δλ)·Δλ; Crisfield 1981, eq. 13). The predictor is the tangent,
//! Δλ₁ = ±s/√(δu_t·δu_t/ℓ² + ψ²), Δu₁ = Δλ₁·δu_t, its sign by [`SignRule`]: by default
//! ([`SignRule::Combined`]) kept while the count of negative pivots of K_T stays (det K_T's
//! sign, Crisfield 1983: no eigenvalue crossed zero, λ cannot have turned), and where the count
//! changed flipped only if δu_t reversed, sign(δu_t,prev·δu_t) < 0 (a limit point; at a
//! bifurcation δu_t is continuous and λ goes on).
//! The arc length adapts to the iterations
//! the last increment took, s ← s·√(I_d/I) (Crisfield 1981, eq. 17), and is cut back on failure.

use crate::error::sig6;
use crate::vector::dot;
use crate::{IterationRecord, NewtonError, NewtonSettings, NonlinearProblem};

mod attempt;
mod level;
use attempt::traced_attempt;
pub use level::solve_level_arc;
use nonlin3d_solver::{LinearSolver, SymmetricMatrix};

/// The constraint on an increment's length.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ArcConstraint {
    /// ‖Δu‖²/ℓ² = s² (ψ = 0; Crisfield 1981).
    Cylindrical,
    /// ‖Δu‖²/ℓ² + ψ²·Δλ² = s² (Riks 1979, Crisfield 1981 with a load term).
    Spherical {
        /// Weight ψ of the load factor (dimensionless: ℓ scales the displacements).
        psi: f64,
    },
}

impl ArcConstraint {
    fn psi2(self) -> f64 {
        match self {
            Self::Cylindrical => 0.0,
            Self::Spherical { psi } => psi * psi,
        }
    }
}

/// How the predictor's sign is chosen (the sign of Δλ₁ in Δλ₁ = ±s/√(δu_t·δu_t/ℓ² + ψ²)).
///
/// The two classical rules fail in different places. det K_T's sign cannot tell a limit point
/// from a bifurcation (both move one eigenvalue μ of K_T through zero) and turns the path back
/// at a bifurcation, where λ goes on. The previous increment's direction inherits the
/// orientation of the last increment: one whose corrector converged backwards along the path
/// (past a sharp snap-back) reverses the path for good, while det K_T's rule keeps the
/// orientation, sign(det K_T)·sign(dλ/ds) being constant along a path without bifurcations.
/// [`SignRule::Combined`] keeps det K_T's rule and tells the two crossings apart by δu_t.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SignRule {
    /// The sign of det K_T (Crisfield 1983): the predictor's Δλ keeps the previous predictor's
    /// sign unless the count of negative pivots changed by an odd number since its start,
    /// sign(Δλ₁ⁿ) = sign(Δλ₁ⁿ⁻¹)·(−1)^(pₙ − pₙ₋₁).
    Inertia,
    /// The previous increment's direction (Feng, Perić and Owen 1996):
    /// sign(Δλ₁) = sign(Δu_prev·δu_t/ℓ² + ψ²·Δλ_prev), the predictor makes an acute angle with
    /// the last increment.
    Direction,
    /// det K_T's rule, with the crossing told apart by the tangent: where the count of
    /// negative pivots is unchanged the sign is kept; where it changed it flips only if δu_t
    /// reversed, sign(Δλ₁ⁿ) = sign(Δλ₁ⁿ⁻¹)·sign(δu_tⁿ⁻¹·δu_tⁿ). At a limit point
    /// φᵀq ≠ 0 (φ the mode of μ, q the reference load) and δu_t = K_T⁻¹q ≈ φ·(φᵀq)/μ reverses
    /// as μ passes zero; at a bifurcation φᵀq = 0 and δu_t stays finite and continuous, so λ
    /// goes on. The default: it follows the sharp snap-backs det K_T's rule follows and the
    /// direction rule does not, and the bifurcation where det K_T's rule turns back
    /// (tests/arc_length.rs).
    Combined,
}

/// Increment control of [`follow_arc_length`]; arc lengths s in units of the load factor
/// (displacements scaled by ℓ = ‖du/dλ‖₂ at the start).
#[derive(Debug, Clone, PartialEq)]
pub struct ArcLength {
    /// Δλ of the first increment's predictor (Abaqus: initial arc length / total arc length
    /// scale factor); the first arc length is s₀ = initial·√(1 + ψ²).
    pub initial: f64,
    /// Smallest arc length: a cutback below it stops with [`NewtonError::ArcLength`].
    pub min: f64,
    /// Largest arc length.
    pub max: f64,
    /// Iterations I_d an increment should take: s ← s·√(I_d/I) after one that took I.
    pub target_iterations: usize,
    /// Largest growth of s from one increment to the next (×).
    pub growth: f64,
    /// s ← cutback·s after a failed attempt.
    pub cutback: f64,
    /// Cylindrical or spherical.
    pub constraint: ArcConstraint,
    /// The predictor's sign.
    pub sign: SignRule,
    /// Most increments (Abaqus: `*STEP, INC=`): then [`ArcStop::Increments`].
    pub max_increments: usize,
    /// Stop once |λ| ≥ this (Abaqus's maximum load proportionality factor).
    pub max_lpf: Option<f64>,
    /// Stop once u at this DOF crosses this value (Abaqus's node, DOF and value).
    pub monitor: Option<(usize, f64)>,
}

impl Default for ArcLength {
    fn default() -> Self {
        Self {
            initial: 0.1,
            min: 1e-5,
            max: 1e30,
            target_iterations: 4,
            growth: 2.0,
            cutback: 0.5,
            constraint: ArcConstraint::Cylindrical,
            sign: SignRule::Combined,
            max_increments: 100,
            max_lpf: None,
            monitor: None,
        }
    }
}

/// Why [`follow_arc_length`] stopped (all normal ends).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ArcStop {
    /// |λ| reached [`ArcLength::max_lpf`].
    MaxLpf,
    /// The monitored DOF crossed its value.
    Displacement,
    /// [`ArcLength::max_increments`] increments were made.
    Increments,
    /// The observer asked to stop.
    Observer,
}

impl std::fmt::Display for ArcStop {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::MaxLpf => "the maximum load proportionality factor was reached",
            Self::Displacement => "the monitored displacement was reached",
            Self::Increments => "the maximum number of increments was made",
            Self::Observer => "stopped by the caller",
        })
    }
}

/// One converged arc-length increment.
#[derive(Debug, Clone, PartialEq)]
pub struct ArcIncrement {
    /// 1-based.
    pub index: usize,
    /// Load factor (load proportionality factor) at its end.
    pub lambda: f64,
    /// Its change over the increment.
    pub delta_lambda: f64,
    /// Arc length s it was held to.
    pub arc: f64,
    /// Corrector iterations (0: the predictor met the tolerance).
    pub iterations: usize,
    /// Failed attempts (cutbacks) before it converged.
    pub cutbacks: usize,
    /// Negative pivots of K_T at its start.
    pub negative_pivots: usize,
    /// Whether [`SignRule::Inertia`] and [`SignRule::Direction`] chose the same sign.
    pub rules_agree: bool,
    /// ‖r‖∞ at its end, N.
    pub residual: f64,
    /// ‖r‖∞ at the predicted state, N.
    pub initial_residual: f64,
    /// The residual tolerance at its end, N ([`residual_tolerance`](crate::residual_tolerance)).
    pub tolerance: f64,
    /// The corrector iterations: ‖r‖∞ after each, ‖δu‖∞, the negative pivots of its
    /// factorisation (step 1: no line search).
    pub records: Vec<IterationRecord>,
    /// The stopping criterion it met, if any (the path ends with it; the observer is told
    /// before, so that it knows the last increment).
    pub stop: Option<ArcStop>,
}

/// The increments made and why the path stopped.
#[derive(Debug, Clone, PartialEq)]
pub struct ArcReport {
    /// Converged increments in order.
    pub increments: Vec<ArcIncrement>,
    /// Why it stopped.
    pub stop: ArcStop,
    /// ℓ = ‖du/dλ‖₂ at the start, the scale of the displacements in the constraint.
    pub scale: f64,
}

/// What an iteration needs besides the problem: a solver and its tangent storage.
struct Work<'a, P: NonlinearProblem + ?Sized> {
    problem: &'a mut P,
    solver: Box<dyn LinearSolver>,
    k: SymmetricMatrix,
    r: Vec<f64>,
    /// −∂r/∂λ when it does not depend on u (no prescribed value changes: the reference load).
    load: Option<Vec<f64>>,
}

impl<P: NonlinearProblem + ?Sized> Work<'_, P> {
    /// r and K_T at (u, λ) (K_T into `k`); the force scale.
    fn evaluate(&mut self, u: &[f64], lambda: f64) -> Result<f64, NewtonError> {
        self.problem
            .evaluate(u, lambda, &mut self.r, Some(&mut self.k))
    }

    /// Factorises `k`: its negative pivots, or the solver's message.
    fn factorize(&mut self) -> Result<usize, String> {
        self.solver
            .factorize(&self.k)
            .map(|f| f.negative_pivots)
            .map_err(|e| e.to_string())
    }

    /// −K⁻¹·b with the current factorisation, ties expanded.
    fn solve(&mut self, b: &[f64]) -> Result<Vec<f64>, String> {
        let mut x: Vec<f64> = b.iter().map(|v| -v).collect();
        self.solver
            .solve_in_place(&mut x, 1)
            .map_err(|e| e.to_string())?;
        self.problem.expand(&mut x);
        Ok(x)
    }

    /// δu_t = du/dλ at (u, λ) with the current factorisation: K_T⁻¹·(−∂r/∂λ) on the free DOFs
    /// plus ū_c on the prescribed ones. ∂r/∂λ = K_fc·ū_c − f_ref from
    /// [`NonlinearProblem::coupling_force`] when prescribed values change, else r(u, λ+1) −
    /// r(u, λ) = −f_ref (kept: it does not depend on u).
    fn rate(&mut self, u: &[f64], lambda: f64) -> Result<Vec<f64>, NewtonError> {
        let n = u.len();
        let mut drdl = vec![0.0; n];
        let prescribed = self
            .problem
            .coupling_force(u, lambda, lambda + 1.0, &mut drdl)?;
        if !prescribed {
            if self.load.is_none() {
                let (mut r0, mut r1) = (vec![0.0; n], vec![0.0; n]);
                self.problem.evaluate(u, lambda, &mut r0, None)?;
                self.problem.evaluate(u, lambda + 1.0, &mut r1, None)?;
                self.load = Some(r1.iter().zip(&r0).map(|(a, b)| a - b).collect());
            }
            if let Some(load) = &self.load {
                drdl.copy_from_slice(load);
            }
        }
        let mut t = self.solve(&drdl).map_err(|why| NewtonError::Setting {
            name: "arc-length",
            reason: format!("the tangent solve failed at λ = {}: {why}", sig6(lambda)),
        })?;
        if prescribed {
            let (mut a, mut b) = (u.to_vec(), u.to_vec());
            self.problem.prescribe(&mut a, lambda + 1.0);
            self.problem.prescribe(&mut b, lambda);
            for ((t, a), b) in t.iter_mut().zip(&a).zip(&b) {
                *t += a - b;
            }
        }
        Ok(t)
    }
}

/// The converged state an increment starts from.
struct Start<'a> {
    u: &'a [f64],
    lambda: f64,
    /// δu_t there.
    rate: &'a [f64],
    /// Its Δλ sign.
    sign: f64,
}

/// The last converged increment, as the next predictor's sign needs it.
struct Previous {
    /// Δu over it.
    du: Vec<f64>,
    /// Δλ over it.
    dl: f64,
    /// Negative pivots of K_T at its start.
    pivots: usize,
    /// Its predictor's sign.
    sign: f64,
}

/// The predictor's sign at a start with `pivots` negative pivots and tangent `rate` (δu_t)
/// after `previous` (+1 for the first increment) by `rule` ([`SignRule`]), and whether the
/// inertia and direction rules agree there. Relative to the previous predictor's sign, not its
/// converged Δλ (which may have turned already).
fn predictor_sign(
    rule: SignRule,
    previous: Option<&Previous>,
    pivots: usize,
    rate: &[f64],
    l2: f64,
    psi2: f64,
) -> (f64, bool) {
    let Some(prev) = previous else {
        return (1.0, true);
    };
    let flip = |yes: bool| if yes { -prev.sign } else { prev.sign };
    // sign(Δλ₁) = sign(det K_T) up to the first one's.
    let inertia = flip((pivots as i64 - prev.pivots as i64).rem_euclid(2) == 1);
    let along = dot(&prev.du, rate) / l2 + psi2 * prev.dl;
    let direction = if along >= 0.0 { 1.0 } else { -1.0 };
    let sign = match rule {
        SignRule::Inertia => inertia,
        SignRule::Direction => direction,
        // The count changed over an increment that kept its predictor's sense: a limit
        // point or a bifurcation, told apart by the direction. Over one whose Δλ turned
        // against its predictor (a limit point within it, or a corrector that converged
        // backwards along the path) det K_T's orientation stands.
        SignRule::Combined if pivots != prev.pivots && prev.dl * prev.sign > 0.0 => direction,
        SignRule::Combined => inertia,
    };
    (sign, inertia == direction)
}

/// Refuses arc lengths that are not finite and positive, a growth below 1, a cutback outside
/// (0, 1), I_d = 0 and ψ < 0.
fn check(arc: &ArcLength) -> Result<(), NewtonError> {
    let ok = |v: f64| v.is_finite() && v > 0.0;
    let psi_ok = match arc.constraint {
        ArcConstraint::Cylindrical => true,
        ArcConstraint::Spherical { psi } => psi.is_finite() && psi >= 0.0,
    };
    if ok(arc.initial)
        && ok(arc.min)
        && arc.max >= arc.min
        && arc.growth >= 1.0
        && arc.cutback > 0.0
        && arc.cutback < 1.0
        && arc.target_iterations > 0
        && psi_ok
    {
        Ok(())
    } else {
        Err(NewtonError::Setting {
            name: "arc-length",
            reason: format!(
                "needs a finite, positive initial = {} and min = {}, max = {} ≥ min, growth = \
                 {} ≥ 1, 0 < cutback = {} < 1, target iterations = {} > 0 and, for the \
                 spherical constraint, a finite ψ ≥ 0",
                arc.initial, arc.min, arc.max, arc.growth, arc.cutback, arc.target_iterations
            ),
        })
    }
}

/// Follows the equilibrium path by arc length from the converged state `u` at `start`
/// (updated to the last converged state), increment by increment (module docs), until a
/// stopping criterion of `arc` or `observe` (told of every converged increment with its state
/// and the problem; true stops) ends it. Each increment's start is factorised once (its inertia and δu_t), each
/// corrector iteration once (full Newton); the residual test is `settings`' (tolerances,
/// `max_iterations`, solver); its line search and kept tangents are not used. A failed attempt
/// (no convergence, divergence, a non-finite value, a singular tangent, no real root of the
/// constraint) is cut back; below [`ArcLength::min`] it stops with [`NewtonError::ArcLength`].
pub fn follow_arc_length<P: NonlinearProblem + ?Sized>(
    problem: &mut P,
    u: &mut Vec<f64>,
    start: f64,
    settings: &NewtonSettings,
    arc: &ArcLength,
    observe: &mut dyn FnMut(&ArcIncrement, &[f64], &mut P) -> bool,
) -> Result<ArcReport, NewtonError> {
    check(arc)?;
    let pattern = problem.pattern();
    let mut solver = settings.solver.build();
    solver.analyze(&pattern)?;
    let n = problem.n();
    let mut w = Work {
        problem,
        solver,
        k: SymmetricMatrix::zeros(pattern),
        r: vec![0.0; n],
        load: None,
    };
    let psi2 = arc.constraint.psi2();
    let mut lambda = start;
    w.problem.prescribe(u, lambda);
    w.evaluate(u, lambda)?;
    let mut scale = 0.0;
    let mut s = arc.initial * (1.0 + psi2).sqrt();
    let mut report = ArcReport {
        increments: Vec::new(),
        stop: ArcStop::Increments,
        scale: 0.0,
    };
    let mut previous: Option<Previous> = None;
    while report.increments.len() < arc.max_increments {
        let index = report.increments.len() + 1;
        let pivots = w.factorize().map_err(|why| NewtonError::ArcLength {
            increment: index,
            lambda,
            arc: s,
            cutbacks: 0,
            reason: format!("the tangent at the converged state is singular: {why}"),
        })?;
        let rate = w.rate(u, lambda)?;
        if scale == 0.0 {
            scale = dot(&rate, &rate).sqrt();
            if !(scale.is_finite() && scale > 0.0) {
                return Err(NewtonError::Setting {
                    name: "arc-length",
                    reason: format!(
                        "nothing moves with the load factor at λ = {} (‖du/dλ‖ = {scale})",
                        sig6(lambda)
                    ),
                });
            }
            report.scale = scale;
        }
        let l2 = scale * scale;
        let (sign, rules_agree) =
            predictor_sign(arc.sign, previous.as_ref(), pivots, &rate, l2, psi2);
        let from = Start {
            u,
            lambda,
            rate: &rate,
            sign,
        };
        let mut cutbacks = 0;
        let (trial, trial_lambda, records, initial_residual, tolerance) = loop {
            match traced_attempt(&mut w, &from, s, (l2, psi2), settings)? {
                Ok(done) => break done,
                Err(reason) => {
                    cutbacks += 1;
                    s *= arc.cutback;
                    if s < arc.min {
                        return Err(NewtonError::ArcLength {
                            increment: index,
                            lambda,
                            arc: s / arc.cutback,
                            cutbacks,
                            reason,
                        });
                    }
                }
            }
        };
        let du: Vec<f64> = trial.iter().zip(u.iter()).map(|(a, b)| a - b).collect();
        let dl = trial_lambda - lambda;
        let crossed = arc.monitor.is_some_and(|(dof, value)| {
            let (a, b) = (u[dof] - value, trial[dof] - value);
            b == 0.0 || a.signum() != b.signum()
        });
        *u = trial;
        lambda = trial_lambda;
        let stop = if crossed {
            Some(ArcStop::Displacement)
        } else if arc.max_lpf.is_some_and(|m| lambda.abs() >= m) {
            Some(ArcStop::MaxLpf)
        } else if index >= arc.max_increments {
            Some(ArcStop::Increments)
        } else {
            None
        };
        let record = ArcIncrement {
            index,
            lambda,
            delta_lambda: dl,
            arc: s,
            iterations: records.len(),
            cutbacks,
            negative_pivots: pivots,
            rules_agree,
            residual: records.last().map_or(initial_residual, |r| r.residual),
            initial_residual,
            tolerance,
            records,
            stop,
        };
        previous = Some(Previous {
            du,
            dl,
            pivots,
            sign,
        });
        let asked = observe(&record, u, &mut *w.problem);
        report.increments.push(record);
        // Crisfield 1981, eq. 17: s ← s·√(I_d/I), I at least 1, growth bounded.
        let iterations = report.increments.last().map_or(0, |i| i.iterations);
        let ratio = (arc.target_iterations as f64 / iterations.max(1) as f64).sqrt();
        s = (s * ratio.min(arc.growth)).clamp(arc.min, arc.max);
        if let Some(stop) = stop.or(asked.then_some(ArcStop::Observer)) {
            report.stop = stop;
            return Ok(report);
        }
    }
    Ok(report)
}
