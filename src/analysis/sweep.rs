//! A sweep of one input: the T-year level of a response under a climate with the input held at
//! each of several values and every other input random, as an engineer sizes a damper against a
//! comfort limit. Every value sees the same storms (inputs, speeds, phases; common random numbers)
//! and one allocation of storms to the wind strata, chosen for all the values' levels together,
//! so that the levels differ by what the input does, not by sampling noise ([`super::annual_sample`]).

use super::Response;
use super::annual_sample::{AnnualDesign, PILOT_SHARE};
use super::exceedance::check_confidence;
use super::hazard::{MAX_SPEED, WIND_SPEED, return_level};
use super::sampling::{DivergedStorm, Draws, OnDivergence, check_samples, peaks_at};
use super::strata::{StormRows, StratifiedPeaks, WindStrata, pilot};
use crate::error::{Error, Result};
use crate::progress::Observer;
use crate::study::Study;
use crate::surrogate::Metamodel;
use crate::uncertainty::{Marginal, rng_from_seed};
use serde::{Deserialize, Serialize};

/// Most values one sweep may hold the input at.
pub const MAX_SWEEP_VALUES: usize = 20;

/// What a sweep is asked.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepOptions {
    /// The swept input's name (a random input of the metamodel other than the wind speed).
    pub input: String,
    pub values: Vec<f64>,
    /// The law of the annual maximum storm speed.
    pub climate: Marginal,
    pub return_period_years: f64,
    /// Storms at each value (the same storms at every value).
    pub samples: usize,
    pub seed: u64,
    pub confidence: f64,
}

/// The T-year level with the input held at one value.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct SweepPoint {
    pub input_value: f64,
    /// The level exceeded in a year with probability 1 − exp(−1/T); none where the sampled storms
    /// do not reach so rare a level.
    pub level: Option<f64>,
    /// Where the band's ends cross that probability.
    pub lower: Option<f64>,
    pub upper: Option<f64>,
}

/// A sweep's answer.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct Sweep {
    pub input: String,
    pub return_period_years: f64,
    pub results: Vec<SweepPoint>,
    /// The input's lowest and highest values among the calibration's experiments: beyond them the
    /// metamodel extrapolates.
    pub calibrated_input_range: [f64; 2],
    /// The law of the annual maximum storm speed at the 10 m station.
    pub climate: Marginal,
    /// Storms run at each value.
    pub samples: usize,
    pub strata: usize,
    pub confidence: f64,
    /// Storms whose free run diverged at some value, counted as exceeding every level there.
    pub diverged_storms: usize,
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
    observer: &dyn Observer,
) -> Result<Sweep> {
    let swept = options.check(study)?;
    response.check(&study.structure)?;
    let calibrated = metamodel.calibrated_range(study, WIND_SPEED)?;
    let strata = options.strata();
    let rows = StormRows {
        inputs: &study.inputs,
        wind: study.inputs.index_of(WIND_SPEED)?,
        climate: &options.climate,
        strata: &strata,
    };
    let design = AnnualDesign { rows, samples: options.samples, calibrated };
    // Every value runs the same rows and storm streams, the swept input replaced.
    let peaks_of = |rows: &[Vec<f64>], first: usize| -> Result<Vec<Vec<f64>>> {
        let storms: Vec<usize> = (first..first + rows.len()).collect();
        let mut by_row = vec![Vec::with_capacity(options.values.len()); rows.len()];
        for &value in &options.values {
            let held: Vec<Vec<f64>> = rows.iter().map(|row| with_value(row, swept, value)).collect();
            let draws =
                Draws { study, rows: &held, storms: &storms, seed: options.seed, on_divergence: OnDivergence::Exceed };
            for (row, peak) in by_row.iter_mut().zip(peaks_at(metamodel, &draws, response, observer)?) {
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
    let sample = design.draw(&mut rng_from_seed(options.seed), peaks_of, aims)?;
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
        calibrated_input_range: metamodel.calibrated_range(study, &options.input)?,
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

impl Sweep {
    /// One row per value.
    pub fn csv(&self, unit_tag: &str) -> String {
        let blank = |x: Option<f64>| x.map_or(String::new(), |x| x.to_string());
        let mut out = format!("{},level_{unit_tag},lower,upper\n", self.input);
        for p in &self.results {
            out += &format!("{},{},{},{}\n", p.input_value, blank(p.level), blank(p.lower), blank(p.upper));
        }
        out
    }
}
