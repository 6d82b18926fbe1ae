//! The metamodel as a value: everything needed to reproduce its predictions, serialisable and
//! versioned.

use super::Parametrization;
use super::batch::{self, BatchError, BatchSample, Divergence, LANES, Lanes, ModeProgram, Sink, Workspace};
use super::narx::NarxTerm;
use super::options::CalibrationOptions;
use super::pce::SparsePce;
use crate::error::{Error, Result};
use crate::problem::{Problem, ProblemSpec};
use crate::wind::ForceSource;
use serde::{Deserialize, Serialize};

pub const FORMAT: &str = "windmeta-pc-narx";
pub const FORMAT_VERSION: u32 = 1;

/// The PC-NARX model of one modal coordinate.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct ModeModel {
    /// Selected NARX terms, in the order of `coefficients`.
    pub terms: Vec<NarxTerm>,
    /// The terms written out, e.g. `y(t-1)` (for people; `terms` is authoritative).
    pub term_names: Vec<String>,
    /// The NARX works on deviations from the static state, (y − y_static) / output_scale and
    /// (Q − Q̄) / input_scale (m and N), at rest at 0 before the storm.
    pub output_scale: f64,
    pub input_scale: f64,
    /// The static modal displacement under the mean wind load.
    pub static_response: StaticResponse,
    /// What the expansions are of (see [`Parametrization`]).
    pub parametrization: Parametrization,
    /// Polynomial chaos expansion of each expanded coefficient over the standard-space inputs.
    pub coefficients: Vec<SparsePce>,
}

/// How the static modal displacement of a sample is predicted.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct StaticResponse {
    /// When true the expansion is of the static gain y_static / Q̄ (m/N), multiplied by the
    /// sample's own mean modal force, which carries the wind speed exactly; when false (some
    /// experiment had Q̄ ≈ 0) it is of y_static itself (m).
    pub per_unit_mean_load: bool,
    pub expansion: SparsePce,
}

impl StaticResponse {
    pub fn evaluate(&self, xi: &[f64], mean_load: f64) -> f64 {
        let value = self.expansion.evaluate(xi);
        if self.per_unit_mean_load { value * mean_load } else { value }
    }
}

/// Roof-normalised modes the metamodel was calibrated on (shapes fixed across samples).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct ModalBasis {
    pub frequencies_rad_s: Vec<f64>,
    pub modal_masses_kg: Vec<f64>,
    /// shapes[mode][floor].
    pub shapes: Vec<Vec<f64>>,
}

/// What the calibration measured about one mode.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
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

/// How the metamodel came about and how well it fits its own experiments.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct CalibrationSummary {
    pub options: CalibrationOptions,
    pub modes: Vec<ModeDiagnostics>,
    /// Mean over modes of the NARX-only calibration mean relative error.
    pub narx_mean_relative_error: f64,
    /// Mean over modes of the full PC-NARX calibration mean relative error.
    pub pc_narx_mean_relative_error: f64,
    /// Wall time of each stage (s).
    pub seconds: StageSeconds,
}

/// Wall time of each stage (s). With the experiments spread over several replicas, the
/// coefficients stage is the fan-out's wall time.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct StageSeconds {
    /// The selection experiments through the reference.
    pub experiments: f64,
    /// Structure selection on them.
    pub structure: f64,
    /// Every other experiment through the reference, and every experiment's NARX fit.
    pub coefficients: f64,
    /// Polynomial chaos expansions and diagnostics.
    pub expansion: f64,
    pub total: f64,
}

/// A calibrated PC-NARX metamodel.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct Metamodel {
    pub format: String,
    pub version: u32,
    /// The study, fully resolved: rebuilding it gives the same inputs, modes, wind and storm grid.
    pub problem: ProblemSpec,
    pub modes: ModalBasis,
    pub models: Vec<ModeModel>,
    pub calibration: CalibrationSummary,
}

impl Metamodel {
    /// Reads a metamodel and checks that this build can use it.
    pub fn from_json(text: &str) -> Result<Metamodel> {
        let value: serde_json::Value =
            serde_json::from_str(text).map_err(|e| Error::invalid("metamodel", format!("not JSON: {e}")))?;
        if value.get("format").and_then(|f| f.as_str()) != Some(FORMAT) {
            return Err(Error::invalid("metamodel", format!("not a {FORMAT} file")));
        }
        match value.get("version").and_then(|v| v.as_u64()) {
            Some(v) if v == FORMAT_VERSION as u64 => {}
            other => {
                return Err(Error::invalid(
                    "metamodel",
                    format!("version {other:?} is not supported (this build reads {FORMAT_VERSION})"),
                ));
            }
        }
        serde_json::from_value(value).map_err(|e| Error::invalid("metamodel", e.to_string()))
    }

    /// Rebuilds the study the metamodel was calibrated on.
    pub fn problem(&self) -> Result<Problem> {
        Problem::from_spec(&self.problem)
    }

    /// The lowest and highest value of a named input over the calibration's experiments: where
    /// the expansions were fitted, beyond which they extrapolate.
    pub fn calibrated_range(&self, problem: &Problem, name: &str) -> Result<[f64; 2]> {
        let index = problem.inputs.index_of(name)?;
        let design = super::design(problem, &self.calibration.options)?.points;
        let values = design.iter().map(|x| x[index]);
        Ok([values.clone().fold(f64::INFINITY, f64::min), values.fold(f64::NEG_INFINITY, f64::max)])
    }

    /// The NARX coefficients of every mode at a physical input sample.
    pub fn coefficients(&self, problem: &Problem, x: &[f64]) -> Vec<Vec<f64>> {
        let xi = problem.inputs.to_standard(x);
        self.models
            .iter()
            .map(|m| {
                let phi: Vec<f64> = m.coefficients.iter().map(|pce| pce.evaluate(&xi)).collect();
                m.parametrization.inverse(&m.terms, &phi)
            })
            .collect()
    }

    fn programs(&self) -> Vec<ModeProgram<'_>> {
        self.models.iter().map(|m| ModeProgram { terms: &m.terms, input_scale: m.input_scale }).collect()
    }

    /// Static levels and coefficients of one sample.
    fn sample(&self, problem: &Problem, x: &[f64], forces: &dyn ForceSource) -> Result<(Vec<f64>, Vec<Vec<f64>>)> {
        problem.inputs.check_sample(x)?;
        let xi = problem.inputs.to_standard(x);
        let levels = self
            .models
            .iter()
            .enumerate()
            .map(|(m, model)| model.static_response.evaluate(&xi, forces.mean(m)))
            .collect();
        Ok((levels, self.coefficients(problem, x)))
    }

    /// Free-runs every mode on the sample's modal forces; modal displacement histories (m). A
    /// diverging free run is an error, never a result.
    pub fn predict(&self, problem: &Problem, x: &[f64], forces: &dyn ForceSource) -> Result<Vec<Vec<f64>>> {
        let (levels, theta) = self.sample(problem, x, forces)?;
        let steps = problem.storm.steps();
        let mut out = vec![vec![0.0; steps]; self.models.len()];
        let samples = [BatchSample { theta, forces }];
        let modes = self.models.len();
        let mut consume = |first: usize, outputs: &[Lanes], _: &[Lanes]| {
            for (k, lanes) in outputs.iter().enumerate() {
                let m = k % modes;
                out[m][first + k / modes] = levels[m] + lanes[0] * self.models[m].output_scale;
            }
        };
        let mut workspace = Workspace::default();
        batch::run(
            &self.programs(),
            &samples,
            steps,
            problem.storm.time_step,
            &mut workspace,
            &mut Sink::Blocks(&mut consume),
        )
        .map_err(|e| batch_error(e, &[None]))?;
        Ok(out)
    }

    /// Peaks over the storm for up to [`LANES`] samples run together, `samples[i]` = (its number
    /// in the request, its inputs, its forces), reduced as `reduction` says: per sample, one peak
    /// per response. The number names a diverging sample. `workspace` holds the batch's buffers;
    /// keep one per thread across calls.
    pub fn peaks(
        &self,
        problem: &Problem,
        samples: &[BatchInput],
        reduction: &Reduction,
        workspace: &mut Workspace,
    ) -> Result<Vec<Vec<f64>>> {
        self.run_peaks(problem, samples, reduction, workspace)?
            .map_err(|e| batch_error(e, &samples.iter().map(|s| Some(s.0)).collect::<Vec<_>>()))
    }

    /// As [`peaks`](Self::peaks), but a sample whose free run diverges, or whose model has no
    /// stable rest (both numerical failures of the model at its inputs), gets `None` instead of
    /// failing the batch: it is taken out and the others run again, with the same results (a
    /// lane's values do not depend on the other lanes).
    pub fn peaks_or_divergence(
        &self,
        problem: &Problem,
        samples: &[BatchInput],
        reduction: &Reduction,
        workspace: &mut Workspace,
    ) -> Result<Vec<Option<Vec<f64>>>> {
        let mut peaks = vec![None; samples.len()];
        let mut left: Vec<usize> = (0..samples.len()).collect();
        while !left.is_empty() {
            let batch: Vec<_> = left.iter().map(|&i| samples[i]).collect();
            match self.run_peaks(problem, &batch, reduction, workspace)? {
                Ok(values) => {
                    left.iter().zip(values).for_each(|(&i, value)| peaks[i] = Some(value));
                    break;
                }
                Err(BatchError::Diverged(Divergence { lane, .. }))
                | Err(BatchError::Model { lane, error: Error::Numerical(_) }) => {
                    left.remove(lane);
                }
                Err(error) => return Err(batch_error(error, &batch.iter().map(|s| Some(s.0)).collect::<Vec<_>>())),
            }
        }
        Ok(peaks)
    }

    /// The batch's peaks, or why a lane failed numerically (the outer error: anything else).
    fn run_peaks(
        &self,
        problem: &Problem,
        samples: &[BatchInput],
        reduction: &Reduction,
        workspace: &mut Workspace,
    ) -> Result<std::result::Result<Vec<Vec<f64>>, BatchError>> {
        let mut levels = Vec::with_capacity(samples.len());
        let mut batch = Vec::with_capacity(samples.len());
        for (lane, &(_, x, forces)) in samples.iter().enumerate() {
            let (level, theta) = match self.sample(problem, x, forces) {
                Ok(sampled) => sampled,
                Err(error @ Error::Numerical(_)) => return Ok(Err(BatchError::Model { lane, error })),
                Err(error) => return Err(error),
            };
            levels.push(level);
            batch.push(BatchSample { theta, forces });
        }
        let (programs, steps, time_step) = (self.programs(), problem.storm.steps(), problem.storm.time_step);
        match reduction {
            Reduction::Combination(weights) => {
                let gains: Vec<f64> =
                    self.models.iter().zip(*weights).map(|(model, w)| w * model.output_scale).collect();
                let mut offsets = [0.0; LANES];
                for (offset, level) in offsets.iter_mut().zip(&levels) {
                    *offset = level.iter().zip(*weights).map(|(l, w)| w * l).sum();
                }
                let mut peaks = [0.0f64; LANES];
                let mut sink = Sink::Peaks { gains: &gains, offsets, peaks: &mut peaks };
                let run = batch::run(&programs, &batch, steps, time_step, workspace, &mut sink);
                Ok(run.map(|()| peaks[..samples.len()].iter().map(|&peak| vec![peak]).collect()))
            }
            Reduction::Motion(sink_for) => {
                let inputs: Vec<&[f64]> = samples.iter().map(|s| s.1).collect();
                let mut level = vec![[0.0; LANES]; self.models.len()];
                for (lane, sample_levels) in levels.iter().enumerate() {
                    sample_levels.iter().zip(&mut level).for_each(|(value, to)| to[lane] = *value);
                }
                let scales = ModalScales {
                    outputs: self.models.iter().map(|m| m.output_scale).collect(),
                    inputs: self.models.iter().map(|m| m.input_scale).collect(),
                    levels: level,
                };
                let mut motion = sink_for(&inputs, &scales)?;
                let mut consume =
                    |first: usize, outputs: &[Lanes], inputs: &[Lanes]| motion.take(first, outputs, inputs);
                let run = batch::run(&programs, &batch, steps, time_step, workspace, &mut Sink::Blocks(&mut consume));
                let peaks = run.map(|()| motion.finish());
                Ok(peaks.map(|peaks| (0..samples.len()).map(|lane| peaks.iter().map(|p| p[lane]).collect()).collect()))
            }
        }
    }
}

/// One sample of a batch: its number in the request, its physical inputs, its forces.
pub type BatchInput<'a> = (usize, &'a [f64], &'a dyn ForceSource);

/// How a batch's runs become one peak per lane.
pub enum Reduction<'a> {
    /// Peak |Σ_m w_m y_m(t)| of a fixed combination of the modal displacements (displacement,
    /// drift, stroke), formed inside the free run's vectorised code.
    Combination(&'a [f64]),
    /// Responses of the motion and the loads (any, accelerations and damper forces included), by
    /// a sink built for the batch: lane i's physical inputs at i, and the scales of its blocks.
    Motion(&'a SinkFactory<'a>),
}

/// Builds a batch's [`MotionSink`] from its lanes' physical inputs and its blocks' scales.
pub type SinkFactory<'a> = dyn Fn(&[&[f64]], &ModalScales) -> Result<Box<dyn MotionSink>> + Sync + 'a;

/// The scales of the free run's blocks, per mode: the output ŷ_m is (y_m − levels[m])/outputs[m]
/// and the input q̂_m is (Q_m − Q̄_m)/inputs[m], `levels[m]` the static level of every lane.
#[derive(Debug, Clone)]
pub struct ModalScales {
    pub outputs: Vec<f64>,
    pub inputs: Vec<f64>,
    pub levels: Vec<Lanes>,
}

/// What a batch's modal motion is reduced to, block by block: one peak per lane.
pub trait MotionSink {
    /// Steps `first..` of a block, every lane: `outputs[i·M + m]` the scaled output ŷ_m at step
    /// first + i and `inputs[i·M + m]` the scaled input q̂_m it read (see [`ModalScales`]).
    fn take(&mut self, first: usize, outputs: &[Lanes], inputs: &[Lanes]);
    /// Per response, every lane's peak, once the storm is over.
    fn finish(&mut self) -> Vec<Lanes>;
}

/// The error of a failed batch, naming the sample where it has a number.
fn batch_error(error: BatchError, numbers: &[Option<usize>]) -> Error {
    let (lane, message) = match error {
        BatchError::Model { lane, error } => (lane, error.to_string()),
        BatchError::Diverged(d) => (d.lane, format!("mode {}: the free run diverged at step {}", d.mode + 1, d.step)),
    };
    match numbers.get(lane).copied().flatten() {
        Some(k) => Error::Numerical(format!("sample {k}: {message}")),
        None => Error::Numerical(message),
    }
}
