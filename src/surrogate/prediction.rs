//! A metamodel's predictions: one sample's modal histories, and the peaks of up to
//! [`PEAK_BATCH`] samples run together through the batched free run, reduced as a [`Reduction`]
//! says.

use super::Metamodel;
use super::batch::{
    self, BatchError, BatchInput, BatchSample, BatchWorkspace, Divergence, ModalScales, ModeProgram, Reduction, Sink,
    SinkFactory,
};
use crate::error::{Error, Result};
use crate::simd::{LANES, Lanes};
use crate::study::Study;
use crate::wind::ForceSource;

/// Samples [`Metamodel::peaks`] takes at once: two batches of [`LANES`], which a combination's peaks
/// run side by side (the free run waits on each step's power, and two batches' chains overlap) and
/// a motion's one after the other.
pub const PEAK_BATCH: usize = 2 * LANES;

impl Metamodel {
    fn programs(&self) -> Vec<ModeProgram<'_>> {
        self.models
            .iter()
            .map(|m| ModeProgram { terms: &m.terms, input_scale: m.input_scale, law: self.damper_law.as_ref() })
            .collect()
    }

    /// Static levels and coefficients of one sample.
    fn sample(&self, study: &Study, x: &[f64], forces: &dyn ForceSource) -> Result<(Vec<f64>, Vec<Vec<f64>>)> {
        study.inputs.check_sample(x)?;
        let germ = self.germ(study, x);
        let levels = self
            .models
            .iter()
            .enumerate()
            .map(|(m, model)| super::metamodel::blend(&germ, |xi| model.static_response.evaluate(xi, forces.mean(m))))
            .collect();
        Ok((levels, self.coefficients(&germ)))
    }

    /// Free-runs every mode on the sample's modal forces; modal displacement histories (m). A
    /// diverging free run is an error, never a result.
    pub fn predict(&self, study: &Study, x: &[f64], forces: &dyn ForceSource) -> Result<Vec<Vec<f64>>> {
        let (levels, theta) = self.sample(study, x, forces)?;
        let steps = study.storm.steps();
        let mut out = vec![vec![0.0; steps]; self.models.len()];
        let samples = [BatchSample { theta, forces }];
        let modes = self.models.len();
        let mut consume = |first: usize, outputs: &[Lanes], _: &[Lanes]| {
            for (k, lanes) in outputs.iter().enumerate() {
                let m = k % modes;
                out[m][first + k / modes] = levels[m] + lanes[0] * self.models[m].output_scale;
            }
        };
        let mut workspace = BatchWorkspace::default();
        batch::run(
            &self.programs(),
            &samples,
            steps,
            study.storm.time_step,
            &mut workspace,
            &mut Sink::Blocks(&mut consume),
        )
        .map_err(|e| batch_error(e, study, &[(None, x)]))?;
        Ok(out)
    }

    /// Peaks over the storm for up to [`PEAK_BATCH`] samples run together, `samples[i]` = (its number
    /// in the request, its inputs, its forces), reduced as `reduction` says: per sample, one peak
    /// per response. The number names a diverging sample. `workspace` holds the batch's buffers;
    /// keep one per thread across calls.
    pub fn peaks(
        &self,
        study: &Study,
        samples: &[BatchInput],
        reduction: &Reduction,
        workspace: &mut BatchWorkspace,
    ) -> Result<Vec<Vec<f64>>> {
        self.run_peaks(study, samples, reduction, workspace)?.map_err(|e| batch_error(e, study, &named(samples)))
    }

    /// As [`peaks`](Self::peaks), but a sample whose free run diverges, or whose model has no
    /// stable rest (both numerical failures of the model at its inputs), gets `None` instead of
    /// failing the batch: it is taken out and the others run again, with the same results (a
    /// lane's values do not depend on the other lanes).
    pub fn peaks_or_divergence(
        &self,
        study: &Study,
        samples: &[BatchInput],
        reduction: &Reduction,
        workspace: &mut BatchWorkspace,
    ) -> Result<Vec<Option<Vec<f64>>>> {
        let mut peaks = vec![None; samples.len()];
        let mut left: Vec<usize> = (0..samples.len()).collect();
        while !left.is_empty() {
            let batch: Vec<_> = left.iter().map(|&i| samples[i]).collect();
            match self.run_peaks(study, &batch, reduction, workspace)? {
                Ok(values) => {
                    left.iter().zip(values).for_each(|(&i, value)| peaks[i] = Some(value));
                    break;
                }
                Err(BatchError::Diverged(Divergence { lane, .. }))
                | Err(BatchError::Model { lane, error: Error::Numerical(_) }) => {
                    left.remove(lane);
                }
                Err(error) => return Err(batch_error(error, study, &named(&batch))),
            }
        }
        Ok(peaks)
    }

    /// The batch's peaks, or why a lane failed numerically (the outer error: anything else).
    fn run_peaks(
        &self,
        study: &Study,
        samples: &[BatchInput],
        reduction: &Reduction,
        workspace: &mut BatchWorkspace,
    ) -> Result<std::result::Result<Vec<Vec<f64>>, BatchError>> {
        let mut levels = Vec::with_capacity(samples.len());
        let mut batch = Vec::with_capacity(samples.len());
        for (lane, &(_, x, forces)) in samples.iter().enumerate() {
            let (level, theta) = match self.sample(study, x, forces) {
                Ok(sampled) => sampled,
                Err(error @ Error::Numerical(_)) => return Ok(Err(BatchError::Model { lane, error })),
                Err(error) => return Err(error),
            };
            levels.push(level);
            batch.push(BatchSample { theta, forces });
        }
        let (programs, steps, time_step) = (self.programs(), study.storm.steps(), study.storm.time_step);
        match reduction {
            Reduction::Combination(weights) => {
                let gains: Vec<f64> =
                    self.models.iter().zip(*weights).map(|(model, w)| w * model.output_scale).collect();
                let offsets: Vec<f64> =
                    levels.iter().map(|level| level.iter().zip(*weights).map(|(l, w)| w * l).sum()).collect();
                let mut peaks = vec![0.0f64; samples.len()];
                let run = batch::run_paired_peaks(
                    &programs, &batch, steps, time_step, workspace, &gains, &offsets, &mut peaks,
                );
                Ok(run.map(|()| peaks.into_iter().map(|peak| vec![peak]).collect()))
            }
            Reduction::Motion(sink_for) => {
                let mut peaks = Vec::with_capacity(samples.len());
                for (g, ((samples, batch), levels)) in
                    samples.chunks(LANES).zip(batch.chunks(LANES)).zip(levels.chunks(LANES)).enumerate()
                {
                    let run = self.motion_peaks(study, samples, batch, levels, sink_for, workspace)?;
                    match run {
                        Ok(batch_peaks) => peaks.extend(batch_peaks),
                        Err(error) => return Ok(Err(error.shifted(g * LANES))),
                    }
                }
                Ok(Ok(peaks))
            }
        }
    }

    /// One batch's peaks of the responses of a motion sink.
    fn motion_peaks(
        &self,
        study: &Study,
        samples: &[BatchInput],
        batch: &[BatchSample],
        levels: &[Vec<f64>],
        sink_for: &SinkFactory,
        workspace: &mut BatchWorkspace,
    ) -> Result<std::result::Result<Vec<Vec<f64>>, BatchError>> {
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
        let mut consume = |first: usize, outputs: &[Lanes], inputs: &[Lanes]| motion.take(first, outputs, inputs);
        let (programs, steps, time_step) = (self.programs(), study.storm.steps(), study.storm.time_step);
        let run = batch::run(&programs, batch, steps, time_step, workspace, &mut Sink::Blocks(&mut consume));
        let peaks = run.map(|()| motion.finish());
        Ok(peaks.map(|peaks| (0..samples.len()).map(|lane| peaks.iter().map(|p| p[lane]).collect()).collect()))
    }
}

/// A batch's samples as its errors name them: their numbers and inputs.
fn named<'a>(samples: &[BatchInput<'a>]) -> Vec<(Option<usize>, &'a [f64])> {
    samples.iter().map(|&(number, x, _)| (Some(number), x)).collect()
}

/// The error of a failed batch, naming the sample (its number where it has one) and its inputs,
/// so that a user can tell an extrapolation (an input far outside the calibrated design) from a
/// defect.
fn batch_error(error: BatchError, study: &Study, samples: &[(Option<usize>, &[f64])]) -> Error {
    let (lane, message) = match error {
        BatchError::Model { lane, error } => (lane, error.to_string()),
        BatchError::Diverged(d) => (d.lane, format!("mode {}: the free run diverged at step {}", d.mode + 1, d.step)),
    };
    let Some(&(number, x)) = samples.get(lane) else { return Error::Numerical(message) };
    let inputs: Vec<String> =
        study.inputs.names().zip(x).map(|(name, value)| format!("{name} = {value:.4e}")).collect();
    let sample = number.map_or_else(|| "the sample".to_string(), |k| format!("sample {k}"));
    Error::Numerical(format!("{sample} ({}): {message}", inputs.join(", ")))
}
