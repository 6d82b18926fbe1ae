//! The metamodel as a value: everything needed to reproduce its predictions, serialisable and
//! versioned.

use super::Parametrization;
use super::damper_law::DamperLaw;
use super::narx::{DamperTerm, NarxTerm};
use super::options::CalibrationOptions;
use super::pce::SparsePce;
use super::refine::RefinementSummary;
use crate::error::{Error, Result};
use crate::study::{Study, StudySpec, WIND_SPEED};
use serde::{Deserialize, Serialize};
use std::sync::OnceLock;

pub const FORMAT: &str = "windmeta-pc-narx";
/// Version 2 names the study `study`; version 1 named it `problem` and is read as well.
pub const FORMAT_VERSION: u32 = 2;
/// The oldest version this build reads.
const OLDEST_READABLE_VERSION: u32 = 1;

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
    /// Scale of the NARX's input deviation Q − Q̄ (N).
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
    /// Expansion of the static gain or level over the standard-space inputs.
    pub expansion: SparsePce,
}

impl StaticResponse {
    /// The static modal displacement (m) at the standard-space point `xi` under the mean modal
    /// force `mean_load` (N).
    pub fn evaluate(&self, xi: &[f64], mean_load: f64) -> f64 {
        let value = self.expansion.evaluate(xi);
        if self.per_unit_mean_load { value * mean_load } else { value }
    }
}

/// Roof-normalised modes the metamodel was calibrated on (shapes fixed across samples).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct ModalBasis {
    /// Natural circular frequency of each mode (rad/s).
    pub frequencies_rad_s: Vec<f64>,
    /// Generalized mass of each mode (kg).
    pub modal_masses_kg: Vec<f64>,
    /// `shapes[mode][floor]`.
    pub shapes: Vec<Vec<f64>>,
}

/// What the calibration measured about one mode.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct ModeDiagnostics {
    /// The mode, 1-based.
    pub mode: usize,
    /// The chosen NARX terms, written out.
    pub selected_terms: Vec<String>,
    /// Distinct candidate structures the selection evaluated.
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
    /// How the refinements of the experiments' coefficients on the simulation error ended.
    #[serde(default)]
    pub refinement: RefinementSummary,
}

/// How the metamodel came about and how well it fits its own experiments.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct CalibrationSummary {
    /// The options the metamodel was calibrated with.
    pub options: CalibrationOptions,
    /// What the calibration measured about each mode.
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
    /// The calibration end to end.
    pub total: f64,
}

/// Where the wind speed's expansions are continued outside the calibration design: the input's
/// index and the design's lowest, median and highest speeds with their germs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct WindContinuation {
    index: usize,
    lowest: SpeedGerm,
    median: SpeedGerm,
    highest: SpeedGerm,
}

/// A wind speed (m/s) and its germ.
#[derive(Debug, Clone, Copy, PartialEq)]
struct SpeedGerm {
    speed: f64,
    germ: f64,
}

/// The germ at which the expansions are evaluated, as a weighted sum of points: one point
/// inside the design, two for a linear continuation outside it.
pub type Germ = Vec<(f64, Vec<f64>)>;

/// A calibrated PC-NARX metamodel.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct Metamodel {
    /// Always `windmeta-pc-narx`: what the file is.
    pub format: String,
    /// Version of the file format; files of every version since 1 are read.
    pub version: u32,
    /// The study, fully resolved: rebuilding it gives the same inputs, modes, wind and storm grid.
    #[serde(alias = "problem")]
    pub study: StudySpec,
    /// The modes the metamodel was calibrated on.
    pub modes: ModalBasis,
    /// One model per retained mode, in mode order.
    pub models: Vec<ModeModel>,
    /// The law of the models' velocity terms; absent where they have none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub damper_law: Option<DamperLaw>,
    /// How the metamodel was calibrated and how well it fits its experiments.
    pub calibration: CalibrationSummary,
    /// Where the wind speed's expansions are continued below the design, found once (see
    /// [`Metamodel::germ`]); `None` where the study has no random wind speed.
    #[serde(skip)]
    #[cfg_attr(feature = "openapi", schema(ignore))]
    pub(super) wind_continuation: OnceLock<Option<WindContinuation>>,
}

impl Metamodel {
    /// Every term reads a mode the file has, every damper term a velocity of steps already run, and
    /// a file whose models read the dampers' law carries it, with a knee for every mode: what the
    /// free run indexes by.
    fn check_terms(&self) -> Result<()> {
        let modes = self.models.len();
        if let Some(term) =
            self.models.iter().flat_map(|m| &m.terms).find(|t| t.output_mode.is_some_and(|j| j >= modes))
        {
            return Err(Error::invalid("metamodel", format!("the term {term} reads a mode the file does not have")));
        }
        // A velocity is a first difference of steps already run; the free run computes each step's
        // secants before the step's outputs.
        if let Some(term) = self.models.iter().flat_map(|m| &m.terms).find(|t| t.damper.is_some() && t.output_lag == 0)
        {
            return Err(Error::invalid(
                "metamodel",
                format!("the damper term {term} reads a lag of 0; they start at 1"),
            ));
        }
        let reads_law = self.models.iter().flat_map(|m| &m.terms).any(|t| t.damper.is_some());
        match &self.damper_law {
            None if reads_law => Err(Error::invalid("metamodel", "its models have damper terms but no damper_law")),
            Some(law)
                if !(law.exponent.is_finite() && law.exponent > 0.0 && law.exponent <= 2.0)
                    || law.knees.len() != modes
                    || !law.knees.iter().all(|k| k.is_finite() && *k > 0.0) =>
            {
                Err(Error::invalid(
                    "metamodel",
                    format!("damper_law needs an exponent in (0, 2] and {modes} finite positive knees"),
                ))
            }
            _ => Ok(()),
        }
    }

    /// Reads a metamodel and checks that this build can use it.
    pub fn from_json(text: &str) -> Result<Metamodel> {
        let value: serde_json::Value =
            serde_json::from_str(text).map_err(|e| Error::invalid("metamodel", format!("not JSON: {e}")))?;
        if value.get("format").and_then(|f| f.as_str()) != Some(FORMAT) {
            return Err(Error::invalid("metamodel", format!("not a {FORMAT} file")));
        }
        match value.get("version").and_then(|v| v.as_u64()) {
            Some(v) if (OLDEST_READABLE_VERSION as u64..=FORMAT_VERSION as u64).contains(&v) => {}
            other => {
                return Err(Error::invalid(
                    "metamodel",
                    format!(
                        "version {other:?} is not supported (this build reads {OLDEST_READABLE_VERSION} to {FORMAT_VERSION})"
                    ),
                ));
            }
        }
        let mut metamodel: Metamodel =
            serde_json::from_value(value).map_err(|e| Error::invalid("metamodel", e.to_string()))?;
        metamodel.check_terms()?;
        // Read, it is of this build's format: written again, it says so.
        metamodel.version = FORMAT_VERSION;
        Ok(metamodel)
    }

    /// Rebuilds the study the metamodel was calibrated on.
    pub fn study(&self) -> Result<Study> {
        Study::from_spec(&self.study)
    }

    /// The lowest and highest value of a named input over the calibration's experiments: where
    /// the expansions were fitted, beyond which they extrapolate.
    pub fn calibrated_range(&self, study: &Study, name: &str) -> Result<[f64; 2]> {
        let index = study.inputs.index_of(name)?;
        let design = super::design(study, &self.calibration.options)?.points;
        let values = design.iter().map(|x| x[index]);
        Ok([values.clone().fold(f64::INFINITY, f64::min), values.fold(f64::NEG_INFINITY, f64::max)])
    }

    /// The expansions' germ at a physical sample: every input's ξ from its marginal, except for a
    /// wind speed below the calibration design's lowest. The Fréchet germ's lower tail is so thin
    /// that ξ is −21 at 18 m/s, where a polynomial of degree 3 to 5 means nothing (validation
    /// failed at 20 and 10 m/s). There every expansion is continued linearly in ln v along the
    /// secant from the design's median speed to its lowest, the other inputs' germs the sample's:
    /// the load falls as v² and the dampers' equivalent damping, a power of the amplitude, is
    /// linear in ln v, and so are the logarithmic coefficients the expansions are of. Measured
    /// from a design starting at 24 m/s (docs/method.md): median peak error 0.9 % at 10 m/s,
    /// against 2.5 % with the coefficients held at the lowest speed's. Above the design the germ
    /// grows slowly (the upper tail is heavy) and the paper dictionary's expansions extrapolate as
    /// they are; those of models with the dampers' law terms do not (at 60 m/s, from a design up to
    /// 46 m/s, median peak roof displacement error 3.4 %, correlation 0.85) and are continued the
    /// same way along the secant from the median speed to the highest (1.1 %, 0.988; both with the
    /// law's knee at 0.3 of the design's first differences, 0.24 % with today's 0.1). The paper
    /// dictionary's are not: continued, their displacement's and RMS acceleration's errors grew
    /// (docs/method.md). Models with the own velocity at another mode's secant hold their
    /// coefficients at the design's highest speed instead: continued, the linear parts' damping,
    /// which grows about as v² over the design while the secant terms' falls, over-damped modes 2
    /// and 3 (at 60 m/s, from a design up to 46 m/s, the peak roof acceleration's mean 0.966 of
    /// the reference's; held, 0.979).
    ///
    /// The continuation's speeds are found once per metamodel, from its design (the design
    /// is a function of the calibration's options).
    pub fn germ(&self, study: &Study, x: &[f64]) -> Germ {
        let xi = study.inputs.to_standard(x);
        let continuation = self.wind_continuation.get_or_init(|| self.find_wind_continuation(study));
        let along = |from: SpeedGerm, to: SpeedGerm, index: usize| {
            let toward = (x[index] / from.speed).ln() / (to.speed / from.speed).ln();
            let mut at_from = xi.clone();
            at_from[index] = from.germ;
            let mut at_to = xi.clone();
            at_to[index] = to.germ;
            vec![(1.0 - toward, at_from), (toward, at_to)]
        };
        match *continuation {
            Some(WindContinuation { index, lowest, median, .. }) if x[index] < lowest.speed => {
                along(lowest, median, index)
            }
            Some(WindContinuation { index, median, highest, .. })
                if x[index] > highest.speed && self.damper_law.is_some() =>
            {
                if self.has_secant_terms() {
                    let mut at_highest = xi;
                    at_highest[index] = highest.germ;
                    vec![(1.0, at_highest)]
                } else {
                    along(median, highest, index)
                }
            }
            _ => vec![(1.0, xi)],
        }
    }

    /// Whether a mode's structure has the own velocity at another mode's secant
    /// ([`DamperTerm::Modulated`]).
    pub fn has_secant_terms(&self) -> bool {
        self.models.iter().flat_map(|m| &m.terms).any(|t| t.damper == Some(DamperTerm::Modulated))
    }

    /// The lowest, median and highest wind speeds of the design, with their germs (see
    /// [`Metamodel::germ`]). A design that covers a range of speeds weights its experiments to the
    /// input model (w = f/g), so those below where the input model's own design of the same size
    /// reaches weigh next to nothing, and there the germ is far out in the Fréchet's thin lower
    /// tail (−10.9 at 20 m/s): its lowest and median speeds are those of the input model's own
    /// design, and only the highest is the covered one. (Evaluated as they were, a design covering
    /// 18-62 m/s gave at 20 m/s a mean peak roof acceleration 2.5 times the reference's.)
    fn find_wind_continuation(&self, study: &Study) -> Option<WindContinuation> {
        let index = study.inputs.index_of(WIND_SPEED).ok()?;
        let speeds_of = |options: &super::CalibrationOptions| -> Option<Vec<f64>> {
            let mut speeds: Vec<f64> = super::design(study, options).ok()?.points.iter().map(|x| x[index]).collect();
            speeds.sort_by(f64::total_cmp);
            Some(speeds)
        };
        let options = &self.calibration.options;
        let covered = speeds_of(options)?;
        let uncovered = match options.cover_wind_speeds {
            Some(_) => Some(speeds_of(&super::CalibrationOptions { cover_wind_speeds: None, ..options.clone() })?),
            None => None,
        };
        let input_model = uncovered.as_ref().unwrap_or(&covered);
        let marginal = &study.inputs.inputs[index].marginal;
        let at = |speed: f64| SpeedGerm { speed, germ: marginal.to_standard(speed) };
        let lowest = at(input_model.first()?.max(*covered.first()?));
        let (median, highest) = (at(input_model[input_model.len() / 2]), at(*covered.last()?));
        let usable = lowest.germ.is_finite()
            && median.germ.is_finite()
            && highest.germ.is_finite()
            && median.speed > lowest.speed
            && highest.speed > median.speed;
        usable.then_some(WindContinuation { index, lowest, median, highest })
    }

    /// The NARX coefficients of every mode at a sample's germ ([`Metamodel::germ`]).
    pub fn coefficients(&self, germ: &Germ) -> Vec<Vec<f64>> {
        self.models
            .iter()
            .map(|m| {
                let phi: Vec<f64> = m.coefficients.iter().map(|pce| blend(germ, |xi| pce.evaluate(xi))).collect();
                m.parametrization.inverse(&m.terms, &phi)
            })
            .collect()
    }
}

/// An expansion's value at a germ: the weighted sum of its values at the germ's points.
pub(super) fn blend(germ: &Germ, f: impl Fn(&[f64]) -> f64) -> f64 {
    germ.iter().map(|(w, xi)| w * f(xi)).sum()
}
