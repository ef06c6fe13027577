//! The problem interface and the finite element implementation of it.

use crate::{DeadLoads, NewtonError};
use nonlin3d_assembly::{Assembler, Constraints, Contribution, System, SystemBuilder};
use nonlin3d_solver::{SymmetricMatrix, SymmetricPattern};
use std::any::Any;
use std::sync::Arc;

/// A discrete nonlinear problem r(u, λ) = 0 with symmetric tangent ∂r/∂u (thesis §2.1,
/// eq. 2.1.3), solved by Newton–Raphson: K_T(u)·Δu = −r(u, λ).
pub trait NonlinearProblem {
    /// Number of unknowns.
    fn n(&self) -> usize;
    /// Sparsity pattern of the tangent (fixed).
    fn pattern(&self) -> Arc<SymmetricPattern>;
    /// Sets the prescribed entries of `u` for load factor λ (their increments are then zero).
    fn prescribe(&self, u: &mut [f64], lambda: f64);
    /// Completes a Newton increment `du` for DOFs the solve left at zero but that depend on
    /// others (tied slaves: du_s = Σ c·du_m). Default: nothing.
    fn expand(&self, _du: &mut [f64]) {}
    /// The change of the residual when the load factor goes from `from` to `to` with the free
    /// DOFs held, linearised at `u` (a state at `from`), into `out`: K_fc(u)·Δu_c − Δf_ext,
    /// Δu_c = u_c(to) − u_c(from) the change of the prescribed values, zero at constrained
    /// rows (folded as the residual is). The right-hand side of the tangent predictor
    /// K_ff Δu_f = −(K_fc Δu_c − Δf_ext) (eq. 2.1.3 linearised at the last converged state).
    /// Returns false when no prescribed value changes (Newton's first iteration from `u` is
    /// then that predictor already) — and by default, for problems without the door.
    fn coupling_force(
        &mut self,
        _u: &[f64],
        _from: f64,
        _to: f64,
        _out: &mut [f64],
    ) -> Result<bool, NewtonError> {
        Ok(false)
    }
    /// Residual r = f_int(u) − f_ext(λ) at (u, λ) into `r` (zero at prescribed entries) and,
    /// when given, the tangent K_T = ∂r/∂u (identity at prescribed entries) (thesis §2.1).
    /// Returns a force scale for relative convergence tests (the largest external or reaction
    /// force). A problem's own failure (a crate above this one, with its own error type) is
    /// returned boxed as [`NewtonError::Problem`] ([`NewtonError::problem`]) and comes out of
    /// path following unchanged.
    fn evaluate(
        &mut self,
        u: &[f64],
        lambda: f64,
        r: &mut [f64],
        tangent: Option<&mut SymmetricMatrix>,
    ) -> Result<f64, NewtonError>;
}

/// The finite element model as a [`NonlinearProblem`]: r(u, λ) = f_int(u) − λ·f_ref − f_dead
/// with supports, prescribed values and ties applied (thesis §2.1, eq. 2.1.3).
///
/// A small adapter over a [`System`]: the solid ([`Assembler`]) is its first contribution, and
/// more can be added ([`with_contributions`](Self::with_contributions): a superelement, a
/// spring); the constraints are the system's, applied once after the contributions are summed.
/// Its parts are private: read through [`assembler`](Self::assembler),
/// [`constraints`](Self::constraints) and [`system`](Self::system); loads and constraints
/// changed through [`add_load`](Self::add_load), [`prescribe_value`](Self::prescribe_value),
/// [`set_dead_load`](DeadLoads::set_dead_load), [`set_constraints`](Self::set_constraints) and
/// [`system_mut`](Self::system_mut) (replaceable tie groups, released DOFs); the reactions of
/// the last evaluation read through [`reactions`](Self::reactions).
pub struct StructuralProblem {
    /// The solid and any other contributions, the constraints, the union pattern.
    system: System,
    /// Reactions of the last evaluation (f_int − f_ext at constrained DOFs).
    reactions: Vec<f64>,
}

impl StructuralProblem {
    /// A problem from an assembler and constraints of the same size; the pattern is the
    /// assembler's cells with the couplings the ties in `constraints` need. Ties whose
    /// couplings the pattern lacks, set later ([`set_constraints`](Self::set_constraints)),
    /// are refused at the first evaluation; reserve them with
    /// [`with_contributions`](Self::with_contributions).
    pub fn new(assembler: Assembler, constraints: Constraints) -> Result<Self, NewtonError> {
        Self::with_contributions(assembler, Vec::new(), constraints, |b| b)
    }

    /// A problem of the solid `assembler` plus `more` contributions (summed after it, in
    /// order), under `constraints`; `reserve` may add couplings to the pattern up front
    /// ([`SystemBuilder::reserve`], [`SystemBuilder::reserve_ties`]: e.g. every candidate
    /// contact pair, so that changing the active set costs no new pattern).
    pub fn with_contributions(
        assembler: Assembler,
        more: Vec<Box<dyn Contribution>>,
        constraints: Constraints,
        reserve: impl FnOnce(SystemBuilder) -> SystemBuilder,
    ) -> Result<Self, NewtonError> {
        check_size(assembler.n(), &constraints)?;
        let n = assembler.n();
        let mut builder = System::builder(constraints).contribution(assembler);
        for c in more {
            builder = builder.boxed(c);
        }
        let system = reserve(builder).build()?;
        Ok(Self {
            system,
            reactions: vec![0.0; n],
        })
    }

    /// The solid: mesh, materials, kernels (for partial internal forces, stresses, a bare
    /// assembly).
    #[allow(clippy::expect_used)]
    pub fn assembler(&self) -> &Assembler {
        // Built with the assembler as the first contribution, and the system cannot lose it.
        self.system
            .find::<Assembler>()
            .expect("the solid is the system's first contribution")
    }

    /// The constrained system: contributions, constraints, pattern.
    pub fn system(&self) -> &System {
        &self.system
    }

    /// The constrained system, to change: tie groups replaced
    /// ([`System::replace_tie_group`]), prescribed DOFs released ([`System::release`]).
    pub fn system_mut(&mut self) -> &mut System {
        &mut self.system
    }

    /// Supports, prescribed values, ties and loads.
    pub fn constraints(&self) -> &Constraints {
        self.system.constraints()
    }

    /// Reactions of the last evaluation: f_int − f_ext at the constrained DOFs (a tie's force
    /// at its slave), zero elsewhere; zeros before the first evaluation.
    pub fn reactions(&self) -> &[f64] {
        &self.reactions
    }

    /// Adds the reference force `value` (N) at DOF `dof`: it acts as λ·`value`
    /// ([`Constraints::add_load`]).
    pub fn add_load(&mut self, dof: usize, value: f64) -> Result<(), NewtonError> {
        Ok(self.system.constraints_mut().add_load(dof, value)?)
    }

    /// Prescribes DOF `dof`: u = λ·`value` (m) ([`Constraints::prescribe`]).
    pub fn prescribe_value(&mut self, dof: usize, value: f64) -> Result<(), NewtonError> {
        Ok(self.system.constraints_mut().prescribe(dof, value)?)
    }

    /// Replaces the constraints and loads as a whole (a new load step's). Refused when their
    /// size is not the model's; ties whose couplings the pattern lacks (not those given to
    /// [`new`](Self::new)) are refused at the next evaluation.
    pub fn set_constraints(&mut self, constraints: Constraints) -> Result<(), NewtonError> {
        check_size(self.system.n(), &constraints)?;
        *self.system.constraints_mut() = constraints;
        Ok(())
    }

    /// The assembler and the constraints, taken apart (other contributions are dropped).
    pub fn into_parts(self) -> Result<(Assembler, Constraints), NewtonError> {
        let (contributions, constraints) = self.system.into_parts();
        let solid = contributions
            .into_iter()
            .find_map(|c| (c as Box<dyn Any>).downcast::<Assembler>().ok())
            .ok_or(NewtonError::Setting {
                name: "problem",
                reason: "the system holds no solid".into(),
            })?;
        Ok((*solid, constraints))
    }
}

/// Refuses constraints of another size than the model's `n` DOFs.
fn check_size(n: usize, constraints: &Constraints) -> Result<(), NewtonError> {
    if n != constraints.n() {
        return Err(NewtonError::Setting {
            name: "constraints",
            reason: format!("{} DOFs for a model of {n}", constraints.n()),
        });
    }
    Ok(())
}

/// The perturbation protocol's door (thesis §3.2): the dead load is the λ-independent part
/// f_dead of the external force.
impl DeadLoads for StructuralProblem {
    fn set_dead_load(&mut self, dof: usize, value: f64) -> Result<(), NewtonError> {
        Ok(self.system.constraints_mut().set_dead_load(dof, value)?)
    }
}

impl NonlinearProblem for StructuralProblem {
    fn n(&self) -> usize {
        self.system.n()
    }

    fn pattern(&self) -> Arc<SymmetricPattern> {
        self.system.pattern().clone()
    }

    fn prescribe(&self, u: &mut [f64], lambda: f64) {
        self.system.prescribe(u, lambda);
    }

    fn expand(&self, du: &mut [f64]) {
        self.system.expand_increment(du);
    }

    /// K(u)·v summed over the contributions ([`System::tangent_product`]), v = Δu_c including
    /// the tied slaves that follow prescribed masters or carry an offset, minus the change of
    /// the external force; then folded onto the masters (Tᵀ) and zeroed at constrained rows
    /// like the residual ([`System::fold`]).
    fn coupling_force(
        &mut self,
        u: &[f64],
        from: f64,
        to: f64,
        out: &mut [f64],
    ) -> Result<bool, NewtonError> {
        let (mut at_to, mut at_from) = (u.to_vec(), u.to_vec());
        self.system.prescribe(&mut at_to, to);
        self.system.prescribe(&mut at_from, from);
        let v: Vec<f64> = at_to.iter().zip(&at_from).map(|(a, b)| a - b).collect();
        if v.iter().all(|&x| x == 0.0) {
            return Ok(false);
        }
        let kv = self.system.tangent_product(u, &v)?;
        let (f_to, f_from) = (self.system.external(to), self.system.external(from));
        for (((o, k), a), b) in out.iter_mut().zip(&kv).zip(&f_to).zip(&f_from) {
            *o = k - (a - b);
        }
        self.system.fold(out)?;
        Ok(true)
    }

    fn evaluate(
        &mut self,
        u: &[f64],
        lambda: f64,
        r: &mut [f64],
        tangent: Option<&mut SymmetricMatrix>,
    ) -> Result<f64, NewtonError> {
        let e = self.system.evaluate(u, lambda, tangent)?;
        r.copy_from_slice(&e.residual);
        let scale = e
            .reactions
            .iter()
            .fold(e.external_max, |a, v| a.max(v.abs()));
        self.reactions = e.reactions;
        Ok(scale)
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::{NewtonSettings, Stepping, follow_path};
    use nonlin3d_element::{ElementKind, IntegrationRule, Kinematics};
    use nonlin3d_laminate::{ShearCoupling, materials};
    use nonlin3d_mesh::{BoxParams, structured_box};

    /// A steel bar 4×1×1 mm of 4 Hex8 along x, fixed on x = 0, nonlinear kinematics; the DOFs
    /// of the x = 0 and x = 4 mm faces.
    pub(crate) fn bar() -> (StructuralProblem, Vec<usize>, Vec<usize>) {
        let mesh = structured_box(&BoxParams::new(
            ElementKind::Hex8,
            [4, 1, 1],
            [4e-3, 1e-3, 1e-3],
        ))
        .unwrap();
        let steel = materials::steel().stiffness().unwrap();
        let assembler = Assembler::new(
            &mesh,
            &[steel],
            ShearCoupling::Exact,
            IntegrationRule::Gauss2,
            IntegrationRule::Gauss2,
            Kinematics::Nonlinear,
        )
        .unwrap();
        let mut c = Constraints::new(assembler.n());
        for r in 0..3 {
            c.fix_nodes(&mesh.node_sets["x0"], r).unwrap();
        }
        let dofs = |set: &str| mesh.node_sets[set].iter().map(|&n| 3 * n).collect();
        let (x0, x1) = (dofs("x0"), dofs("x1"));
        (StructuralProblem::new(assembler, c).unwrap(), x0, x1)
    }

    /// The reactions read through the accessor balance the applied load: Σ R_x on x = 0 =
    /// −Σ F_x on x = 4 mm up to the x-residuals of the 16 free nodes (element forces sum to
    /// zero), each within the tolerance 1e-8·F, F the largest nodal force = force/4: so
    /// |Σ R_x + force| ≤ 16·1e-8·force/4 = 4e-8·force.
    #[test]
    fn the_reactions_balance_the_loads_added_through_the_problem() {
        let (mut problem, x0, x1) = bar();
        let force = 100.0;
        for &d in &x1 {
            problem.add_load(d, force / x1.len() as f64).unwrap();
        }
        assert!(problem.reactions().iter().all(|&r| r == 0.0));
        let mut u = vec![0.0; problem.n()];
        let settings = NewtonSettings::default();
        follow_path(
            &mut problem,
            &mut u,
            &[1.0],
            &settings,
            &Stepping::default(),
        )
        .unwrap();
        let reaction: f64 = x0.iter().map(|&d| problem.reactions()[d]).sum();
        assert!(
            (reaction + force).abs() <= 4.0 * settings.relative_tolerance * force,
            "{reaction} N"
        );
        assert!(u[x1[0]] > 0.0);
    }

    /// The bar's problem alone (another pattern than the other tests' models).
    pub(crate) fn bar_problem() -> StructuralProblem {
        bar().0
    }

    /// Constraints of another size are refused by name, and the problem keeps its own.
    #[test]
    fn constraints_of_another_size_are_refused() {
        let (mut problem, _, x1) = bar();
        problem.prescribe_value(x1[0], 1e-6).unwrap();
        let before = problem.constraints().clone();
        let n = problem.n();
        let e = problem
            .set_constraints(Constraints::new(n + 3))
            .unwrap_err();
        assert_eq!(
            e.to_string(),
            format!(
                "invalid setting constraints: {} DOFs for a model of {n}",
                n + 3
            )
        );
        assert_eq!(problem.constraints(), &before);
        problem.set_constraints(Constraints::new(n)).unwrap();
        let (assembler, constraints) = problem.into_parts().unwrap();
        assert_eq!((assembler.n(), constraints.prescribed().count()), (n, 0));
    }
}
