//! The error type of `nonlin3d-vcct`.

/// What can go wrong computing release rates or applying a criterion.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum VcctError {
    /// A vector whose length does not match the model.
    #[error("{what}: expected length {expected}, got {got}")]
    Length {
        /// Which vector.
        what: &'static str,
        /// Expected (3 × nodes).
        expected: usize,
        /// Given.
        got: usize,
    },
    /// A displacement or force is NaN or infinite.
    #[error("{what}: non-finite value at DOF {dof}")]
    NonFinite {
        /// Which vector.
        what: &'static str,
        /// The DOF.
        dof: usize,
    },
    /// The front has no points.
    #[error("the delamination front has no points")]
    EmptyFront,
    /// A front descriptor names a node the model does not have.
    #[error("front node {node} out of range ({count} nodes)")]
    Node {
        /// The node.
        node: usize,
        /// Number of nodes.
        count: usize,
    },
    /// A closure area Δa × width is zero, negative or not finite.
    #[error("front node {node}: closure area {area} m² (degenerate front descriptor)")]
    Area {
        /// The corner node.
        node: usize,
        /// Its area.
        area: f64,
    },
    /// A criterion parameter that is not positive and finite.
    #[error(
        "criterion parameter {name} = {value}: toughnesses must lie between 1e-3 and 1e12 J/m², exponents between 1e-3 and 100"
    )]
    Criterion {
        /// Parameter.
        name: &'static str,
        /// Value.
        value: f64,
    },
    /// The inputs of the error estimate (docs/ACCURACY.md §3) do not fit together.
    #[error("error estimate: {reason}")]
    Estimate {
        /// Which front and why.
        reason: String,
    },
}
