//! The error type of `nonlin3d-substructure`.

/// "node v, x": a DOF in the user's words (3 per node, node-major, 0-based, full-mesh nodes).
fn dof_name(d: usize) -> String {
    format!("node {}, {}", d / 3, ["x", "y", "z"][d % 3])
}

/// What can go wrong partitioning a mesh, condensing a linear region or recovering it. Nodes
/// and cells are those of the full mesh unless said otherwise.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SubstructureError {
    /// One side of the partition has no cell.
    #[error("the {region} region has no cell")]
    EmptyRegion {
        /// "linear" or "nonlinear".
        region: &'static str,
    },
    /// The linear and nonlinear cells share no node: there is nothing to condense onto.
    #[error(
        "the linear region ({linear} cells) shares no node with the nonlinear region \
         ({nonlinear} cells): no interface to condense onto"
    )]
    NoInterface {
        /// Cells of the linear region.
        linear: usize,
        /// Cells of the nonlinear region.
        nonlinear: usize,
    },
    /// A listed cell does not exist.
    #[error("cell {cell} does not exist (the mesh has {count} cells)")]
    CellOutOfRange {
        /// The cell.
        cell: usize,
        /// Cells of the mesh.
        count: usize,
    },
    /// A named cell set the mesh does not have.
    #[error("the mesh has no cell set \"{name}\"")]
    UnknownSet {
        /// The name asked for.
        name: String,
    },
    /// The linear region's interior stiffness K_ii is singular (a part of the region neither
    /// supported nor attached to the interface, or a mechanism): names the DOF.
    #[error(
        "the linear region's interior is singular at {} (pivot {pivot:e}, diagonal {diagonal:e}): \
         a part of the region is neither supported nor attached to the interface",
        dof_name(*dof)
    )]
    SingularInterior {
        /// The full-mesh DOF (3 per node).
        dof: usize,
        /// The pivot found.
        pivot: f64,
        /// |K_dd|, the scale of the test.
        diagonal: f64,
    },
    /// K_ii has negative eigenvalues (a linear region must be stable at u = 0).
    #[error("the linear region's interior stiffness has {count} negative eigenvalues")]
    IndefiniteInterior {
        /// Negative pivots of the factorisation.
        count: usize,
    },
    /// A tie touches an interior node of the linear region (ties are kept in the nonlinear
    /// region only).
    #[error(
        "the tie of {} involves the linear region's interior node {node}: ties must lie in \
         the nonlinear region (or on the interface)",
        dof_name(*slave)
    )]
    TieInLinearRegion {
        /// The tie's slave DOF (full mesh).
        slave: usize,
        /// The interior node it touches.
        node: usize,
    },
    /// A vector, matrix or constraint set of the wrong size.
    #[error("{what}: expected {expected}, got {got}")]
    Length {
        /// What.
        what: &'static str,
        /// Expected size.
        expected: usize,
        /// Given size.
        got: usize,
    },
    /// The mesh is invalid.
    #[error(transparent)]
    Mesh(#[from] nonlin3d_mesh::MeshError),
    /// Assembling the linear region, or mapping the constraints, failed.
    #[error(transparent)]
    Assembly(#[from] nonlin3d_assembly::AssemblyError),
    /// The sparse solver failed (other than a zero pivot, reported as
    /// [`SingularInterior`](Self::SingularInterior)).
    #[error(transparent)]
    Solver(#[from] nonlin3d_solver::SolverError),
}
