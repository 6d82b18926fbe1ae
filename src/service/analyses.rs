//! Annual (hazard), fragility, sensitivity, serviceability and sweep requests as one
//! [`AnalysisRequest`]: what a client asks, how it is checked, and
//! the sampling that answers it, shared by the synchronous routes and the workers that run large
//! requests as operations.

use super::ServeArgs;
use super::checks::{ServiceabilityAnswer, ServiceabilityRequest, SweepAnswer, SweepRequest};
use super::exceedance::check_reference_storm_budget;
use super::rendering::Rendering;
use super::schema::thresholds_schema;
use crate::analysis::{
    CertifyOptions, ClimateSpec, DEFAULT_RETURN_PERIODS, Fragility, FragilityOptions, HazardCurve, HazardOptions,
    Response, ResponseKind, ResponseName, Sampling, Sensitivity, StormRunner, check_confidence, climate_or_own,
    fragility_svg, hazard_svg, metamodel_fragility, metamodel_hazard, metamodel_sensitivity, metamodel_serviceability,
    metamodel_sweep, serviceability_svg, sweep_svg,
};
use crate::error::{Error, Result};
use crate::progress::Observer;
use crate::study::Study;
use crate::surrogate::Metamodel;
use crate::uncertainty::Marginal;
use serde::{Deserialize, Serialize};
use utoipa::ToSchema;

/// `POST /v1/metamodels/{id}/hazard`: every field optional.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(default, deny_unknown_fields)]
pub struct HazardRequest {
    /// Storms run through the metamodel; at most the server's `--max-analysis-storms`.
    #[schema(minimum = 1, maximum = 1000000, default = 20000)]
    #[serde(deserialize_with = "crate::count::count")]
    pub samples: usize,
    #[schema(default = 1)]
    #[serde(deserialize_with = "crate::count::seed")]
    pub seed: u64,
    /// Floor (1-based); the roof when absent.
    #[schema(minimum = 1, maximum = 200)]
    #[serde(default, deserialize_with = "crate::count::optional_count")]
    pub floor: Option<usize>,
    /// Damper group (1-based) instead of a floor, for `damper_force` and `damper_stroke`: the
    /// largest among the group's dampers.
    #[schema(minimum = 1, maximum = 10)]
    #[serde(default, deserialize_with = "crate::count::optional_count")]
    pub group: Option<usize>,
    pub response: ResponseKind,
    /// The law of the annual maximum storm speed at 10 m; the metamodel's `wind_speed` marginal
    /// when absent.
    pub climate: Option<ClimateSpec>,
    /// Peak values (in the response's unit) at which to report the annual probability; 50 spread over the sampled
    /// peaks when absent.
    #[schema(schema_with = thresholds_schema)]
    pub thresholds: Option<Vec<f64>>,
    /// Return periods (years, from 1 to 10⁶); 1, 10, 50, 100, 500, 700, 1000 and 10 000 when
    /// absent. The T-year level is exceeded in a year with probability 1 − exp(−1/T) (≈ 1/T for long
    /// periods; 0.632 for T = 1).
    #[schema(max_items = 100)]
    pub return_periods: Option<Vec<f64>>,
    /// A limit (in the response's unit) whose annual probability and reliability index are reported.
    #[schema(minimum = 0, maximum = 1e9)]
    pub limit: Option<f64>,
    #[schema(exclusive_minimum = 0, exclusive_maximum = 1, default = 0.95)]
    pub confidence: f64,
    pub sampling: Sampling,
    /// Certify the curve with this many storms run through both the reference model and the
    /// metamodel, shared out over the wind strata where the two can disagree (at most the
    /// request's storms and the server's bound). A certified request always runs as an operation.
    pub certify: Option<CertifyOptions>,
}

impl Default for HazardRequest {
    fn default() -> Self {
        HazardRequest {
            samples: 20_000,
            seed: 1,
            floor: None,
            group: None,
            response: ResponseKind::Displacement,
            climate: None,
            thresholds: None,
            return_periods: None,
            limit: None,
            confidence: 0.95,
            sampling: Sampling::Stratified,
            certify: None,
        }
    }
}

/// `POST /v1/metamodels/{id}/fragility`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(default, deny_unknown_fields)]
pub struct FragilityRequest {
    /// Storm speeds at 10 m (m/s, 0 to 150), 1 to 200 of them; 20 to 60 by 2 when absent.
    #[schema(min_items = 1, max_items = 200)]
    pub wind_speeds: Vec<f64>,
    /// Peak values (in the response's unit).
    #[schema(schema_with = thresholds_schema)]
    pub thresholds: Option<Vec<f64>>,
    /// Storms at each speed.
    #[schema(minimum = 2, maximum = 1000000, default = 500)]
    #[serde(deserialize_with = "crate::count::count")]
    pub samples: usize,
    #[schema(default = 1)]
    #[serde(deserialize_with = "crate::count::seed")]
    pub seed: u64,
    #[schema(minimum = 1, maximum = 200)]
    #[serde(default, deserialize_with = "crate::count::optional_count")]
    pub floor: Option<usize>,
    /// Damper group (1-based) instead of a floor, for `damper_force` and `damper_stroke`: the
    /// largest among the group's dampers.
    #[schema(minimum = 1, maximum = 10)]
    #[serde(default, deserialize_with = "crate::count::optional_count")]
    pub group: Option<usize>,
    pub response: ResponseKind,
    #[schema(exclusive_minimum = 0, exclusive_maximum = 1, default = 0.95)]
    pub confidence: f64,
    /// Certify every speed's probabilities with this many storms per speed run through both the
    /// reference model and the metamodel (at most the storms per speed; all speeds' together
    /// within the server's bound). A certified request always runs as an operation.
    pub certify: Option<CertifyOptions>,
}

impl HazardRequest {
    /// The analysis's options: the climate resolved (the metamodel's own wind law by default).
    fn options(&self, study: &Study) -> Result<HazardOptions> {
        Ok(HazardOptions {
            climate: climate_or_own(self.climate.as_ref(), study)?,
            samples: self.samples,
            seed: self.seed,
            thresholds: self.thresholds.clone(),
            return_periods: self.return_periods.clone().unwrap_or_else(|| DEFAULT_RETURN_PERIODS.to_vec()),
            limit: self.limit,
            confidence: self.confidence,
            sampling: self.sampling,
            certify: self.certify,
        })
    }
}

impl Default for FragilityRequest {
    fn default() -> Self {
        FragilityRequest {
            wind_speeds: (0..=20).map(|k| 20.0 + 2.0 * k as f64).collect(),
            thresholds: None,
            samples: 500,
            seed: 1,
            floor: None,
            group: None,
            response: ResponseKind::Displacement,
            confidence: 0.95,
            certify: None,
        }
    }
}

impl FragilityRequest {
    /// The analysis's options; the thresholds are required.
    fn options(&self) -> Result<FragilityOptions> {
        let thresholds = self.thresholds.clone().ok_or_else(|| Error::invalid("thresholds", "are required"))?;
        Ok(FragilityOptions {
            wind_speeds: self.wind_speeds.clone(),
            thresholds,
            samples_per_speed: self.samples,
            seed: self.seed,
            confidence: self.confidence,
            certify: self.certify,
        })
    }
}

/// `POST /v1/metamodels/{id}/sensitivity`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(default, deny_unknown_fields)]
pub struct SensitivityRequest {
    /// Rows N of each of the two base samples: N·(groups + 2) storms are run.
    #[schema(minimum = 10, maximum = 1000000, default = 1024)]
    #[serde(deserialize_with = "crate::count::count")]
    pub samples: usize,
    #[schema(default = 1)]
    #[serde(deserialize_with = "crate::count::seed")]
    pub seed: u64,
    #[schema(minimum = 1, maximum = 200)]
    #[serde(default, deserialize_with = "crate::count::optional_count")]
    pub floor: Option<usize>,
    /// Damper group (1-based) instead of a floor, for `damper_force` and `damper_stroke`: the
    /// largest among the group's dampers.
    #[schema(minimum = 1, maximum = 10)]
    #[serde(default, deserialize_with = "crate::count::optional_count")]
    pub group: Option<usize>,
    pub response: ResponseKind,
    #[schema(exclusive_minimum = 0, exclusive_maximum = 1, default = 0.95)]
    pub confidence: f64,
}

impl Default for SensitivityRequest {
    fn default() -> Self {
        SensitivityRequest {
            samples: 1024,
            seed: 1,
            floor: None,
            group: None,
            response: ResponseKind::Displacement,
            confidence: 0.95,
        }
    }
}

/// Any analysis request, as queued.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "analysis", rename_all = "snake_case")]
pub enum AnalysisRequest {
    Hazard(HazardRequest),
    Fragility(FragilityRequest),
    Sensitivity(SensitivityRequest),
    Serviceability(ServiceabilityRequest),
    Sweep(SweepRequest),
}

/// A large analysis request as queued.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct AnalysisJob {
    pub metamodel_id: String,
    pub request: AnalysisRequest,
}

/// An annual curve of a metamodel's peak response.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct HazardAnswer {
    #[serde(flatten)]
    pub curve: HazardCurve,
    #[schema(value_type = ResponseName)]
    pub response: Response,
    pub metamodel_id: String,
}

/// Fragility curves of a metamodel's peak response.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct FragilityAnswer {
    #[serde(flatten)]
    pub fragility: Fragility,
    #[schema(value_type = ResponseName)]
    pub response: Response,
    pub metamodel_id: String,
}

/// Sobol indices of a metamodel's peak response.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct SensitivityAnswer {
    #[serde(flatten)]
    pub sensitivity: Sensitivity,
    #[schema(value_type = ResponseName)]
    pub response: Response,
    pub metamodel_id: String,
}

/// What an analysis answers (a serviceability check or a sweep has no one response).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(untagged)]
pub enum AnalysisAnswer {
    Hazard(Box<HazardAnswer>),
    Fragility(Box<FragilityAnswer>),
    Sensitivity(Box<SensitivityAnswer>),
    Serviceability(Box<ServiceabilityAnswer>),
    Sweep(Box<SweepAnswer>),
}

impl AnalysisRequest {
    /// The storms the request runs through the metamodel.
    pub fn storms(&self, study: &Study) -> usize {
        match self {
            AnalysisRequest::Hazard(r) => r.samples,
            AnalysisRequest::Fragility(r) => r.samples.saturating_mul(r.wind_speeds.len()),
            AnalysisRequest::Sensitivity(r) => {
                let random = study.inputs.inputs.iter().filter(|i| !matches!(i.marginal, Marginal::Constant { .. }));
                r.samples.saturating_mul(random.count() + 3)
            }
            AnalysisRequest::Serviceability(r) => r.samples,
            // No value is refused by the sweep's own check, naming `values`.
            AnalysisRequest::Sweep(r) => r.samples.saturating_mul(r.values.len().max(1)),
        }
    }

    /// The storms it runs through the reference model as well (a certified answer's); none: 0.
    pub fn reference_storms(&self) -> usize {
        match self {
            AnalysisRequest::Fragility(r) => {
                r.certify.map_or(0, |c| c.reference_storms.saturating_mul(r.wind_speeds.len()))
            }
            AnalysisRequest::Hazard(r) => r.certify.map_or(0, |c| c.reference_storms),
            AnalysisRequest::Serviceability(r) => {
                r.certify.map_or(0, |c| c.reference_storms.saturating_mul(r.criteria.len()))
            }
            AnalysisRequest::Sensitivity(_) | AnalysisRequest::Sweep(_) => 0,
        }
    }

    /// The one response the request names, checked against the study's structure (a
    /// serviceability check names its responses in its criteria: none).
    fn response(&self, study: &Study) -> Result<Option<Response>> {
        let (floor, group, kind) = match self {
            AnalysisRequest::Hazard(r) => (r.floor, r.group, r.response),
            AnalysisRequest::Fragility(r) => (r.floor, r.group, r.response),
            AnalysisRequest::Sensitivity(r) => (r.floor, r.group, r.response),
            AnalysisRequest::Sweep(r) => (r.floor, r.group, r.response),
            AnalysisRequest::Serviceability(_) => return Ok(None),
        };
        kind.located(floor, group, &study.structure).map(Some)
    }

    /// The checks that need the study but no sampling; errors name the field.
    pub fn check(&self, config: &ServeArgs, study: &Study) -> Result<()> {
        let storms = self.storms(study);
        if storms == 0 || storms > config.max_analysis_storms {
            return Err(Error::invalid(
                "samples",
                format!("the request runs {storms} storms; this server allows 1 to {}", config.max_analysis_storms),
            ));
        }
        self.response(study)?;
        check_reference_storm_budget(self.reference_storms(), config)?;
        match self {
            AnalysisRequest::Hazard(r) => r.options(study)?.check(),
            AnalysisRequest::Fragility(r) => r.options()?.check(),
            AnalysisRequest::Sensitivity(r) if r.samples < 10 => Err(Error::invalid("samples", "must be at least 10")),
            AnalysisRequest::Sensitivity(r) => check_confidence(r.confidence),
            AnalysisRequest::Serviceability(r) => r.options(study).map(drop),
            AnalysisRequest::Sweep(r) => r.options(study).map(drop),
        }
    }

    /// Samples the metamodel and answers (blocking; parallel over storms); its storms, and a
    /// certified answer's reference storms, run where `storms` puts them.
    pub fn answer(
        &self,
        metamodel: &Metamodel,
        study: &Study,
        metamodel_id: &str,
        storms: &dyn StormRunner,
        observer: &dyn Observer,
    ) -> Result<AnalysisAnswer> {
        let metamodel_id = metamodel_id.to_string();
        let located = self.response(study)?;
        let response = || located.expect("every request but a serviceability check names one response");
        Ok(match self {
            AnalysisRequest::Hazard(r) => {
                let options = r.options(study)?;
                let curve = metamodel_hazard(metamodel, study, response(), &options, storms, observer)?;
                AnalysisAnswer::Hazard(Box::new(HazardAnswer { curve, response: response(), metamodel_id }))
            }
            AnalysisRequest::Fragility(r) => {
                let fragility = metamodel_fragility(metamodel, study, response(), &r.options()?, storms, observer)?;
                AnalysisAnswer::Fragility(Box::new(FragilityAnswer { fragility, response: response(), metamodel_id }))
            }
            AnalysisRequest::Sensitivity(r) => {
                let sensitivity = metamodel_sensitivity(
                    metamodel,
                    study,
                    response(),
                    r.samples,
                    r.seed,
                    r.confidence,
                    storms,
                    observer,
                )?;
                AnalysisAnswer::Sensitivity(Box::new(SensitivityAnswer {
                    sensitivity,
                    response: response(),
                    metamodel_id,
                }))
            }
            AnalysisRequest::Serviceability(r) => {
                let check = metamodel_serviceability(metamodel, study, &r.options(study)?, storms, observer)?;
                AnalysisAnswer::Serviceability(Box::new(ServiceabilityAnswer { check, metamodel_id }))
            }
            AnalysisRequest::Sweep(r) => {
                let sweep = metamodel_sweep(metamodel, study, response(), &r.options(study)?, storms, observer)?;
                AnalysisAnswer::Sweep(Box::new(SweepAnswer { sweep, response: response(), metamodel_id }))
            }
        })
    }
}

impl AnalysisAnswer {
    /// The content type and body: JSON, CSV of an annual curve, SVG of an annual curve or of
    /// fragility curves; JSON where the asked format does not apply.
    pub fn render(&self, rendering: Rendering) -> (&'static str, String) {
        match (self, rendering) {
            (AnalysisAnswer::Hazard(a), Rendering::Csv) => ("text/csv", a.curve.csv(a.response.unit_tag())),
            (AnalysisAnswer::Hazard(a), Rendering::Svg) => (
                "image/svg+xml",
                hazard_svg(&a.curve, &format!("{} x ({})", a.response.per_storm(), a.response.unit())),
            ),
            (AnalysisAnswer::Fragility(a), Rendering::Svg) => {
                ("image/svg+xml", fragility_svg(&a.fragility, &a.response.per_storm()))
            }
            (AnalysisAnswer::Serviceability(a), Rendering::Csv) => ("text/csv", a.check.csv()),
            (AnalysisAnswer::Serviceability(a), Rendering::Svg) => ("image/svg+xml", serviceability_svg(&a.check)),
            (AnalysisAnswer::Sweep(a), Rendering::Csv) => ("text/csv", a.sweep.csv(a.response.unit_tag())),
            (AnalysisAnswer::Sweep(a), Rendering::Svg) => {
                let label =
                    format!("{}-year {} ({})", a.sweep.return_period_years, a.response.per_storm(), a.response.unit());
                ("image/svg+xml", sweep_svg(&a.sweep, &label, None))
            }
            _ => ("application/json", serde_json::to_string(self).expect("an answer serialises")),
        }
    }
}
