//! A serviceability check's certification: each criterion's governing floor corrected by storms
//! run through both the reference model and the metamodel, as an annual curve is
//! ([`crate::analysis::certification::certified_hazard`]).

use super::CriterionCheck;
use crate::analysis::answers::hazard::return_level;
use crate::analysis::certification::certified_hazard::PairedStrata;
use crate::analysis::certification::certify::CertifyOptions;
use crate::analysis::sampling::strata::StratifiedPeaks;
use crate::study::Order;
use serde::{Deserialize, Serialize};

/// A criterion's governing floor certified by storms through both models.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct CriterionCertification {
    /// The governing floor, the one certified.
    pub floor: usize,
    /// Storms run through both the reference model and the metamodel.
    pub reference_storms: usize,
    /// The reference model they were run through.
    pub order: Order,
    /// The metamodel's own level and band at that floor.
    pub metamodel_value: Option<f64>,
    /// The lower end of the metamodel's own band.
    pub metamodel_lower: Option<f64>,
    /// The upper end of the metamodel's own band.
    pub metamodel_upper: Option<f64>,
}

/// Replaces the governing floor's level and band by the certified ones and judges again.
pub(super) fn certify_governing(
    judged: &mut CriterionCheck,
    at: usize,
    column: &StratifiedPeaks,
    paired: &PairedStrata,
    certify: &CertifyOptions,
    confidence: f64,
) {
    let levels = paired.levels_with(column);
    let level =
        return_level(&levels, judged.return_period_years, |x| paired.exceedance(column, x, confidence).estimate);
    judged.certification = Some(CriterionCertification {
        floor: judged.governing_floor,
        reference_storms: certify.reference_storms,
        order: certify.order,
        metamodel_value: judged.value,
        metamodel_lower: judged.lower,
        metamodel_upper: judged.upper,
    });
    let profile = &mut judged.profile;
    (profile.values[at], profile.lower[at], profile.upper[at]) = (level.value, level.lower, level.upper);
    (judged.value, judged.lower, judged.upper) = (level.value, level.lower, level.upper);
    judged.utilisation = level.value.map(|v| v / judged.limit);
    if judged.strength.is_none() {
        judged.verdict = super::level_verdict(&judged.profile);
    }
}
