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
