//! The exact contact constraint of an active pair as a tie, and its contact force (thesis §2.7:
//! w_upper = w_lower at the pairs in contact, here along the deformed normal).
//!
//! Constraint: n·(u_up − u_low) = −g₀, g₀ = n·(X_up − X_low), i.e. the deformed gap
//! n·(x_up − x_low) is zero with n frozen over a pass. With k the upper node's component of
//! largest |n_k| (not prescribed) as the slave s:
//!
//! u_s = Σ_{j≠k} (−n_j/n_k) u_up,j + Σ_j (n_j/n_k) u_low,j − g₀/n_k.
//!
//! Contact force. The system folds the residual r = f_int − f_ext onto the masters
//! (r′_m = r_m + c_m r_s) and keeps r_s as the slave's reaction R_s. At a converged state
//! r′_m ≈ 0 at free masters, so r_up,j = −c_j R_s = (n_j/n_k) R_s and r_low,j = −(n_j/n_k) R_s:
//! the unbalanced force at the upper node is p·n and at the lower node −p·n with
//!
//! p = R_s / n_k,
//!
//! the force the base exerts on the sublaminate along n: compressive (faces pressed together)
//! when p > 0, tensile when p < 0.

use crate::Pair;
use nonlin3d_assembly::Tie;

/// The slave component of a pair's tie: the upper node's component with the largest |n_k|
/// among those `free` allows (not prescribed); None if none is free or n has no such component.
pub fn slave_component(pair: Pair, n: [f64; 3], free: impl Fn(usize) -> bool) -> Option<usize> {
    (0..3)
        .filter(|&k| free(3 * pair.upper + k) && n[k] != 0.0)
        .max_by(|&a, &b| n[a].abs().total_cmp(&n[b].abs()))
}

/// The tie n·(u_up − u_low) = −g₀ of `pair` with slave component `k` (module docs).
pub fn contact_tie(pair: Pair, n: [f64; 3], g0: f64, k: usize) -> Tie {
    weighted_tie(pair, n, g0, k, &[])
}

/// The tie g(pair) + Σ_t w_t g(pair_t) = 0 of the gaps g = n·(u_up − u_low) + g₀ of `pair`
/// (slave component `k` of its upper node) and of the pairs `others` = (pair_t, n_t, g₀_t, w_t):
/// the constraint g̃_m = 0 of a mid-edge pair whose end corners are open (w_t = −α, docs of
/// `active`). Slave value u_s = Σ c_j u_j + offset with c = −n_j/n_k (upper), +n_j/n_k (lower)
/// and −w_t n_t,j/n_k, +w_t n_t,j/n_k on the others' nodes, offset −(g₀ + Σ w_t g₀_t)/n_k.
pub fn weighted_tie(
    pair: Pair,
    n: [f64; 3],
    g0: f64,
    k: usize,
    others: &[(Pair, [f64; 3], f64, f64)],
) -> Tie {
    let nk = n[k];
    let mut masters = Vec::with_capacity(5 + 6 * others.len());
    for j in (0..3).filter(|&j| j != k && n[j] != 0.0) {
        masters.push((3 * pair.upper + j, -n[j] / nk));
    }
    for j in (0..3).filter(|&j| n[j] != 0.0) {
        masters.push((3 * pair.lower + j, n[j] / nk));
    }
    let mut offset = g0;
    for &(q, m, g0q, w) in others {
        for j in (0..3).filter(|&j| m[j] != 0.0) {
            masters.push((3 * q.upper + j, -w * m[j] / nk));
            masters.push((3 * q.lower + j, w * m[j] / nk));
        }
        offset += w * g0q;
    }
    Tie {
        slave: 3 * pair.upper + k,
        masters,
        offset: -offset / nk,
    }
}

/// A tie that couples both whole nodes of `pair` and of the pairs `others` (slave the upper
/// node's z, masters the lower node's three DOFs and every DOF of the others' nodes):
/// reserving it reserves what any contact tie of the pair needs, whatever its normal, slave
/// component and open end corners (the pattern is node-blocked).
pub fn candidate_tie(pair: Pair, others: &[Pair]) -> Tie {
    let mut masters: Vec<(usize, f64)> = (0..3).map(|j| (3 * pair.lower + j, 1.0)).collect();
    for q in others {
        for j in 0..3 {
            masters.push((3 * q.upper + j, 1.0));
            masters.push((3 * q.lower + j, 1.0));
        }
    }
    Tie {
        slave: 3 * pair.upper + 2,
        masters,
        offset: 0.0,
    }
}

/// The contact force p = R_s / n_k of a pair tied with slave component `k` (module docs), from
/// the reactions of an evaluation (N, compressive positive).
pub fn contact_force(reactions: &[f64], pair: Pair, n: [f64; 3], k: usize) -> f64 {
    reactions[3 * pair.upper + k] / n[k]
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    /// The tie's slave value makes the deformed gap along n exactly zero for any masters'
    /// values, and the slave is the component of largest |n_k| among the free ones.
    #[test]
    fn the_tie_closes_the_gap_along_the_normal() {
        let pair = Pair { upper: 5, lower: 2 };
        let n = {
            let v = [0.1f64, -0.3, 0.95];
            let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
            v.map(|c| c / l)
        };
        let g0 = 2e-4;
        let k = slave_component(pair, n, |_| true).unwrap();
        assert_eq!(k, 2);
        assert_eq!(slave_component(pair, n, |d| d != 17), Some(1));
        let t = contact_tie(pair, n, g0, k);
        let mut u: Vec<f64> = (0..18)
            .map(|d| 1e-3 * ((d * 37 % 11) as f64 - 5.0))
            .collect();
        u[t.slave] = t.masters.iter().map(|&(m, c)| c * u[m]).sum::<f64>() + t.offset;
        let rel: f64 = (0..3).map(|j| n[j] * (u[15 + j] - u[6 + j])).sum();
        assert_relative_eq!(rel, -g0, epsilon = 1e-16);
    }

    /// The weighted tie makes g(pair) − α Σ g(ends) exactly zero for any masters' values, the
    /// gaps g = n·(u_up − u_low) + g₀ each along its own normal.
    #[test]
    fn the_weighted_tie_closes_the_weighted_gap() {
        let pair = Pair { upper: 5, lower: 2 };
        let a = Pair { upper: 4, lower: 1 };
        let b = Pair { upper: 3, lower: 0 };
        let n = [0.0, 0.6, 0.8];
        let (na, nb) = ([0.6, 0.0, 0.8], [0.0, 0.0, 1.0]);
        let (g0, ga, gb) = (1e-4, -2e-4, 3e-4);
        let alpha = crate::ALPHA;
        let t = weighted_tie(pair, n, g0, 2, &[(a, na, ga, -alpha), (b, nb, gb, -alpha)]);
        let mut u: Vec<f64> = (0..18)
            .map(|d| 1e-3 * ((d * 37 % 11) as f64 - 5.0))
            .collect();
        u[t.slave] = t.masters.iter().map(|&(m, c)| c * u[m]).sum::<f64>() + t.offset;
        let gap = |p: Pair, n: [f64; 3], g0: f64| -> f64 {
            (0..3)
                .map(|j| n[j] * (u[3 * p.upper + j] - u[3 * p.lower + j]))
                .sum::<f64>()
                + g0
        };
        let c = gap(pair, n, g0) - alpha * (gap(a, na, ga) + gap(b, nb, gb));
        assert!(c.abs() < 1e-16, "{c:e}");
    }

    /// Forces p·n on the upper node and −p·n on the lower node, folded through the tie, leave
    /// zero at every master and p·n_k at the slave: the formula gives p back.
    #[test]
    fn the_slave_reaction_gives_the_contact_force() {
        let pair = Pair { upper: 1, lower: 0 };
        let n = [0.0, 0.6, 0.8];
        let k = slave_component(pair, n, |_| true).unwrap();
        let t = contact_tie(pair, n, 0.0, k);
        let p = 42.0;
        let mut r = [0.0; 6];
        for j in 0..3 {
            r[3 + j] = p * n[j];
            r[j] = -p * n[j];
        }
        let rs = r[t.slave];
        for &(m, c) in &t.masters {
            r[m] += c * rs;
        }
        r[t.slave] = 0.0;
        assert!(r.iter().all(|x| x.abs() < 1e-13), "{r:?}");
        let mut reactions = [0.0; 6];
        reactions[t.slave] = rs;
        assert_relative_eq!(
            contact_force(&reactions, pair, n, k),
            p,
            max_relative = 1e-15
        );
    }
}
