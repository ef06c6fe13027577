//! The two ways [`condense`](crate::condense) forms K_red = K_bb − K_bi K_ii⁻¹ K_ib and the
//! loads' −K_bi K_ii⁻¹ x (thesis §2.6):
//!
//! - [`by_schur`]: one partial LDLᵀ of [K_ii K_ib; K_bi K_bb] with the interface last, K_red
//!   its trailing block ([`SchurComplement`]);
//! - [`by_blocks`]: K_ii factorised alone and K_ii⁻¹K_ib formed in blocks of right-hand sides
//!   (`CondenseSettings::schur = false`).
//!
//! Both keep what solves K_ii x = b for the recovery ([`Interior`]).

use crate::SubstructureError;
use crate::dofs::{Class, Split};
use nonlin3d_solver::{
    FaerMode, FaerOrdering, FaerSolver, LinearSolver, SchurComplement, SolverError,
    SymmetricMatrix, SymmetricPattern,
};
use std::sync::Arc;
use std::time::Instant;

/// What solves K_ii x = b after a condensation.
pub(crate) enum Interior {
    /// The partial factor (its interior sweeps).
    Schur(Box<SchurComplement>),
    /// K_ii's own factor (interior numbering).
    Faer(Box<FaerSolver>),
}

impl Interior {
    /// x ← K_ii⁻¹ x, x in the interior's order ([`Split::interior`]).
    pub(crate) fn solve(&mut self, x: &mut [f64]) -> Result<(), SolverError> {
        match self {
            Self::Schur(s) => s.solve_interior(x),
            Self::Faer(f) => f.solve_in_place(x, 1),
        }
    }
}

/// K_red (dense, row-major, interface order), −K_bi K_ii⁻¹ x of the three load vectors, the
/// interior's solver, and what it cost.
pub(crate) struct Reduced {
    pub kred: Vec<f64>,
    pub loads: [Vec<f64>; 3],
    pub interior: Interior,
    pub factor_entries: usize,
    /// Right-hand sides per block (0: the partial factorisation).
    pub block: usize,
    pub asymmetry: f64,
    /// Seconds in the ordering and factorisation.
    pub factored_s: f64,
}

/// K_red from one partial LDLᵀ of K's free DOFs, interior `s.interior` ordered by
/// `ordering`, interface `s.boundary` last (K_red read from the interface's block, so exact
/// also where K_red is singular). Errors: a zero pivot of K_ii (its DOF of the linear
/// sub-mesh), negative pivots.
pub(crate) fn by_schur(
    k: &SymmetricMatrix,
    s: &Split,
    ordering: FaerOrdering,
    rhs: &[Vec<f64>; 3],
) -> Result<Reduced, SubstructureError> {
    let clock = Instant::now();
    let mut schur = SchurComplement::analyze(k.pattern(), &s.interior, &s.boundary, ordering)?;
    let out = schur.factorize(k)?;
    if out.negative_pivots > 0 {
        return Err(SubstructureError::IndefiniteInterior {
            count: out.negative_pivots,
        });
    }
    let factored_s = clock.elapsed().as_secs_f64();
    let loads = [
        schur.reduce(&rhs[0])?,
        schur.reduce(&rhs[1])?,
        schur.reduce(&rhs[2])?,
    ];
    Ok(Reduced {
        kred: out.schur,
        loads,
        factor_entries: schur.factor_entries(),
        interior: Interior::Schur(Box::new(schur)),
        block: 0,
        asymmetry: 0.0,
        factored_s,
    })
}

/// K_red by K_ii's factor (on `threads`, ordered by `ordering`) and blocks of `block` right-hand
/// sides K_ii⁻¹K_ib (0: all at once). Errors: a zero pivot of K_ii (its DOF of the linear
/// sub-mesh), negative pivots.
pub(crate) fn by_blocks(
    k: &SymmetricMatrix,
    s: &Split,
    (block, threads, ordering): (usize, usize, FaerOrdering),
    rhs: &[Vec<f64>; 3],
) -> Result<Reduced, SubstructureError> {
    let clock = Instant::now();
    let b = blocks(k, s)?;
    let (mut solver, factor_entries) = factorise(&b.kii, s, threads, ordering)?;
    let factored_s = clock.elapsed().as_secs_f64();
    let (ni, nb) = (s.interior.len(), s.boundary.len());
    let mut x = rhs.concat();
    solver.solve_in_place(&mut x, 3)?;
    let reduce = |x: &[f64]| times_kbi(&b.kib, x).iter().map(|v| -v).collect();
    let loads = [
        reduce(&x[..ni]),
        reduce(&x[ni..2 * ni]),
        reduce(&x[2 * ni..]),
    ];
    let block = if block == 0 { nb.max(1) } else { block };
    let mut kred = b.kbb;
    let mut x = vec![0.0; ni * block.min(nb.max(1))];
    for start in (0..nb).step_by(block) {
        let w = block.min(nb - start);
        let x = &mut x[..ni * w];
        x.fill(0.0);
        for c in 0..w {
            for &(i, v) in &b.kib[start + c] {
                x[c * ni + i] = v;
            }
        }
        solver.solve_in_place(x, w)?;
        for c in 0..w {
            let col = &x[c * ni..(c + 1) * ni];
            for (a, kib) in b.kib.iter().enumerate() {
                let dot: f64 = kib.iter().map(|&(i, v)| v * col[i]).sum();
                kred[a * nb + start + c] -= dot;
            }
        }
    }
    let asymmetry = symmetrise(&mut kred, nb);
    Ok(Reduced {
        kred,
        loads,
        interior: Interior::Faer(Box::new(solver)),
        factor_entries,
        block,
        asymmetry,
        factored_s,
    })
}

/// The blocks of K the condensation needs: K_ii (sparse, factorised), K_ib by interface column
/// (interior index, value), K_bb dense row-major.
struct Blocks {
    kii: SymmetricMatrix,
    kib: Vec<Vec<(usize, f64)>>,
    kbb: Vec<f64>,
}

/// Splits the lower-triangle `k` into K_ii, K_ib and K_bb by `class`.
fn blocks(k: &SymmetricMatrix, s: &Split) -> Result<Blocks, SubstructureError> {
    let (ni, nb) = (s.interior.len(), s.boundary.len());
    let (cp, ri) = (k.pattern().col_ptr(), k.pattern().row_idx());
    let mut columns: Vec<Vec<usize>> = vec![Vec::new(); ni];
    let mut kib: Vec<Vec<(usize, f64)>> = vec![Vec::new(); nb];
    let mut kbb = vec![0.0; nb * nb];
    let mut ii = Vec::new();
    for j in 0..k.n() {
        for p in cp[j]..cp[j + 1] {
            let (i, v) = (ri[p], k.values()[p]);
            match (s.class[i], s.class[j]) {
                // Interior numbering follows the linear numbering: i ≥ j stays lower.
                (Class::Interior(a), Class::Interior(b)) => {
                    columns[b].push(a);
                    ii.push((a, b, v));
                }
                (Class::Interior(a), Class::Boundary(b))
                | (Class::Boundary(b), Class::Interior(a)) => {
                    kib[b].push((a, v));
                }
                (Class::Boundary(a), Class::Boundary(b)) => {
                    kbb[a * nb + b] = v;
                    kbb[b * nb + a] = v;
                }
                _ => {}
            }
        }
    }
    let pattern = Arc::new(SymmetricPattern::from_lower_columns(ni, &columns)?);
    // K's columns hold their rows ascending with the diagonal, and the interior numbering
    // follows the linear one, so the values came in the pattern's order (no search per entry);
    // the slow path only if the pattern had to add a diagonal.
    let kii = if pattern.nnz_lower() == ii.len() {
        SymmetricMatrix::from_values(pattern, ii.into_iter().map(|(_, _, v)| v).collect())?
    } else {
        let mut kii = SymmetricMatrix::zeros(pattern);
        for (a, b, v) in ii {
            kii.add(a, b, v)?;
        }
        kii
    };
    Ok(Blocks { kii, kib, kbb })
}

/// Factorises K_ii; a zero pivot names its DOF of the linear sub-mesh.
fn factorise(
    kii: &SymmetricMatrix,
    s: &Split,
    threads: usize,
    ordering: FaerOrdering,
) -> Result<(FaerSolver, usize), SubstructureError> {
    let mut solver = FaerSolver::new(FaerMode::Ldlt)
        .with_threads(threads)
        .with_ordering(ordering);
    let analysis = solver.analyze(kii.pattern())?;
    match solver.factorize(kii) {
        Ok(f) if f.negative_pivots > 0 => Err(SubstructureError::IndefiniteInterior {
            count: f.negative_pivots,
        }),
        Ok(_) => Ok((solver, analysis.factor_entries)),
        Err(SolverError::ZeroPivot {
            equation,
            dof,
            pivot,
            diagonal,
        }) => Err(SolverError::ZeroPivot {
            equation,
            dof: s.interior[dof],
            pivot,
            diagonal,
        }
        .into()),
        Err(e) => Err(e.into()),
    }
}

/// y = K_bi x for one interior vector x (K_bi = K_ibᵀ by interface column).
fn times_kbi(kib: &[Vec<(usize, f64)>], x: &[f64]) -> Vec<f64> {
    kib.iter()
        .map(|col| col.iter().map(|&(i, v)| v * x[i]).sum())
        .collect()
}

/// K ← (K + Kᵀ)/2 for a dense row-major n × n `k`; returns max |K − Kᵀ| / max |K| before.
pub(crate) fn symmetrise(k: &mut [f64], n: usize) -> f64 {
    let scale = k.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut worst = 0.0f64;
    for a in 0..n {
        for b in 0..a {
            let (x, y) = (k[a * n + b], k[b * n + a]);
            worst = worst.max((x - y).abs());
            let m = 0.5 * (x + y);
            k[a * n + b] = m;
            k[b * n + a] = m;
        }
    }
    if scale > 0.0 { worst / scale } else { 0.0 }
}
