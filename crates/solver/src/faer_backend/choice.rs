//! [`FaerOrdering::Auto`]'s choice between AMD, nested dissection and METIS by the symbolic
//! factor's flops (Σ c_k² over the column counts).

use super::FaerOrdering;
use super::counts::factor_flops;
use crate::SolverError;
use faer::sparse::linalg::cholesky::{SymbolicCholesky, SymmetricOrdering};

/// A symbolic factor, or why it could not be made.
pub(super) type SymbolicResult = Result<SymbolicCholesky<usize>, SolverError>;

/// [`FaerOrdering::Auto`]'s comparison: AMD (if `with_amd`), nested dissection and METIS, the
/// symbolic factor with the fewest flops kept, earlier candidates winning ties. The candidates
/// are made side by side (`rayon::join`: each a pure function of the pattern, so the choice and
/// its structure are the same on any number of threads); below `AUTO_METIS_ONLY_DOFS` their
/// three structures fit beside each other. A METIS failure only removes METIS from the
/// comparison. From [`super::AUTO_METIS_ONLY_DOFS`] DOFs on (`n`) METIS alone, nested
/// dissection only if METIS fails.
pub(super) fn auto_choice(
    symbolic_for: &(dyn Fn(SymmetricOrdering<'_, usize>) -> SymbolicResult + Sync),
    nested: &(dyn Fn() -> SymbolicResult + Sync),
    metis: &(dyn Fn() -> SymbolicResult + Sync),
    with_amd: bool,
    n: usize,
) -> Result<(SymbolicCholesky<usize>, FaerOrdering), SolverError> {
    if n >= super::AUTO_METIS_ONLY_DOFS {
        return match metis() {
            Ok(m) => Ok((m, FaerOrdering::Metis)),
            Err(_) => Ok((nested()?, FaerOrdering::NestedDissection)),
        };
    }
    let (amd, (nd, metis)) = rayon::join(
        || with_amd.then(|| symbolic_for(SymmetricOrdering::Amd)),
        || rayon::join(nested, metis),
    );
    let mut best: Option<(SymbolicCholesky<usize>, FaerOrdering)> = None;
    let mut best_flops = f64::INFINITY;
    for (candidate, ordering) in [
        (amd.transpose()?, FaerOrdering::Amd),
        (Some(nd?), FaerOrdering::NestedDissection),
        (metis.ok(), FaerOrdering::Metis),
    ] {
        if let Some(c) = candidate
            && factor_flops(&c) < best_flops
        {
            best_flops = factor_flops(&c);
            best = Some((c, ordering));
        }
    }
    match best {
        // AMD won with no permutation (faer's identity): it goes in as a custom order. faer's
        // `SymmetricOrdering::Identity` skips the step that reads `Side::Lower`, and would take
        // our lower-triangle pattern as an upper one (a diagonal factor; `counts.rs`'s tests
        // met it).
        Some((amd, FaerOrdering::Amd)) if amd.perm().is_none() => {
            let identity: Vec<usize> = (0..n).collect();
            Ok((
                symbolic_for(SymmetricOrdering::Custom(faer::perm::PermRef::new_checked(
                    &identity, &identity, n,
                )))?,
                FaerOrdering::Amd,
            ))
        }
        Some(b) => Ok(b),
        // Nested dissection always gives a factor or an error, so something was compared.
        None => Err(SolverError::Faer(
            "no ordering gave a symbolic factor with finite flops".into(),
        )),
    }
}
