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
    /// Substructuring failed (empty region, singular interior: which DOF).
    #[error(transparent)]
    Substructure(#[from] nonlin3d_substructure::SubstructureError),
    /// Crack-face contact failed (a cycle, too many passes).
    #[error(transparent)]
    Contact(#[from] nonlin3d_contact::ContactError),
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
    /// The model lacks a node or cell set that its supports, load or output need.
    #[error("the model has no {kind} set '{name}'")]
    MissingSet {
        /// `node` or `cell`.
        kind: &'static str,
        /// The set's name.
        name: String,
    },
    /// No node of the model where one is needed.
    #[error("the model has no node on {what}")]
    NoNodeAt {
        /// Where, and what for.
        what: &'static str,
    },
    /// The model has no material (its cells index none).
    #[error("the model has no material")]
    NoMaterial,
    /// A material's 6 × 6 stiffness has no inverse, so its compliance (which sizes the
    /// perturbation force) does not exist.
    #[error(
        "material {index}: the stiffness matrix is singular, so the perturbation force cannot \
         be sized from it (give loads.perturbation_n)"
    )]
    SingularMaterial {
        /// 0-based index among the model's materials.
        index: usize,
    },
    /// A matrix or value came out infinite or NaN.
    #[error("{what} is not finite")]
    NotFinite {
        /// What, in words.
        what: String,
    },
    /// A level of the sweep failed; says which and at what strain (or load).
    #[error("level {index} ({quantity} {value}): {source}")]
    Level {
        /// 0-based level index.
        index: usize,
        /// `strain` or `load`.
        quantity: &'static str,
        /// The level's strain (or load, N), as the scene gives it.
        value: f64,
        /// Why it failed.
        source: Box<Error>,
    },
    /// The sublaminate was pushed into the base: without contact (thesis §2.7) that branch is
    /// not physical, so the run stops rather than report it.
    #[error(
        "level {index} (strain {strain}): the sublaminate buckled into the base (largest \
         crack-face separation {separation_mm:.4} mm); without contact this branch is not \
         physical — raise loads.perturbation_n or lower analysis.max_increment"
    )]
    BuckledIntoBase {
        /// 0-based level index.
        index: usize,
        /// The level's strain.
        strain: f64,
        /// The largest crack-face separation w(upper) − w(lower), mm (negative: overlap).
        separation_mm: f64,
    },
    /// A step of a deck did not finish: which step (1-based), its `*STEP` line, and why.
    #[error("step {step} (line {line}): {reason}")]
    Step {
        /// 1-based step number.
        step: usize,
        /// The `*STEP` line in the deck.
        line: usize,
        /// Why: the increment, step time and what did not converge.
        reason: String,
    },
    /// A DOF given two `*CLOAD`s in one step with different amplitudes (CalculiX refuses it
    /// too).
    #[error(
        "line {line}, *CLOAD: node {node} DOF {dof} is loaded twice in the step with different \
         amplitudes (CalculiX refuses this too)"
    )]
    LoadedTwice {
        /// The second `*CLOAD` line.
        line: usize,
        /// The node's number in the deck.
        node: usize,
        /// The DOF, 1–3.
        dof: u8,
    },
    /// An initial increment (`solve --initial-increment`) outside (0, 1].
    #[error("initial increment {value}: expected a fraction of the step period in (0, 1]")]
    InitialIncrement {
        /// The value given.
        value: f64,
    },
    /// Results that could not be written as JSON.
    #[error("writing JSON: {0}")]
    Json(#[from] serde_json::Error),
    /// The output writer's state was left inconsistent by a panic in another thread.
    #[error("the output writer's lock was poisoned by a panic in another thread")]
    OutputLock,
    /// A plot that could not be drawn or written.
    #[error("plotting {}: {reason}", path.display())]
    Plot {
        /// The SVG file.
        path: std::path::PathBuf,
        /// What the plotting library said.
        reason: String,
    },
    /// SIGINT and SIGTERM could not be blocked, or their thread not started.
    #[error("setting up SIGINT/SIGTERM: {0}")]
    Signal(std::io::Error),
    /// A parametric study (`[sweep]`, `nonlin3d sweep`): its table, plan or cases, in words
    /// that name the field, the case and its values.
    #[error("{0}")]
    Sweep(String),
    /// A run that stopped part-way: why, and where what converged before was kept.
    #[error(
        "{source}\n(the {kept} converged before are in {}, {summary} \"complete\": false)",
        folder.display()
    )]
    Partial {
        /// Why it stopped.
        source: Box<Error>,
        /// The output folder.
        folder: std::path::PathBuf,
        /// `levels` (a scene) or `increments` (a deck).
        kept: &'static str,
        /// The file that says the run is incomplete: `results.json` or `summary.json`.
        summary: &'static str,
    },
}
