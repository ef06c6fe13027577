//! The `[analysis]` table of a scene: integration, Newton, tolerances, increments, solver
//! (docs/SCENES.md, "analysis").

use nonlin3d_element::IntegrationRule;
use serde::{Deserialize, Serialize};

/// Integration rule names in scenes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum RuleName {
    /// 2×2×2 Gauss (the thesis's choice for Hex20).
    #[default]
    Gauss2,
    /// 3×3×3 Gauss.
    Gauss3,
    /// Selective-reduced (Hex8 only).
    SelectiveReduced,
}

impl RuleName {
    /// The rule.
    pub fn rule(self) -> IntegrationRule {
        match self {
            Self::Gauss2 => IntegrationRule::Gauss2,
            Self::Gauss3 => IntegrationRule::Gauss3,
            Self::SelectiveReduced => IntegrationRule::SelectiveReduced,
        }
    }
}

/// Newton variants (thesis §2.1: full, or modified with K_T kept for several iterations).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum NewtonName {
    /// Full Newton–Raphson (tangent every iteration; the default).
    #[default]
    Full,
    /// Modified Newton–Raphson: K_T factorised at each increment's start and
    /// then every `refactor_every` iterations, or after an iteration that did not halve ‖r‖∞;
    /// the same converged states as `full` to the residual tolerance, in about 0.6 of its
    /// factorisations. The levels up to the one that takes the §3.2 perturbation are solved
    /// with full Newton (the branch is picked there). Not the default: on the hard case of a
    /// level 4× past buckling it lands on unstable states (docs/PERFORMANCE.md, "Modified Newton
    /// as an option").
    Modified,
    /// Quasi-Newton: BFGS updates (20 pairs) of a factorised tangent kept across increments,
    /// refactorised when an iteration lets ‖r‖∞ grow; the stability of each converged level
    /// from one extra factorisation there.
    Bfgs,
}

/// How the path to each level is followed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum PathName {
    /// Load (strain) control: increments of the load factor with cutback (the thesis's way).
    #[default]
    Load,
    /// Arc length (Crisfield 1981/1983): the load factor is an unknown held to a length of
    /// path, so limit points are passed; each level is then landed on by Newton at its value.
    ArcLength,
}

/// Which strain–displacement relations give the VCCT forces (§2.8).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum ForceKinematics {
    /// Nonlinear (consistent with the solution; the default, no linear substructure here).
    #[default]
    Nonlinear,
    /// Linear (the thesis's recommendation where the front lies in a linear substructure).
    Linear,
}

/// Where a level past the buckling level starts (docs/SCENES.md, "analysis").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum StartName {
    /// From the error estimate's companion mesh's converged state at the same level, carried
    /// onto this mesh with its contact set (nested iteration): the companion follows the path
    /// (bifurcation, §3.2 perturbation, contact passes), this mesh solves each level from its
    /// state; a level whose start does not converge is followed as with `path`. The default;
    /// it acts where the companion runs (`[mesh] error_estimate = "companion"`, the default) on
    /// load-controlled embedded, edge and through-width models without substructures.
    #[default]
    Companion,
    /// Every level followed on this mesh from the previous level (the thesis's way).
    Path,
}

/// Solution options.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AnalysisOptions {
    /// Integration rule.
    #[serde(default)]
    pub integration: RuleName,
    /// Absolute residual tolerance in N, honoured as given (the thesis used 1e-4 N, §4.4).
    /// Absent (the default): the relative criterion only, ‖r‖∞ ≤ 1e-8·F with F the largest
    /// external or reaction force, which does not depend on the units (docs/THEORY.md,
    /// "Convergence criteria"). Given: ‖r‖∞ ≤ tolerance_n alone; refused at the first increment
    /// whose forces make it unreachable in double precision (below 1e-14·F).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tolerance_n: Option<f64>,
    /// Full (default), modified or quasi-Newton.
    #[serde(default)]
    pub newton: NewtonName,
    /// Iterations between refactorisations for modified Newton.
    #[serde(default = "default_refactor")]
    pub refactor_every: usize,
    /// VCCT force kinematics.
    #[serde(default)]
    pub vcct_forces: ForceKinematics,
    /// `load` (the default) or `arc-length` path following to each level; with `arc-length`
    /// the first arc of a level moves the load factor by at most `max_increment`.
    #[serde(default)]
    pub path: PathName,
    /// Largest load increment as a fraction of the largest strain (or load).
    #[serde(default = "default_max_increment")]
    pub max_increment: f64,
    /// Most increment attempts (converged or cut back) towards one level before the run stops
    /// with an error naming the level: bounds the time a hopeless level can take.
    #[serde(default = "default_max_attempts")]
    pub max_attempts: usize,
    /// Linear solver.
    #[serde(default)]
    pub solver: SolverName,
    /// Where a level past the buckling level starts: `companion` (default) or `path`.
    #[serde(default)]
    pub start: StartName,
    /// Threads for the factorisation with the faer solvers (0, the default: all cores, or
    /// `--threads N`; 1: sequential). Results are bitwise identical for any count.
    #[serde(default = "default_threads")]
    pub threads: usize,
}

/// Linear solver names in scenes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum SolverName {
    /// The default: with full Newton (one solve per factorisation) `faer-mixed` from
    /// 10 000 DOF on (`nonlin3d_solver::MIXED_FROM_DOFS`: 0.81–0.88 of the CPU at 13.5–18.4 k
    /// DOF) and `faer` below; `faer` with modified Newton or BFGS (many solves per
    /// factorisation, each refined in f64: mixed precision costs 1.5× on the plate decks).
    #[default]
    Auto,
    /// faer's supernodal/simplicial LDLᵀ with AMD, nested-dissection or METIS ordering (`FaerOrdering::Auto`: METIS from 10 000 DOF, below whichever needs the fewest flops), f64.
    Faer,
    /// The thesis's profile (skyline) LDLᵀ with RCM ordering.
    Profile,
    /// `faer` with an f32 factor refined in f64 (falls back to f64 where f32 is not enough).
    FaerMixed,
}

fn default_threads() -> usize {
    0
}

fn default_refactor() -> usize {
    4
}
fn default_max_increment() -> f64 {
    0.25
}
fn default_max_attempts() -> usize {
    100
}

impl Default for AnalysisOptions {
    fn default() -> Self {
        Self {
            integration: RuleName::Gauss2,
            tolerance_n: None,
            newton: NewtonName::Full,
            path: PathName::Load,
            refactor_every: default_refactor(),
            vcct_forces: ForceKinematics::Nonlinear,
            max_increment: default_max_increment(),
            max_attempts: default_max_attempts(),
            solver: SolverName::Auto,
            start: StartName::Companion,
            threads: default_threads(),
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    /// A scene without an `[analysis]` table and one with an empty table get the same options:
    /// `Default` and the fields' serde defaults must not drift apart (they did once: a scene
    /// without the table ran modified Newton while the documented default was full).
    #[test]
    fn no_table_and_an_empty_table_mean_the_same() {
        let empty: AnalysisOptions = toml::from_str("").unwrap();
        assert_eq!(AnalysisOptions::default(), empty);
        assert_eq!(empty.newton, NewtonName::Full);
    }
}
