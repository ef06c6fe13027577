//! Hexahedral meshes for nonlin3d (thesis chapter 3).
//!
//! | item | what it is |
//! |---|---|
//! | [`Mesh`], [`Cell`] | nodes, Hex8/Hex20 cells (Abaqus/VTK order) with material and ply angle, named sets |
//! | [`BoxParams`], [`structured_box`] | a graded structured box with the boundary sets x0 … z1 |
//! | [`EmbeddedParams`], [`embedded_delamination`] | the embedded delamination model (ellipse, eq. 3.1.1–3.1.2, or rectangle, Fig. 3.1.3), Fig. 3.1.1 / 3.2.1, with optional ply-level layers ([`PlyLayout`], chapter 7) |
//! | [`edge_delamination`], [`thin_film`] | the edge (§5.5) and thin-film (§5.3) variants |
//! | [`ThroughWidthParams`], [`through_width_delamination`] | the through-width (plane strain) delamination model, Fig. 3.2.3 |
//! | [`Partition`], [`nonlinear_region`], [`FrontShape`] | the nonlinear and linear substructures of §2.6 / Fig. 3.2.2: the sublaminate ℓ inside the front, or the whole sublaminate |
//! | [`AccuracyRow`], [`ACCURACY_TABLE`], [`DEFAULT_MESH`] | a target accuracy of G → front-resolving knobs; the default mesh of a scene without knobs (measured on the reference circle, scaled by h and the front length); `coarsened()` on the parameters gives the error estimate's companion mesh, [`CompanionKind`] what it keeps |
//! | [`Front`], [`FrontPoint`] | delamination-front descriptor for VCCT (§2.8, Fig. 2.8.1): c, a/a′, b/b′, d, cells, Δa, θ, S |
//! | [`quality`], [`CellQuality`] | minimum scaled Jacobian and aspect ratio per cell |
//! | [`Transfer`] | nodal fields carried from one mesh onto another's nodes (isoparametric interpolation, crack faces kept apart): a coarse state as a fine mesh's start |
//! | [`inp`], [`read_inp`] | Abaqus/CalculiX `.inp` deck writer, and reader of a documented subset |
//! | [`vtu`] | VTU (VTK XML unstructured grid) and PVD series output |
//!
//! ```
//! use nonlin3d_mesh::{BoxParams, structured_box, quality};
//! use nonlin3d_element::ElementKind;
//! let mesh = structured_box(&BoxParams::new(ElementKind::Hex20, [4, 3, 2], [4e-3, 3e-3, 1e-3])).unwrap();
//! assert_eq!(mesh.cells.len(), 24);
//! assert!(quality(&mesh).unwrap().iter().all(|q| (q.min_scaled_jacobian - 1.0).abs() < 1e-12));
//! ```
#![deny(missing_docs)]
#![cfg_attr(
    not(test),
    warn(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

mod error;
mod front;
mod generators;
mod io;
mod model;
pub mod names;
mod quality;
mod transfer;

pub use error::MeshError;
pub use front::{Front, FrontPoint, FrontWidths};
pub use generators::{
    ACCURACY_TABLE, AccuracyRow, BoxParams, Centre, CompanionKind, DEFAULT_MESH,
    DEFAULT_STRIP_GRADING, EllipticMap, EmbeddedParams, FrontBand, FrontShape, LayerBand, MidEdges,
    NonlinearRegion, Partition, PlyLayout, REFERENCE_FRONT, ThroughWidthParams, edge_delamination,
    ellipse_distance, embedded_delamination, embedded_delamination_with_front, graded_coordinates,
    graded_from_first, nonlinear_region, quarter_front_length, structured_box, thin_film,
    through_width_delamination,
};
pub use io::inp_read::{
    Amplitude, ContactPairs, Controls, InpModel, NodeRef, NotUsed, OutputKind, OutputRequest,
    OutputVariable, ReadBoundary, ReadCload, ReadStep, RiksData, StaticData, Totals, read_inp,
    read_inp_file,
};
pub use io::{inp, vtu};
pub use model::{Cell, Imperfection, Mesh};
pub use quality::{CellQuality, quality};
pub use transfer::Transfer;
