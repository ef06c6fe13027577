//! Application of the constraints to an assembled, unconstrained system (thesis §2.2: the
//! boundary conditions of eq. 2.1.3 imposed by prescription), done once per evaluation after
//! every contribution has been added.
//!
//! - ties u_s = Σ_k c_k u_{m_k} + λ b are folded: r′ = Tᵀ r, K′ = Tᵀ K T, the slave's row and
//!   column become the identity and its residual (the force the tie carries) its reaction;
//! - prescribed DOFs u_p = base + λ v: r_p = 0 (its reaction is r_p before zeroing), identity
//!   rows and columns in K.
//!
//! The positions of the masked rows and columns are found once per set of constrained DOFs
//! (one pass over the pattern) and kept in [`Masks`] until that set changes.

use crate::{AssemblyError, Constraints};
use nonlin3d_solver::{SymmetricMatrix, SymmetricPattern};
use std::sync::Mutex;

/// Positions of the tangent entries in the rows and columns of the constrained DOFs (with
/// whether each is on the diagonal), for the set of constrained DOFs they were found for.
#[derive(Default)]
struct FixedMask {
    dofs: Vec<usize>,
    positions: Vec<(usize, bool)>,
}

/// Positions of the tangent entries in each tie slave's row and column, with the index on the
/// other side ((position, j) for entry (s, j) or (j, s)), for the slaves they were found for.
#[derive(Default)]
struct TieMask {
    slaves: Vec<usize>,
    entries: Vec<Vec<(usize, usize)>>,
}

/// The cached masks of one pattern (reset when the pattern changes).
#[derive(Default)]
pub(crate) struct Masks {
    fixed: Mutex<FixedMask>,
    ties: Mutex<TieMask>,
}

impl Masks {
    /// Applies `constraints` to the unconstrained residual `r` = Σ f_int − f_ext and, when
    /// given, the tangent `k` on `pattern`: ties folded (r′ = Tᵀr, K′ = TᵀKT), then zeros at
    /// constrained rows of r and identity rows and columns in K. Writes the reactions (r at
    /// each constrained DOF before zeroing, zero elsewhere) into `reactions`.
    pub(crate) fn apply(
        &self,
        pattern: &SymmetricPattern,
        constraints: &Constraints,
        r: &mut [f64],
        reactions: &mut [f64],
        mut k: Option<&mut SymmetricMatrix>,
    ) -> Result<(), AssemblyError> {
        if !constraints.ties().is_empty() {
            let mut mask = self.ties.lock().unwrap_or_else(|e| e.into_inner());
            let slaves: Vec<usize> = constraints.ties().iter().map(|t| t.slave).collect();
            if k.is_some() && mask.slaves != slaves {
                *mask = tie_mask(pattern, slaves);
            }
            let k = k.as_deref_mut().map(|k| (k, &*mask));
            fold_ties(constraints, r, reactions, k)?;
        }
        let mut fixed: Vec<usize> = constraints.prescribed().map(|(d, _)| d).collect();
        fixed.sort_unstable();
        fixed.dedup();
        for &d in &fixed {
            reactions[d] = r[d];
            r[d] = 0.0;
        }
        if let Some(k) = k {
            let mut mask = self.fixed.lock().unwrap_or_else(|e| e.into_inner());
            if mask.dofs != fixed {
                *mask = fixed_mask(pattern, fixed);
            }
            let vals = k.values_mut();
            for &(p, diagonal) in &mask.positions {
                vals[p] = if diagonal { 1.0 } else { 0.0 };
            }
        }
        Ok(())
    }
}

/// The tangent positions in the rows and columns of the (sorted) DOFs `fixed`: one pass
/// over the pattern, done again only when the set of constrained DOFs changes.
fn fixed_mask(pattern: &SymmetricPattern, fixed: Vec<usize>) -> FixedMask {
    let n = pattern.n();
    let mut is_fixed = vec![false; n];
    for &d in &fixed {
        is_fixed[d] = true;
    }
    let (cp, ri) = (pattern.col_ptr(), pattern.row_idx());
    let mut positions = Vec::new();
    for j in 0..n {
        for (p, &i) in ri.iter().enumerate().take(cp[j + 1]).skip(cp[j]) {
            if is_fixed[i] || is_fixed[j] {
                positions.push((p, i == j));
            }
        }
    }
    FixedMask {
        dofs: fixed,
        positions,
    }
}

/// The tangent positions in the rows and columns of the tie slaves `slaves` (in tie order):
/// one pass over the pattern, done again only when the slaves change.
fn tie_mask(pattern: &SymmetricPattern, slaves: Vec<usize>) -> TieMask {
    let n = pattern.n();
    let mut tie_of = vec![usize::MAX; n];
    for (t, &s) in slaves.iter().enumerate() {
        tie_of[s] = t;
    }
    let (cp, ri) = (pattern.col_ptr(), pattern.row_idx());
    let mut entries = vec![Vec::new(); slaves.len()];
    for j in 0..n {
        for (p, &i) in ri.iter().enumerate().take(cp[j + 1]).skip(cp[j]) {
            if let Some(e) = entries.get_mut(tie_of[i]) {
                e.push((p, j));
            }
            if i != j
                && let Some(e) = entries.get_mut(tie_of[j])
            {
                e.push((p, i));
            }
        }
    }
    TieMask { slaves, entries }
}

/// Folds each tie's slave onto its masters (K′ = TᵀKT, r′ = Tᵀr for u_s = Σ c_k u_{m_k}),
/// slave by slave: r_m += c·r_s; K_{m j} += c·K_{s j} (twice on the diagonal m = j, which stands
/// for both triangles); K_{m m′} += c c′ K_ss; then the slave's row and column become the
/// identity and its residual (the force the tie carries) its reaction. `k` comes with the
/// stored positions of each slave's row and column (a `TieMask` made for these ties).
fn fold_ties(
    constraints: &Constraints,
    r: &mut [f64],
    reactions: &mut [f64],
    k: Option<(&mut SymmetricMatrix, &TieMask)>,
) -> Result<(), AssemblyError> {
    for t in constraints.ties() {
        let rs = r[t.slave];
        for &(m, c) in &t.masters {
            r[m] += c * rs;
        }
        reactions[t.slave] = rs;
        r[t.slave] = 0.0;
    }
    let Some((k, mask)) = k else {
        return Ok(());
    };
    let entries = &mask.entries;
    for (t, tie) in constraints.ties().iter().enumerate() {
        let s = tie.slave;
        let missing = |i: usize, j: usize| AssemblyError::Tie {
            slave: s,
            reason: format!(
                "the tangent has no entry ({i}, {j}): build the problem after adding ties \
                 (Assembler::tie; StructuralProblem::new calls it), or reserve the tie's \
                 couplings when building the System"
            ),
        };
        // Current values of row s (other slaves' folds may have added to it).
        let row: Vec<(usize, f64)> = entries[t]
            .iter()
            .map(|&(p, j)| (j, k.values()[p]))
            .collect();
        let kss = k.get(s, s);
        for &(m, c) in &tie.masters {
            for &(j, v) in row.iter().filter(|e| e.0 != s) {
                let w = if j == m { 2.0 * c * v } else { c * v };
                k.add(m, j, w).map_err(|_| missing(m, j))?;
            }
        }
        for (a, &(m, c)) in tie.masters.iter().enumerate() {
            for &(m2, c2) in &tie.masters[..=a] {
                k.add(m, m2, c * c2 * kss).map_err(|_| missing(m, m2))?;
            }
        }
        let values = k.values_mut();
        for &(p, j) in &entries[t] {
            values[p] = if j == s { 1.0 } else { 0.0 };
        }
    }
    Ok(())
}

/// The couplings a tie needs in a pattern for its fold (K′ = TᵀKT) to stay inside it: every
/// master coupled with every DOF the slave is coupled with (its own node's included) and with
/// the other masters. Returns
/// the first missing pair (master, DOF), `neighbours` giving the coupled nodes of each node
/// (both triangles, sorted, itself included).
pub(crate) fn missing_coupling(
    neighbours: &[Vec<usize>],
    slave: usize,
    masters: &[(usize, f64)],
) -> Option<(usize, usize)> {
    let coupled = |a: usize, b: usize| neighbours[a / 3].binary_search(&(b / 3)).is_ok();
    for &(m, _) in masters {
        for &v in &neighbours[slave / 3] {
            if !coupled(m, 3 * v) {
                return Some((m, 3 * v));
            }
        }
        for &(m2, _) in masters {
            if !coupled(m, m2) {
                return Some((m, m2));
            }
        }
    }
    None
}

/// The coupled nodes of each node of a node-blocked `pattern` (both triangles, sorted, the
/// node itself included).
pub(crate) fn node_neighbours(pattern: &SymmetricPattern) -> Vec<Vec<usize>> {
    let nodes = pattern.n() / 3;
    let mut out: Vec<Vec<usize>> = (0..nodes).map(|v| vec![v]).collect();
    for j in 0..nodes {
        for &i in pattern.column(3 * j).iter().skip(3).step_by(3) {
            out[j].push(i / 3);
            out[i / 3].push(j);
        }
    }
    for l in &mut out {
        l.sort_unstable();
        l.dedup();
    }
    out
}
