//! What users read off many storms: peak statistics, exceedance curves with confidence bands,
//! annual curves and return levels under a wind climate, fragility curves, Sobol indices, and the
//! validation of a metamodel against the reference.

mod annual_sample;
mod certified_hazard;
mod certify;
mod climate;
mod demands;
mod exceedance;
mod fragility;
mod hazard;
mod motion_peaks;
mod peaks;
mod plot;
mod profile;
mod reference;
mod reference_storms;
mod response;
mod sampling;
mod serviceability;
mod sobol;
mod strata;
mod sweep;
mod validated_responses;
mod validation;

pub use certified_hazard::HazardCertification;
pub use certify::{
    Certification, CertifiedCurve, CertifyOptions, MAX_REFERENCE_STORMS, certified_curve, certify_exceedance,
    check_reference_storms, exceedance_figure,
};
pub use climate::{
    ClimateCoverage, ClimateSpec, annual_probability_of_period, climate_or_own, period_of_annual_probability,
};
pub use demands::{Demands, metamodel_demands};
pub use exceedance::{
    ExceedanceCurve, MAX_THRESHOLD, MAX_THRESHOLDS, automatic_thresholds, check_confidence, check_thresholds,
    exceedance_csv, exceedance_curve, max_exceedance_gap,
};
pub use fragility::{
    Fragility, FragilityCurve, FragilityOptions, LognormalFragility, MAX_WIND_SPEEDS, fragility, metamodel_fragility,
};
pub use hazard::{
    DEFAULT_RETURN_PERIODS, HazardCurve, HazardOptions, MAX_RETURN_PERIOD, Reliability, ReturnLevel, WIND_SPEED,
    hazard_curve, metamodel_hazard,
};
pub use peaks::{PeakSummary, pearson, quantile};
pub use plot::{exceedance_svg, fragility_svg, hazard_svg, profile_svg, serviceability_svg, sweep_svg, validation_svg};
pub use profile::{PeakProfile, ProfileSamples, check_quantile, metamodel_profiles, profile_responses};
pub use reference::{reference_history, reference_peak};
pub use reference_storms::{
    OnThisMachine, PairedPeak, PairedRuns, ReferenceRunner, paired_peaks, paired_peaks_at, reference_storm_seed,
};
pub use response::{Response, ResponseKind, ResponseName, ResponseView, STANDARD_GRAVITY};
pub use sampling::{
    DivergedStorm, Draws, MAX_SAMPLES, OnDivergence, check_samples, describe_diverged, metamodel_peaks, peaks_at,
};
pub use serviceability::{
    BUILT_IN, Criterion, CriterionCheck, CriterionChoice, FailureMode, LevelProfile, RiskCategory, Serviceability,
    ServiceabilityOptions, Statistic, StrengthCheck, StrengthTarget, Verdict, built_in, metamodel_serviceability,
};
pub use sobol::{STORM_GROUP, Sensitivity, SobolIndex, metamodel_sensitivity, sobol_indices};
pub use strata::Sampling;
pub use sweep::{MAX_SWEEP_VALUES, Sweep, SweepOptions, SweepPoint, metamodel_sweep};
pub use validated_responses::ResponseValidation;
pub use validation::{ValidationReport, validate};
