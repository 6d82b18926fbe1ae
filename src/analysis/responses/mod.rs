//! Responses: what a storm does to the building and how it is read. The physical responses a user
//! asks about (displacements, drifts, accelerations, damper forces and strokes) and the view of a
//! sample's modal motion they are read from, the peaks of a metamodel batch formed while it runs,
//! the reference model's histories and peaks, the statistics of a set of peaks, and the responses of
//! a three-dimensional building (per direction and at the corners of its floors).
//!
//! The bottom room: it imports no other room of `analysis`, only the layers below it.

pub(super) mod motion_peaks;
pub(super) mod peaks;
pub(super) mod reference;
pub(super) mod response;
pub(super) mod spatial;
