//! Sampling a metamodel's peaks in parallel, for every analysis: storms drawn from the input
//! model (or given rows of inputs and their storm streams), run by batches of [`PEAK_BATCH`] through
//! the free run, reduced to the peaks of one or several responses; and the input model with some
//! inputs held that such storms are drawn from.

use super::reference_storms::{PairedPeak, PairedRuns};
use super::runner::StormRunner;
pub use super::storms::{Draws, OnDivergence};
use crate::analysis::responses::motion_peaks::motion_sink;
use crate::analysis::responses::response::Response;
use crate::error::{Error, Result};
use crate::progress::{Observer, Progress};
use crate::study::{Study, WIND_SPEED};
use crate::surrogate::{BatchInput, BatchWorkspace, Metamodel, ModalScales, PEAK_BATCH, Reduction};
use crate::uncertainty::{InputModel, monte_carlo, rng_from_seed};
use crate::wind::{self, ForceSource, WindLoads};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Most samples one sampling request may ask for.
pub const MAX_SAMPLES: usize = 1_000_000;

/// Peaks of `response` over `samples` storms of the metamodel, inputs drawn from `inputs` (the
/// metamodel's own, possibly with some held fixed). Sample k's inputs and storm depend only on
/// (seed, k). A diverging free run fails the request rather than being dropped.
#[allow(clippy::too_many_arguments)]
pub fn metamodel_peaks(
    metamodel: &Metamodel,
    study: &Study,
    inputs: &InputModel,
    samples: usize,
    seed: u64,
    response: Response,
    runner: &dyn StormRunner,
    observer: &dyn Observer,
) -> Result<Vec<f64>> {
    check_samples(samples)?;
    let rows = monte_carlo(inputs, samples, &mut rng_from_seed(seed));
    let storms: Vec<usize> = (0..samples).collect();
    let draws = Draws { study, rows: &rows, storms: &storms, seed, on_divergence: OnDivergence::Fail };
    peaks_at(metamodel, &draws, response, runner, observer)
}

/// Errs unless 1 ≤ samples ≤ [`MAX_SAMPLES`].
pub fn check_samples(samples: usize) -> Result<()> {
    if samples == 0 || samples > MAX_SAMPLES {
        return Err(Error::invalid("samples", format!("must be between 1 and {MAX_SAMPLES}, got {samples}")));
    }
    Ok(())
}

/// The study's input model with the `fixed` inputs held at their values, the others drawn from
/// their laws; errors name `fixed.<input>`: an input the study does not have, a value outside its
/// law's support, a wind speed the wind model refuses.
pub fn held_inputs(study: &Study, fixed: &BTreeMap<String, f64>) -> Result<InputModel> {
    let mut inputs = study.inputs.clone();
    for (name, value) in fixed {
        let speed = if name == WIND_SPEED { WindLoads::check_speed(*value) } else { Ok(()) };
        inputs = speed.and_then(|()| inputs.with_fixed(name, *value)).map_err(|error| match error {
            Error::Invalid { reason, .. } => Error::invalid(format!("fixed.{name}"), reason),
            other => other,
        })?;
    }
    Ok(inputs)
}

/// At most this many diverged storms are named in an answer.
pub const NAMED_DIVERGED_STORMS: usize = 5;

/// A storm whose metamodel free run diverged, named with its inputs so that a user can tell an
/// extrapolation far outside the calibrated inputs from a defect.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct DivergedStorm {
    /// The storm stream its wind was drawn from (with the analysis's seed, it reruns the storm).
    pub storm: usize,
    /// Its physical inputs, by name.
    pub inputs: BTreeMap<String, f64>,
}

impl std::fmt::Display for DivergedStorm {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let inputs: Vec<String> = self.inputs.iter().map(|(name, value)| format!("{name} = {value:.4e}")).collect();
        write!(f, "storm {} ({})", self.storm, inputs.join(", "))
    }
}

/// Named diverged storms on one line, for a report.
pub fn describe_diverged(storms: &[DivergedStorm]) -> String {
    storms.iter().map(ToString::to_string).collect::<Vec<_>>().join("; ")
}

/// Appends to `named`, up to [`NAMED_DIVERGED_STORMS`], the rows whose peak is infinite, with
/// their storm streams.
pub fn name_diverged(
    inputs: &InputModel,
    rows: &[Vec<f64>],
    storms: impl IntoIterator<Item = usize>,
    peaks: &[f64],
    named: &mut Vec<DivergedStorm>,
) {
    let diverged = rows.iter().zip(storms).zip(peaks).filter(|(_, peak)| peak.is_infinite());
    let room = NAMED_DIVERGED_STORMS.saturating_sub(named.len());
    named.extend(diverged.take(room).map(|((row, storm), _)| DivergedStorm {
        storm,
        inputs: inputs.names().map(str::to_string).zip(row.iter().copied()).collect(),
    }));
}

/// Peaks of `response` for every row of `draws`, run where `runner` puts them, reporting progress
/// and stopping when `observer` asks.
pub fn peaks_at(
    metamodel: &Metamodel,
    draws: &Draws,
    response: Response,
    runner: &dyn StormRunner,
    observer: &dyn Observer,
) -> Result<Vec<f64>> {
    Ok(peak_sets_at(metamodel, draws, &[response], runner, observer)?.into_iter().map(|peaks| peaks[0]).collect())
}

/// Peaks of each of `responses` for every row of `draws` (`[row][response]`). A damper group's
/// envelope is the largest peak of its dampers, all run together.
pub fn peak_sets_at(
    metamodel: &Metamodel,
    draws: &Draws,
    responses: &[Response],
    runner: &dyn StormRunner,
    observer: &dyn Observer,
) -> Result<Vec<Vec<f64>>> {
    let members: Vec<Vec<Response>> =
        responses.iter().map(|r| r.members(&draws.study.structure)).collect::<Result<_>>()?;
    let sets = runner.floor_peak_sets(metamodel, draws, &members.concat(), observer)?;
    let largest_of_members = |row: Vec<f64>| -> Vec<f64> {
        let mut rest = &row[..];
        members
            .iter()
            .map(|m| {
                let (these, after) = rest.split_at(m.len());
                rest = after;
                these.iter().fold(0.0, |a: f64, &b| a.max(b))
            })
            .collect()
    };
    Ok(sets.into_iter().map(largest_of_members).collect())
}

/// Peaks of each of the floor responses `responses` for every row of `draws`, on this machine's
/// cores by batches of [`PEAK_BATCH`], reporting progress and stopping when `observer` asks; a failure
/// names the sample by its number, the rows' counted from `first`. One displacement, drift or
/// stroke is a combination formed inside the free run; anything else comes from the batch's
/// blocks (a motion sink of `analysis::responses`), every response from the same runs.
pub fn floor_peak_sets_at(
    metamodel: &Metamodel,
    draws: &Draws,
    responses: &[Response],
    first: usize,
    observer: &dyn Observer,
) -> Result<Vec<Vec<f64>>> {
    let Draws { study, rows, storms, seed, on_divergence } = *draws;
    assert_eq!(rows.len(), storms.len(), "one storm per row");
    let path = metamodel.calibration.options.wind;
    let weights = match responses {
        [response] => response.modal_weights(&metamodel.modes.shapes, &study.structure)?,
        _ => None,
    };
    let sink_for = |inputs: &[&[f64]], scales: &ModalScales| {
        motion_sink(study, &metamodel.modes.shapes, responses, inputs, scales)
    };
    let reduction = match &weights {
        Some(weights) => Reduction::Combination(weights),
        None => Reduction::Motion(&sink_for),
    };
    let (done, total) = (AtomicUsize::new(0), rows.len());
    let peaks: Vec<Vec<Vec<f64>>> = rows
        .par_chunks(PEAK_BATCH)
        .zip(storms.par_chunks(PEAK_BATCH))
        .enumerate()
        .map_init(
            || (wind::TransformWorkspace::default(), BatchWorkspace::default()),
            |(wind_workspace, batch_workspace), (chunk, (xs, keys))| {
                if observer.cancelled() {
                    return Err(Error::Cancelled);
                }
                let storms = xs
                    .iter()
                    .zip(keys)
                    .map(|(x, &k)| Ok(study.sample_storm(x, path, seed, k, wind_workspace)?.1))
                    .collect::<Result<Vec<_>>>()?;
                let batch: Vec<BatchInput> = xs
                    .iter()
                    .zip(&storms)
                    .enumerate()
                    .map(|(i, (x, f))| (first + chunk * PEAK_BATCH + i, &x[..], f as &dyn ForceSource))
                    .collect();
                let peaks = match on_divergence {
                    OnDivergence::Fail => metamodel.peaks(study, &batch, &reduction, batch_workspace)?,
                    OnDivergence::Exceed => metamodel
                        .peaks_or_divergence(study, &batch, &reduction, batch_workspace)?
                        .into_iter()
                        .map(|peaks| peaks.unwrap_or_else(|| vec![f64::INFINITY; responses.len()]))
                        .collect(),
                };
                let done = done.fetch_add(xs.len(), Ordering::Relaxed) + xs.len();
                observer.progress(Progress::Samples { done, total });
                Ok(peaks)
            },
        )
        .collect::<Result<_>>()?;
    Ok(peaks.concat())
}

/// Storms on this machine's cores, in parallel.
pub struct OnThisMachine;

impl StormRunner for OnThisMachine {
    fn pairs(
        &self,
        runs: &PairedRuns,
        rows: &[Vec<f64>],
        storms: &[usize],
        observer: &dyn Observer,
    ) -> Result<Vec<PairedPeak>> {
        runs.run(rows, storms, observer)
    }

    fn floor_peak_sets(
        &self,
        metamodel: &Metamodel,
        draws: &Draws,
        responses: &[Response],
        observer: &dyn Observer,
    ) -> Result<Vec<Vec<f64>>> {
        floor_peak_sets_at(metamodel, draws, responses, 0, observer)
    }
}
