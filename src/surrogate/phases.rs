//! The calibration in three phases, so that its experiments can be fitted anywhere:
//!
//! 1. [`plan`]: the Latin-hypercube design, the reference on the selection experiments, the scales of
//!    the deviations ([`select`]) and each mode's NARX structure ([`Selection::structure`]), all
//!    decided on those few experiments; a mode's structure can be chosen anywhere, the selection
//!    experiments run again there ([`Selection::rerun`]);
//! 2. [`fit_experiments`]: for any experiments, the reference storm and every mode's refined NARX
//!    coefficients: independent of each other, small to send back ([`ExperimentFit`]), the same
//!    numbers on whichever machine runs them;
//! 3. [`assemble`](super::assembly::assemble) (in `assembly`): the polynomial chaos expansions of
//!    the coefficients and static levels, fitted where the caller says, and the diagnostics.
//!
//! Only the selection experiments' histories are held in memory (a full-size experiment's are
//! 4 MB); every other experiment is reduced to its coefficients as soon as it has run.

use super::damper_law::{DamperLaw, KNEE_FRACTION};
use super::design::design;
use super::identify::{Record, StructureChoice, least_squares, select_structure, simulate};
use super::metamodel::StageSeconds;
use super::narx::relative_error;
use super::options::CalibrationOptions;
use super::refine::{RefinementOutcome, refine};
use crate::error::{Error, Result};
use crate::progress::{Observer, Progress, check};
use crate::simd::LANES;
use crate::study::Study;
use crate::wind::TransformWorkspace;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

/// What every experiment's fit needs, decided on the selection experiments. Small and
/// serialisable; rebuilding it from the same study and options gives the same plan.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CalibrationPlan {
    /// The design's physical inputs, by experiment.
    pub design: Vec<Vec<f64>>,
    /// Experiments the structures were chosen on (evenly spread over the design).
    pub selection: Vec<usize>,
    /// Per mode, the root-mean-square deviation of the output and of the modal force over the
    /// selection experiments: the NARX works on deviations divided by these.
    pub scales: Vec<(f64, f64)>,
    /// Per mode, the chosen NARX structure.
    pub structures: Vec<StructureChoice>,
    /// The law of velocity terms, where the dampers are nonlinear and the options ask for them.
    #[serde(default)]
    pub damper_law: Option<DamperLaw>,
}

impl CalibrationPlan {
    /// The experiments not in the selection, in order.
    pub fn remaining(&self) -> Vec<usize> {
        (0..self.design.len()).filter(|k| !self.selection.contains(k)).collect()
    }
}

/// What phase 3 needs of one experiment.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ExperimentFit {
    /// The experiment's index in the design.
    pub index: usize,
    /// Per mode: mean modal force (N).
    pub mean_load: Vec<f64>,
    /// Per mode: static modal displacement at rest under that force (m).
    pub static_displacement: Vec<f64>,
    /// Per mode: the refined NARX coefficients of the plan's structure.
    pub coefficients: Vec<Vec<f64>>,
    /// Per mode: free-run relative error with these coefficients (infinite if it diverged).
    pub narx_errors: Vec<f64>,
    /// Per mode: how the refinement on the simulation error ended (None: not refined).
    #[serde(default)]
    pub refinements: Vec<Option<RefinementOutcome>>,
}

/// One experiment's histories for every mode: modal forces and reference modal displacements.
#[derive(Clone)]
pub(super) struct Experiment {
    q: Vec<Vec<f64>>,
    pub(super) q_mean: Vec<f64>,
    pub(super) y: Vec<Vec<f64>>,
    /// Per mode, the least 1 + a₂ its NARX model's linear part may have: half the structure's
    /// own viscous damping of the mode, 1 − exp(−2ζωΔt), as the exact discrete oscillator has it.
    damping_floors: Vec<f64>,
}

/// The share of a mode's structural damping its NARX model's linear part keeps at least (see
/// [`Experiment::damping_floors`]): on frame40-kn, refined without a floor, the linear parts of
/// modes 2 and 3 held about two thirds and all of it on average when the dampers' terms took the
/// rest, and a few experiments none. With the whole of it as the floor the own velocity's terms
/// no longer lowered the free-run error enough to be selected (the metamodel came out as without
/// them).
const DAMPING_FLOOR_SHARE: f64 = 0.5;

impl Experiment {
    /// Runs experiments `indices` of `design` through the reduced-order reference, eight at a
    /// time in vector lanes.
    fn run_batch(
        study: &Study,
        options: &CalibrationOptions,
        design: &[Vec<f64>],
        indices: &[usize],
        workspace: &mut TransformWorkspace,
        observer: &dyn Observer,
    ) -> Result<Vec<Experiment>> {
        let samples = indices
            .iter()
            .map(|&k| {
                let x = design.get(k).ok_or_else(|| Error::invalid("experiment", format!("no experiment {k}")))?;
                let (p, coarse) = study.sample_storm(x, options.wind, options.seed, k, workspace)?;
                Ok((p, coarse.on_grid(&study.storm)))
            })
            .collect::<Result<Vec<_>>>()?;
        let responses = study.integrate_reduced_batch(&samples, observer)?;
        let dt = study.storm.time_step;
        let experiments = samples
            .into_iter()
            .zip(responses)
            .map(|((p, forces), response)| {
                let damping_floors = study
                    .sample_modes(&p)
                    .frequencies
                    .iter()
                    .map(|omega| DAMPING_FLOOR_SHARE * -(-2.0 * p.damping_ratio * omega * dt).exp_m1())
                    .collect();
                Experiment { q: forces.series, q_mean: forces.mean, y: response.displacements, damping_floors }
            })
            .collect();
        Ok(experiments)
    }

    /// Every mode's record, scaled as the plan says; with coupling each shares all modes' outputs.
    pub(super) fn records(&self, scales: &[(f64, f64)], coupled: bool, law: Option<&Arc<DamperLaw>>) -> Vec<Record> {
        let scaled = |series: &[f64], rest: f64, scale: f64| -> Arc<[f64]> {
            series.iter().map(|v| (v - rest) / scale).collect()
        };
        let outputs: Vec<Arc<[f64]>> =
            self.y.iter().zip(scales).map(|(y, &(scale, _))| scaled(y, y[0], scale)).collect();
        let secants = match law {
            Some(law) if coupled => Record::secants_of(&outputs, law),
            _ => Vec::new(),
        };
        (0..self.y.len())
            .map(|m| Record {
                y: outputs[m].clone(),
                q: scaled(&self.q[m], self.q_mean[m], scales[m].1),
                q_rest: 0.0,
                outputs: if coupled { outputs.clone() } else { Vec::new() },
                mode: m,
                law: law.cloned(),
                secants: secants.clone(),
            })
            .collect()
    }

    fn fit(
        &self,
        index: usize,
        plan: &CalibrationPlan,
        options: &CalibrationOptions,
        observer: &dyn Observer,
    ) -> Result<ExperimentFit> {
        let coupled = coupled(options, plan.scales.len());
        let mut fit = ExperimentFit {
            index,
            mean_load: self.q_mean.clone(),
            static_displacement: self.y.iter().map(|y| y[0]).collect(),
            coefficients: Vec::new(),
            narx_errors: Vec::new(),
            refinements: Vec::new(),
        };
        let law = plan.damper_law.clone().map(Arc::new);
        let records = self.records(&plan.scales, coupled, law.as_ref());
        for ((record, structure), floor) in records.iter().zip(&plan.structures).zip(&self.damping_floors) {
            let start = least_squares(&structure.terms, record)?;
            let (theta, refinement) = refine(options.refinement, &structure.terms, start, record, *floor, observer)?;
            let error = simulate(&structure.terms, &theta, record)
                .map_or(f64::INFINITY, |y_hat| relative_error(&record.y, &y_hat));
            fit.coefficients.push(theta);
            fit.narx_errors.push(error);
            fit.refinements.push(refinement);
        }
        Ok(fit)
    }
}

pub(super) fn coupled(options: &CalibrationOptions, modes: usize) -> bool {
    options.narx.coupling_lags > 0 && modes > 1
}

/// Root mean square over every experiment and instant.
fn pooled_rms<'a>(series: impl Iterator<Item = &'a [f64]>, rest: impl Fn(usize) -> f64) -> f64 {
    let (mut sum, mut count) = (0.0, 0usize);
    for (e, s) in series.enumerate() {
        let r = rest(e);
        sum += s.iter().map(|v| (v - r) * (v - r)).sum::<f64>();
        count += s.len();
    }
    (sum / count as f64).sqrt().max(f64::MIN_POSITIVE)
}

/// Phase 1 done: the plan, with the selection experiments' histories kept for phase 3.
pub struct Planned {
    /// The plan every experiment's fit follows.
    pub plan: CalibrationPlan,
    pub(super) selection: Vec<Experiment>,
    /// Wall time of phase 1's stages (s).
    pub seconds: StageSeconds,
}

/// Phase 1 on this machine: [`select`], then every mode's structure.
pub fn plan(study: &Study, options: &CalibrationOptions, observer: &dyn Observer) -> Result<Planned> {
    let selection = select(study, options, observer)?;
    let stage = Instant::now();
    let structures = (0..selection.modes())
        .map(|mode| {
            check(observer)?;
            observer.progress(Progress::Structure { mode: mode + 1 });
            selection.structure(mode, options, observer)
        })
        .collect::<Result<_>>()?;
    Ok(selection.planned(structures, stage.elapsed().as_secs_f64()))
}

/// Phase 1 up to the structures: the selection experiments run, the deviations' scales and the
/// dampers' law decided, and what each mode's structure is chosen on. (Cloned only when a
/// task still holds it as the job goes on, which is rare.)
#[derive(Clone)]
pub struct Selection {
    /// The plan so far: every field but `structures`, which is empty.
    pub plan: CalibrationPlan,
    experiments: Vec<Experiment>,
    /// Per selection experiment, every mode's record.
    records: Vec<Vec<Record>>,
    /// Wall time of the selection experiments (s).
    pub seconds: StageSeconds,
}

/// The design, the selection experiments through the reference (in parallel), the deviations'
/// scales and the dampers' law.
pub fn select(study: &Study, options: &CalibrationOptions, observer: &dyn Observer) -> Result<Selection> {
    options.check()?;
    let started = Instant::now();
    let design = design(study, options)?.points;
    let k = design.len();
    let stride = (k as f64 / options.selection_experiments.min(k) as f64).max(1.0);
    let selection: Vec<usize> =
        (0..options.selection_experiments.min(k)).map(|i| (i as f64 * stride) as usize).collect();
    let experiments = run_selection(study, options, &design, &selection, observer)?;
    let seconds = StageSeconds { experiments: started.elapsed().as_secs_f64(), ..Default::default() };
    // The NARX works on deviations from the static state at rest under the mean load: y′ = y − y(0),
    // Q′ = Q − Q̄. Polynomial terms then act on the fluctuation, and the static level (a smooth
    // function of the inputs) gets its own expansion instead of hiding in a constant.
    let modes = study.modes.count();
    let scales: Vec<(f64, f64)> = (0..modes)
        .map(|m| {
            let y = pooled_rms(experiments.iter().map(|e| &e.y[m][..]), |e| experiments[e].y[m][0]);
            let q = pooled_rms(experiments.iter().map(|e| &e.q[m][..]), |e| experiments[e].q_mean[m]);
            (y, q)
        })
        .collect();
    let nonlinear_dampers = study.damper_exponent != 1.0 && !study.structure.dampers.is_empty();
    let damper_law = (nonlinear_dampers && options.narx.damper_terms).then(|| DamperLaw {
        exponent: study.damper_exponent,
        knees: (0..modes)
            .map(|m| {
                let (sum, count) = experiments.iter().fold((0.0, 0usize), |(sum, count), e| {
                    let squares: f64 = e.y[m].windows(2).map(|w| (w[1] - w[0]).powi(2)).sum();
                    (sum + squares, count + e.y[m].len() - 1)
                });
                (KNEE_FRACTION * (sum / count as f64).sqrt() / scales[m].0).max(1e-100)
            })
            .collect(),
    });
    let plan = CalibrationPlan { design, selection, scales, structures: Vec::new(), damper_law };
    Ok(Selection::of(plan, experiments, options, seconds))
}

/// Experiments `selection` of `design` through the reduced-order reference, in parallel batches.
fn run_selection(
    study: &Study,
    options: &CalibrationOptions,
    design: &[Vec<f64>],
    selection: &[usize],
    observer: &dyn Observer,
) -> Result<Vec<Experiment>> {
    let (done, total) = (AtomicUsize::new(0), design.len());
    let experiments: Vec<Vec<Experiment>> = selection
        .par_chunks(LANES)
        .map_init(TransformWorkspace::default, |workspace, chunk| {
            check(observer)?;
            let experiments = Experiment::run_batch(study, options, design, chunk, workspace, observer)?;
            for _ in chunk {
                observer.progress(Progress::Experiments { done: done.fetch_add(1, Ordering::Relaxed) + 1, total });
            }
            Ok(experiments)
        })
        .collect::<Result<_>>()?;
    Ok(experiments.into_iter().flatten().collect())
}

impl Selection {
    fn of(
        plan: CalibrationPlan,
        experiments: Vec<Experiment>,
        options: &CalibrationOptions,
        seconds: StageSeconds,
    ) -> Selection {
        let law = plan.damper_law.clone().map(Arc::new);
        let coupled = coupled(options, plan.scales.len());
        let records = experiments.iter().map(|e| e.records(&plan.scales, coupled, law.as_ref())).collect();
        Selection { plan, experiments, records, seconds }
    }

    /// The selection of `plan` (as [`select`] decided it on this study and these options) on a
    /// machine that does not hold it: its experiments run again, the same histories to the bit.
    pub fn rerun(
        study: &Study,
        options: &CalibrationOptions,
        plan: &CalibrationPlan,
        observer: &dyn Observer,
    ) -> Result<Selection> {
        let plan = CalibrationPlan { structures: Vec::new(), ..plan.clone() };
        let experiments = run_selection(study, options, &plan.design, &plan.selection, observer)?;
        Ok(Selection::of(plan, experiments, options, StageSeconds::default()))
    }

    /// The number of modes.
    pub fn modes(&self) -> usize {
        self.plan.scales.len()
    }

    /// Mode `mode`'s NARX structure, chosen on the selection experiments.
    pub fn structure(
        &self,
        mode: usize,
        options: &CalibrationOptions,
        observer: &dyn Observer,
    ) -> Result<StructureChoice> {
        if mode >= self.modes() {
            return Err(Error::invalid("mode", format!("the study has {} modes, not {}", self.modes(), mode + 1)));
        }
        let chosen: Vec<Record> = self.records.iter().map(|r| r[mode].clone()).collect();
        let dictionary = options.narx.dictionary(mode, self.modes(), self.plan.damper_law.is_some());
        select_structure(&dictionary, &chosen, &chosen, options.narx.max_terms, observer)
    }

    /// Phase 1 done with these structures, chosen in `seconds`.
    pub fn planned(self, structures: Vec<StructureChoice>, seconds: f64) -> Planned {
        let plan = CalibrationPlan { structures, ..self.plan };
        Planned { plan, selection: self.experiments, seconds: StageSeconds { structure: seconds, ..self.seconds } }
    }
}

impl Planned {
    /// Phase 2 for the selection experiments, whose histories are at hand.
    pub fn fit_selection(&self, options: &CalibrationOptions, observer: &dyn Observer) -> Result<Vec<ExperimentFit>> {
        self.selection
            .par_iter()
            .zip(&self.plan.selection)
            .map(|(experiment, &index)| {
                check(observer)?;
                experiment.fit(index, &self.plan, options, observer)
            })
            .collect()
    }
}

/// Phase 2: experiments `indices` of the plan through the reference and the NARX fit, in parallel.
/// `done_before` experiments of the design were done already (for progress reports).
pub fn fit_experiments(
    study: &Study,
    options: &CalibrationOptions,
    plan: &CalibrationPlan,
    indices: &[usize],
    done_before: usize,
    observer: &dyn Observer,
) -> Result<Vec<ExperimentFit>> {
    let done = AtomicUsize::new(done_before);
    let total = plan.design.len();
    let fits: Vec<Vec<ExperimentFit>> = indices
        .par_chunks(LANES)
        .map_init(TransformWorkspace::default, |workspace, chunk| {
            check(observer)?;
            let experiments = Experiment::run_batch(study, options, &plan.design, chunk, workspace, observer)?;
            experiments
                .iter()
                .zip(chunk)
                .map(|(experiment, &k)| {
                    let fit = experiment.fit(k, plan, options, observer)?;
                    observer.progress(Progress::Experiments { done: done.fetch_add(1, Ordering::Relaxed) + 1, total });
                    Ok(fit)
                })
                .collect()
        })
        .collect::<Result<_>>()?;
    Ok(fits.into_iter().flatten().collect())
}
