//! The mesh generators of thesis chapter 3: the structured box, the embedded delamination
//! (§3.1–3.2, Fig. 3.1.1 / 3.2.1, with its edge and thin-film variants) and the through-width
//! delamination (Fig. 3.2.3). Each names its sets with the constants of [`crate::names`].
//! `partition` splits a generated delamination model into the nonlinear and linear
//! substructures of §2.6 and Fig. 3.2.2.

mod accuracy;
mod coarse;
pub use coarse::CompanionKind;
mod embedded;
mod grading;
mod partition;
mod structured;
mod through_width;

pub use accuracy::{
    ACCURACY_TABLE, AccuracyRow, DEFAULT_MESH, REFERENCE_FRONT, quarter_front_length,
};
pub use embedded::{
    Centre, EllipticMap, EmbeddedParams, FrontBand, LayerBand, MidEdges, PlyLayout,
    edge_delamination, embedded_delamination, embedded_delamination_with_front, thin_film,
};
pub use grading::{graded_coordinates, graded_from_first};
pub(crate) use grading::{grid_index, grid_position};
pub use partition::{FrontShape, NonlinearRegion, Partition, ellipse_distance, nonlinear_region};
pub use structured::{BoxParams, structured_box};
pub use through_width::{DEFAULT_STRIP_GRADING, ThroughWidthParams, through_width_delamination};
