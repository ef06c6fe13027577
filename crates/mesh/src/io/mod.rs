//! Mesh input and output: the Abaqus/CalculiX `.inp` deck writer ([`inp`]) and the VTU/PVD
//! writer ([`vtu`]). (The `.inp` reader, `crate::inp_read`, reads what [`inp`] writes.)

pub mod inp;
pub mod vtu;
