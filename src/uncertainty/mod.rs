//! Uncertain inputs: marginal distributions, a named input model, Latin hypercube and Monte Carlo
//! designs, and the isoprobabilistic map to the standard space polynomial chaos is built on.

mod marginal;
mod model;
mod sampling;

pub use marginal::{Marginal, StandardSpace};
pub use model::{Input, InputModel, parse_assignment};
pub use sampling::{Rng, latin_hypercube, monte_carlo, rng_from_seed, stream_seed};
