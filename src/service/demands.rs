//! Demand requests: a pelicun demand sample of a stored metamodel at one wind speed, answered at
//! once (a demand sample is a file for a loss assessment, not an operation's JSON result).

use super::ServeArgs;
use crate::analysis::{OnThisMachine, metamodel_demands};
use crate::error::{Error, Result};
use crate::progress::Observer;
use crate::study::Study;
use crate::surrogate::Metamodel;
use serde::{Deserialize, Serialize};
use utoipa::ToSchema;

/// Most storms in one demand sample: a FEMA P-58 assessment uses a few hundred to a few thousand
/// realisations, and a row holds every floor's and storey's demand.
pub const MAX_DEMAND_SAMPLES: usize = 10_000;

/// `POST /v1/metamodels/{id}/demands`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct DemandsRequest {
    /// The storm speed at 10 m (m/s), inside the metamodel's wind-speed law's support.
    #[schema(exclusive_minimum = 0, exclusive_maximum = 150)]
    pub wind_speed: f64,
    /// Storms, the rows of the sample; at most 10 000 and the server's `--max-sync-samples` (the
    /// contract a server serves states its own bound).
    #[schema(minimum = 1, maximum = 10000, default = 1000)]
    #[serde(default = "default_samples", deserialize_with = "crate::count::count")]
    pub samples: usize,
    #[schema(default = 1)]
    #[serde(default = "default_seed", deserialize_with = "crate::count::seed")]
    pub seed: u64,
}

fn default_samples() -> usize {
    1000
}

fn default_seed() -> u64 {
    1
}

impl DemandsRequest {
    /// The checks that need no sampling; errors name the field.
    pub fn check(&self, config: &ServeArgs) -> Result<()> {
        let bound = MAX_DEMAND_SAMPLES.min(config.max_sync_samples);
        if self.samples == 0 || self.samples > bound {
            return Err(Error::invalid("samples", format!("must be between 1 and {bound}, got {}", self.samples)));
        }
        if !(self.wind_speed > 0.0 && self.wind_speed < 150.0) {
            return Err(Error::invalid("wind_speed", format!("must lie in (0, 150) m/s, got {}", self.wind_speed)));
        }
        Ok(())
    }

    /// The demand sample as pelicun reads it (blocking; parallel over storms).
    pub fn answer(&self, metamodel: &Metamodel, study: &Study, observer: &dyn Observer) -> Result<String> {
        Ok(metamodel_demands(metamodel, study, self.wind_speed, self.samples, self.seed, &OnThisMachine, observer)?
            .pelicun_csv())
    }
}
