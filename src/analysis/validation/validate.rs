//! Validation of a metamodel against the reference model on fresh samples (the paper's section
//! 4.3.2): the same inputs and the same storm through both, then errors, peak correlation (Fig. 6)
//! and the exceedance curves of the peaks (Fig. 7).

use super::validated_responses::{CheckedPeaks, ResponseValidation, compare};
use crate::analysis::responses::peaks::{pearson, quantile};
use crate::analysis::responses::response::Response;
use crate::analysis::responses::response::ResponseView;
use crate::analysis::sampling::exceedance::{
    ExceedanceCurve, automatic_thresholds, exceedance_curve, max_exceedance_gap,
};
use crate::dynamics::{ModalMotion, ModalResponse, SampleModel};
use crate::error::{Error, Result};
use crate::progress::{Observer, Progress, check};
use crate::simd::LANES;
use crate::study::{PhysicalParameters, Study};
use crate::surrogate::Metamodel;
use crate::surrogate::narx::relative_error;
use crate::uncertainty::{InputModel, Marginal, monte_carlo, rng_from_seed};
use crate::wind::{ModalForces, TransformWorkspace};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

/// What a validation measured.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct ValidationReport {
    /// Storms run through both models.
    pub samples: usize,
    /// The seed of their inputs and winds.
    pub seed: u64,
    /// Inputs held at a value for this validation (e.g. the wind speed at an end of the calibrated
    /// range); the others were drawn from the input model.
    #[serde(default)]
    pub fixed: BTreeMap<String, f64>,
    /// Pearson correlation of the peak roof displacements, reference against metamodel.
    pub peak_correlation: f64,
    /// Full PC-NARX on the validation samples: mean over samples of Σ(u − û)²/Σ(u − ū)² of the roof.
    pub mean_relative_error: f64,
    /// The same per modal coordinate.
    pub mode_mean_relative_errors: Vec<f64>,
    /// Median over samples of |peak_meta − peak_ref| / peak_ref.
    pub median_peak_relative_error: f64,
    /// 95th percentile of the same.
    pub p95_peak_relative_error: f64,
    /// From the calibration: NARX-only mean relative error, mean over modes.
    pub calibration_mean_relative_error: f64,
    /// Per checked response (roof displacement, largest drift, roof acceleration, largest damper
    /// force): correlation, median and 95th-percentile relative error, exceedance-curve gap.
    #[serde(default)]
    pub responses: Vec<ResponseValidation>,
    /// Largest vertical gap between the two empirical exceedance curves of the roof peak.
    pub max_exceedance_gap: f64,
    /// The reference's exceedance curve of the roof peak, at thresholds spread over both models' peaks.
    pub reference_exceedance: ExceedanceCurve,
    /// The metamodel's exceedance curve of the roof peak, at the reference's thresholds.
    pub metamodel_exceedance: ExceedanceCurve,
    /// The reference's peak roof displacement in each storm (m).
    pub reference_peak: Vec<f64>,
    /// The metamodel's peak roof displacement in the same storms (m).
    pub metamodel_peak: Vec<f64>,
    /// Median wall time per sample (s) of the reference integration and of the metamodel free run.
    pub reference_seconds_per_sample: f64,
    /// Median wall time per sample (s) of the metamodel's free run.
    pub metamodel_seconds_per_sample: f64,
}

struct SampleResult {
    reference: CheckedPeaks,
    metamodel: CheckedPeaks,
    roof_error: f64,
    mode_errors: Vec<f64>,
    reference_seconds: f64,
    metamodel_seconds: f64,
}

/// What a validation sample is compared with: the metamodel, on the study's storms.
struct Comparison<'a> {
    metamodel: &'a Metamodel,
    study: &'a Study,
}

impl Comparison<'_> {
    /// Sample `k` (inputs `x`, parameters and modal forces `storm`) through the metamodel, against
    /// its `reference` response, which took `reference_seconds`.
    fn compare(
        &self,
        k: usize,
        x: &[f64],
        (p, forces): &(PhysicalParameters, ModalForces),
        reference: ModalResponse,
        reference_seconds: f64,
    ) -> Result<SampleResult> {
        let (study, dt) = (self.study, self.study.storm.time_step);
        let (modes, dampers) = (study.sample_modes(p), study.dampers(p)?);
        let started = Instant::now();
        let predicted = self
            .metamodel
            .predict(study, x, forces)
            .map_err(|e| Error::Numerical(format!("validation sample {k}: {e}")))?;
        let metamodel_seconds = started.elapsed().as_secs_f64();
        let mode_errors: Vec<f64> =
            reference.displacements.iter().zip(&predicted).map(|(y, y_hat)| relative_error(y, y_hat)).collect();
        let model = SampleModel::new(&modes, p.damping_ratio, &dampers);
        let reference = reference.motion();
        let predicted = ModalMotion::from_displacements(predicted, dt);
        let (shapes, structure) = (&self.metamodel.modes.shapes, &study.structure);
        let reference_view = ResponseView::new(shapes, structure, &reference, &model, forces, dt);
        let metamodel_view = ResponseView::new(shapes, structure, &predicted, &model, forces, dt);
        let roof = Response::Displacement { floor: structure.floors() };
        let (u, u_hat) = (roof.history(&reference_view)?, roof.history(&metamodel_view)?);
        Ok(SampleResult {
            reference: CheckedPeaks::of(&reference_view)?,
            metamodel: CheckedPeaks::of(&metamodel_view)?,
            roof_error: relative_error(&u, &u_hat),
            mode_errors,
            reference_seconds,
            metamodel_seconds,
        })
    }
}

/// Runs `samples` fresh Monte Carlo samples of `inputs` (the study's input model, possibly with
/// some inputs held) through the reference and the metamodel.
pub fn validate(
    metamodel: &Metamodel,
    study: &Study,
    inputs: &InputModel,
    samples: usize,
    seed: u64,
    observer: &dyn Observer,
) -> Result<ValidationReport> {
    if !(2..=100_000).contains(&samples) {
        return Err(Error::invalid("samples", format!("must be between 2 and 100000, got {samples}")));
    }
    if inputs.len() != study.inputs.len() {
        return Err(Error::invalid("inputs", "the sampled inputs must be the study's, some possibly held"));
    }
    let fixed: BTreeMap<String, f64> = inputs
        .inputs
        .iter()
        .zip(&study.inputs.inputs)
        .filter_map(|(sampled, study)| match (sampled.marginal, study.marginal) {
            (_, Marginal::Constant { .. }) => None,
            (Marginal::Constant { value }, _) => Some((sampled.name.clone(), value)),
            _ => None,
        })
        .collect();
    let xs = monte_carlo(inputs, samples, &mut rng_from_seed(seed));
    let path = metamodel.calibration.options.wind;
    let against = Comparison { metamodel, study };
    let done = AtomicUsize::new(0);
    let results: Vec<Vec<SampleResult>> = xs
        .par_chunks(LANES)
        .enumerate()
        .map_init(TransformWorkspace::default, |workspace, (chunk, xs)| {
            check(observer)?;
            // The chunk's storms through the reduced reference together, in vector lanes.
            let first = chunk * LANES;
            let storms = xs
                .iter()
                .enumerate()
                .map(|(i, x)| {
                    let (p, coarse) = study.sample_storm(x, path, seed, first + i, workspace)?;
                    Ok((p, coarse.on_grid(&study.storm)))
                })
                .collect::<Result<Vec<_>>>()?;
            let started = Instant::now();
            let references = study.integrate_reduced_batch(&storms, observer)?;
            let reference_seconds = started.elapsed().as_secs_f64() / xs.len() as f64;
            let compared = xs.iter().zip(storms.iter().zip(references)).enumerate();
            compared
                .map(|(i, (x, (storm, reference)))| {
                    let result = against.compare(first + i, x, storm, reference, reference_seconds)?;
                    observer
                        .progress(Progress::Samples { done: done.fetch_add(1, Ordering::Relaxed) + 1, total: samples });
                    Ok(result)
                })
                .collect()
        })
        .collect::<Result<_>>()?;
    let results: Vec<SampleResult> = results.into_iter().flatten().collect();
    let n = results.len() as f64;
    let reference: Vec<CheckedPeaks> = results.iter().map(|r| r.reference.clone()).collect();
    let metamodel_peaks: Vec<CheckedPeaks> = results.iter().map(|r| r.metamodel.clone()).collect();
    let responses = compare(&reference, &metamodel_peaks);
    let reference_peak: Vec<f64> = reference.iter().map(CheckedPeaks::roof_displacement).collect();
    let metamodel_peak: Vec<f64> = metamodel_peaks.iter().map(CheckedPeaks::roof_displacement).collect();
    let mut peak_errors: Vec<f64> =
        reference_peak.iter().zip(&metamodel_peak).map(|(r, m)| (m - r).abs() / r).collect();
    peak_errors.sort_by(f64::total_cmp);
    let modes = metamodel.models.len();
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        quantile(&v, 0.5)
    };
    let all: Vec<f64> = reference_peak.iter().chain(&metamodel_peak).copied().collect();
    let thresholds = automatic_thresholds(&all, 60);
    Ok(ValidationReport {
        samples,
        seed,
        fixed,
        peak_correlation: pearson(&reference_peak, &metamodel_peak),
        mean_relative_error: results.iter().map(|r| r.roof_error).sum::<f64>() / n,
        mode_mean_relative_errors: (0..modes)
            .map(|m| results.iter().map(|r| r.mode_errors[m]).sum::<f64>() / n)
            .collect(),
        median_peak_relative_error: quantile(&peak_errors, 0.5),
        p95_peak_relative_error: quantile(&peak_errors, 0.95),
        calibration_mean_relative_error: metamodel.calibration.narx_mean_relative_error,
        responses,
        max_exceedance_gap: max_exceedance_gap(&reference_peak, &metamodel_peak),
        reference_exceedance: exceedance_curve(&reference_peak, &thresholds, 0.95),
        metamodel_exceedance: exceedance_curve(&metamodel_peak, &thresholds, 0.95),
        reference_seconds_per_sample: median(results.iter().map(|r| r.reference_seconds).collect()),
        metamodel_seconds_per_sample: median(results.iter().map(|r| r.metamodel_seconds).collect()),
        reference_peak,
        metamodel_peak,
    })
}
