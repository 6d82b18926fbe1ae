//! Exceedance requests: what a client asks, how it is checked (the server's bounds here, the rest by
//! the analysis's [`ExceedanceOptions`]), the options it converts into for [`metamodel_exceedance`]
//! (shared by the synchronous route and the worker that runs large requests as operations), and
//! the answer in each of its renderings.

use super::ServeArgs;
use super::rendering::Rendering;
use super::schema::{fixed_inputs_schema, thresholds_schema};
use crate::analysis::{
    Certification, CertifyOptions, Exceedance, ExceedanceCurve, ExceedanceOptions, PeakProfile, Response, ResponseKind,
    ResponseName, StormRunner, exceedance_csv, exceedance_figure, metamodel_exceedance,
};
use crate::error::{Error, Result};
use crate::progress::Observer;
use crate::structure::MAX_FLOORS;
use crate::study::Study;
use crate::surrogate::Metamodel;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use utoipa::ToSchema;

/// `POST /v1/metamodels/{id}/exceedance`: every field optional.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(default, deny_unknown_fields)]
pub struct ExceedanceRequest {
    /// Monte Carlo samples (storms) drawn from the input model; at most the server's
    /// `--max-samples` (20 000 by default).
    #[schema(minimum = 1, maximum = 1000000, default = 1000)]
    #[serde(deserialize_with = "crate::count::count")]
    pub samples: usize,
    #[schema(default = 1)]
    #[serde(deserialize_with = "crate::count::seed")]
    pub seed: u64,
    /// Floor (1-based, at most the structure's floors); the roof when absent.
    #[schema(minimum = 1, maximum = 200)]
    #[serde(default, deserialize_with = "crate::count::optional_count")]
    pub floor: Option<usize>,
    /// Damper group (1-based) instead of a floor, for `damper_force` and `damper_stroke`: the
    /// largest among the group's dampers.
    #[schema(minimum = 1, maximum = 10)]
    #[serde(default, deserialize_with = "crate::count::optional_count")]
    pub group: Option<usize>,
    pub response: ResponseKind,
    /// Peak values (in the response's unit: m, m/s² or N; 0 to 10⁹) at which to evaluate the curve; 50 evenly spread over the sampled
    /// peaks when absent.
    #[schema(schema_with = thresholds_schema)]
    pub thresholds: Option<Vec<f64>>,
    /// Inputs held fixed, by name (e.g. `{"wind_speed": 40}`), each inside its marginal's support.
    #[schema(schema_with = fixed_inputs_schema)]
    pub fixed: BTreeMap<String, f64>,
    /// Level of the Clopper-Pearson band (and of the profile's band), in (0, 1).
    #[schema(exclusive_minimum = 0, exclusive_maximum = 1, default = 0.95)]
    pub confidence: f64,
    /// When given, in (0, 1), the answer also holds `profile`: this quantile of the response's
    /// peaks at every floor where the response exists (e.g. 0.9: the 90 % peak drift of each
    /// storey), with a distribution-free band at `confidence`, from the same storms as the curve.
    #[schema(exclusive_minimum = 0, exclusive_maximum = 1)]
    pub profile_quantile: Option<f64>,
    /// Certify the curve: this many further storms run through both the reference model and the
    /// metamodel correct it, so that its probabilities are unbiased for the reference model and
    /// their band holds the metamodel's own error. A certified request always runs as an operation.
    pub certify: Option<CertifyOptions>,
}

impl Default for ExceedanceRequest {
    fn default() -> Self {
        ExceedanceRequest {
            samples: 1000,
            seed: 1,
            floor: None,
            group: None,
            response: ResponseKind::Displacement,
            thresholds: None,
            fixed: BTreeMap::new(),
            confidence: 0.95,
            profile_quantile: None,
            certify: None,
        }
    }
}

impl ExceedanceRequest {
    /// The analysis's options.
    pub fn options(&self) -> ExceedanceOptions {
        ExceedanceOptions {
            samples: self.samples,
            seed: self.seed,
            fixed: self.fixed.clone(),
            thresholds: self.thresholds.clone(),
            confidence: self.confidence,
            profile_quantile: self.profile_quantile,
            certify: self.certify,
        }
    }

    /// The checks that need no metamodel: the server's bounds, the floor's, and the options';
    /// errors name the field.
    pub fn check(&self, config: &ServeArgs) -> Result<()> {
        if self.samples == 0 || self.samples > config.max_samples {
            return Err(Error::invalid("samples", format!("must be between 1 and {}", config.max_samples)));
        }
        self.options().check()?;
        if let Some(floor) = self.floor
            && !(1..=MAX_FLOORS).contains(&floor)
        {
            return Err(Error::invalid("floor", format!("must be between 1 and {MAX_FLOORS}, got {floor}")));
        }
        if let Some(certify) = &self.certify {
            check_reference_storm_budget(certify.reference_storms, config)?;
        }
        Ok(())
    }

    /// The checks that need the study but no sampling (the response's floor or group, the held
    /// inputs' names and supports), so that a request queued as an operation cannot fail on them.
    pub fn check_against(&self, study: &Study) -> Result<()> {
        self.response.located(self.floor, self.group, &study.structure)?;
        self.options().inputs(study).map(drop)
    }

    /// Samples the metamodel and builds the curve (blocking; parallel over samples); its storms,
    /// and a certified curve's reference storms, run where `storms` puts them.
    pub fn answer(
        &self,
        metamodel: &Metamodel,
        study: &Study,
        metamodel_id: &str,
        storms: &dyn StormRunner,
        observer: &dyn Observer,
    ) -> Result<ExceedanceAnswer> {
        let response = self.response.located(self.floor, self.group, &study.structure)?;
        let Exceedance { curve, certification, profile } =
            metamodel_exceedance(metamodel, study, response, &self.options(), storms, observer)?;
        let metamodel_id = metamodel_id.to_string();
        Ok(ExceedanceAnswer { curve, response, profile, certification, metamodel_id })
    }
}

/// Errs, naming the field, when a request runs more reference storms in all than the server's
/// `--max-reference-storms`.
pub fn check_reference_storm_budget(storms: usize, config: &ServeArgs) -> Result<()> {
    if storms > config.max_reference_storms {
        return Err(Error::invalid(
            "certify.reference_storms",
            format!(
                "the request runs {storms} reference storms; this server allows at most {}",
                config.max_reference_storms
            ),
        ));
    }
    Ok(())
}

/// An exceedance curve of a metamodel's sampled peaks, with its band.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct ExceedanceAnswer {
    #[serde(flatten)]
    pub curve: ExceedanceCurve,
    #[schema(value_type = ResponseName)]
    pub response: Response,
    /// The quantile profile, when the request asked for one.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub profile: Option<PeakProfile>,
    /// What the reference storms did, when the request asked for a certified curve (whose
    /// `probabilities`, `lower` and `upper` are then the certified ones).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub certification: Option<Certification>,
    pub metamodel_id: String,
}

impl ExceedanceAnswer {
    /// The content type and the body (blocking: an SVG of a long curve takes milliseconds).
    pub fn render(&self, rendering: Rendering) -> (&'static str, String) {
        let curve = &self.curve;
        match rendering {
            Rendering::Json => ("application/json", serde_json::to_string(self).expect("a curve serialises")),
            Rendering::Csv => ("text/csv", exceedance_csv(curve, self.certification.as_ref(), &self.response)),
            Rendering::Svg => {
                let label = format!("{} x ({})", self.response.per_storm(), self.response.unit());
                ("image/svg+xml", exceedance_figure(curve, self.certification.as_ref(), &label))
            }
        }
    }
}

/// A large exceedance request as queued.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ExceedanceJob {
    pub metamodel_id: String,
    pub request: ExceedanceRequest,
}
