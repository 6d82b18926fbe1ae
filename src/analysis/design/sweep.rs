//! A sweep of one input: the T-year level of a response under a climate with the input held at
//! each of several values and every other input random, as an engineer sizes a damper against a
//! comfort limit. Every value sees the same storms (inputs, speeds, phases; common random numbers)
//! and one allocation of storms to the wind strata, chosen for all the values' levels together,
//! so that the levels differ by what the input does, not by sampling noise ([`crate::analysis::sampling::annual_sample`]).

use crate::analysis::answers::hazard::{MAX_SPEED, WIND_SPEED, return_level};
use crate::analysis::responses::response::Response;
use crate::analysis::sampling::annual_sample::{AnnualDesign, PILOT_SHARE};
use crate::analysis::sampling::draws::{DivergedStorm, Draws, OnDivergence, check_samples, peaks_at};
use crate::analysis::sampling::exceedance::check_confidence;
use crate::analysis::sampling::runner::StormRunner;
use crate::analysis::sampling::strata::{StormRows, StratifiedPeaks, WindStrata, pilot};
use crate::error::{Error, Result};
use crate::progress::Observer;
use crate::study::Study;
use crate::surrogate::Metamodel;
use crate::uncertainty::{InputModel, Marginal, rng_from_seed};
use serde::{Deserialize, Serialize};

/// Most values one sweep may hold the input at.
pub const MAX_SWEEP_VALUES: usize = 20;

/// What a sweep is asked.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepOptions {
    /// The swept input's name (a random input of the metamodel other than the wind speed).
    pub input: String,
    /// The values the input is held at, each inside its law's support.
    pub values: Vec<f64>,
    /// The law of the annual maximum storm speed.
    pub climate: Marginal,
    /// The return period (years) whose level is swept.
    pub return_period_years: f64,
    /// Storms at each value (the same storms at every value).
    pub samples: usize,
    /// The seed of the storms' inputs, speeds and phases.
    pub seed: u64,
    /// The level of the bands.
    pub confidence: f64,
}

/// The T-year level with the input held at one value.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct SweepPoint {
    /// The value the input was held at.
    pub input_value: f64,
    /// The level exceeded in a year with probability 1 − exp(−1/T); none where the sampled storms
    /// do not reach so rare a level.
    pub level: Option<f64>,
    /// Where the band's ends cross that probability.
    pub lower: Option<f64>,
    /// The level where the band's upper end crosses the level's probability.
    pub upper: Option<f64>,
}

/// A sweep's answer.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct Sweep {
    /// The swept input's name.
    pub input: String,
    /// The return period (years) whose level was swept.
    pub return_period_years: f64,
    /// The level at each value, in the order asked.
    pub results: Vec<SweepPoint>,
    /// The input's lowest and highest values among the calibration's experiments: beyond them the
    /// metamodel extrapolates.
    pub calibrated_input_range: [f64; 2],
    /// The law of the annual maximum storm speed at the 10 m station.
    pub climate: Marginal,
    /// Storms run at each value.
    pub samples: usize,
    /// Wind strata the storms were drawn in.
    pub strata: usize,
    /// The level of the bands.
    pub confidence: f64,
    /// Storms whose free run diverged at some value, counted as exceeding every level there.
    pub diverged_storms: usize,
    /// The first few diverged storms with their inputs.
    #[serde(default)]
    pub first_diverged: Vec<DivergedStorm>,
}

impl SweepOptions {
    /// Checks everything but the sampling against the study; errors name the field. Answers the
    /// swept input's position.
    pub fn check(&self, study: &Study) -> Result<usize> {
        check_samples(self.samples)?;
        check_confidence(self.confidence)?;
        let index = study.inputs.index_of(&self.input).map_err(|e| match e {
            Error::Invalid { reason, .. } => Error::invalid("input", reason),
            other => other,
        })?;
        if self.input == WIND_SPEED {
            return Err(Error::invalid("input", "the wind speed is the climate's; fragility curves hold it at speeds"));
        }
        let marginal = study.inputs.inputs[index].marginal;
        if let Marginal::Constant { value } = marginal {
            return Err(Error::invalid("input", format!("`{}` is held at {value} in this metamodel", self.input)));
        }
        if self.values.is_empty() || self.values.len() > MAX_SWEEP_VALUES {
            return Err(Error::invalid("values", format!("give 1 to {MAX_SWEEP_VALUES} values")));
        }
        if let Some(v) = self.values.iter().find(|v| !marginal.contains(**v)) {
            let (lo, hi) = marginal.support();
            return Err(Error::invalid(
                "values",
                format!("{v} lies outside the support [{lo}, {hi}] of `{}`'s distribution", self.input),
            ));
        }
        let t = self.return_period_years;
        if !(t.is_finite() && (1.0..=1e6).contains(&t)) {
            return Err(Error::invalid("return_period_years", format!("must be from 1 to 1e6 years, got {t}")));
        }
        pilot(&self.strata(), self.samples, PILOT_SHARE, "samples")?;
        Ok(index)
    }

    fn strata(&self) -> WindStrata {
        WindStrata::new(&self.climate, (1.0 / self.return_period_years).min(1e-4), MAX_SPEED)
    }
}

/// The sweep of `options.input` for a metamodel's `response`.
pub fn metamodel_sweep(
    metamodel: &Metamodel,
    study: &Study,
    response: Response,
    options: &SweepOptions,
    runner: &dyn StormRunner,
    observer: &dyn Observer,
) -> Result<Sweep> {
    let swept = options.check(study)?;
    response.check(&study.structure)?;
    let calibrated =
        [metamodel.calibrated_range(study, WIND_SPEED)?, metamodel.calibrated_range(study, &options.input)?];
    let peaks_of = |rows: &[Vec<f64>], first: usize| {
        let storms: Vec<usize> = (first..first + rows.len()).collect();
        let draws = Draws { study, rows, storms: &storms, seed: options.seed, on_divergence: OnDivergence::Exceed };
        peaks_at(metamodel, &draws, response, runner, observer)
    };
    sweep_levels(&study.inputs, options, swept, calibrated, peaks_of)
}

/// The sweep of input `swept` of `inputs` (the wind speed the climate's): `peaks_of(rows, first)`
/// answers a peak per row (`first`: the rows run before, so that every row gets its own storm);
/// `calibrated`: the calibration's range of the wind speed and of the swept input.
pub fn sweep_levels(
    inputs: &InputModel,
    options: &SweepOptions,
    swept: usize,
    calibrated: [[f64; 2]; 2],
    mut peaks_of: impl FnMut(&[Vec<f64>], usize) -> Result<Vec<f64>>,
) -> Result<Sweep> {
    let strata = options.strata();
    let rows = StormRows { inputs, wind: inputs.index_of(WIND_SPEED)?, climate: &options.climate, strata: &strata };
    let design = AnnualDesign { rows, samples: options.samples, calibrated: calibrated[0] };
    // Every value runs the same rows and storm streams, the swept input replaced.
    let by_value = |rows: &[Vec<f64>], first: usize| -> Result<Vec<Vec<f64>>> {
        let mut by_row = vec![Vec::with_capacity(options.values.len()); rows.len()];
        for &value in &options.values {
            let held: Vec<Vec<f64>> = rows.iter().map(|row| with_value(row, swept, value)).collect();
            for (row, peak) in by_row.iter_mut().zip(peaks_of(&held, first)?) {
                row.push(peak);
            }
        }
        Ok(by_row)
    };
    let period = options.return_period_years;
    let level_of = |column: &StratifiedPeaks| {
        return_level(&column.finite_peaks(), period, |x| column.exceedance(x, options.confidence))
    };
    let aims = |pilot: &[StratifiedPeaks]| {
        pilot.iter().enumerate().filter_map(|(c, column)| Some((c, level_of(column).value?))).collect()
    };
    let sample = design.draw(&mut rng_from_seed(options.seed), by_value, aims)?;
    let results = options
        .values
        .iter()
        .zip(&sample.columns)
        .map(|(&input_value, column)| {
            let level = level_of(column);
            SweepPoint { input_value, level: level.value, lower: level.lower, upper: level.upper }
        })
        .collect();
    Ok(Sweep {
        input: options.input.clone(),
        return_period_years: period,
        results,
        calibrated_input_range: calibrated[1],
        climate: options.climate,
        samples: sample.storms,
        strata: strata.count(),
        confidence: options.confidence,
        diverged_storms: sample.diverged,
        first_diverged: sample.first_diverged,
    })
}

fn with_value(row: &[f64], index: usize, value: f64) -> Vec<f64> {
    let mut row = row.to_vec();
    row[index] = value;
    row
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::annual_probability_of_period;
    use crate::analysis::answers::hazard::tests::lognormal_scatter_level;
    use crate::uncertainty::Input;

    /// peak = v·exp(σz)/(1 + c) with c the swept input: the same storms at every value make the
    /// levels exactly proportional to 1/(1 + c), and c = 0 holds the quadrature's level.
    #[test]
    fn the_same_storms_at_every_value() {
        let climate = Marginal::Gumbel { location: 22.0, scale: 2.2 };
        let inputs = InputModel::new(vec![
            Input { name: "z".into(), marginal: Marginal::Normal { mean: 0.0, sd: 1.0 } },
            Input { name: WIND_SPEED.into(), marginal: Marginal::Frechet { mean: 30.0, sd: 3.5 } },
            Input { name: "c".into(), marginal: Marginal::Uniform { lower: 0.0, upper: 1.0 } },
        ])
        .unwrap();
        let options = SweepOptions {
            input: "c".into(),
            values: vec![0.0, 0.5, 1.0],
            climate,
            return_period_years: 50.0,
            samples: 10_000,
            // A 95 % band: over seeds 1 to 7 it held the exact level six times (seed 3 missed by 0.4 %).
            seed: 1,
            confidence: 0.95,
        };
        let peaks_of =
            |rows: &[Vec<f64>], _| Ok(rows.iter().map(|r| r[1] * (0.15 * r[0]).exp() / (1.0 + r[2])).collect());
        let sweep = sweep_levels(&inputs, &options, 2, [[15.0, 45.0], [0.0, 1.0]], peaks_of).unwrap();
        let level = |i: usize| sweep.results[i].level.unwrap();
        assert!((level(1) / level(0) - 1.0 / 1.5).abs() < 1e-12, "{:?}", sweep.results);
        assert!((level(2) / level(0) - 0.5).abs() < 1e-12, "{:?}", sweep.results);
        let exact = lognormal_scatter_level(&climate, 0.15, annual_probability_of_period(50.0));
        let first = &sweep.results[0];
        assert!(first.lower.unwrap() <= exact && exact <= first.upper.unwrap(), "{exact}: {first:?}");
        assert!(sweep.samples <= 10_000 && sweep.strata > 1);
    }
}
