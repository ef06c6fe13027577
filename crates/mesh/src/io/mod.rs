//! Mesh input and output: the Abaqus/CalculiX `.inp` deck writer ([`inp`]) and reader
//! (`inp_read`: meshes, materials, steps; it reads what [`inp`] writes, and CalculiX decks),
//! and the VTU/PVD writer ([`vtu`]).

pub mod inp;
pub(crate) mod inp_read;
pub mod vtu;
