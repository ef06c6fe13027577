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
