//! Calibration (section 3.3, steps 1-5) on one machine: a Latin-hypercube design, one storm per
//! experiment through the reduced-order reference, then per mode the NARX structure, the
//! coefficients of every experiment refined on the simulation error, and their sparse polynomial
//! chaos expansions. The phases themselves are in `phases`, so that replicas can share them.

use super::assembly::{assemble, fit_expansions};
use super::metamodel::{Metamodel, StageSeconds};
use super::options::CalibrationOptions;
use super::phases::{fit_experiments, plan};
use crate::error::Result;
use crate::progress::Observer;
use crate::study::Study;
use std::time::Instant;

/// Calibrates a PC-NARX metamodel of `study` (with its storm grid and input model) on this
/// machine: the three phases of [`super::phases`], every experiment fitted here.
pub fn calibrate(study: &Study, options: &CalibrationOptions, observer: &dyn Observer) -> Result<Metamodel> {
    let planned = plan(study, options, observer)?;
    let stage = Instant::now();
    let mut fits = planned.fit_selection(options, observer)?;
    let remaining = planned.plan.remaining();
    fits.extend(fit_experiments(study, options, &planned.plan, &remaining, planned.plan.selection.len(), observer)?);
    let seconds = StageSeconds { coefficients: stage.elapsed().as_secs_f64(), ..planned.seconds.clone() };
    let expand = |targets: &[Vec<f64>]| fit_expansions(study, options, &planned.plan.design, targets, observer);
    assemble(study, options, &planned, fits, seconds, &expand, observer)
}
