//! What users read off many storms: peak statistics, and later exceedance curves and validation.

mod peaks;

pub use peaks::{PeakSummary, quantile};
