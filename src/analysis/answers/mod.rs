//! Answers: the analyses a user asks of a metamodel, each an options type (where it has several
//! fields), its checks naming the field at fault, and a `metamodel_*` entry point that the command
//! line and the service call alike: exceedance curves, annual (hazard) curves, fragility curves,
//! peak profiles, Sobol indices and demand samples.
//!
//! May import `responses`, `sampling` and `certification`.

pub(super) mod demands;
pub(super) mod exceedance;
pub(super) mod fragility;
pub(super) mod hazard;
pub(super) mod profile;
pub(super) mod sobol;
