//! Storms run through both the reference model and the metamodel, for certified answers: the same
//! inputs and the same wind through each, the peaks of one response from each.

use super::{Draws, OnDivergence, Response, reference_peak};
use crate::dynamics::ModalMotion;
use crate::error::{Error, Result};
use crate::progress::{Observer, Progress, check};
use crate::study::{Order, StormRun, Study, WindPath};
use crate::surrogate::Metamodel;
use crate::uncertainty::{InputModel, monte_carlo, rng_from_seed, stream_seed};
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};

/// One storm run through both models: the reference's peak and the metamodel's (infinite when
/// its free run diverged: it exceeds every threshold).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairedPeak {
    pub reference: f64,
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
    let rows = monte_carlo(inputs, storms, &mut rng_from_seed(seed));
    let streams: Vec<usize> = (0..storms).collect();
    let draws = Draws { study, rows: &rows, storms: &streams, seed, on_divergence: OnDivergence::Exceed };
    paired_peaks_at(metamodel, &draws, response, order, observer)
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
    rows.par_iter()
        .zip(storms)
        .map(|(x, &k)| {
            check(observer)?;
            let run = study.reference_run(x, order, path, &mut rng_from_seed(stream_seed(seed, k as u64)))?;
            let pair = PairedPeak {
                reference: reference_peak(study, x, &run, response)?,
                metamodel: metamodel_peak(metamodel, study, x, &run, response)?,
            };
            observer.progress(Progress::Samples { done: done.fetch_add(1, Ordering::Relaxed) + 1, total });
            Ok(pair)
        })
        .collect()
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
