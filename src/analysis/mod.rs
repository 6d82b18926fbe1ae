//! What users read off many storms: peak statistics, exceedance curves with confidence bands, and
//! the validation of a metamodel against the reference.

mod exceedance;
mod peaks;
mod plot;
mod response;
mod validation;

pub use exceedance::{
    ExceedanceCurve, MAX_SAMPLES, automatic_thresholds, check_confidence, exceedance_curve, max_exceedance_gap,
    metamodel_peaks,
};
pub use peaks::{PeakSummary, quantile};
pub use plot::{exceedance_svg, validation_svg};
pub use response::Response;
pub use validation::{ValidationReport, validate};
