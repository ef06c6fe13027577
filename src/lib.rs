//! nonlin3d: geometrically nonlinear 3-D finite element analysis of delaminated composite
//! laminates, after J. D. Whitcomb, NASA TM-100655 (1988).
//!
//! This facade re-exports the layers under `crates/` and composes them:
//!
//! | module | crate | owns |
//! |---|---|---|
//! | [`laminate`] | `nonlin3d-laminate` | ply stiffness, rotation, stacks, Cholesky factor (§2.1, §2.9) |
//! | [`element`] | `nonlin3d-element` | Hex8/Hex20, quadrature, B0BL3D / ESTIF3D kernels, eigen-analysis (§2.1–2.5) |
//! | [`mesh`] | `nonlin3d-mesh` | the Mesh model with named sets, structured box generator, quality, VTU/PVD output (§3) |
//! | [`assembly`] | `nonlin3d-assembly` | constraints, deterministic parallel assembly of residual and tangent, reactions (§2.2–2.3) |
//! | [`newton`] | `nonlin3d-newton` | Newton–Raphson path following: line search, modified Newton, load stepping with cutback, inertia (§2.1, §4.4) |
//! | [`solver`] | `nonlin3d-solver` | sparse patterns and matrices, RCM/AMD, profile LDLᵀ, faer Cholesky, inertia (§2.4) |
//! | [`vcct`] | `nonlin3d-vcct` | G_I, G_II, G_III along the front by virtual crack closure, mixed-mode criteria (§2.8) |
//! | [`scene`] | this crate | `Scene`: the serde/TOML description of an analysis (docs/SCENES.md) |
//! | [`model`] | this crate | the finite element model of a scene (mesh, front, materials, boundary-condition family), built from it; its supports, load and perturbation force, held once for the constraints and the exported deck (§3.2) |
//! | [`analysis`] | this crate | the pipeline scene → mesh → constraints → Newton (perturbation, strain sweep) → VCCT (§3.2, ch. 5) |
//! | [`results`], [`report`], [`plot`], [`output`] | this crate | `results.json`, front CSVs, VTU/PVD series, SVG plots; the output folder written level by level, atomically |
//! | [`export`] | this crate | a scene as a CalculiX deck: the `nonlin3d export` command |
//! | [`deck`] | this crate | solving an Abaqus/CalculiX deck: the `nonlin3d solve` command |
//! | [`eigen_check`] | this crate | the element eigen-check (§2.5): `nonlin3d eigen-check` |
//! | [`log`], [`provenance`] | this crate | Newton's iterations as data (a `tracing` layer), `status.sta` and `convergence.cvg`; program, input hash, resolved scene, solver, times and memory in results.json / summary.json |
//! | [`study`] | this crate | speed against error: a scene over knob settings, Richardson references, the Pareto front (`nonlin3d study`) |
//! | [`sweep`] | this crate | parametric studies: a scene's `[sweep]` planned into one scene per case, run in parallel or case by case (job arrays), merged into a table and plot: `nonlin3d sweep` |
//! | [`budget`] | this crate | memory limits (`--max-memory`, available memory, RLIMIT_AS, cgroup) and a model's size before it is built |
//!
//! Substructuring and contact come as their own crates in later releases.
//!
//! ```no_run
//! // The thesis's reference case end to end (what `nonlin3d run` does without a scene).
//! let scene = nonlin3d::Scene::reference()?;
//! let results = nonlin3d::Analysis::new(scene)?.run()?;
//! print!("{}", nonlin3d::report::table(&results));
//! # Ok::<(), nonlin3d::Error>(())
//! ```
#![deny(missing_docs)]
#![warn(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

pub mod analysis;
mod atomic;
pub mod budget;
mod checks;
pub mod contact;
pub mod deck;
pub mod eigen_check;
pub mod export;
pub mod fields;
pub mod log;
pub mod model;
pub mod output;
pub mod plot;
mod problem;
pub mod provenance;
pub mod report;
pub mod results;
pub mod scene;
pub mod study;
pub mod substructure;
pub mod sweep;

/// The README's code blocks, compiled and run as doc-tests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
mod error;

pub use analysis::Analysis;
pub use error::Error;
pub use nonlin3d_assembly as assembly;
pub use nonlin3d_element as element;
pub use nonlin3d_laminate as laminate;
pub use nonlin3d_mesh as mesh;
pub use nonlin3d_newton as newton;
pub use nonlin3d_solver as solver;
pub use nonlin3d_vcct as vcct;
pub use results::Results;
pub use scene::Scene;
