//! The requests that start jobs and are not analyses of a metamodel: a calibration (resolved into
//! its study and options, with its cost checked before it is queued) and a validation.

use super::ServeArgs;
use super::schema;
use crate::analysis::ClimateCoverage;
use crate::error::{Error, Result};
use crate::structure::CustomStructure;
use crate::study::{Study, StudySpec};
use crate::surrogate::{CalibrationCost, CalibrationOptions, Refinement, WindCoverage, design};
use crate::uncertainty::Marginal;
use crate::wind::WindSite;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// `POST /v1/calibrations`: every field optional, the paper's values by default.
#[derive(Debug, Clone, Default, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(default, deny_unknown_fields)]
pub struct CalibrationRequest {
    /// A built-in study (`GET /v1/presets`); `frame40-kn` when neither this nor `structure` is given.
    #[schema(example = "frame40-kn", pattern = "^(frame40|frame40-kn)$")]
    pub preset: Option<String>,
    /// A structure of your own instead of a preset.
    pub structure: Option<CustomStructure>,
    /// Marginals replacing the preset's, by input name (`youngs_modulus`, `mass_factor`,
    /// `damping_ratio`, `damper_c1` … `damper_c4`, `wind_speed`).
    #[schema(schema_with = schema::marginals_schema)]
    pub inputs: BTreeMap<String, Marginal>,
    /// The wind site (terrain, profile, spectrum) replacing the preset's.
    pub wind: Option<WindSite>,
    /// Exponent α of the nonlinear viscous dampers, F = c·|v|^α·sign(v).
    #[schema(exclusive_minimum = 0, maximum = 2)]
    pub damper_exponent: Option<f64>,
    /// Modes kept in the reduced model (3 in the paper), at most 10 and the structure's floors.
    #[schema(minimum = 1, maximum = 10)]
    #[serde(default, deserialize_with = "crate::count::optional_count")]
    pub modes: Option<usize>,
    /// Storm length (s); 900 in the paper, at most a day. With the time step it sets the steps per
    /// storm (at most 10⁷), which with the experiments are checked against the server's budget.
    #[schema(exclusive_minimum = 0, maximum = 86400)]
    pub duration_s: Option<f64>,
    /// Time step (s); 0.01 in the paper, at least 0.1 ms, at most π/ω_up and the duration.
    #[schema(minimum = 0.0001)]
    pub time_step_s: Option<f64>,
    /// Reference runs on the Latin hypercube (K; 200 in the paper), at most the server's
    /// `--max-experiments` (1000 by default).
    #[schema(minimum = 4, maximum = 5000)]
    #[serde(default, deserialize_with = "crate::count::optional_count")]
    pub experiments: Option<usize>,
    /// Seed of the design and of the experiments' storms (1 by default).
    #[serde(default, deserialize_with = "crate::count::optional_seed")]
    pub seed: Option<u64>,
    /// The NARX dictionary (degrees, lags, coupling, damper terms).
    pub narx: Option<crate::surrogate::narx::NarxOptions>,
    /// The polynomial chaos expansions of the coefficients (degrees, truncation, interactions).
    pub pce: Option<crate::surrogate::pce::PceOptions>,
    /// How each experiment's coefficients are refined on the simulation error.
    pub refinement: Option<Refinement>,
    /// Wind speeds (m/s) the design must cover beyond the input model's spread: half the
    /// experiments spread evenly over them, the fits weighted so the expansions stay the input
    /// model's. At most one of this and `cover_climate`.
    pub cover_wind_speeds: Option<WindCoverage>,
    /// Cover a climate: from its 1-year speed to its speed of `annual_probability`.
    pub cover_climate: Option<ClimateCoverage>,
}

impl CalibrationRequest {
    /// The study and the options, checked; errors name the field.
    pub fn resolve(&self, config: &ServeArgs) -> Result<(Study, CalibrationOptions)> {
        let preset = if self.preset.is_none() && self.structure.is_none() {
            Some(crate::study::DEFAULT_PRESET.into())
        } else {
            self.preset.clone()
        };
        let spec = StudySpec {
            preset,
            structure: self.structure.clone(),
            spatial_structure: None,
            inputs: self.inputs.clone(),
            wind: self.wind.clone(),
            damper_exponent: self.damper_exponent,
            modes: self.modes,
            duration_s: self.duration_s,
            time_step_s: self.time_step_s,
        };
        let study = Study::from_spec(&spec)?;
        let defaults = CalibrationOptions::default();
        let options = CalibrationOptions {
            experiments: self.experiments.unwrap_or(defaults.experiments),
            seed: self.seed.unwrap_or(defaults.seed),
            narx: self.narx.clone().unwrap_or(defaults.narx),
            pce: self.pce.clone().unwrap_or(defaults.pce),
            refinement: self.refinement.unwrap_or(defaults.refinement),
            cover_wind_speeds: match (&self.cover_wind_speeds, &self.cover_climate) {
                (Some(_), Some(_)) => {
                    return Err(Error::invalid("cover_climate", "give cover_wind_speeds or cover_climate, not both"));
                }
                (Some(speeds), None) => Some(*speeds),
                (None, Some(climate)) => Some(climate.wind_speeds("cover_climate")?),
                (None, None) => None,
            },
            ..defaults
        };
        options.check()?;
        if options.cover_wind_speeds.is_some() {
            design(&study, &options)?; // the range inside the wind speed's support
        }
        if options.experiments > config.max_experiments {
            return Err(Error::invalid("experiments", format!("at most {} on this server", config.max_experiments)));
        }
        CalibrationCost::estimate(&study, &options, rayon::current_num_threads())
            .check(config.max_job_memory_mb as f64 * 1024.0 * 1024.0, config.max_job_steps as f64)?;
        Ok((study, options))
    }
}

/// `POST /v1/metamodels/{id}/validations`: fresh samples through the reference and the metamodel.
#[derive(Debug, Clone, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(default, deny_unknown_fields)]
pub struct ValidationRequest {
    /// Fresh Monte Carlo samples, each one reference storm.
    #[schema(minimum = 2, maximum = 5000, default = 200)]
    #[serde(deserialize_with = "crate::count::count")]
    pub samples: usize,
    /// Seed of the fresh samples and their storms.
    #[schema(default = 1000)]
    #[serde(deserialize_with = "crate::count::seed")]
    pub seed: u64,
    /// Inputs held, by name: `{"wind_speed": 60}` validates at one end of a calibrated range.
    #[schema(schema_with = schema::fixed_inputs_schema)]
    pub fixed: BTreeMap<String, f64>,
}

impl Default for ValidationRequest {
    fn default() -> Self {
        ValidationRequest { samples: 200, seed: 1000, fixed: BTreeMap::new() }
    }
}

/// A validation as queued: the request and the metamodel it is about.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ValidationJob {
    /// The stored metamodel validated.
    pub metamodel_id: String,
    /// Fresh samples, each one reference storm.
    pub samples: usize,
    /// Seed of the samples and their storms.
    pub seed: u64,
    /// Inputs held, by name.
    #[serde(default)]
    pub fixed: BTreeMap<String, f64>,
}

/// Most samples a validation job may ask for (each is one reference storm).
pub const MAX_VALIDATION_SAMPLES: usize = 5000;
