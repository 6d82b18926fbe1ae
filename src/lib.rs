//! windmeta: rapid uncertainty quantification of tall buildings under stochastic wind.
//!
//! The numerical core follows the data's way through the method: a [`structure`] reduced to its
//! first modes, [`wind`] loads simulated by spectral representation, [`dynamics`] of the damped
//! building as the reference model, [`uncertainty`] in the inputs, the [`problem`] that ties a
//! structure, its inputs and its storms together, the PC-NARX [`surrogate`] and the [`analysis`]
//! of its samples. The core is synchronous and deterministic for a given seed; long work in it
//! stops when asked through [`cancel`].
//!
//! On top of it sit the offline commands ([`cli`]) and the HTTP service ([`service`]: axum on
//! tokio, sqlx), the only module with an async runtime.

pub mod analysis;
pub mod cancel;
#[cfg(feature = "cli")]
pub mod cli;
pub mod dynamics;
pub mod error;
mod linalg;
mod optimise;
pub mod problem;
#[cfg(feature = "service")]
pub mod service;
pub mod structure;
pub mod surrogate;
pub mod uncertainty;
pub mod whole;
pub mod wind;
