//! The shallow two-bar (von Mises) truss of the arc-length tests, its closed form and a
//! runner (see tests/arc_length.rs for the mechanics).
#![allow(dead_code)]

use nonlin3d_newton::{
    ArcIncrement, ArcLength, ArcReport, NewtonError, NewtonSettings, NonlinearProblem, SignRule,
    follow_arc_length,
};
use nonlin3d_solver::{SymmetricMatrix, SymmetricPattern};
use std::sync::Arc;

pub const EA: f64 = 1.0;
pub const L: f64 = 1.0;
pub const H: f64 = 0.1;

pub fn l0() -> f64 {
    (L * L + H * H).sqrt()
}
pub fn force(w: f64) -> f64 {
    EA * w * (H - w) * (2.0 * H - w) / l0().powi(3)
}
pub fn stiffness(w: f64) -> f64 {
    EA * (2.0 * H * H - 6.0 * H * w + 3.0 * w * w) / l0().powi(3)
}
pub fn p_max() -> f64 {
    2.0 * EA * H.powi(3) / (3.0 * 3f64.sqrt() * l0().powi(3))
}

/// The truss with the reference load P_max (so λ = 1 at the limit point): DOF 0 = w; with a
/// spring, DOF 1 = v, the load point.
pub struct Truss {
    pub spring: Option<f64>,
}

impl NonlinearProblem for Truss {
    fn n(&self) -> usize {
        if self.spring.is_some() { 2 } else { 1 }
    }
    fn pattern(&self) -> Arc<SymmetricPattern> {
        let all: Vec<usize> = (0..self.n()).collect();
        Arc::new(SymmetricPattern::from_dof_lists(self.n(), &[all]).unwrap())
    }
    fn prescribe(&self, _u: &mut [f64], _lambda: f64) {}
    fn evaluate(
        &mut self,
        u: &[f64],
        lambda: f64,
        r: &mut [f64],
        tangent: Option<&mut SymmetricMatrix>,
    ) -> Result<f64, NewtonError> {
        let load = lambda * p_max();
        let w = u[0];
        match self.spring {
            None => r[0] = force(w) - load,
            Some(k) => {
                r[0] = force(w) - k * (u[1] - w);
                r[1] = k * (u[1] - w) - load;
            }
        }
        if let Some(t) = tangent {
            t.set_zero();
            t.add(0, 0, stiffness(w)).unwrap();
            if let Some(k) = self.spring {
                t.add(0, 0, k).unwrap();
                t.add(0, 1, -k).unwrap();
                t.add(1, 1, k).unwrap();
            }
        }
        Ok(load.abs().max(force(w).abs()).max(p_max() * 1e-3))
    }
}

/// The converged (λ, u) of every increment.
pub type States = Vec<(f64, Vec<f64>)>;

/// Runs the arc length from rest; the converged (λ, u) of every increment, and the report.
pub fn run(spring: Option<f64>, arc: &ArcLength) -> (States, Vec<ArcIncrement>, ArcReport) {
    let mut problem = Truss { spring };
    let mut u = vec![0.0; problem.n()];
    let mut states = Vec::new();
    let report = follow_arc_length(
        &mut problem,
        &mut u,
        0.0,
        &NewtonSettings::default(),
        arc,
        &mut |inc, u, _| {
            states.push((inc.lambda, u.to_vec()));
            false
        },
    )
    .unwrap();
    let increments = report.increments.clone();
    (states, increments, report)
}

/// The arc to past the second limit point: stop when w crosses 2.5h.
pub fn to_far_side(sign: SignRule) -> ArcLength {
    ArcLength {
        initial: 0.1,
        max: 0.2,
        sign,
        monitor: Some((0, 2.5 * H)),
        max_increments: 400,
        ..ArcLength::default()
    }
}

/// The residual test (1e-8·F, F ≤ 1.1·P_max here since |P(w)| ≤ P_max on [0, 2.5h]… and the
/// load) bounds |λ − P(w)/P_max| by 1e-8·F/P_max ≤ 1e-8·max(1, |λ|, |P(w)|/P_max); 1e-7 leaves
/// a factor of 5 for P(2.5h)/P_max ≈ 1.9.
pub const ON_CURVE: f64 = 1e-7;

/// The soft spring of the snap-back case: the constraint couples w and v, so increments take
/// 2–3 corrector iterations (the spring-less truss's cylindrical constraint fixes w and
/// converges in one).
pub fn soft() -> Option<f64> {
    Some(EA * H * H / (2.0 * l0().powi(3)))
}

impl nonlin3d_newton::DeadLoads for Truss {
    fn set_dead_load(&mut self, _dof: usize, _value: f64) -> Result<(), NewtonError> {
        Ok(())
    }
}
