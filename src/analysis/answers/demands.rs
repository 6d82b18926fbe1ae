//! Demands for loss assessment: per storm at one wind speed, the peak acceleration of every floor
//! and the peak inter-storey drift ratio of every storey, as pelicun (the FEMA P-58 engine behind
//! the NHERI SimCenter tools) reads a demand sample.

use crate::analysis::responses::response::{Response, STANDARD_GRAVITY};
use crate::analysis::sampling::draws::{Draws, OnDivergence, check_samples, peak_sets_at};
use crate::error::{Error, Result};
use crate::progress::Observer;
use crate::study::{Study, WIND_SPEED};
use crate::surrogate::Metamodel;
use crate::uncertainty::{monte_carlo, rng_from_seed};
use std::fmt::Write;

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
    let peaks = peak_sets_at(metamodel, &draws, &responses, observer)?;
    let heights = study.structure.storey_heights();
    let floor_accelerations = peaks
        .iter()
        .map(|storm| std::iter::once(0.0).chain(storm[..floors].iter().map(|a| a / STANDARD_GRAVITY)).collect())
        .collect();
    let drift_ratios =
        peaks.iter().map(|storm| storm[floors..].iter().zip(&heights).map(|(d, h)| d / h).collect()).collect();
    Ok(Demands { wind_speed, floor_accelerations, drift_ratios })
}

impl Demands {
    /// pelicun's demand sample: a header of `event-type-location-direction` names (`1-PFA-j-1`,
    /// `1-PID-j-1`), a `Units` row, then one row per storm under its index.
    pub fn pelicun_csv(&self) -> String {
        let floors = self.drift_ratios.first().map_or(0, Vec::len);
        let mut csv = String::new();
        let pfa = (0..=floors).map(|j| format!(",1-PFA-{j}-1"));
        let pid = (1..=floors).map(|j| format!(",1-PID-{j}-1"));
        csv.extend(pfa.chain(pid));
        csv.push_str("\nUnits");
        csv.push_str(&",g".repeat(floors + 1));
        csv.push_str(&",rad".repeat(floors));
        csv.push('\n');
        for (storm, (accelerations, ratios)) in self.floor_accelerations.iter().zip(&self.drift_ratios).enumerate() {
            write!(csv, "{storm}").expect("writing to a string");
            for value in accelerations.iter().chain(ratios) {
                write!(csv, ",{value:e}").expect("writing to a string");
            }
            csv.push('\n');
        }
        csv
    }
}

#[cfg(test)]
mod tests {
    use super::Demands;

    /// Two storms of a two-storey building, by hand.
    #[test]
    fn the_csv_is_pelicuns_demand_sample() {
        let demands = Demands {
            wind_speed: 40.0,
            floor_accelerations: vec![vec![0.0, 0.01, 0.02], vec![0.0, 0.03, 0.04]],
            drift_ratios: vec![vec![0.001, 0.002], vec![0.003, 0.004]],
        };
        let expected = ",1-PFA-0-1,1-PFA-1-1,1-PFA-2-1,1-PID-1-1,1-PID-2-1\nUnits,g,g,g,rad,rad\n\
                        0,0e0,1e-2,2e-2,1e-3,2e-3\n1,0e0,3e-2,4e-2,3e-3,4e-3\n";
        assert_eq!(demands.pelicun_csv(), expected);
    }
}
