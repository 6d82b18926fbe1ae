//! Calibration (section 3.3, steps 1-5): a Latin-hypercube design, one storm per experiment through
//! the reduced-order reference, then per mode the NARX structure, the coefficients of every
//! experiment refined on the simulation error, and their sparse polynomial chaos expansions. The
//! options, the progress reports, the diagnostics, and the whole calibration on one machine; the
//! phases themselves are in `phases`.

use super::Parametrization;
use super::identify::Refinement;
use super::metamodel::{Metamodel, StageSeconds};
use super::narx::NarxOptions;
use super::pce::PceOptions;
use super::phases::{assemble, fit_experiments, plan};
use crate::error::{Error, Result};
use crate::problem::{Problem, WindPath};
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// Everything about a calibration that is not the study itself; the defaults are the paper's.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(default, deny_unknown_fields)]
pub struct CalibrationOptions {
    /// Experiments K of the Latin-hypercube design.
    pub experiments: usize,
    pub seed: u64,
    pub narx: NarxOptions,
    pub pce: PceOptions,
    pub refinement: Refinement,
    /// Experiments on which candidate structures are compared (evenly spread over the design).
    pub selection_experiments: usize,
    /// How the experiments' wind is generated.
    pub wind: WindPath,
    /// What the expansions are of; by default the stable gains whenever the experiments admit them.
    pub parametrization: Option<Parametrization>,
}

impl Default for CalibrationOptions {
    fn default() -> Self {
        CalibrationOptions {
            experiments: 200,
            seed: 1,
            narx: NarxOptions::default(),
            pce: PceOptions::default(),
            refinement: Refinement::LevenbergMarquardt,
            selection_experiments: 20,
            wind: WindPath::Modal,
            parametrization: None,
        }
    }
}

/// Most experiments a calibration may ask for.
pub const MAX_EXPERIMENTS: usize = 5000;

impl CalibrationOptions {
    pub fn validate(&self) -> Result<()> {
        if !(4..=MAX_EXPERIMENTS).contains(&self.experiments) {
            return Err(Error::invalid(
                "experiments",
                format!("must be between 4 and {MAX_EXPERIMENTS}, got {}", self.experiments),
            ));
        }
        if self.selection_experiments == 0 {
            return Err(Error::invalid("selection_experiments", "must be at least 1"));
        }
        self.narx.validate()?;
        self.pce.validate()
    }
}

/// Where a calibration is; reported to an observer as it goes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(tag = "stage", rename_all = "snake_case")]
pub enum Progress {
    /// Experiments through the reference (and, after the structures, their NARX fits).
    Experiments {
        done: usize,
        total: usize,
    },
    Structure {
        mode: usize,
    },
    Expansion {
        mode: usize,
    },
    /// Sampling or validation storms done.
    Samples {
        done: usize,
        total: usize,
    },
}

/// Who watches a calibration: progress reports and a way to stop it.
pub trait Observer: Sync {
    fn progress(&self, progress: Progress);
    fn cancelled(&self) -> bool {
        false
    }
}

/// An observer that ignores progress and never cancels.
pub struct Silent;

impl Observer for Silent {
    fn progress(&self, _: Progress) {}
}

/// What the calibration measured about one mode.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
pub struct ModeDiagnostics {
    pub mode: usize,
    pub selected_terms: Vec<String>,
    pub candidate_structures: usize,
    /// Mean free-run relative error of the one-step fits of the chosen structure (selection set).
    pub structure_error: f64,
    /// NARX only: mean over experiments of the free-run relative error with each experiment's own
    /// refined coefficients.
    pub narx_mean_relative_error: f64,
    /// Full PC-NARX: the same with the coefficients and the static level from their expansions.
    pub pc_narx_mean_relative_error: f64,
    /// Corrected leave-one-out error of the static level's expansion.
    pub static_level_loo_error: f64,
    /// Corrected leave-one-out error of each coefficient's expansion.
    pub coefficient_loo_errors: Vec<f64>,
    /// Terms kept in each coefficient's expansion.
    pub coefficient_pce_terms: Vec<usize>,
    /// Experiments whose free run diverged; their error is infinite, so the means above show it.
    pub diverged_experiments: usize,
}

/// Calibrates a PC-NARX metamodel of `problem` (with its storm grid and input model) on this
/// machine: the three phases of [`super::phases`], every experiment fitted here.
pub fn calibrate(problem: &Problem, options: &CalibrationOptions, observer: &dyn Observer) -> Result<Metamodel> {
    let planned = plan(problem, options, observer)?;
    let stage = Instant::now();
    let mut fits = planned.fit_selection(options, observer)?;
    let remaining = planned.plan.remaining();
    fits.extend(fit_experiments(problem, options, &planned.plan, &remaining, planned.plan.selection.len(), observer)?);
    let seconds = StageSeconds { coefficients: stage.elapsed().as_secs_f64(), ..planned.seconds.clone() };
    assemble(problem, options, &planned, fits, seconds, observer)
}
