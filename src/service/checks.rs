//! Serviceability and sweep requests: what a design office asks of a stored metamodel to sign a
//! design and to size its dampers, checked here and answered by the library.

use crate::analysis::{
    CertifyOptions, ClimateSpec, CriterionChoice, Response, ResponseKind, Serviceability, ServiceabilityOptions, Sweep,
    SweepOptions, climate_or_own,
};
use crate::error::Result;
use crate::study::Study;
use serde::{Deserialize, Serialize};
use utoipa::ToSchema;

/// `POST /v1/metamodels/{id}/serviceability`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(default, deny_unknown_fields)]
pub struct ServiceabilityRequest {
    /// The law of the annual maximum storm speed at 10 m; the metamodel's `wind_speed` marginal
    /// when absent.
    pub climate: Option<ClimateSpec>,
    /// 1 to 20 criteria: built-in names (`nbcc-residential`, `nbcc-office`, `drift-h400`) or
    /// criteria in full; the three built-ins when absent.
    #[schema(min_items = 1, max_items = 20)]
    pub criteria: Vec<CriterionChoice>,
    /// Storms, each judged at every criterion and floor; at most the server's `--max-analysis-storms`.
    #[schema(minimum = 1, maximum = 1000000, default = 20000)]
    #[serde(deserialize_with = "crate::count::count")]
    pub samples: usize,
    #[schema(default = 1)]
    #[serde(deserialize_with = "crate::count::seed")]
    pub seed: u64,
    #[schema(exclusive_minimum = 0, exclusive_maximum = 1, default = 0.95)]
    pub confidence: f64,
    /// Certify each criterion's governing floor with this many storms run through both the
    /// reference model and the metamodel, shared out over the wind strata (at most the request's
    /// storms; all criteria's together within the server's bound). A certified check always runs
    /// as an operation.
    pub certify: Option<CertifyOptions>,
}

impl Default for ServiceabilityRequest {
    fn default() -> Self {
        ServiceabilityRequest {
            climate: None,
            criteria: crate::analysis::BUILT_IN.iter().map(|name| CriterionChoice::BuiltIn(name.to_string())).collect(),
            samples: 20_000,
            seed: 1,
            confidence: 0.95,
            certify: None,
        }
    }
}

impl ServiceabilityRequest {
    /// The check's options, every criterion checked against the study.
    pub fn options(&self, study: &Study) -> Result<ServiceabilityOptions> {
        let floors = study.structure.floors();
        let options = ServiceabilityOptions {
            climate: climate_or_own(self.climate.as_ref(), study)?,
            criteria: self.criteria.iter().map(|c| c.criterion(floors)).collect::<Result<_>>()?,
            samples: self.samples,
            seed: self.seed,
            confidence: self.confidence,
            certify: self.certify,
        };
        options.resolve(study)?;
        Ok(options)
    }
}

/// `POST /v1/metamodels/{id}/sweep`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct SweepRequest {
    /// The input held at each value: a random input of the metamodel other than `wind_speed`,
    /// e.g. `damper_c4`.
    pub input: String,
    /// 1 to 20 values inside the input's support.
    #[schema(min_items = 1, max_items = 20)]
    pub values: Vec<f64>,
    /// The return period (years, from 1 to 10⁶) whose level is reported.
    #[serde(default = "ten_years")]
    #[schema(minimum = 1, maximum = 1000000, default = 10)]
    pub return_period_years: f64,
    #[serde(default)]
    pub response: ResponseKind,
    /// Floor (1-based); the roof when absent.
    #[schema(minimum = 1, maximum = 200)]
    #[serde(default, deserialize_with = "crate::count::optional_count")]
    pub floor: Option<usize>,
    /// Damper group (1-based) instead of a floor, for `damper_force` and `damper_stroke`.
    #[schema(minimum = 1, maximum = 10)]
    #[serde(default, deserialize_with = "crate::count::optional_count")]
    pub group: Option<usize>,
    /// The law of the annual maximum storm speed at 10 m; the metamodel's `wind_speed` marginal
    /// when absent.
    #[serde(default)]
    pub climate: Option<ClimateSpec>,
    /// Storms at each value (the same storms at every value); all values' together at most the
    /// server's `--max-analysis-storms`.
    #[schema(minimum = 1, maximum = 1000000, default = 10000)]
    #[serde(default = "ten_thousand", deserialize_with = "crate::count::count")]
    pub samples: usize,
    #[schema(default = 1)]
    #[serde(default = "one", deserialize_with = "crate::count::seed")]
    pub seed: u64,
    #[schema(exclusive_minimum = 0, exclusive_maximum = 1, default = 0.95)]
    #[serde(default = "ninety_five_percent")]
    pub confidence: f64,
}

fn ten_years() -> f64 {
    10.0
}

fn ten_thousand() -> usize {
    10_000
}

fn one() -> u64 {
    1
}

fn ninety_five_percent() -> f64 {
    0.95
}

impl SweepRequest {
    /// The sweep's options, checked against the study.
    pub fn options(&self, study: &Study) -> Result<SweepOptions> {
        let options = SweepOptions {
            input: self.input.clone(),
            values: self.values.clone(),
            climate: climate_or_own(self.climate.as_ref(), study)?,
            return_period_years: self.return_period_years,
            samples: self.samples,
            seed: self.seed,
            confidence: self.confidence,
        };
        options.check(study)?;
        Ok(options)
    }
}

/// A serviceability check of a metamodel.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct ServiceabilityAnswer {
    #[serde(flatten)]
    pub check: Serviceability,
    pub metamodel_id: String,
}

/// A sweep of a metamodel's input.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct SweepAnswer {
    #[serde(flatten)]
    pub sweep: Sweep,
    #[schema(value_type = crate::analysis::ResponseName)]
    pub response: Response,
    pub metamodel_id: String,
}
