//! The error type of `nonlin3d-contact`.

use crate::Pair;

/// What stops a contact analysis.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ContactError {
    /// The mesh lacks a crack-face node set.
    #[error("the mesh has no node set {name}: contact needs the paired crack faces")]
    MissingSet {
        /// The set's name.
        name: &'static str,
    },
    /// The two crack faces have different numbers of nodes.
    #[error("the crack faces are not paired: {upper} upper-face nodes, {lower} lower-face nodes")]
    Pairing {
        /// Upper-face nodes.
        upper: usize,
        /// Lower-face nodes.
        lower: usize,
    },
    /// A crack-face node that cannot take part.
    #[error("crack-face node {node}: {reason}")]
    Node {
        /// The node.
        node: usize,
        /// Why.
        reason: String,
    },
    /// A vector of the wrong length.
    #[error("{what}: {got} entries, expected {expected}")]
    Length {
        /// Which vector.
        what: &'static str,
        /// Expected length.
        expected: usize,
        /// Given length.
        got: usize,
    },
    /// A setting out of range.
    #[error("invalid contact setting {name}: {reason}")]
    Setting {
        /// The setting.
        name: &'static str,
        /// Why.
        reason: String,
    },
    /// The active set came back to one it had at this level: the pairs that flip between the
    /// two visits close and open in turn.
    #[error(
        "contact at λ = {lambda}: the active set repeats after {passes} passes (a cycle); the pairs that flip: {}",
        list(.pairs)
    )]
    Cycle {
        /// The level's load factor.
        lambda: f64,
        /// Passes made at the level.
        passes: usize,
        /// The pairs whose state changed between the two visits of the set.
        pairs: Vec<Pair>,
    },
    /// The set still changed after the pass limit.
    #[error(
        "contact at λ = {lambda}: the active set still changes after {passes} passes (last change: {closed} closed, {opened} opened)"
    )]
    Passes {
        /// The level's load factor.
        lambda: f64,
        /// Passes made.
        passes: usize,
        /// Pairs closed by the last change.
        closed: usize,
        /// Pairs opened by the last change.
        opened: usize,
    },
    /// A re-solve at the same load with a new set did not converge (passes without a fallback
    /// to path following: [`Contact::settle`](crate::Contact::settle)).
    #[error(
        "contact at λ = {lambda}: the re-solve of pass {pass} ({closed} closed, {opened} opened) did not converge ({why})"
    )]
    Resolve {
        /// The load factor.
        lambda: f64,
        /// The pass (1-based).
        pass: usize,
        /// Pairs closed by the pass's change.
        closed: usize,
        /// Pairs opened by it.
        opened: usize,
        /// Newton's termination.
        why: String,
    },
    /// A re-solve converged on a state whose tangent has negative pivots where the caller asked
    /// for stable states only ([`Contact::set_stable_only`](crate::Contact::set_stable_only):
    /// a level started from a state predicted on a stable branch).
    #[error(
        "contact at λ = {lambda}: a pass converged on a state with {pivots} negative pivots where a stable one was asked for"
    )]
    Unstable {
        /// The load factor.
        lambda: f64,
        /// Negative pivots of the tangent there.
        pivots: usize,
    },
    /// Holding the same set again with the current normals (refresh passes) does not remove
    /// the overlap.
    #[error(
        "contact at λ = {lambda}: {passes} refresh passes (the same set held again) do not remove the overlap at {pair}: {:.2e} → {:.2e} mm over the last 5{}",
        before * 1e3,
        overlap * 1e3,
        if *external {
            "; in the thesis's approximation (mode = \"thesis\") the held upper node drags its lower node along through the front cell, so holding it at the lower node's height never catches up: use mode = \"two_body\" or a longer front cell"
        } else {
            ""
        }
    )]
    Refresh {
        /// The load factor.
        lambda: f64,
        /// Refresh passes in a row.
        passes: usize,
        /// The pair that overlaps most.
        pair: Pair,
        /// The overlap 5 refresh passes before, m.
        before: f64,
        /// The overlap now, m.
        overlap: f64,
        /// Whether the thesis's approximation ([`Mode::External`](crate::Mode::External)).
        external: bool,
    },
    /// Path following or a re-solve failed.
    #[error(transparent)]
    Newton(#[from] nonlin3d_newton::NewtonError),
    /// The constraints refused the contact ties or prescriptions.
    #[error(transparent)]
    Assembly(#[from] nonlin3d_assembly::AssemblyError),
}

/// The first pairs of a list, with how many more.
fn list(pairs: &[Pair]) -> String {
    const SHOWN: usize = 8;
    let mut s: Vec<String> = pairs.iter().take(SHOWN).map(Pair::to_string).collect();
    if pairs.len() > SHOWN {
        s.push(format!("and {} more", pairs.len() - SHOWN));
    }
    s.join(", ")
}
