//! Demands for loss assessment: per storm at one wind speed, the peak acceleration of every floor
//! and the peak inter-storey drift ratio of every storey, as pelicun (the FEMA P-58 engine behind
//! the NHERI SimCenter tools) reads a demand sample.

use crate::analysis::responses::response::{Response, STANDARD_GRAVITY};
use crate::analysis::sampling::draws::{Draws, OnDivergence, check_samples, peak_sets_at};
use crate::analysis::sampling::runner::StormRunner;
use crate::error::{Error, Result};
use crate::progress::Observer;
use crate::study::{Study, WIND_SPEED};
use crate::surrogate::Metamodel;
use crate::uncertainty::{monte_carlo, rng_from_seed};

/// The peak demands of storms at one wind speed, every other input drawn from its law.
#[derive(Debug, Clone, PartialEq)]
pub struct Demands {
    /// The storm speed at 10 m (m/s).
    pub wind_speed: f64,
    /// `floor_accelerations[storm][j]`: the peak acceleration of floor j (g), j = 0 the ground,
    /// which the wind does not move.
    pub floor_accelerations: Vec<Vec<f64>>,
    /// `drift_ratios[storm][j − 1]`: the peak drift of storey j over its height (rad), j = 1 the
    /// storey below floor 1.
    pub drift_ratios: Vec<Vec<f64>>,
}

/// `samples` storms of the metamodel at `wind_speed` (storm k's inputs and phases depend only on
/// (seed, k), as in an exceedance curve with the speed held: a floor's column is that curve's
/// peaks). A storm whose free run diverges is an error naming it: a demand file has no infinity.
pub fn metamodel_demands(
    metamodel: &Metamodel,
    study: &Study,
    wind_speed: f64,
    samples: usize,
    seed: u64,
    runner: &dyn StormRunner,
    observer: &dyn Observer,
) -> Result<Demands> {
    check_samples(samples)?;
    if !wind_speed.is_finite() {
        return Err(Error::invalid("wind_speed", format!("must be a finite speed, got {wind_speed}")));
    }
    let inputs = study.inputs.clone().with_fixed(WIND_SPEED, wind_speed).map_err(|e| match e {
        Error::Invalid { reason, .. } => Error::invalid("wind_speed", reason),
        other => other,
    })?;
    let floors = study.structure.floors();
    let mut responses: Vec<Response> = (1..=floors).map(|floor| Response::Acceleration { floor }).collect();
    responses.extend((1..=floors).map(|floor| Response::Drift { floor }));
    let rows = monte_carlo(&inputs, samples, &mut rng_from_seed(seed));
    let storms: Vec<usize> = (0..samples).collect();
    let draws = Draws { study, rows: &rows, storms: &storms, seed, on_divergence: OnDivergence::Fail };
    let peaks = peak_sets_at(metamodel, &draws, &responses, runner, observer)?;
    let heights = study.structure.storey_heights();
    let floor_accelerations = peaks
        .iter()
        .map(|storm| std::iter::once(0.0).chain(storm[..floors].iter().map(|a| a / STANDARD_GRAVITY)).collect())
        .collect();
    let drift_ratios =
        peaks.iter().map(|storm| storm[floors..].iter().zip(&heights).map(|(d, h)| d / h).collect()).collect();
    Ok(Demands { wind_speed, floor_accelerations, drift_ratios })
}
