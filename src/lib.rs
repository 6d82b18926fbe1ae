//! windmeta: rapid uncertainty quantification of tall buildings under stochastic wind.
//!
//! The numerical core follows the data's way through the method: a [`structure`] reduced to its
//! first modes, [`wind`] loads simulated by spectral representation, [`dynamics`] of the damped
//! building as the reference model, [`uncertainty`] in the inputs, the [`study`] that ties a
//! structure, its inputs and its storms together, the PC-NARX [`surrogate`] whose batched free run
//! computes on the eight-lane vectors of [`simd`], and the [`analysis`] of its samples. The core is
//! synchronous and deterministic for a given seed; long work in it reports its [`progress`] and
//! stops when asked.
//!
//! On top of it sit the offline commands ([`cli`]) and the HTTP service ([`service`]: axum on
//! tokio, sqlx), the only module with an async runtime.

// Every public item says what it is: `cargo doc` is built with warnings denied in CI.
#![warn(missing_docs)]

pub mod analysis;
#[cfg(feature = "cli")]
pub mod cli;
pub mod count;
pub mod dynamics;
pub mod error;
mod linalg;
pub mod optimise;
pub mod progress;
#[cfg(feature = "service")]
pub mod service;
pub mod simd;
pub mod structure;
pub mod study;
pub mod surrogate;
pub mod uncertainty;
pub mod wind;
