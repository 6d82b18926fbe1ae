//! Storms run through both the reference model and the metamodel, for certified answers: the same
//! inputs and the same wind through each, the peaks of one response from each.

use super::storms::{Draws, OnDivergence};
use crate::analysis::responses::reference::reference_peak;
use crate::analysis::responses::response::Response;
use crate::dynamics::ModalMotion;
use crate::error::{Error, Result};
use crate::progress::{Observer, Progress, check};
use crate::simd::LANES;
use crate::study::{Order, StormRun, Study, WindPath};
use crate::surrogate::Metamodel;
use crate::uncertainty::{InputModel, monte_carlo, rng_from_seed, stream_seed};
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};

/// One storm run through both models: the reference's peak and the metamodel's (infinite when
/// its free run diverged: it exceeds every threshold).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairedPeak {
    /// The reference model's peak.
    pub reference: f64,
    /// The metamodel's peak in the same storm; infinite when its free run diverged.
    pub metamodel: f64,
}

/// The seed of a request's reference storms: a stream apart from its metamodel storms (which are
/// drawn with the request's own seed), so that the two sets are independent.
pub fn reference_storm_seed(seed: u64) -> u64 {
    stream_seed(seed, u64::MAX)
}

/// `storms` draws of `inputs` (storm k's wind from stream k of `seed`) through the reference model
/// of `order` and the metamodel, and the peak of `response` in each.
#[allow(clippy::too_many_arguments)]
pub fn paired_peaks(
    metamodel: &Metamodel,
    study: &Study,
    inputs: &InputModel,
    storms: usize,
    seed: u64,
    response: Response,
    order: Order,
    observer: &dyn Observer,
) -> Result<Vec<PairedPeak>> {
    let (rows, streams) = reference_rows(inputs, storms, seed);
    PairedRuns { metamodel, study, seed, response, order }.run(&rows, &streams, observer)
}

/// `storms` draws of `inputs` from `seed`, storm k's wind from stream k.
pub fn reference_rows(inputs: &InputModel, storms: usize, seed: u64) -> (Vec<Vec<f64>>, Vec<usize>) {
    (monte_carlo(inputs, storms, &mut rng_from_seed(seed)), (0..storms).collect())
}

/// What fixes a certified answer's storms through both models, apart from their rows: the models,
/// the seed of their winds, the response read and the reference's order.
#[derive(Clone, Copy)]
pub struct PairedRuns<'a> {
    /// The metamodel run beside the reference.
    pub metamodel: &'a Metamodel,
    /// The study whose reference model runs the storms.
    pub study: &'a Study,
    /// The reference storms' seed ([`reference_storm_seed`] of the request's).
    pub seed: u64,
    /// The response whose peaks are compared.
    pub response: Response,
    /// The reference model: the retained modes or every floor.
    pub order: Order,
}

impl PairedRuns<'_> {
    /// `rows` (row i's wind from stream `storms[i]` of the seed) through both models, here.
    pub fn run(&self, rows: &[Vec<f64>], storms: &[usize], observer: &dyn Observer) -> Result<Vec<PairedPeak>> {
        let draws = Draws { study: self.study, rows, storms, seed: self.seed, on_divergence: OnDivergence::Exceed };
        paired_peaks_at(self.metamodel, &draws, self.response, self.order, observer)
    }
}

/// The rows of `draws` (row i's wind from stream `draws.storms[i]` of `draws.seed`) through the
/// reference model of `order` and the metamodel, and the peak of `response` in each. A full-order
/// storm is the floor field, and the metamodel sees its projection on the modes; a reduced-order
/// storm is drawn as the metamodel's calibration drew its own. A metamodel run that diverges has
/// an infinite peak, whatever `draws.on_divergence` says.
pub fn paired_peaks_at(
    metamodel: &Metamodel,
    draws: &Draws,
    response: Response,
    order: Order,
    observer: &dyn Observer,
) -> Result<Vec<PairedPeak>> {
    let Draws { study, rows, storms, seed, .. } = *draws;
    response.check(&study.structure)?;
    let path = match order {
        Order::Reduced => metamodel.calibration.options.wind,
        Order::Full => WindPath::Field,
    };
    let (done, total) = (AtomicUsize::new(0), rows.len());
    let rng = |k: usize| rng_from_seed(stream_seed(seed, k as u64));
    let pair = |x: &[f64], run: &StormRun| -> Result<PairedPeak> {
        let pair = PairedPeak {
            reference: reference_peak(study, x, run, response)?,
            metamodel: metamodel_peak(metamodel, study, x, run, response)?,
        };
        observer.progress(Progress::ReferenceStorms { done: done.fetch_add(1, Ordering::Relaxed) + 1, total });
        Ok(pair)
    };
    if order == Order::Full {
        return rows
            .par_iter()
            .zip(storms)
            .map(|(x, &k)| {
                check(observer)?;
                pair(x, &study.reference_run(x, order, path, &mut rng(k))?)
            })
            .collect();
    }
    // Reduced-order storms eight at a time, in vector lanes.
    let chunks: Vec<Vec<PairedPeak>> = rows
        .par_chunks(LANES)
        .zip(storms.par_chunks(LANES))
        .map(|(xs, ks)| {
            check(observer)?;
            let xs: Vec<&[f64]> = xs.iter().map(Vec::as_slice).collect();
            let mut rngs: Vec<_> = ks.iter().map(|&k| rng(k)).collect();
            let runs = study.reduced_reference_runs(&xs, path, &mut rngs, observer)?;
            xs.iter().zip(&runs).map(|(x, run)| pair(x, run)).collect()
        })
        .collect::<Result<_>>()?;
    Ok(chunks.into_iter().flatten().collect())
}

/// The metamodel's peak of `response` in the storm of the reference run `run`: its free run on the
/// run's modal forces, read through the same equations as the reduced reference's.
fn metamodel_peak(metamodel: &Metamodel, study: &Study, x: &[f64], run: &StormRun, response: Response) -> Result<f64> {
    let Some(forces) = &run.modal_forces else {
        return Err(Error::Internal("a reference run without its modal forces".into()));
    };
    let displacements = match metamodel.predict(study, x, forces) {
        Ok(displacements) => displacements,
        Err(Error::Numerical(_)) => return Ok(f64::INFINITY),
        Err(other) => return Err(other),
    };
    let predicted = StormRun {
        roof: Vec::new(),
        modal_forces: run.modal_forces.clone(),
        modal_motion: Some(ModalMotion::from_displacements(displacements, study.storm.time_step)),
        floor_motion: None,
        wind_seconds: 0.0,
        integration_seconds: 0.0,
    };
    reference_peak(study, x, &predicted, response)
}
