//! Calibration (section 3.3, steps 1-5): a Latin-hypercube design, one storm per experiment through
//! the reduced-order reference, then per mode the NARX structure, the coefficients of every
//! experiment refined on the simulation error, and their sparse polynomial chaos expansions.

use super::Parametrization;
use super::identify::{Record, Refinement, least_squares, refine, select_structure, simulate};
use super::metamodel::{
    CalibrationSummary, FORMAT, FORMAT_VERSION, Metamodel, ModalBasis, ModeModel, StageSeconds, StaticResponse,
};
use super::narx::{NarxOptions, relative_error};
use super::pce::{PceOptions, SparsePce};
use crate::dynamics::integrate_reduced;
use crate::error::{Error, Result};
use crate::problem::{Problem, WindPath};
use crate::uncertainty::{latin_hypercube, rng_from_seed};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
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
    Experiments {
        done: usize,
        total: usize,
    },
    Structure {
        mode: usize,
    },
    Coefficients {
        mode: usize,
        done: usize,
        total: usize,
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

/// One experiment's data for every mode: modal forces and reference modal displacements.
struct Experiment {
    q: Vec<Vec<f64>>,
    q_mean: Vec<f64>,
    y: Vec<Vec<f64>>,
}

fn check_cancel(observer: &dyn Observer) -> Result<()> {
    if observer.cancelled() { Err(Error::Cancelled) } else { Ok(()) }
}

/// Runs the reference on the design, in parallel; experiment k's storm depends only on (seed, k).
fn run_experiments(
    problem: &Problem,
    design: &[Vec<f64>],
    options: &CalibrationOptions,
    observer: &dyn Observer,
) -> Result<Vec<Experiment>> {
    let done = AtomicUsize::new(0);
    let total = design.len();
    design
        .par_iter()
        .enumerate()
        .map(|(k, x)| {
            check_cancel(observer)?;
            let (p, forces) = problem.sample_storm(x, options.wind, options.seed, k)?;
            let dampers = problem.dampers(&p)?;
            let response = integrate_reduced(
                &problem.sample_modes(&p),
                p.damping_ratio,
                &dampers,
                &forces,
                problem.storm.time_step,
            )?;
            observer.progress(Progress::Experiments { done: done.fetch_add(1, Ordering::Relaxed) + 1, total });
            Ok(Experiment { q: forces.series, q_mean: forces.mean, y: response.displacements })
        })
        .collect()
}

/// Root mean square over every experiment and instant.
fn pooled_rms<'a>(series: impl Iterator<Item = &'a Vec<f64>>) -> f64 {
    let (mut sum, mut count) = (0.0, 0usize);
    for s in series {
        sum += s.iter().map(|v| v * v).sum::<f64>();
        count += s.len();
    }
    (sum / count as f64).sqrt().max(f64::MIN_POSITIVE)
}

/// Calibrates a PC-NARX metamodel of `problem` (with its storm grid and input model).
pub fn calibrate(problem: &Problem, options: &CalibrationOptions, observer: &dyn Observer) -> Result<Metamodel> {
    options.validate()?;
    let started = Instant::now();
    let design = latin_hypercube(&problem.inputs, options.experiments, &mut rng_from_seed(options.seed));
    let experiments = run_experiments(problem, &design, options, observer)?;
    let mut seconds = StageSeconds { experiments: started.elapsed().as_secs_f64(), ..Default::default() };
    let xi: Vec<Vec<f64>> = design.iter().map(|x| problem.inputs.to_standard(x)).collect();
    let modes = problem.modes.count();
    // The NARX works on deviations from the static state at rest under the mean load: y′ = y − y(0),
    // Q′ = Q − Q̄. Polynomial terms then act on the fluctuation, and the static level (a smooth
    // function of the inputs) gets its own expansion instead of hiding in a constant. Every mode's
    // scaled deviations are shared by all modes' records (the coupling terms read them).
    let deviation = |series: &[f64], rest: f64| -> Vec<f64> { series.iter().map(|v| v - rest).collect() };
    let scales: Vec<(f64, f64)> = (0..modes)
        .map(|m| {
            let y: Vec<Vec<f64>> = experiments.iter().map(|e| deviation(&e.y[m], e.y[m][0])).collect();
            let q: Vec<Vec<f64>> = experiments.iter().map(|e| deviation(&e.q[m], e.q_mean[m])).collect();
            (pooled_rms(y.iter()), pooled_rms(q.iter()))
        })
        .collect();
    let scaled =
        |series: &[f64], rest: f64, scale: f64| -> Arc<[f64]> { series.iter().map(|v| (v - rest) / scale).collect() };
    let outputs: Vec<Vec<Arc<[f64]>>> =
        experiments.iter().map(|e| (0..modes).map(|m| scaled(&e.y[m], e.y[m][0], scales[m].0)).collect()).collect();
    let inputs: Vec<Vec<Arc<[f64]>>> =
        experiments.iter().map(|e| (0..modes).map(|m| scaled(&e.q[m], e.q_mean[m], scales[m].1)).collect()).collect();
    let coupled = options.narx.coupling_lags > 0 && modes > 1;
    let k = experiments.len();
    let stride = (k as f64 / options.selection_experiments.min(k) as f64).max(1.0);
    let selection: Vec<usize> =
        (0..options.selection_experiments.min(k)).map(|i| (i as f64 * stride) as usize).collect();

    let mut models = Vec::new();
    let mut diagnostics = Vec::new();
    for mode in 0..modes {
        check_cancel(observer)?;
        observer.progress(Progress::Structure { mode: mode + 1 });
        let (output_scale, input_scale) = scales[mode];
        let records: Vec<Record> = (0..k)
            .map(|e| Record {
                y: outputs[e][mode].clone(),
                q: inputs[e][mode].clone(),
                q_rest: 0.0,
                outputs: if coupled { outputs[e].clone() } else { Vec::new() },
            })
            .collect();
        let dictionary = options.narx.dictionary(mode, modes);
        let largest_load = experiments.iter().map(|e| e.q_mean[mode].abs()).fold(0.0, f64::max);
        let per_unit_mean_load = experiments.iter().all(|e| e.q_mean[mode].abs() > 1e-6 * largest_load);
        let static_targets: Vec<f64> = experiments
            .iter()
            .map(|e| if per_unit_mean_load { e.y[mode][0] / e.q_mean[mode] } else { e.y[mode][0] })
            .collect();
        let static_response = StaticResponse {
            per_unit_mean_load,
            expansion: SparsePce::fit(&problem.inputs, &xi, &static_targets, &options.pce)?,
        };
        let stage = Instant::now();
        let chosen: Vec<Record> = selection.iter().map(|&i| records[i].clone()).collect();
        let structure = select_structure(&dictionary, &chosen, &chosen, options.narx.max_terms)?;
        let terms = structure.terms.clone();
        seconds.structure += stage.elapsed().as_secs_f64();

        let stage = Instant::now();
        let done = AtomicUsize::new(0);
        let fitted: Vec<(Vec<f64>, f64)> = records
            .par_iter()
            .map(|record| {
                check_cancel(observer)?;
                let start = least_squares(&terms, record)?;
                let theta = refine(options.refinement, &terms, start, record);
                let error =
                    simulate(&terms, &theta, record).map_or(f64::INFINITY, |y_hat| relative_error(&record.y, &y_hat));
                observer.progress(Progress::Coefficients {
                    mode: mode + 1,
                    done: done.fetch_add(1, Ordering::Relaxed) + 1,
                    total: k,
                });
                Ok((theta, error))
            })
            .collect::<Result<_>>()?;
        seconds.coefficients += stage.elapsed().as_secs_f64();

        check_cancel(observer)?;
        observer.progress(Progress::Expansion { mode: mode + 1 });
        let stage = Instant::now();
        let thetas: Vec<Vec<f64>> = fitted.iter().map(|(theta, _)| theta.clone()).collect();
        let parametrization = options.parametrization.unwrap_or_else(|| Parametrization::choose(&terms, &thetas));
        let expanded: Vec<Vec<f64>> = fitted.iter().map(|(theta, _)| parametrization.forward(&terms, theta)).collect();
        let expansions: Vec<SparsePce> = (0..terms.len())
            .into_par_iter()
            .map(|i| {
                let targets: Vec<f64> = expanded.iter().map(|phi| phi[i]).collect();
                SparsePce::fit(&problem.inputs, &xi, &targets, &options.pce)
            })
            .collect::<Result<_>>()?;
        seconds.expansion += stage.elapsed().as_secs_f64();

        let pc_errors: Vec<f64> = records
            .par_iter()
            .zip(&xi)
            .zip(&experiments)
            .map(|((record, xi), experiment)| {
                let phi: Vec<f64> = expansions.iter().map(|pce| pce.evaluate(xi)).collect();
                let theta = parametrization.inverse(&terms, &phi);
                let level = static_response.evaluate(xi, experiment.q_mean[mode]);
                simulate(&terms, &theta, record).map_or(f64::INFINITY, |y_hat| {
                    let full: Vec<f64> = y_hat.iter().map(|v| level + v * output_scale).collect();
                    relative_error(&experiment.y[mode], &full)
                })
            })
            .collect();
        let narx_errors: Vec<f64> = fitted.iter().map(|(_, e)| *e).collect();
        let diverged = narx_errors.iter().chain(&pc_errors).filter(|e| !e.is_finite()).count();
        let mean = |errors: &[f64]| errors.iter().sum::<f64>() / errors.len() as f64;
        diagnostics.push(ModeDiagnostics {
            mode: mode + 1,
            selected_terms: terms.iter().map(|t| t.to_string()).collect(),
            candidate_structures: structure.candidates,
            structure_error: structure.error,
            narx_mean_relative_error: mean(&narx_errors),
            pc_narx_mean_relative_error: mean(&pc_errors),
            static_level_loo_error: static_response.expansion.loo_error,
            coefficient_loo_errors: expansions.iter().map(|p| p.loo_error).collect(),
            coefficient_pce_terms: expansions.iter().map(|p| p.terms.len()).collect(),
            diverged_experiments: diverged,
        });
        models.push(ModeModel {
            term_names: terms.iter().map(|t| t.to_string()).collect(),
            terms,
            output_scale,
            input_scale,
            static_response,
            parametrization,
            coefficients: expansions,
        });
    }
    seconds.total = started.elapsed().as_secs_f64();
    let count = diagnostics.len() as f64;
    let modes = &problem.modes;
    Ok(Metamodel {
        format: FORMAT.into(),
        version: FORMAT_VERSION,
        problem: problem.resolved_spec(),
        modes: ModalBasis {
            frequencies_rad_s: modes.frequencies.clone(),
            modal_masses_kg: modes.modal_masses.clone(),
            shapes: (0..modes.count()).map(|m| modes.shapes.col(m).iter().copied().collect()).collect(),
        },
        models,
        calibration: CalibrationSummary {
            options: options.clone(),
            narx_mean_relative_error: diagnostics.iter().map(|d| d.narx_mean_relative_error).sum::<f64>() / count,
            pc_narx_mean_relative_error: diagnostics.iter().map(|d| d.pc_narx_mean_relative_error).sum::<f64>() / count,
            modes: diagnostics,
            seconds,
        },
    })
}
