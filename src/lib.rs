//! windmeta: rapid uncertainty quantification of tall buildings under stochastic wind.
//!
//! The numerical core follows the data's way through the method: a [`structure`] reduced to its
//! first modes, [`wind`] loads simulated by spectral representation, [`dynamics`] of the damped
//! building as the reference model, [`uncertainty`] in the inputs, and the [`problem`] that ties a
//! structure, its inputs and its storms together. Everything here is synchronous and deterministic
//! for a given seed.

pub mod analysis;
pub mod cancel;
pub mod cli;
pub mod dynamics;
pub mod error;
mod linalg;
pub mod problem;
pub mod service;
pub mod structure;
pub mod surrogate;
pub mod uncertainty;
pub mod whole;
pub mod wind;
