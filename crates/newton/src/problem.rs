//! The problem interface and the finite element implementation of it.

use crate::{DeadLoads, NewtonError};
use nonlin3d_assembly::{Assembler, Constraints};
use nonlin3d_solver::{SymmetricMatrix, SymmetricPattern};
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
/// Its parts are private: the assembler and the constraints are read through
/// [`assembler`](Self::assembler) and [`constraints`](Self::constraints), loads and constraints
/// changed through [`add_load`](Self::add_load), [`prescribe_value`](Self::prescribe_value),
/// [`set_dead_load`](DeadLoads::set_dead_load) and [`set_constraints`](Self::set_constraints),
/// and the reactions of the last evaluation read through [`reactions`](Self::reactions).
pub struct StructuralProblem {
    /// The assembler (mesh, materials, kernels).
    assembler: Assembler,
    /// Supports, prescribed displacements, loads.
    constraints: Constraints,
    /// Reactions of the last evaluation (f_int − f_ext at constrained DOFs).
    reactions: Vec<f64>,
}

impl StructuralProblem {
    /// A problem from an assembler and constraints of the same size.
    /// With ties in `constraints`, the assembler's pattern is extended for them
    /// ([`Assembler::tie`]); ties whose couplings the pattern lacks, set later
    /// ([`set_constraints`](Self::set_constraints)), are refused at the first evaluation.
    pub fn new(mut assembler: Assembler, constraints: Constraints) -> Result<Self, NewtonError> {
        check_size(&assembler, &constraints)?;
        if !constraints.ties().is_empty() {
            assembler.tie(&constraints)?;
        }
        let n = assembler.n();
        Ok(Self {
            assembler,
            constraints,
            reactions: vec![0.0; n],
        })
    }

    /// The assembler: mesh, materials, kernels, pattern (for partial internal forces, stresses,
    /// a bare assembly).
    pub fn assembler(&self) -> &Assembler {
        &self.assembler
    }

    /// Supports, prescribed values, ties and loads.
    pub fn constraints(&self) -> &Constraints {
        &self.constraints
    }

    /// Reactions of the last evaluation: f_int − f_ext at the constrained DOFs (a tie's force
    /// at its slave), zero elsewhere; zeros before the first evaluation.
    pub fn reactions(&self) -> &[f64] {
        &self.reactions
    }

    /// Adds the reference force `value` (N) at DOF `dof`: it acts as λ·`value`
    /// ([`Constraints::add_load`]).
    pub fn add_load(&mut self, dof: usize, value: f64) -> Result<(), NewtonError> {
        Ok(self.constraints.add_load(dof, value)?)
    }

    /// Prescribes DOF `dof`: u = λ·`value` (m) ([`Constraints::prescribe`]).
    pub fn prescribe_value(&mut self, dof: usize, value: f64) -> Result<(), NewtonError> {
        Ok(self.constraints.prescribe(dof, value)?)
    }

    /// Replaces the constraints and loads as a whole (a new load step's). Refused when their
    /// size is not the model's; ties whose couplings the pattern lacks (not those given to
    /// [`new`](Self::new)) are refused at the next evaluation.
    pub fn set_constraints(&mut self, constraints: Constraints) -> Result<(), NewtonError> {
        check_size(&self.assembler, &constraints)?;
        self.constraints = constraints;
        Ok(())
    }

    /// The assembler and the constraints, taken apart.
    pub fn into_parts(self) -> (Assembler, Constraints) {
        (self.assembler, self.constraints)
    }
}

/// Refuses constraints of another size than the assembler's.
fn check_size(assembler: &Assembler, constraints: &Constraints) -> Result<(), NewtonError> {
    if assembler.n() != constraints.n() {
        return Err(NewtonError::Setting {
            name: "constraints",
            reason: format!("{} DOFs for a model of {}", constraints.n(), assembler.n()),
        });
    }
    Ok(())
}

/// The perturbation protocol's door (thesis §3.2): the dead load is the λ-independent part
/// f_dead of the external force.
impl DeadLoads for StructuralProblem {
    fn set_dead_load(&mut self, dof: usize, value: f64) -> Result<(), NewtonError> {
        Ok(self.constraints.set_dead_load(dof, value)?)
    }
}

impl NonlinearProblem for StructuralProblem {
    fn n(&self) -> usize {
        self.assembler.n()
    }

    fn pattern(&self) -> Arc<SymmetricPattern> {
        self.assembler.pattern().clone()
    }

    fn prescribe(&self, u: &mut [f64], lambda: f64) {
        self.constraints.apply(u, lambda);
    }

    fn expand(&self, du: &mut [f64]) {
        self.constraints.expand_increment(du);
    }

    /// K(u)·v from the cells that hold a changed prescribed value
    /// ([`Assembler::tangent_product`]), v = Δu_c including the tied slaves that follow
    /// prescribed masters or carry an offset; then folded onto the masters (Tᵀ) and zeroed at
    /// constrained rows like the residual.
    fn coupling_force(
        &mut self,
        u: &[f64],
        from: f64,
        to: f64,
        out: &mut [f64],
    ) -> Result<bool, NewtonError> {
        let (mut at_to, mut at_from) = (u.to_vec(), u.to_vec());
        self.constraints.apply(&mut at_to, to);
        self.constraints.apply(&mut at_from, from);
        let v: Vec<f64> = at_to.iter().zip(&at_from).map(|(a, b)| a - b).collect();
        if v.iter().all(|&x| x == 0.0) {
            return Ok(false);
        }
        let kv = self.assembler.tangent_product(u, &v)?;
        let (mut f_to, mut f_from) = (vec![0.0; u.len()], vec![0.0; u.len()]);
        self.constraints.external(to, &mut f_to);
        self.constraints.external(from, &mut f_from);
        for (((o, k), a), b) in out.iter_mut().zip(&kv).zip(&f_to).zip(&f_from) {
            *o = k - (a - b);
        }
        for t in self.constraints.ties() {
            let s = out[t.slave];
            for &(m, c) in &t.masters {
                out[m] += c * s;
            }
            out[t.slave] = 0.0;
        }
        for (d, _) in self.constraints.prescribed() {
            out[d] = 0.0;
        }
        Ok(true)
    }

    fn evaluate(
        &mut self,
        u: &[f64],
        lambda: f64,
        r: &mut [f64],
        tangent: Option<&mut SymmetricMatrix>,
    ) -> Result<f64, NewtonError> {
        let (res, reactions, _) = self
            .assembler
            .residual(u, lambda, &self.constraints, tangent)?;
        r.copy_from_slice(&res);
        let mut f = vec![0.0; u.len()];
        self.constraints.external(lambda, &mut f);
        let scale = f
            .iter()
            .chain(&reactions)
            .fold(0.0f64, |a, v| a.max(v.abs()));
        self.reactions = reactions;
        Ok(scale)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{NewtonSettings, Stepping, follow_path};
    use nonlin3d_element::{ElementKind, IntegrationRule, Kinematics};
    use nonlin3d_laminate::{ShearCoupling, materials};
    use nonlin3d_mesh::{BoxParams, structured_box};

    /// A steel bar 4×1×1 mm of 4 Hex8 along x, fixed on x = 0, nonlinear kinematics; the DOFs
    /// of the x = 0 and x = 4 mm faces.
    fn bar() -> (StructuralProblem, Vec<usize>, Vec<usize>) {
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
        let (assembler, constraints) = problem.into_parts();
        assert_eq!((assembler.n(), constraints.prescribed().count()), (n, 0));
    }
}
