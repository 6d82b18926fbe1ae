//! A study as it arrives from a file or a request.

use crate::structure::CustomStructure;
use crate::structure::spatial::CustomSpatialStructure;
use crate::uncertainty::Marginal;
use crate::wind::WindSite;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// A study as it arrives from a file or a request; every field is optional, with the paper's values
/// as defaults.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(default, deny_unknown_fields)]
pub struct StudySpec {
    /// A preset name; ignored for the structure when `structure` is given.
    pub preset: Option<String>,
    /// A custom structure instead of the preset's.
    pub structure: Option<CustomStructure>,
    /// A custom three-dimensional building (sway along x and y and twist at every floor) instead
    /// of a three-dimensional preset's; the command line's `modes`, `simulate` and `sample-peaks`
    /// take it, calibrations do not yet.
    pub spatial_structure: Option<CustomSpatialStructure>,
    /// Marginals that replace the defaults, by input name.
    pub inputs: BTreeMap<String, Marginal>,
    /// The wind site; the paper's when absent.
    pub wind: Option<WindSite>,
    /// Exponent α of the damper law (0.38 in the paper).
    pub damper_exponent: Option<f64>,
    /// Retained modes N_m (3 in the paper).
    pub modes: Option<usize>,
    /// Storm duration T (s), 900 in the paper.
    pub duration_s: Option<f64>,
    /// Time step Δt (s), 0.01 in the paper.
    pub time_step_s: Option<f64>,
}
