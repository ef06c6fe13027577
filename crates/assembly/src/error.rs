//! The error type of `nonlin3d-assembly`.

/// What can go wrong setting up or running an assembly.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum AssemblyError {
    /// A cell's element evaluation failed (inverted element, bad input): names the cell.
    #[error(transparent)]
    Element(#[from] nonlin3d_element::ElementError),
    /// The sparsity pattern or a scatter failed.
    #[error(transparent)]
    Solver(#[from] nonlin3d_solver::SolverError),
    /// The mesh is invalid.
    #[error(transparent)]
    Mesh(#[from] nonlin3d_mesh::MeshError),
    /// A material could not be rotated or is invalid.
    #[error(transparent)]
    Laminate(#[from] nonlin3d_laminate::LaminateError),
    /// A constraint or load refers to a DOF that does not exist, or has a non-finite value.
    #[error("{what}: DOF {dof} invalid ({n} DOFs) or value {value} not finite")]
    BadDof {
        /// Constraint or load.
        what: &'static str,
        /// The DOF.
        dof: usize,
        /// Number of DOFs.
        n: usize,
        /// The value.
        value: f64,
    },
    /// A cell refers to a material index that does not exist.
    #[error("cell {cell}: material {material} of {count}")]
    Material {
        /// Cell.
        cell: usize,
        /// Its material index.
        material: usize,
        /// Number of materials.
        count: usize,
    },
    /// A tie that cannot be imposed: names the slave DOF and why.
    #[error("tie of DOF {slave}: {reason}")]
    Tie {
        /// The slave DOF.
        slave: usize,
        /// Why.
        reason: String,
    },
    /// A vector of the wrong length.
    #[error("{what}: expected length {expected}, got {got}")]
    Length {
        /// Which vector.
        what: &'static str,
        /// Expected.
        expected: usize,
        /// Given.
        got: usize,
    },
    /// A tie replaced into a [`System`](crate::System) whose fold needs a coupling outside the
    /// system's pattern (reserve it when building the system).
    #[error(
        "{group}: the tie of {} onto master {} needs {} coupled with {}, which the system's \
         pattern does not hold (reserve the tie or the coupling when building the System)",
        dof_name(*slave), dof_name(*master), dof_name(*master), dof_name(*dof)
    )]
    Unreserved {
        /// The tie group being replaced.
        group: crate::TieGroup,
        /// The tie's slave DOF.
        slave: usize,
        /// The master whose coupling is missing.
        master: usize,
        /// The DOF it would have to be coupled with.
        dof: usize,
    },
    /// The sparsity pattern is not node-blocked (three DOFs per node, every node coupled with
    /// all three DOFs of its neighbours), which the scatter relies on.
    #[error("pattern column {column}: {reason}")]
    Pattern {
        /// The column where it was found.
        column: usize,
        /// What is wrong.
        reason: String,
    },
}

/// "DOF d (node v, x)": a DOF in the user's words (3 per node, node-major, 0-based).
fn dof_name(d: usize) -> String {
    format!("DOF {d} (node {}, {})", d / 3, ["x", "y", "z"][d % 3])
}
