//! Design checks: what a design office signs or sizes with, built on the annual answers: the
//! serviceability check of several criteria at once, and the sweep of one input's value.
//!
//! May import every room but `writers`.

pub(super) mod serviceability;
pub(super) mod sweep;
