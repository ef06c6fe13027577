//! Fixed and prescribed DOFs, ties in replaceable groups and nodal loads, scaled by the load
//! factor λ. How they are applied to an assembled system is `constrain.rs`.

use crate::AssemblyError;
use std::collections::{BTreeMap, BTreeSet};

/// Constraints and loads of a model with `n` DOFs (3 per node, node-major).
///
/// At load factor λ: prescribed DOF d has value base(d) + λ·value(d) (fixed DOFs 0; `base` is
/// 0 unless set with [`prescribe_ramp`](Self::prescribe_ramp)), the external force is λ·f (nodal
/// loads added with [`add_load`](Self::add_load)) plus the fixed part `dead` (loads held at full
/// value whatever λ, e.g. the thesis's perturbation load before it is removed, or the loads of
/// earlier steps).
#[derive(Debug, Clone, PartialEq)]
pub struct Constraints {
    n: usize,
    prescribed: BTreeMap<usize, (f64, f64)>,
    loads: Vec<f64>,
    dead: Vec<f64>,
    ties: Vec<Tie>,
    /// The group of each tie (parallel to `ties`).
    groups: Vec<TieGroup>,
    /// Groups whose offsets are held at full value whatever λ ([`Constraints::hold_offsets`]).
    held: BTreeSet<TieGroup>,
}

/// A set of ties replaced or removed as a whole ([`Constraints::replace_tie_group`]), e.g. the
/// active contact pairs of one surface. [`Constraints::tie`] adds to [`TieGroup::DEFAULT`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
pub struct TieGroup(pub u32);

impl TieGroup {
    /// The group of the ties added with [`Constraints::tie`].
    pub const DEFAULT: Self = Self(0);
}

impl std::fmt::Display for TieGroup {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "tie group {}", self.0)
    }
}

/// A linear tie between DOFs: u_slave = Σ c_k·u_{master_k} + λ·offset (a multi-point
/// constraint, as Abaqus's `*EQUATION`). The slave is eliminated: its row and column of the
/// tangent are folded onto the masters (K′ = TᵀKT, r′ = Tᵀr) and replaced by the identity, and
/// its value follows the masters. Masters may be free or prescribed but not slaves themselves.
#[derive(Debug, Clone, PartialEq)]
pub struct Tie {
    /// The dependent DOF.
    pub slave: usize,
    /// (master DOF, coefficient).
    pub masters: Vec<(usize, f64)>,
    /// Constant part at λ = 1 (scaled by λ like a prescribed value, unless its group's offsets
    /// are held: [`Constraints::hold_offsets`]).
    pub offset: f64,
}

impl Constraints {
    /// No constraints and no loads on `n` DOFs.
    pub fn new(n: usize) -> Self {
        Self {
            n,
            prescribed: BTreeMap::new(),
            loads: vec![0.0; n],
            dead: vec![0.0; n],
            ties: Vec::new(),
            groups: Vec::new(),
            held: BTreeSet::new(),
        }
    }

    /// Holds the offsets of the ties of `group` at their full value whatever λ (`held`), or
    /// scales them by λ again (the default): u_s = Σ c·u_m + b instead of + λ·b, e.g. a contact
    /// pair's initial gap, a geometric fact that does not grow with the load. Applies to the
    /// group's present and future ties.
    pub fn hold_offsets(&mut self, group: TieGroup, held: bool) {
        if held {
            self.held.insert(group);
        } else {
            self.held.remove(&group);
        }
    }

    /// Whether the offsets of `group` are held ([`hold_offsets`](Self::hold_offsets)).
    pub fn offsets_held(&self, group: TieGroup) -> bool {
        self.held.contains(&group)
    }

    /// Ties DOF `slave` to `masters`: u_slave = Σ c·u_master + λ·`offset`, in
    /// [`TieGroup::DEFAULT`]. Errors: a DOF out of range, a non-finite coefficient, the slave
    /// among its masters, a slave that is already a slave or prescribed, or a chain (a master
    /// that is a slave, or a slave that is a master of an earlier tie).
    pub fn tie(
        &mut self,
        slave: usize,
        masters: &[(usize, f64)],
        offset: f64,
    ) -> Result<(), AssemblyError> {
        self.tie_in(TieGroup::DEFAULT, slave, masters, offset)
    }

    /// [`tie`](Self::tie) into group `group` (appended after every tie there is).
    pub fn tie_in(
        &mut self,
        group: TieGroup,
        slave: usize,
        masters: &[(usize, f64)],
        offset: f64,
    ) -> Result<(), AssemblyError> {
        self.check_tie(&self.ties, slave, masters, offset)?;
        self.ties.push(Tie {
            slave,
            masters: masters.to_vec(),
            offset,
        });
        self.groups.push(group);
        Ok(())
    }

    /// Replaces every tie of `group` by `ties` (none: the group is removed), all or nothing:
    /// each new tie is checked as [`tie`](Self::tie) checks it against the ties of the other
    /// groups and the new ones before it; on error nothing changes. The replaced group's ties
    /// move to the end of [`ties`](Self::ties) (the fold order).
    pub fn replace_tie_group(
        &mut self,
        group: TieGroup,
        ties: &[Tie],
    ) -> Result<(), AssemblyError> {
        let mut kept: Vec<Tie> = Vec::with_capacity(self.ties.len() + ties.len());
        let mut groups = Vec::with_capacity(kept.capacity());
        for (t, &g) in self.ties.iter().zip(&self.groups) {
            if g != group {
                kept.push(t.clone());
                groups.push(g);
            }
        }
        for t in ties {
            self.check_tie(&kept, t.slave, &t.masters, t.offset)?;
            kept.push(t.clone());
            groups.push(group);
        }
        self.ties = kept;
        self.groups = groups;
        Ok(())
    }

    /// The ties of `group`, in fold order.
    pub fn tie_group(&self, group: TieGroup) -> impl Iterator<Item = &Tie> + '_ {
        self.ties
            .iter()
            .zip(&self.groups)
            .filter(move |(_, g)| **g == group)
            .map(|(t, _)| t)
    }

    /// The group of each tie of [`ties`](Self::ties), in the same order.
    pub fn tie_groups(&self) -> &[TieGroup] {
        &self.groups
    }

    /// Checks a tie against the ties `ties` (see [`tie`](Self::tie)).
    fn check_tie(
        &self,
        ties: &[Tie],
        slave: usize,
        masters: &[(usize, f64)],
        offset: f64,
    ) -> Result<(), AssemblyError> {
        let bad = |reason: String| AssemblyError::Tie { slave, reason };
        if slave >= self.n || !offset.is_finite() {
            return Err(bad(format!(
                "slave out of range ({} DOFs) or offset {offset}",
                self.n
            )));
        }
        if masters.is_empty() {
            return Err(bad("no masters".into()));
        }
        for &(m, c) in masters {
            if m >= self.n || !c.is_finite() {
                return Err(bad(format!("master {m} out of range or coefficient {c}")));
            }
            if m == slave {
                return Err(bad("the slave is among its own masters".into()));
            }
            if masters.iter().filter(|x| x.0 == m).count() > 1 {
                return Err(bad(format!("master {m} listed twice")));
            }
            if ties.iter().any(|t| t.slave == m) {
                return Err(bad(format!(
                    "master {m} is itself a slave (chains are not supported)"
                )));
            }
        }
        if self.prescribed.contains_key(&slave) {
            return Err(bad("the slave is prescribed".into()));
        }
        if ties
            .iter()
            .any(|t| t.slave == slave || t.masters.iter().any(|&(m, _)| m == slave))
        {
            return Err(bad("already a slave, or a master of another tie".into()));
        }
        Ok(())
    }

    /// The ties, in the order given.
    pub fn ties(&self) -> &[Tie] {
        &self.ties
    }

    /// Makes an increment `du` consistent with the ties: du_slave = Σ c·du_master (the Newton
    /// solve leaves slave entries at zero).
    pub fn expand_increment(&self, du: &mut [f64]) {
        for t in &self.ties {
            let v: f64 = t
                .masters
                .iter()
                .map(|&(m, c)| c * du.get(m).copied().unwrap_or(0.0))
                .sum();
            if let Some(x) = du.get_mut(t.slave) {
                *x = v;
            }
        }
    }

    /// Number of DOFs.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Prescribes DOF `dof` to λ·`value` (0 = fixed). A later call overrides.
    pub fn prescribe(&mut self, dof: usize, value: f64) -> Result<(), AssemblyError> {
        if dof >= self.n || !value.is_finite() || self.ties.iter().any(|t| t.slave == dof) {
            return Err(AssemblyError::BadDof {
                what: "prescribed DOF (or a tie's slave)",
                dof,
                n: self.n,
                value,
            });
        }
        self.prescribed.insert(dof, (0.0, value));
        Ok(())
    }

    /// Prescribes DOF `dof` to ramp from `from` (λ = 0) to `to` (λ = 1), as a step of an
    /// Abaqus deck does from the previous step's value.
    pub fn prescribe_ramp(&mut self, dof: usize, from: f64, to: f64) -> Result<(), AssemblyError> {
        if dof >= self.n || !from.is_finite() || !to.is_finite() {
            return Err(AssemblyError::BadDof {
                what: "prescribed DOF",
                dof,
                n: self.n,
                value: to,
            });
        }
        self.prescribed.insert(dof, (from, to - from));
        Ok(())
    }

    /// Releases DOF `dof` (no longer prescribed: free, or a slave-to-be). Returns whether it
    /// was prescribed.
    pub fn release(&mut self, dof: usize) -> bool {
        self.prescribed.remove(&dof).is_some()
    }

    /// Fixes DOF `r` (0 = x, 1 = y, 2 = z) of every node in `nodes`.
    pub fn fix_nodes(&mut self, nodes: &[usize], r: usize) -> Result<(), AssemblyError> {
        for &n in nodes {
            self.prescribe(3 * n + r, 0.0)?;
        }
        Ok(())
    }

    /// Adds a nodal force to DOF `dof`, scaled by λ.
    pub fn add_load(&mut self, dof: usize, value: f64) -> Result<(), AssemblyError> {
        if dof >= self.n || !value.is_finite() {
            return Err(AssemblyError::BadDof {
                what: "load",
                dof,
                n: self.n,
                value,
            });
        }
        self.loads[dof] += value;
        Ok(())
    }

    /// Sets the λ-independent (dead) force at DOF `dof` (0 removes it).
    pub fn set_dead_load(&mut self, dof: usize, value: f64) -> Result<(), AssemblyError> {
        if dof >= self.n || !value.is_finite() {
            return Err(AssemblyError::BadDof {
                what: "dead load",
                dof,
                n: self.n,
                value,
            });
        }
        self.dead[dof] = value;
        Ok(())
    }

    /// Whether DOF `d` is constrained.
    pub fn is_constrained(&self, d: usize) -> bool {
        self.prescribed.contains_key(&d)
    }

    /// Constrained DOFs and their values at λ = 1.
    pub fn prescribed(&self) -> impl Iterator<Item = (usize, f64)> + '_ {
        self.prescribed.iter().map(|(&d, &(b, v))| (d, b + v))
    }

    /// Sets the constrained entries of `u` to their values at load factor λ: prescribed DOFs,
    /// then tied slaves from their masters (offsets × λ, or × 1 in held groups).
    pub fn apply(&self, u: &mut [f64], lambda: f64) {
        for (&d, &(b, v)) in &self.prescribed {
            if let Some(x) = u.get_mut(d) {
                *x = b + lambda * v;
            }
        }
        for (t, g) in self.ties.iter().zip(&self.groups) {
            let scale = if self.held.contains(g) { 1.0 } else { lambda };
            let v: f64 = t
                .masters
                .iter()
                .map(|&(m, c)| c * u.get(m).copied().unwrap_or(0.0))
                .sum();
            if let Some(x) = u.get_mut(t.slave) {
                *x = v + scale * t.offset;
            }
        }
    }

    /// External force at load factor λ into `f`.
    pub fn external(&self, lambda: f64, f: &mut [f64]) {
        for ((fi, l), d) in f.iter_mut().zip(&self.loads).zip(&self.dead) {
            *fi = lambda * l + d;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tie(slave: usize, master: usize) -> Tie {
        Tie {
            slave,
            masters: vec![(master, 1.0)],
            offset: 0.0,
        }
    }

    /// A group is replaced as a whole, after the other groups' ties; a replacement that breaks
    /// a rule (here a chain through another group's slave) changes nothing.
    #[test]
    fn a_tie_group_is_replaced_all_or_nothing() {
        let mut c = Constraints::new(30);
        c.tie(0, &[(1, 1.0)], 0.0).unwrap();
        c.replace_tie_group(TieGroup(2), &[tie(3, 4), tie(5, 6)])
            .unwrap();
        c.tie(7, &[(8, 1.0)], 0.0).unwrap();
        c.replace_tie_group(TieGroup(2), &[tie(9, 10)]).unwrap();
        let slaves: Vec<usize> = c.ties().iter().map(|t| t.slave).collect();
        assert_eq!(slaves, [0, 7, 9]);
        assert_eq!(
            c.tie_groups(),
            [TieGroup::DEFAULT, TieGroup::DEFAULT, TieGroup(2)]
        );
        let before = c.clone();
        // The second new tie's master is the first's slave: a chain, refused, nothing changes.
        let err = c.replace_tie_group(TieGroup(2), &[tie(11, 12), tie(13, 11)]);
        assert!(matches!(err, Err(AssemblyError::Tie { slave: 13, .. })));
        // A master that is another group's slave.
        let err = c.replace_tie_group(TieGroup(2), &[tie(14, 0)]);
        assert!(matches!(err, Err(AssemblyError::Tie { slave: 14, .. })));
        assert_eq!(c, before);
        // The replaced group's old slave may be used again, as a master now.
        c.replace_tie_group(TieGroup(2), &[tie(15, 9)]).unwrap();
        c.replace_tie_group(TieGroup(2), &[]).unwrap();
        assert_eq!(c.tie_group(TieGroup(2)).count(), 0);
        assert_eq!(c.ties().len(), 2);
    }

    /// A held group's offset is the same at every λ; another group's grows with λ; releasing
    /// the hold scales it again.
    #[test]
    fn held_offsets_do_not_scale_with_the_load_factor() {
        let mut c = Constraints::new(6);
        let held = TieGroup(3);
        c.tie(0, &[(1, 1.0)], 0.5).unwrap();
        c.replace_tie_group(
            held,
            &[Tie {
                slave: 2,
                masters: vec![(3, 2.0)],
                offset: -0.25,
            }],
        )
        .unwrap();
        c.hold_offsets(held, true);
        assert!(c.offsets_held(held) && !c.offsets_held(TieGroup::DEFAULT));
        let mut u = vec![1.0; 6];
        for lambda in [0.0, 0.4, 1.0] {
            c.apply(&mut u, lambda);
            assert_eq!(u[0], 1.0 + lambda * 0.5);
            assert_eq!(u[2], 2.0 - 0.25);
        }
        c.hold_offsets(held, false);
        c.apply(&mut u, 0.4);
        assert_eq!(u[2], 2.0 - 0.4 * 0.25);
    }

    /// A released DOF is free: not constrained, its value left alone by `apply`, and it may
    /// become a slave.
    #[test]
    fn a_released_dof_is_free() {
        let mut c = Constraints::new(6);
        c.prescribe(2, 0.5).unwrap();
        assert!(c.tie(2, &[(3, 1.0)], 0.0).is_err());
        assert!(c.release(2));
        assert!(!c.is_constrained(2) && !c.release(2));
        let mut u = vec![7.0; 6];
        c.apply(&mut u, 1.0);
        assert_eq!(u[2], 7.0);
        c.tie(2, &[(3, 1.0)], 0.0).unwrap();
    }
}
