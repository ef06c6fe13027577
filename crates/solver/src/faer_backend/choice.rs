//! [`FaerOrdering::Auto`]'s choice between AMD, nested dissection and METIS by the symbolic
//! factor's flops (Σ c_k² over the column counts).

use super::FaerOrdering;
use super::counts::factor_flops;
use crate::SolverError;
use faer::sparse::linalg::cholesky::{SymbolicCholesky, SymmetricOrdering};

/// A symbolic factor, or why it could not be made.
pub(super) type SymbolicResult = Result<SymbolicCholesky<usize>, SolverError>;

/// [`FaerOrdering::Auto`]'s comparison: AMD (if `with_amd`), nested dissection and METIS, the
/// symbolic factor with the fewest flops kept, earlier candidates winning ties. One symbolic
/// factor is kept alive beside the one being made: a loser's structure is dropped at once
/// (AMD's is rebuilt from its order if it wins). A METIS failure only removes METIS from the
/// comparison. From [`super::AUTO_METIS_ONLY_DOFS`] DOFs on (`n`) METIS alone, nested
/// dissection only if METIS fails.
pub(super) fn auto_choice(
    symbolic_for: &dyn Fn(SymmetricOrdering<'_, usize>) -> SymbolicResult,
    nested: &dyn Fn() -> SymbolicResult,
    metis: &dyn Fn() -> SymbolicResult,
    with_amd: bool,
    n: usize,
) -> Result<(SymbolicCholesky<usize>, FaerOrdering), SolverError> {
    if n >= super::AUTO_METIS_ONLY_DOFS {
        return match metis() {
            Ok(m) => Ok((m, FaerOrdering::Metis)),
            Err(_) => Ok((nested()?, FaerOrdering::NestedDissection)),
        };
    }
    let mut best_flops = f64::INFINITY;
    let mut amd_perm: Option<Option<(Vec<usize>, Vec<usize>)>> = None;
    if with_amd {
        let amd = symbolic_for(SymmetricOrdering::Amd)?;
        best_flops = factor_flops(&amd);
        amd_perm = Some(
            amd.perm()
                .map(|p| (p.arrays().0.to_vec(), p.arrays().1.to_vec())),
        );
    }
    let mut best: Option<(SymbolicCholesky<usize>, FaerOrdering)> = None;
    let nd = nested()?;
    if factor_flops(&nd) < best_flops {
        best_flops = factor_flops(&nd);
        best = Some((nd, FaerOrdering::NestedDissection));
    } else {
        drop(nd);
    }
    if let Ok(m) = metis()
        && factor_flops(&m) < best_flops
    {
        best = Some((m, FaerOrdering::Metis));
    }
    match (best, amd_perm) {
        (Some(b), _) => Ok(b),
        (None, Some(Some((fwd, inv)))) => Ok((
            symbolic_for(SymmetricOrdering::Custom(faer::perm::PermRef::new_checked(
                &fwd, &inv, n,
            )))?,
            FaerOrdering::Amd,
        )),
        // AMD won with no permutation (faer's identity) — or nothing was compared, which
        // cannot happen: nested dissection always gives a factor or an error. The identity
        // goes in as a custom order: faer's `SymmetricOrdering::Identity` skips the step that
        // reads `Side::Lower`, and would take our lower-triangle pattern as an upper one (a
        // diagonal factor; `counts.rs`'s tests met it).
        (None, _) => {
            let identity: Vec<usize> = (0..n).collect();
            Ok((
                symbolic_for(SymmetricOrdering::Custom(faer::perm::PermRef::new_checked(
                    &identity, &identity, n,
                )))?,
                FaerOrdering::Amd,
            ))
        }
    }
}
