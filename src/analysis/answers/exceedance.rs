//! The exceedance curve of a metamodel's peak response, as a user asks for it: storms drawn from
//! the input model (some inputs possibly held at a value), the curve P(peak > x) at the thresholds
//! asked for or at thresholds spread over the sampled peaks, with its Clopper-Pearson band;
//! optionally certified by storms through both models ([`certify_exceedance`]), and optionally
//! with the profile of a quantile of the response's peaks up the height, from the same storms.

use super::profile::{PeakProfile, check_quantile, metamodel_profiles};
use crate::analysis::certification::certify::{
    Certification, CertifyOptions, certify_exceedance, check_reference_storms,
};
use crate::analysis::responses::response::Response;
use crate::analysis::sampling::draws::{check_samples, held_inputs, metamodel_peaks};
use crate::analysis::sampling::exceedance::{
    ExceedanceCurve, automatic_thresholds, check_confidence, check_thresholds,
};
use crate::analysis::sampling::runner::StormRunner;
use crate::error::{Error, Result, require_finite};
use crate::progress::Observer;
use crate::study::Study;
use crate::surrogate::Metamodel;
use crate::uncertainty::InputModel;
use std::collections::BTreeMap;

/// Thresholds spread over the sampled peaks when none are asked for.
const AUTOMATIC_THRESHOLDS: usize = 50;

/// What an exceedance curve is asked.
#[derive(Debug, Clone, PartialEq)]
pub struct ExceedanceOptions {
    /// Storms drawn from the input model (1 to [`crate::analysis::MAX_SAMPLES`]).
    pub samples: usize,
    /// Storm k's inputs and phases depend only on (seed, k).
    pub seed: u64,
    /// Inputs held at a value, by name (each inside its law's support, a wind speed within the
    /// wind model's range); the others are drawn from their laws.
    pub fixed: BTreeMap<String, f64>,
    /// Peak values (in the response's unit) at which to evaluate the curve; 50 spread evenly over
    /// the sampled peaks when absent.
    pub thresholds: Option<Vec<f64>>,
    /// Level of the Clopper-Pearson band (and of the profile's band), in (0, 1).
    pub confidence: f64,
    /// When given, in (0, 1), the answer also holds the profile of this quantile of the response's
    /// peaks at every floor where the response exists, from the same storms as the curve.
    pub profile_quantile: Option<f64>,
    /// Certify the curve with this many further storms through both the reference model and the
    /// metamodel.
    pub certify: Option<CertifyOptions>,
}

impl ExceedanceOptions {
    /// Checks everything that needs no study; errors name the field.
    pub fn check(&self) -> Result<()> {
        check_samples(self.samples)?;
        check_confidence(self.confidence)?;
        if let Some(p) = self.profile_quantile {
            check_quantile(p).map_err(|_| {
                Error::invalid("profile_quantile", format!("must lie strictly between 0 and 1, got {p}"))
            })?;
        }
        if let Some(thresholds) = &self.thresholds {
            check_thresholds(thresholds)?;
        }
        for (name, value) in &self.fixed {
            require_finite(&format!("fixed.{name}"), *value)?;
        }
        if let Some(certify) = &self.certify {
            check_reference_storms(certify.reference_storms, self.samples, "certify.reference_storms")?;
        }
        Ok(())
    }

    /// The input model the storms are drawn from: the study's, with the `fixed` inputs held;
    /// errors name `fixed.<input>`.
    pub fn inputs(&self, study: &Study) -> Result<InputModel> {
        held_inputs(study, &self.fixed)
    }
}

/// An exceedance curve and what came with it.
#[derive(Debug, Clone, PartialEq)]
pub struct Exceedance {
    /// The curve at its thresholds with its band; the certified one when certification was asked.
    pub curve: ExceedanceCurve,
    /// What the reference storms did, when the curve was certified.
    pub certification: Option<Certification>,
    /// The profile of the quantile asked for in `profile_quantile`.
    pub profile: Option<PeakProfile>,
}

/// The exceedance curve of a metamodel's peak `response`, with what `options` asks besides; a
/// certified curve's reference storms run where `runner` puts them.
///
/// With a profile, every floor's peaks come from one pass over the storms and the response's
/// peaks are read off them (a damper group's, the largest of its dampers'): the same storms and
/// the same peaks as without one.
pub fn metamodel_exceedance(
    metamodel: &Metamodel,
    study: &Study,
    response: Response,
    options: &ExceedanceOptions,
    runner: &dyn StormRunner,
    observer: &dyn Observer,
) -> Result<Exceedance> {
    options.check()?;
    response.check(&study.structure)?;
    let inputs = options.inputs(study)?;
    let (samples, seed) = (options.samples, options.seed);
    let (peaks, profile) = match options.profile_quantile {
        None => (metamodel_peaks(metamodel, study, &inputs, samples, seed, response, runner, observer)?, None),
        Some(p) => {
            let all = metamodel_profiles(metamodel, study, &inputs, samples, seed, response.kind(), runner, observer)?;
            let columns: Vec<usize> = response
                .members(&study.structure)?
                .iter()
                .map(|m| all.responses.iter().position(|r| r == m).expect("every floor with the response is profiled"))
                .collect();
            let profile = all.quantile_profile(p, options.confidence)?;
            let largest = |peaks: &Vec<f64>| columns.iter().fold(0.0, |m: f64, &c| m.max(peaks[c]));
            (all.peaks.iter().map(largest).collect(), Some(profile))
        }
    };
    let thresholds = options.thresholds.clone().unwrap_or_else(|| automatic_thresholds(&peaks, AUTOMATIC_THRESHOLDS));
    let (curve, certification) = certify_exceedance(
        metamodel,
        study,
        &inputs,
        &peaks,
        &thresholds,
        options.certify.as_ref(),
        seed,
        response,
        options.confidence,
        runner,
        observer,
    )?;
    Ok(Exceedance { curve, certification, profile })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::study::Order;

    fn options() -> ExceedanceOptions {
        ExceedanceOptions {
            samples: 100,
            seed: 1,
            fixed: BTreeMap::new(),
            thresholds: None,
            confidence: 0.95,
            profile_quantile: None,
            certify: None,
        }
    }

    #[test]
    fn bad_options_name_the_field() {
        assert!(options().check().is_ok());
        let cases = [
            ("samples", ExceedanceOptions { samples: 0, ..options() }),
            ("confidence", ExceedanceOptions { confidence: 1.0, ..options() }),
            ("profile_quantile", ExceedanceOptions { profile_quantile: Some(1.5), ..options() }),
            ("thresholds", ExceedanceOptions { thresholds: Some(vec![0.1, -0.2]), ..options() }),
            ("thresholds", ExceedanceOptions { thresholds: Some(vec![]), ..options() }),
            ("fixed.wind_speed", ExceedanceOptions { fixed: [("wind_speed".into(), f64::NAN)].into(), ..options() }),
            (
                "certify.reference_storms",
                ExceedanceOptions {
                    certify: Some(CertifyOptions { reference_storms: 101, order: Order::Reduced }),
                    ..options()
                },
            ),
        ];
        for (field, options) in cases {
            let error = options.check().unwrap_err();
            assert!(error.to_string().starts_with(&format!("{field}:")), "{field}: {error}");
        }
    }

    /// A held input is checked against the study: a name it does not have, a value outside its
    /// law's support, a wind speed the wind model refuses; each error names `fixed.<input>`.
    #[test]
    fn held_inputs_are_checked_against_the_study() {
        let study = Study::preset("frame40-kn").unwrap();
        let held = |name: &str, value: f64| ExceedanceOptions { fixed: [(name.into(), value)].into(), ..options() };
        let inputs = held("wind_speed", 32.0).inputs(&study).unwrap();
        assert_eq!(*inputs.marginal("wind_speed").unwrap(), crate::uncertainty::Marginal::Constant { value: 32.0 });
        for (name, value) in [("colour", 3.0), ("damping_ratio", -1.0), ("wind_speed", -3.0), ("wind_speed", 200.0)] {
            let error = held(name, value).inputs(&study).unwrap_err();
            assert!(error.to_string().starts_with(&format!("fixed.{name}:")), "{name} = {value}: {error}");
        }
    }
}
