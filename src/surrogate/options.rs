//! What a calibration is asked to do besides the study: the design's size and seed, the NARX
//! dictionary, the expansions, the refinement, with the paper's values as defaults.

use super::Parametrization;
use super::narx::NarxOptions;
use super::pce::PceOptions;
use super::refine::Refinement;
use crate::error::{Error, Result};
use crate::study::WindPath;
use serde::{Deserialize, Serialize};

/// Everything about a calibration that is not the study itself; the defaults are the paper's.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(default, deny_unknown_fields)]
pub struct CalibrationOptions {
    /// Experiments K of the Latin-hypercube design.
    pub experiments: usize,
    /// Seed of the Latin-hypercube design and of the experiments' storms.
    pub seed: u64,
    /// The NARX dictionary and its structure selection.
    pub narx: NarxOptions,
    /// The polynomial chaos expansions of the coefficients.
    pub pce: PceOptions,
    /// How each experiment's coefficients are refined on the simulation error.
    pub refinement: Refinement,
    /// Experiments on which candidate structures are compared (evenly spread over the design).
    pub selection_experiments: usize,
    /// How the experiments' wind is generated.
    pub wind: WindPath,
    /// What the expansions are of; by default the stable gains whenever the experiments admit them.
    pub parametrization: Option<Parametrization>,
    /// Wind speeds the design must cover beyond the input model's own spread, e.g. up to a
    /// climate's 100 000-year speed; the fits are weighted so the expansions stay the input model's.
    pub cover_wind_speeds: Option<WindCoverage>,
}

impl Default for CalibrationOptions {
    fn default() -> Self {
        CalibrationOptions {
            experiments: 200,
            seed: 1,
            narx: NarxOptions::default(),
            pce: PceOptions::default(),
            refinement: Refinement::LevenbergMarquardt,
            selection_experiments: 20,
            wind: WindPath::Modal,
            parametrization: None,
            cover_wind_speeds: None,
        }
    }
}

/// Most experiments a calibration may ask for.
pub const MAX_EXPERIMENTS: usize = 5000;

impl CalibrationOptions {
    /// Refuses options outside their bounds, naming the field.
    pub fn check(&self) -> Result<()> {
        if !(4..=MAX_EXPERIMENTS).contains(&self.experiments) {
            return Err(Error::invalid(
                "experiments",
                format!("must be between 4 and {MAX_EXPERIMENTS}, got {}", self.experiments),
            ));
        }
        if self.selection_experiments == 0 {
            return Err(Error::invalid("selection_experiments", "must be at least 1"));
        }
        self.narx.check()?;
        if let Some(coverage) = &self.cover_wind_speeds {
            coverage.check()?;
        }
        self.pce.check()
    }
}

/// The wind speeds (m/s at the 10 m station) a calibration's design must cover.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(deny_unknown_fields)]
pub struct WindCoverage {
    /// Lowest speed to cover (m/s).
    #[cfg_attr(feature = "openapi", schema(exclusive_minimum = 0, maximum = 150))]
    pub lower: f64,
    /// Highest speed to cover (m/s).
    #[cfg_attr(feature = "openapi", schema(exclusive_minimum = 0, maximum = 150))]
    pub upper: f64,
}

/// The fastest station speed a design may cover (m/s), as for climates.
const MAX_SPEED: f64 = 150.0;

impl WindCoverage {
    /// Refuses speeds outside (0, 150] m/s or a lower speed not below the upper.
    pub fn check(&self) -> Result<()> {
        let field = "cover_wind_speeds";
        if !(self.lower.is_finite() && self.upper.is_finite() && self.lower > 0.0 && self.upper <= MAX_SPEED) {
            return Err(Error::invalid(
                field,
                format!(
                    "lower and upper must be speeds in (0, {MAX_SPEED}] m/s, got {} and {}",
                    self.lower, self.upper
                ),
            ));
        }
        if self.lower >= self.upper {
            return Err(Error::invalid(field, format!("lower ({}) must be below upper ({})", self.lower, self.upper)));
        }
        Ok(())
    }
}
