//! The error type of `nonlin3d-mesh`.

/// What can go wrong building, checking or writing a mesh; variants name the cell, node or set.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MeshError {
    /// A cell has the wrong number of nodes for its kind.
    #[error("cell {cell}: {kind} needs {expected} nodes, has {got}")]
    NodeCount {
        /// Cell index.
        cell: usize,
        /// Element kind name.
        kind: &'static str,
        /// Nodes required.
        expected: usize,
        /// Nodes given.
        got: usize,
    },
    /// A cell or set refers to a node that does not exist.
    #[error("{owner}: node {node} does not exist ({count} nodes)")]
    NodeIndex {
        /// Which cell or set.
        owner: String,
        /// The index.
        node: usize,
        /// Number of nodes.
        count: usize,
    },
    /// A set refers to a cell that does not exist, or a face number outside 0..6.
    #[error("{owner}: cell {cell}{} does not exist ({count} cells)", face.map_or(String::new(), |f| format!(" (face {f})")))]
    CellIndex {
        /// Which set.
        owner: String,
        /// The cell index.
        cell: usize,
        /// The face, for face sets.
        face: Option<u8>,
        /// Number of cells.
        count: usize,
    },
    /// A coordinate or ply angle is NaN or infinite.
    #[error("{what} {index} is not finite")]
    NonFinite {
        /// `"node"` or `"ply angle of cell"`.
        what: &'static str,
        /// Its index.
        index: usize,
    },
    /// A cell is inverted or degenerate: det J ≤ 0 somewhere.
    #[error(
        "cell {cell}: det J = {det:e} ≤ 0 at reference point (ξ, η, ζ) = ({}, {}, {}): the cell is inverted or degenerate (check lengths and counts)",
        xi[0],
        xi[1],
        xi[2]
    )]
    Inverted {
        /// Cell index.
        cell: usize,
        /// Where (reference coordinates).
        xi: [f64; 3],
        /// The determinant.
        det: f64,
    },
    /// Generator parameters out of range (named).
    #[error("invalid parameter {name}: {reason}")]
    Parameter {
        /// The parameter.
        name: &'static str,
        /// Why.
        reason: String,
    },
    /// An input deck line that cannot be read or asks for something not implemented: where
    /// (file and line), what (keyword, parameter or data line) and why.
    #[error("{at}, {what}: {reason}")]
    Deck {
        /// `line N`, or `FILE line N` in an included file.
        at: String,
        /// The keyword, with the parameter or data field concerned.
        what: String,
        /// Why.
        reason: String,
    },
    /// A mesh lacks a set that an operation needs.
    #[error("the mesh has no {kind} set `{name}`: {purpose}")]
    MissingSet {
        /// `"node"` or `"cell"`.
        kind: &'static str,
        /// The set's name.
        name: &'static str,
        /// What it is needed for.
        purpose: &'static str,
    },
    /// The offset ℓ of the thesis's substructure partition (§3.2, Fig. 3.2.2) is out of range.
    #[error("substructure offset ℓ = {offset_mm} mm: {reason}")]
    Offset {
        /// ℓ, mm.
        offset_mm: f64,
        /// Why, with the largest ℓ that works when there is one.
        reason: String,
    },
    /// A front node of the mesh lies off the front shape given for it.
    #[error(
        "front node {node} lies {distance_mm:.4} mm from the given front shape: the shape was \
         made from other parameters than the mesh"
    )]
    FrontMismatch {
        /// The node.
        node: usize,
        /// Its inside distance from the shape, mm.
        distance_mm: f64,
    },
    /// Writing a file failed.
    #[error("writing {path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The I/O error.
        source: std::io::Error,
    },
}
