//! Uncertain inputs: marginal distributions, a named input model, Latin hypercube and Monte Carlo
//! designs, and the isoprobabilistic map to the standard space polynomial chaos is built on.

mod marginal;
mod model;
mod sampling;

pub use marginal::{Marginal, StandardSpace};
pub use model::{Input, InputModel, parse_assignment};
pub use sampling::{Rng, latin_hypercube, monte_carlo, rng_from_seed, stream_seed};

/// Simpson's rule for ∫ f over [a, b] with n (even) intervals: the independent quadrature the
/// tests check densities and annual curves against.
#[cfg(test)]
pub(crate) fn simpson(f: impl Fn(f64) -> f64, a: f64, b: f64, n: usize) -> f64 {
    let h = (b - a) / n as f64;
    let weight = |i: usize| {
        if i == 0 || i == n {
            1.0
        } else if i % 2 == 1 {
            4.0
        } else {
            2.0
        }
    };
    (0..=n).map(|i| weight(i) * f(a + i as f64 * h)).sum::<f64>() * h / 3.0
}
