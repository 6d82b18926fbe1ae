//! Exceedance requests: what a client asks, how it is checked, and the sampling that answers it,
//! shared by the synchronous route and the worker that runs large requests as operations.

use super::ServeArgs;
use crate::analysis::ExceedanceCurve;
use crate::analysis::{Response, automatic_thresholds, check_confidence, exceedance_curve, metamodel_peaks};
use crate::error::{Error, Result};
use crate::problem::Problem;
use crate::surrogate::{Metamodel, Observer};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use utoipa::ToSchema;

/// Which response's peak the curve is of.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default, ToSchema)]
#[serde(rename_all = "snake_case")]
pub enum ResponseKind {
    /// Floor displacement (m).
    #[default]
    Displacement,
    /// Inter-storey drift below the floor (m).
    Drift,
}

/// `POST /v1/metamodels/{id}/exceedance`: every field optional.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(default, deny_unknown_fields)]
pub struct ExceedanceRequest {
    /// Monte Carlo samples (storms) drawn from the input model.
    #[schema(minimum = 1, default = 1000)]
    pub samples: usize,
    #[schema(default = 1)]
    pub seed: u64,
    /// Floor (1-based); the roof when absent.
    #[schema(minimum = 1)]
    pub floor: Option<usize>,
    pub response: ResponseKind,
    /// Peak values (m) at which to evaluate the curve; 50 evenly spread over the sampled peaks when absent.
    pub thresholds: Option<Vec<f64>>,
    /// Inputs held fixed, by name (e.g. `{"wind_speed": 40}`), each inside its marginal's support.
    pub fixed: BTreeMap<String, f64>,
    /// Level of the Clopper-Pearson band, in (0, 1).
    #[schema(exclusive_minimum = 0, exclusive_maximum = 1, default = 0.95)]
    pub confidence: f64,
}

impl Default for ExceedanceRequest {
    fn default() -> Self {
        ExceedanceRequest {
            samples: 1000,
            seed: 1,
            floor: None,
            response: ResponseKind::Displacement,
            thresholds: None,
            fixed: BTreeMap::new(),
            confidence: 0.95,
        }
    }
}

/// Most thresholds a request may list.
const MAX_THRESHOLDS: usize = 10_000;

impl ExceedanceRequest {
    /// The checks that need no metamodel; errors name the field.
    pub fn check(&self, config: &ServeArgs) -> Result<()> {
        if self.samples == 0 || self.samples > config.max_samples {
            return Err(Error::invalid("samples", format!("must be between 1 and {}", config.max_samples)));
        }
        check_confidence(self.confidence)?;
        if let Some(t) = &self.thresholds
            && (t.is_empty() || t.len() > MAX_THRESHOLDS || t.iter().any(|x| !x.is_finite()))
        {
            return Err(Error::invalid("thresholds", format!("must be 1 to {MAX_THRESHOLDS} finite numbers")));
        }
        Ok(())
    }

    /// Samples the metamodel and builds the curve (blocking; parallel over samples).
    pub fn answer(
        &self,
        metamodel: &Metamodel,
        problem: &Problem,
        metamodel_id: &str,
        observer: &dyn Observer,
    ) -> Result<ExceedanceAnswer> {
        let floor = self.floor.unwrap_or(problem.structure.floors());
        let response = match self.response {
            ResponseKind::Displacement => Response::Displacement { floor },
            ResponseKind::Drift => Response::Drift { floor },
        };
        let mut inputs = problem.inputs.clone();
        for (name, value) in &self.fixed {
            inputs = inputs.with_fixed(name, *value).map_err(|error| match error {
                Error::Invalid { reason, .. } => Error::invalid(format!("fixed.{name}"), reason),
                other => other,
            })?;
        }
        let peaks = metamodel_peaks(metamodel, problem, &inputs, self.samples, self.seed, response, observer)?;
        let thresholds = self.thresholds.clone().unwrap_or_else(|| automatic_thresholds(&peaks, 50));
        let curve = exceedance_curve(&peaks, &thresholds, self.confidence);
        Ok(ExceedanceAnswer { curve, response, metamodel_id: metamodel_id.to_string() })
    }
}

/// An exceedance curve of a metamodel's sampled peaks, with its band.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct ExceedanceAnswer {
    #[serde(flatten)]
    pub curve: ExceedanceCurve,
    pub response: Response,
    pub metamodel_id: String,
}

/// A large exceedance request as queued.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ExceedanceJob {
    pub metamodel_id: String,
    pub request: ExceedanceRequest,
}
