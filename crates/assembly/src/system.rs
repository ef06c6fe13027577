//! The constrained system: contributions summed on one pattern, then the constraints applied
//! once (thesis eq. 2.1.3 with its boundary conditions, §2.2):
//!
//! r(u, λ) = Tᵀ (Σ_c f_int,c(u) − f_ext(λ)) with zeros at prescribed rows,
//! K(u) = Tᵀ (Σ_c ∂f_int,c/∂u) T with identity rows and columns at prescribed DOFs and slaves,
//!
//! u_p = base_p + λ v_p at prescribed DOFs, u_s = Σ_k c_k u_{m_k} + λ b_s at tied slaves (T the
//! map from the masters to the slaves). The pattern is the union of the contributions'
//! couplings, the fill the ties' folds need, and couplings reserved up front; it is built once,
//! so a tie group replaced later within the reserved couplings costs no new pattern and no new
//! symbolic analysis of the solver. Ties outside it are reserved later by
//! [`System::reserve_ties`]: the pattern is built again (the solver must then analyse anew).

use crate::constrain::{Masks, missing_coupling, node_neighbours};
use crate::contribution::check_len;
use crate::solid::pattern::{whole_nodes, with_lone_nodes};
use crate::{AssemblyError, Constraints, Contribution, Tie, TieGroup};
use nonlin3d_solver::{SymmetricMatrix, SymmetricPattern};
use std::any::Any;
use std::collections::HashMap;
use std::sync::{Arc, OnceLock};

/// Contributions, constraints and the union pattern (see the module docs). Made by
/// [`System::builder`].
pub struct System {
    n: usize,
    contributions: Vec<Box<dyn Contribution>>,
    constraints: Constraints,
    pattern: Arc<SymmetricPattern>,
    /// The coupled nodes of each node in `pattern` (for the checks of replaced ties).
    neighbours: OnceLock<Vec<Vec<usize>>>,
    masks: Masks,
    builds: usize,
    /// The couplings reserved at build (kept for a rebuild by [`System::reserve_ties`]).
    reserved: Vec<Vec<usize>>,
    /// The ties reserved at build and since.
    reserved_ties: Vec<Tie>,
}

/// What [`System::builder`] collects before the pattern is built.
pub struct SystemBuilder {
    contributions: Vec<Box<dyn Contribution>>,
    constraints: Constraints,
    reserved: Vec<Vec<usize>>,
    reserved_ties: Vec<Tie>,
}

/// One evaluation of the constrained system at (u, λ).
#[derive(Debug, Clone, PartialEq)]
pub struct Evaluation {
    /// r = Tᵀ(Σ f_int − f_ext), zero at constrained DOFs (prescribed and slaves).
    pub residual: Vec<f64>,
    /// Σ f_int − f_ext at constrained DOFs before zeroing (for a slave: the force its tie
    /// carries), zero elsewhere.
    pub reactions: Vec<f64>,
    /// Σ_c E_c(u).
    pub energy: f64,
    /// ‖f_ext(λ)‖∞, the largest external force (a force scale for convergence tests).
    pub external_max: f64,
}

impl SystemBuilder {
    /// Adds contribution `c` (summed in the order added; the first writes, the others add).
    pub fn contribution(mut self, c: impl Contribution) -> Self {
        self.contributions.push(Box::new(c));
        self
    }

    /// Adds a boxed contribution.
    pub fn boxed(mut self, c: Box<dyn Contribution>) -> Self {
        self.contributions.push(c);
        self
    }

    /// Reserves the couplings of a dense block over `dofs` (widened to whole nodes), e.g. the
    /// nodes of a candidate contact pair, for contributions or ties that come later.
    pub fn reserve(mut self, dofs: &[usize]) -> Self {
        self.reserved.push(dofs.to_vec());
        self
    }

    /// Reserves what folding each of `ties` needs (its masters coupled with everything its
    /// slave is coupled with, and with each other), as if they were among the constraints:
    /// e.g. every candidate tie of an active-set contact, so that any subset of them can later
    /// be made a tie group with [`System::replace_tie_group`].
    pub fn reserve_ties(mut self, ties: &[Tie]) -> Self {
        self.reserved_ties.extend_from_slice(ties);
        self
    }

    /// Builds the union pattern (once) and hands it to every contribution.
    pub fn build(self) -> Result<System, AssemblyError> {
        let n = self.constraints.n();
        let mut contributions = self.contributions;
        let pattern = build_pattern(
            &mut contributions,
            &self.constraints,
            &self.reserved,
            &self.reserved_ties,
        )?;
        Ok(System {
            n,
            contributions,
            constraints: self.constraints,
            pattern,
            neighbours: OnceLock::new(),
            masks: Masks::default(),
            builds: 1,
            reserved: self.reserved,
            reserved_ties: self.reserved_ties,
        })
    }
}

/// The union pattern of the contributions' couplings, the `reserved` blocks and the fill of
/// the constraints' ties and the `reserved_ties`, handed to every contribution.
fn build_pattern(
    contributions: &mut [Box<dyn Contribution>],
    constraints: &Constraints,
    reserved: &[Vec<usize>],
    reserved_ties: &[Tie],
) -> Result<Arc<SymmetricPattern>, AssemblyError> {
    let n = constraints.n();
    let mut lists: Vec<Vec<usize>> = Vec::new();
    for c in contributions.iter() {
        lists.extend(c.couplings());
    }
    lists.extend(reserved.iter().cloned());
    for l in &lists {
        if let Some(&d) = l.iter().find(|&&d| d >= n) {
            return Err(AssemblyError::Length {
                what: "coupled DOF",
                expected: n,
                got: d,
            });
        }
    }
    let ties: Vec<&Tie> = constraints.ties().iter().chain(reserved_ties).collect();
    let pattern = Arc::new(union_pattern(n, lists, &ties)?);
    for c in contributions.iter_mut() {
        c.adopt(&pattern)?;
    }
    Ok(pattern)
}

/// The node-blocked pattern of `lists` (each a dense block, widened to whole nodes) with the
/// fill of `ties`: a list holding a slave couples with the slave's masters too, and each tie's
/// slave and masters are coupled (K′ = TᵀKT stays inside); nodes in no list keep their block.
fn union_pattern(
    n: usize,
    lists: Vec<Vec<usize>>,
    ties: &[&Tie],
) -> Result<SymmetricPattern, AssemblyError> {
    let mut masters: HashMap<usize, Vec<usize>> = HashMap::new();
    for t in ties {
        if t.slave >= n || t.masters.iter().any(|m| m.0 >= n) {
            return Err(AssemblyError::Tie {
                slave: t.slave,
                reason: format!("a DOF of the tie is out of range ({n} DOFs)"),
            });
        }
        masters
            .entry(t.slave)
            .or_default()
            .extend(t.masters.iter().map(|m| m.0));
    }
    let mut all: Vec<Vec<usize>> = lists
        .into_iter()
        .map(|l| {
            let mut l = whole_nodes(l);
            let extra: Vec<usize> = l
                .iter()
                .filter_map(|x| masters.get(x))
                .flatten()
                .copied()
                .collect();
            if extra.is_empty() {
                return l;
            }
            l.extend(extra);
            whole_nodes(l)
        })
        .collect();
    all.extend(ties.iter().map(|t| {
        let mut l: Vec<usize> = t.masters.iter().map(|m| m.0).collect();
        l.push(t.slave);
        whole_nodes(l)
    }));
    Ok(SymmetricPattern::from_dof_lists(
        n,
        &with_lone_nodes(all, n),
    )?)
}

impl System {
    /// A builder for a system under `constraints` (its size is the system's).
    pub fn builder(constraints: Constraints) -> SystemBuilder {
        SystemBuilder {
            contributions: Vec::new(),
            constraints,
            reserved: Vec::new(),
            reserved_ties: Vec::new(),
        }
    }

    /// Number of DOFs.
    pub fn n(&self) -> usize {
        self.n
    }

    /// The union pattern (fixed for the system's life).
    pub fn pattern(&self) -> &Arc<SymmetricPattern> {
        &self.pattern
    }

    /// How many times the pattern was built (1: no change since [`SystemBuilder::build`]; one
    /// more for each [`reserve_ties`](Self::reserve_ties) that had to widen it).
    pub fn pattern_builds(&self) -> usize {
        self.builds
    }

    /// A zero tangent on the pattern.
    pub fn new_tangent(&self) -> SymmetricMatrix {
        SymmetricMatrix::zeros(self.pattern.clone())
    }

    /// The constraints and loads.
    pub fn constraints(&self) -> &Constraints {
        &self.constraints
    }

    /// The loads of the constraints, to change (nodal and dead loads; prescribed values and
    /// ties too, but a tie added here is checked only when the tangent is folded
    /// ([`AssemblyError::Tie`]): prefer [`replace_tie_group`](Self::replace_tie_group)).
    pub fn constraints_mut(&mut self) -> &mut Constraints {
        &mut self.constraints
    }

    /// The contributions (in summation order) and the constraints, taken apart (a contribution
    /// is recovered by type with `Box<dyn Any>`'s `downcast`, e.g. an
    /// [`Assembler`](crate::Assembler) to build another system with other constraints).
    pub fn into_parts(self) -> (Vec<Box<dyn Contribution>>, Constraints) {
        (self.contributions, self.constraints)
    }

    /// The contributions, in summation order.
    pub fn contributions(&self) -> impl Iterator<Item = &dyn Contribution> + '_ {
        self.contributions.iter().map(|c| &**c)
    }

    /// The first contribution of type `T` (e.g. the [`Assembler`](crate::Assembler), for
    /// [`partial_internal`](crate::Assembler::partial_internal)).
    pub fn find<T: Contribution>(&self) -> Option<&T> {
        self.contributions
            .iter()
            .find_map(|c| (&**c as &dyn Any).downcast_ref::<T>())
    }

    /// Replaces the ties of `group` by `ties` (none: removed) without a new pattern: every
    /// coupling each tie's fold needs must be in the pattern (reserved when building, see
    /// [`SystemBuilder::reserve_ties`]), else [`AssemblyError::Unreserved`] names the tie and
    /// the two DOFs. All or nothing; the other checks as [`Constraints::replace_tie_group`].
    pub fn replace_tie_group(
        &mut self,
        group: TieGroup,
        ties: &[Tie],
    ) -> Result<(), AssemblyError> {
        let neighbours = self
            .neighbours
            .get_or_init(|| node_neighbours(&self.pattern));
        for t in ties {
            if t.slave >= self.n || t.masters.iter().any(|m| m.0 >= self.n) {
                // Out of range: reported by the constraints' own check below.
                continue;
            }
            if let Some((master, dof)) = missing_coupling(neighbours, t.slave, &t.masters) {
                return Err(AssemblyError::Unreserved {
                    group,
                    slave: t.slave,
                    master,
                    dof,
                });
            }
        }
        self.constraints.replace_tie_group(group, ties)
    }

    /// Reserves what folding each of `ties` needs, as [`SystemBuilder::reserve_ties`] does at
    /// build, for ties found to be needed later (a contact set that grew beyond the pairs
    /// reserved): if the pattern holds every coupling already, nothing changes and `false` is
    /// returned; else the pattern is built again with them (every contribution adopts it, the
    /// tangents made before no longer fit: make them anew, and a solver analysed for the old
    /// pattern must analyse again) and `true` is returned. Errors: a DOF out of range.
    pub fn reserve_ties(&mut self, ties: &[Tie]) -> Result<bool, AssemblyError> {
        let neighbours = self
            .neighbours
            .get_or_init(|| node_neighbours(&self.pattern));
        let held = |t: &Tie| {
            t.slave < self.n
                && t.masters.iter().all(|m| m.0 < self.n)
                && missing_coupling(neighbours, t.slave, &t.masters).is_none()
        };
        if ties.iter().all(held) {
            return Ok(false);
        }
        let mut reserved_ties = self.reserved_ties.clone();
        reserved_ties.extend_from_slice(ties);
        let pattern = build_pattern(
            &mut self.contributions,
            &self.constraints,
            &self.reserved,
            &reserved_ties,
        )?;
        self.reserved_ties = reserved_ties;
        self.pattern = pattern;
        self.neighbours = OnceLock::new();
        self.masks = Masks::default();
        self.builds += 1;
        Ok(true)
    }

    /// Releases prescribed DOF `dof` (free from the next evaluation on). Returns whether it was
    /// prescribed.
    pub fn release(&mut self, dof: usize) -> bool {
        self.constraints.release(dof)
    }

    /// Sets the constrained entries of `u` for load factor λ ([`Constraints::apply`]).
    pub fn prescribe(&self, u: &mut [f64], lambda: f64) {
        self.constraints.apply(u, lambda);
    }

    /// Completes an increment at the tied slaves ([`Constraints::expand_increment`]).
    pub fn expand_increment(&self, du: &mut [f64]) {
        self.constraints.expand_increment(du);
    }

    /// f_ext(λ) = λ f + f_dead + Σ_c f_ext,c(λ).
    pub fn external(&self, lambda: f64) -> Vec<f64> {
        let mut f = vec![0.0; self.n];
        self.constraints.external(lambda, &mut f);
        for c in &self.contributions {
            c.add_external(lambda, &mut f);
        }
        f
    }

    /// The unconstrained Σ_c f_int,c(u) and tangent Σ_c ∂f_int,c/∂u (every value written)
    /// into `tangent` when given; returns Σ_c E_c.
    pub fn assemble(
        &self,
        u: &[f64],
        internal: &mut [f64],
        mut tangent: Option<&mut SymmetricMatrix>,
    ) -> Result<f64, AssemblyError> {
        check_len("displacements", u, self.n)?;
        check_len("internal forces", internal, self.n)?;
        if let Some(k) = tangent.as_deref()
            && !(Arc::ptr_eq(k.pattern(), &self.pattern) || **k.pattern() == *self.pattern)
        {
            return Err(AssemblyError::Length {
                what: "tangent entries (make it with System::new_tangent)",
                expected: self.pattern.nnz_lower(),
                got: k.pattern().nnz_lower(),
            });
        }
        let Some((first, rest)) = self.contributions.split_first() else {
            internal.fill(0.0);
            if let Some(k) = tangent {
                k.set_zero();
            }
            return Ok(0.0);
        };
        let mut energy = first.set(u, internal, tangent.as_deref_mut())?;
        for c in rest {
            energy += c.add(u, internal, tangent.as_deref_mut())?;
        }
        Ok(energy)
    }

    /// The constrained system at (u, λ): the contributions summed, then the constraints applied
    /// once (module docs); the tangent into `tangent` when given.
    pub fn evaluate(
        &self,
        u: &[f64],
        lambda: f64,
        mut tangent: Option<&mut SymmetricMatrix>,
    ) -> Result<Evaluation, AssemblyError> {
        let mut r = vec![0.0; self.n];
        let energy = self.assemble(u, &mut r, tangent.as_deref_mut())?;
        let f = self.external(lambda);
        for (r, f) in r.iter_mut().zip(&f) {
            *r -= f;
        }
        let mut reactions = vec![0.0; self.n];
        self.masks.apply(
            &self.pattern,
            &self.constraints,
            &mut r,
            &mut reactions,
            tangent,
        )?;
        Ok(Evaluation {
            residual: r,
            reactions,
            energy,
            external_max: f.iter().fold(0.0f64, |a, v| a.max(v.abs())),
        })
    }

    /// v ← Tᵀ v with zeros at constrained rows: a force vector constrained as the residual is
    /// (each slave's entry added to its masters, c·v_s, then zeroed; prescribed rows zeroed),
    /// e.g. the coupling force K_fc·Δu_c − Δf_ext of a change of prescribed values.
    pub fn fold(&self, v: &mut [f64]) -> Result<(), AssemblyError> {
        check_len("force vector", v, self.n)?;
        for t in self.constraints.ties() {
            let s = v[t.slave];
            for &(m, c) in &t.masters {
                v[m] += c * s;
            }
            v[t.slave] = 0.0;
        }
        for (d, _) in self.constraints.prescribed() {
            v[d] = 0.0;
        }
        Ok(())
    }

    /// y = Σ_c ∂f_int,c/∂u(u)·v, the unconstrained tangent times v.
    pub fn tangent_product(&self, u: &[f64], v: &[f64]) -> Result<Vec<f64>, AssemblyError> {
        check_len("displacements", u, self.n)?;
        check_len("product vector", v, self.n)?;
        let mut y = vec![0.0; self.n];
        for c in &self.contributions {
            c.add_product(u, v, &mut y)?;
        }
        Ok(y)
    }
}
