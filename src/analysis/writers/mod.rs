//! Writers: the answers as files, SVG figures and CSV tables. Pure formatting of an answer, kept
//! apart from the analyses so that no analysis depends on how it is drawn.
//!
//! The top room: it may import every other room, and none imports it.

pub(super) mod csv;
pub(super) mod plot;
