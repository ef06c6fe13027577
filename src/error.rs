//! The facade's error type: every layer's error, wrapped.

/// Anything the nonlin3d pipeline can fail with.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// Invalid material or laminate input.
    #[error(transparent)]
    Laminate(#[from] nonlin3d_laminate::LaminateError),
    /// An element kernel failed (inverted element, bad input).
    #[error(transparent)]
    Element(#[from] nonlin3d_element::ElementError),
    /// Invalid mesh or mesh output failure.
    #[error(transparent)]
    Mesh(#[from] nonlin3d_mesh::MeshError),
    /// Assembly failed.
    #[error(transparent)]
    Assembly(#[from] nonlin3d_assembly::AssemblyError),
    /// Path following failed.
    #[error(transparent)]
    Newton(#[from] nonlin3d_newton::NewtonError),
    /// A linear solve failed (zero pivot, bad input).
    #[error(transparent)]
    Solver(#[from] nonlin3d_solver::SolverError),
    /// VCCT failed (degenerate front, bad input).
    #[error(transparent)]
    Vcct(#[from] nonlin3d_vcct::VcctError),
    /// A scene that cannot be parsed or describes an impossible model; names the field.
    #[error("scene: {0}")]
    Scene(String),
    /// Reading or writing a file.
    #[error("{path}: {source}")]
    Io {
        /// The file or directory.
        path: std::path::PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// The model would not fit in the memory the process may use: the estimate, the limit and
    /// the scene fields that set the size (`budget`).
    #[error("{0}")]
    TooLarge(Box<crate::budget::Refusal>),
    /// A memory size that cannot be read (`--max-memory`).
    #[error("memory size '{text}': {reason}")]
    MemorySize {
        /// The text given.
        text: String,
        /// What is wrong with it.
        reason: String,
    },
    /// A numerical step produced no answer (named).
    #[error("{0}")]
    Numerical(String),
}
