//! What users read off many storms: peak statistics, exceedance curves with confidence bands,
//! annual curves and return levels under a wind climate, fragility curves, Sobol indices, design
//! checks, and the validation of a metamodel against the reference.
//!
//! The files are grouped in rooms, each importing only the rooms listed before it (and the files
//! of a room form no cycle either), so that what an answer is built on can be read from the bottom
//! up:
//!
//! 1. `responses`: the physical responses and how a storm's motion is read into them and into
//!    peaks (the metamodel's batches, the reference model's histories).
//! 2. `sampling`: storms drawn and run through the metamodel (or through both models), the wind
//!    climate, and the estimators of what the storms say (exceedance curves and their bands,
//!    stratified annual probabilities).
//! 3. `certification`: the metamodel's estimates corrected by storms through both models.
//! 4. `answers`: the analyses a user asks for, each with its options and `metamodel_*` entry
//!    point (exceedance, annual, fragility, profile, sensitivity, demands).
//! 5. `validation`: a metamodel against the reference model on fresh storms.
//! 6. `design`: serviceability checks and sweeps, built on the annual answers.
//! 7. `writers`: the answers as SVG figures and CSV tables; no analysis depends on them.
//!
//! Code outside this module uses the names re-exported here, never a room's path.

mod answers;
mod certification;
mod design;
mod responses;
mod sampling;
mod validation;
mod writers;

pub use answers::demands::{Demands, metamodel_demands};
pub use answers::exceedance::{Exceedance, ExceedanceOptions, metamodel_exceedance};
pub use answers::fragility::{
    Fragility, FragilityCurve, FragilityOptions, LognormalFragility, MAX_WIND_SPEEDS, fragility, metamodel_fragility,
};
pub use answers::hazard::{
    DEFAULT_RETURN_PERIODS, HazardCurve, HazardOptions, MAX_RETURN_PERIOD, Reliability, ReturnLevel, WIND_SPEED,
    hazard_curve, metamodel_hazard,
};
pub use answers::profile::{PeakProfile, ProfileSamples, check_quantile, metamodel_profiles, profile_responses};
pub use answers::sobol::{STORM_GROUP, Sensitivity, SobolIndex, metamodel_sensitivity, sobol_indices};
pub use certification::certified_hazard::HazardCertification;
pub use certification::certify::{
    Certification, CertifiedCurve, CertifyOptions, MAX_REFERENCE_STORMS, certified_curve, certify_exceedance,
    check_reference_storms,
};
pub use design::serviceability::{
    BUILT_IN, Criterion, CriterionCheck, CriterionChoice, FailureMode, LevelProfile, RiskCategory, Serviceability,
    ServiceabilityOptions, Statistic, StrengthCheck, StrengthTarget, Verdict, built_in, metamodel_serviceability,
};
pub use design::sweep::{MAX_SWEEP_VALUES, Sweep, SweepOptions, SweepPoint, metamodel_sweep};
pub use responses::peaks::{PeakSummary, pearson, quantile};
pub use responses::reference::{reference_history, reference_peak};
pub use responses::response::{Response, ResponseKind, ResponseName, ResponseView, STANDARD_GRAVITY};
pub use responses::spatial::{SpatialKind, SpatialResponse};
pub use sampling::climate::{
    ClimateCoverage, ClimateSpec, annual_probability_of_period, climate_or_own, period_of_annual_probability,
};
pub use sampling::draws::{
    DivergedStorm, Draws, MAX_SAMPLES, OnDivergence, OnThisMachine, check_samples, describe_diverged,
    floor_peak_sets_at, held_inputs, metamodel_peaks, peaks_at,
};
pub use sampling::exceedance::{
    ExceedanceCurve, MAX_THRESHOLD, MAX_THRESHOLDS, automatic_thresholds, check_confidence, check_thresholds,
    exceedance_curve, max_exceedance_gap,
};
pub use sampling::reference_storms::{PairedPeak, PairedRuns, paired_peaks, paired_peaks_at, reference_storm_seed};
pub use sampling::runner::StormRunner;
pub use sampling::strata::Sampling;
pub use validation::validate::{ValidationReport, validate};
pub use validation::validated_responses::ResponseValidation;
pub use writers::csv::exceedance_csv;
pub use writers::plot::{
    exceedance_figure, exceedance_svg, fragility_svg, hazard_svg, profile_svg, serviceability_svg, sweep_svg,
    validation_svg,
};
