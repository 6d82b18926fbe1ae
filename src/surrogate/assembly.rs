//! Phase 3 of the calibration (see `phases`): the sparse polynomial chaos expansions of every
//! experiment's coefficients and static level over the inputs, fitted all at once wherever the
//! caller runs them ([`fit_expansions`] on this machine's cores, or spread over replicas), then
//! the PC-NARX error on the selection experiments, the diagnostics and the metamodel.

use super::Parametrization;
use super::identify::{Record, simulate};
use super::metamodel::{
    CalibrationSummary, FORMAT, FORMAT_VERSION, Metamodel, ModalBasis, ModeDiagnostics, ModeModel, StageSeconds,
    StaticResponse,
};
use super::narx::{NarxTerm, relative_error};
use super::options::CalibrationOptions;
use super::pce::SparsePce;
use super::phases::{ExperimentFit, Planned, coupled};
use super::refine::RefinementSummary;
use crate::error::{Error, Result};
use crate::progress::{Observer, Progress, check};
use crate::study::Study;
use rayon::prelude::*;
use std::sync::Arc;
use std::time::Instant;

/// The targets of one mode's expansions: its static level per unit mean load (or as it is, where
/// some experiment has next to none) and its coefficients in the chosen parametrization, by
/// experiment.
struct ModeTargets {
    per_unit_mean_load: bool,
    parametrization: Parametrization,
    /// The static level's targets, then each coefficient's.
    targets: Vec<Vec<f64>>,
}

impl ModeTargets {
    fn of(fits: &[ExperimentFit], mode: usize, terms: &[NarxTerm], options: &CalibrationOptions) -> ModeTargets {
        let largest_load = fits.iter().map(|f| f.mean_load[mode].abs()).fold(0.0, f64::max);
        let per_unit_mean_load = fits.iter().all(|f| f.mean_load[mode].abs() > 1e-6 * largest_load);
        let static_targets: Vec<f64> = fits
            .iter()
            .map(|f| {
                let y0 = f.static_displacement[mode];
                if per_unit_mean_load { y0 / f.mean_load[mode] } else { y0 }
            })
            .collect();
        let thetas: Vec<Vec<f64>> = fits.iter().map(|f| f.coefficients[mode].clone()).collect();
        let parametrization = options.parametrization.unwrap_or_else(|| Parametrization::choose(terms, &thetas));
        let expanded: Vec<Vec<f64>> = thetas.iter().map(|theta| parametrization.forward(terms, theta)).collect();
        let mut targets = vec![static_targets];
        targets.extend((0..terms.len()).map(|i| expanded.iter().map(|phi| phi[i]).collect()));
        ModeTargets { per_unit_mean_load, parametrization, targets }
    }
}

/// The sparse polynomial chaos expansion of each of `targets` (one value per experiment of
/// `design`) over the study's inputs, on this machine's cores.
pub fn fit_expansions(
    study: &Study,
    options: &CalibrationOptions,
    design: &[Vec<f64>],
    targets: &[Vec<f64>],
    observer: &dyn Observer,
) -> Result<Vec<SparsePce>> {
    let xi: Vec<Vec<f64>> = design.iter().map(|x| study.inputs.to_standard(x)).collect();
    let weights = super::design::design(study, options)?.weights;
    if weights.len() != xi.len() {
        return Err(Error::Numerical("the plan's design is not the options' design".into()));
    }
    targets.par_iter().map(|t| SparsePce::fit(&study.inputs, &xi, t, &weights, &options.pce, observer)).collect()
}

/// Fits expansions as [`fit_expansions`] does, wherever it runs them.
pub type ExpansionFitter<'a> = dyn Fn(&[Vec<f64>]) -> Result<Vec<SparsePce>> + 'a;

/// Phase 3: the expansions of every experiment's coefficients and static level over the inputs
/// (fitted by `expand`, every mode's at once), the PC-NARX error on the selection experiments, and
/// the metamodel. `fits` holds every experiment of the design, in any order.
pub fn assemble(
    study: &Study,
    options: &CalibrationOptions,
    planned: &Planned,
    mut fits: Vec<ExperimentFit>,
    mut seconds: StageSeconds,
    expand: &ExpansionFitter,
    observer: &dyn Observer,
) -> Result<Metamodel> {
    let started = Instant::now();
    let plan = &planned.plan;
    fits.sort_by_key(|f| f.index);
    if fits.iter().map(|f| f.index).ne(0..plan.design.len()) {
        return Err(Error::Numerical("assembling needs one fit of every experiment of the design".into()));
    }
    let xi: Vec<Vec<f64>> = plan.design.iter().map(|x| study.inputs.to_standard(x)).collect();
    let modes = plan.structures.len();
    let law = plan.damper_law.clone().map(Arc::new);
    let selection_records: Vec<Vec<Record>> =
        planned.selection.iter().map(|e| e.records(&plan.scales, coupled(options, modes), law.as_ref())).collect();
    let targets: Vec<ModeTargets> =
        plan.structures.iter().enumerate().map(|(mode, s)| ModeTargets::of(&fits, mode, &s.terms, options)).collect();
    observer.progress(Progress::Expansion { mode: 1 });
    let mut expansions = expand(&targets.iter().flat_map(|t| t.targets.clone()).collect::<Vec<_>>())?.into_iter();
    let mut models = Vec::new();
    let mut diagnostics = Vec::new();
    for (mode, ModeTargets { per_unit_mean_load, parametrization, .. }) in targets.into_iter().enumerate() {
        check(observer)?;
        observer.progress(Progress::Expansion { mode: mode + 1 });
        let (output_scale, input_scale) = plan.scales[mode];
        let structure = &plan.structures[mode];
        let terms = structure.terms.clone();
        let missing = || Error::Internal("fewer expansions came back than were asked for".into());
        let static_response = StaticResponse { per_unit_mean_load, expansion: expansions.next().ok_or_else(missing)? };
        let expansions: Vec<SparsePce> = expansions.by_ref().take(terms.len()).collect();
        if expansions.len() != terms.len() {
            return Err(missing());
        }
        let pc_errors: Vec<f64> = planned
            .selection
            .par_iter()
            .zip(&plan.selection)
            .zip(&selection_records)
            .map(|((experiment, &index), records)| {
                let phi: Vec<f64> = expansions.iter().map(|pce| pce.evaluate(&xi[index])).collect();
                let theta = parametrization.inverse(&terms, &phi);
                let level = static_response.evaluate(&xi[index], experiment.q_mean[mode]);
                simulate(&terms, &theta, &records[mode]).map_or(f64::INFINITY, |y_hat| {
                    let full: Vec<f64> = y_hat.iter().map(|v| level + v * output_scale).collect();
                    relative_error(&experiment.y[mode], &full)
                })
            })
            .collect();
        let narx_errors: Vec<f64> = fits.iter().map(|f| f.narx_errors[mode]).collect();
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
            refinement: RefinementSummary::of(
                &fits.iter().filter_map(|f| f.refinements.get(mode).copied().flatten()).collect::<Vec<_>>(),
            ),
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
    seconds.expansion = started.elapsed().as_secs_f64();
    seconds.total = seconds.experiments + seconds.structure + seconds.coefficients + seconds.expansion;
    let count = diagnostics.len() as f64;
    let modes = &study.modes;
    Ok(Metamodel {
        format: FORMAT.into(),
        version: FORMAT_VERSION,
        study: study.resolved_spec(),
        modes: ModalBasis {
            frequencies_rad_s: modes.frequencies.clone(),
            modal_masses_kg: modes.modal_masses.clone(),
            shapes: (0..modes.count()).map(|m| modes.shapes.col(m).iter().copied().collect()).collect(),
        },
        models,
        damper_law: plan.damper_law.clone(),
        calibration: CalibrationSummary {
            options: options.clone(),
            narx_mean_relative_error: diagnostics.iter().map(|d| d.narx_mean_relative_error).sum::<f64>() / count,
            pc_narx_mean_relative_error: diagnostics.iter().map(|d| d.pc_narx_mean_relative_error).sum::<f64>() / count,
            modes: diagnostics,
            seconds,
        },
        wind_continuation: Default::default(),
    })
}
