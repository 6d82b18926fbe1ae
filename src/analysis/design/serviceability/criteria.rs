//! What a serviceability check judges: criteria a user defines or picks from the built-ins, each
//! a response's T-year level over a range of floors against a limit, and the reliability targets
//! of ASCE 7 that a strength criterion is judged against.

use crate::analysis::{Response, ResponseKind, STANDARD_GRAVITY};
use crate::error::{Error, Result};
use crate::structure::Structure;
use serde::{Deserialize, Serialize};
use statrs::distribution::{ContinuousCDF, Normal};

/// Most criteria one check may judge.
pub const MAX_CRITERIA: usize = 20;

/// Longest return period (years) a criterion may name (as an annual analysis's).
const MAX_RETURN_PERIOD: f64 = 1e6;

/// Which value of a storm a criterion judges.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(rename_all = "snake_case")]
pub enum Statistic {
    /// The storm's peak.
    #[default]
    Peak,
    /// The root mean square over the storm (accelerations only).
    Rms,
}

/// A check of a response's T-year level over a range of floors against a limit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(deny_unknown_fields)]
pub struct Criterion {
    /// The criterion's name in the answer (1 to 64 characters).
    #[cfg_attr(feature = "openapi", schema(min_length = 1, max_length = 64))]
    pub name: String,
    /// `displacement`, `drift`, `acceleration`, `damper_force` or `damper_stroke` (an RMS
    /// acceleration is `acceleration` with `statistic` `rms`).
    pub response: ResponseKind,
    /// Which value of each storm is judged: its peak (the default) or, for an acceleration, its RMS.
    #[serde(default)]
    pub statistic: Statistic,
    /// The return period (years, from 1 to 10⁶) whose level is judged: the level exceeded in a year
    /// with probability 1 − exp(−1/T).
    #[cfg_attr(feature = "openapi", schema(minimum = 1, maximum = 1000000))]
    pub return_period_years: f64,
    /// The limit in SI: m/s² for accelerations, m for displacements, drifts and strokes, N for
    /// damper forces. Give this or `limit_per_storey_height`.
    #[serde(default)]
    #[cfg_attr(feature = "openapi", schema(exclusive_minimum = 0, maximum = 1e9))]
    pub limit: Option<f64>,
    /// For drift: the limit as a fraction of each storey's height (1/400 = 0.0025), instead of
    /// `limit`.
    #[serde(default)]
    #[cfg_attr(feature = "openapi", schema(exclusive_minimum = 0, maximum = 1))]
    pub limit_per_storey_height: Option<f64>,
    /// The lowest and highest floors judged (1-based, inclusive); every floor where the response
    /// exists when absent.
    #[serde(default)]
    #[cfg_attr(feature = "openapi", schema(min_items = 2, max_items = 2))]
    pub floors: Option<[usize; 2]>,
    /// Judge the annual probability of exceeding the limit against ASCE 7's target reliability
    /// instead of the T-year level against the limit.
    #[serde(default)]
    pub strength: Option<StrengthTarget>,
}

/// ASCE 7's risk categories of buildings (Table 1.5-1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub enum RiskCategory {
    /// Buildings whose failure is a low risk to human life.
    I,
    /// Buildings not in categories I, III and IV (offices, dwellings).
    II,
    /// Buildings whose failure is a substantial risk to human life (assembly, schools).
    III,
    /// Essential facilities (hospitals, emergency services).
    IV,
}

/// The consequence of a failure, the rows of ASCE 7 Table 1.3-1.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(rename_all = "snake_case")]
pub enum FailureMode {
    /// Not sudden and not leading to widespread progression of damage.
    NotSudden,
    /// Either sudden or leading to widespread progression of damage.
    SuddenOrWidespread,
    /// Sudden and resulting in widespread progression of damage.
    SuddenAndWidespread,
}

/// The target a strength criterion's annual probability of exceeding its limit is judged against.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(deny_unknown_fields)]
pub struct StrengthTarget {
    /// The building's risk category.
    pub risk_category: RiskCategory,
    /// The consequence of the failure the limit marks.
    pub failure: FailureMode,
}

impl StrengthTarget {
    /// The target annual probability of failure of ASCE 7-16 Table 1.3-1 (load conditions without
    /// earthquake). The table's reliability indices are for a 50-year service period: β = −Φ⁻¹(50·P).
    pub fn annual_probability(&self) -> f64 {
        use FailureMode::*;
        use RiskCategory::*;
        match (self.failure, self.risk_category) {
            (NotSudden, I) => 1.25e-4,
            (NotSudden, II) => 3.0e-5,
            (NotSudden, III) => 1.25e-5,
            (NotSudden, IV) => 5.0e-6,
            (SuddenOrWidespread, I) => 3.0e-5,
            (SuddenOrWidespread, II) => 5.0e-6,
            (SuddenOrWidespread, III) => 2.0e-6,
            (SuddenOrWidespread, IV) => 7.0e-7,
            (SuddenAndWidespread, I) => 5.0e-6,
            (SuddenAndWidespread, II) => 7.0e-7,
            (SuddenAndWidespread, III) => 2.5e-7,
            (SuddenAndWidespread, IV) => 1.0e-7,
        }
    }

    /// The annual reliability index of the target, −Φ⁻¹(P).
    pub fn annual_beta(&self) -> f64 {
        -Normal::standard().inverse_cdf(self.annual_probability())
    }
}

/// The built-in criteria by name, with where their values come from (docs/serviceability.md).
pub const BUILT_IN: [&str; 3] = ["nbcc-residential", "nbcc-office", "drift-h400"];

/// Floors of the top of the building the comfort criteria judge by default.
const TOP_FLOORS: usize = 10;

/// The built-in criterion `name` for a building of `floors` floors: the NBCC commentary's 10-year
/// peak accelerations (15 milli-g residential, 25 milli-g office) on the top ten floors, and a
/// 10-year drift of h/400 on every storey.
pub fn built_in(name: &str, floors: usize) -> Result<Criterion> {
    let top = [floors.saturating_sub(TOP_FLOORS - 1).max(1), floors];
    let comfort = |milli_g: f64| Criterion {
        name: name.to_string(),
        response: ResponseKind::Acceleration,
        statistic: Statistic::Peak,
        return_period_years: 10.0,
        limit: Some(milli_g * 1e-3 * STANDARD_GRAVITY),
        limit_per_storey_height: None,
        floors: Some(top),
        strength: None,
    };
    match name {
        "nbcc-residential" => Ok(comfort(15.0)),
        "nbcc-office" => Ok(comfort(25.0)),
        "drift-h400" => Ok(Criterion {
            name: name.to_string(),
            response: ResponseKind::Drift,
            statistic: Statistic::Peak,
            return_period_years: 10.0,
            limit: None,
            limit_per_storey_height: Some(1.0 / 400.0),
            floors: None,
            strength: None,
        }),
        _ => Err(Error::invalid(
            "criteria",
            format!("unknown criterion `{name}`; the built-in criteria are {}", BUILT_IN.join(", ")),
        )),
    }
}

/// A criterion as a request gives it: a built-in's name, or a criterion in full.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(untagged)]
pub enum CriterionChoice {
    /// `nbcc-residential`, `nbcc-office` or `drift-h400`.
    BuiltIn(String),
    /// A criterion given in full.
    Defined(Criterion),
}

impl<'de> Deserialize<'de> for CriterionChoice {
    /// A string names a built-in; anything else is a criterion, whose own error is reported
    /// rather than "no variant matched".
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> std::result::Result<Self, D::Error> {
        use serde::de::Error as _;
        match serde_json::Value::deserialize(deserializer)? {
            serde_json::Value::String(name) => Ok(CriterionChoice::BuiltIn(name)),
            other => Criterion::deserialize(other).map(CriterionChoice::Defined).map_err(D::Error::custom),
        }
    }
}

impl CriterionChoice {
    /// The criterion for a building of `floors` floors.
    pub fn criterion(&self, floors: usize) -> Result<Criterion> {
        match self {
            CriterionChoice::BuiltIn(name) => built_in(name, floors),
            CriterionChoice::Defined(criterion) => Ok(criterion.clone()),
        }
    }
}

/// A criterion made concrete for a building: the response at each judged floor and its limit.
#[derive(Debug, Clone)]
pub struct ResolvedCriterion {
    /// The criterion as given.
    pub criterion: Criterion,
    /// The response at each judged floor, bottom up.
    pub responses: Vec<Response>,
    /// The limit at each of `responses` (SI).
    pub limits: Vec<f64>,
}

impl Criterion {
    /// The response of the criterion's kind and statistic at `floor`.
    fn response_at(&self, floor: usize) -> Response {
        match self.statistic {
            Statistic::Rms => Response::RmsAcceleration { floor },
            Statistic::Peak => self.response.at_floor(floor),
        }
    }

    /// Checks the criterion against `structure` and makes it concrete; errors name the field as
    /// `{field}.…` (e.g. `criteria[2].limit`).
    pub fn resolve(&self, structure: &Structure, field: &str) -> Result<ResolvedCriterion> {
        let invalid = |name: &str, reason: String| Error::invalid(format!("{field}.{name}"), reason);
        if self.name.is_empty() || self.name.chars().count() > 64 {
            return Err(invalid("name", "must be 1 to 64 characters".into()));
        }
        if self.response == ResponseKind::RmsAcceleration {
            return Err(invalid("response", "name `acceleration` with `statistic` `rms`".into()));
        }
        if self.statistic == Statistic::Rms && self.response != ResponseKind::Acceleration {
            return Err(invalid("statistic", "`rms` is taken of accelerations only".into()));
        }
        let t = self.return_period_years;
        if !(t.is_finite() && (1.0..=MAX_RETURN_PERIOD).contains(&t)) {
            return Err(invalid(
                "return_period_years",
                format!("must be from 1 to {MAX_RETURN_PERIOD:e} years, got {t}"),
            ));
        }
        let heights = structure.storey_heights();
        let limit_of: Box<dyn Fn(usize) -> f64> = match (self.limit, self.limit_per_storey_height) {
            (Some(limit), None) if limit.is_finite() && limit > 0.0 && limit <= 1e9 => Box::new(move |_| limit),
            (Some(limit), None) => {
                return Err(invalid("limit", format!("must lie in (0, 1e9] in SI units, got {limit}")));
            }
            (None, Some(ratio)) if self.response != ResponseKind::Drift => {
                return Err(invalid("limit_per_storey_height", format!("applies to drift only, not {ratio}")));
            }
            (None, Some(ratio)) if ratio.is_finite() && ratio > 0.0 && ratio <= 1.0 => {
                Box::new(move |floor| ratio * heights[floor - 1])
            }
            (None, Some(ratio)) => {
                return Err(invalid("limit_per_storey_height", format!("must lie in (0, 1], got {ratio}")));
            }
            (None, None) => return Err(invalid("limit", "give `limit` or `limit_per_storey_height`".into())),
            (Some(_), Some(_)) => {
                return Err(invalid("limit", "give `limit` or `limit_per_storey_height`, not both".into()));
            }
        };
        let floors = structure.floors();
        let [lowest, highest] = self.floors.unwrap_or([1, floors]);
        if lowest == 0 || lowest > highest || highest > floors {
            return Err(invalid(
                "floors",
                format!("must be [lowest, highest] with 1 <= lowest <= highest <= {floors}, got [{lowest}, {highest}]"),
            ));
        }
        let responses: Vec<Response> =
            (lowest..=highest).map(|floor| self.response_at(floor)).filter(|r| r.check(structure).is_ok()).collect();
        if responses.is_empty() {
            return Err(invalid(
                "floors",
                format!("no floor from {lowest} to {highest} has a {}", self.response.name()),
            ));
        }
        let limits = responses.iter().map(|r| limit_of(r.floor().expect("a floor's response"))).collect();
        Ok(ResolvedCriterion { criterion: self.clone(), responses, limits })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The transcription of ASCE 7-16 Table 1.3-1 is checked against the table's own other column:
    /// its 50-year indices β = −Φ⁻¹(50·P) are 2.5, 3.0, 3.25, 3.5 / 3.0, 3.5, 3.75, 4.0 /
    /// 3.5, 4.0, 4.25, 4.5 (the table rounds them to a quarter, hence the 0.1).
    #[test]
    fn asce_targets_agree_with_the_tables_fifty_year_indices() {
        use FailureMode::*;
        use RiskCategory::*;
        let table = [
            (NotSudden, [2.5, 3.0, 3.25, 3.5]),
            (SuddenOrWidespread, [3.0, 3.5, 3.75, 4.0]),
            (SuddenAndWidespread, [3.5, 4.0, 4.25, 4.5]),
        ];
        for (failure, betas) in table {
            for (risk_category, beta) in [I, II, III, IV].into_iter().zip(betas) {
                let target = StrengthTarget { risk_category, failure };
                let fifty_years = -Normal::standard().inverse_cdf(50.0 * target.annual_probability());
                assert!((fifty_years - beta).abs() < 0.1, "{target:?}: {fifty_years} vs {beta}");
            }
        }
    }

    #[test]
    fn built_ins_judge_the_top_ten_floors_and_every_storey() {
        let residential = built_in("nbcc-residential", 40).unwrap();
        assert_eq!(residential.floors, Some([31, 40]));
        assert!((residential.limit.unwrap() - 0.147_099_75).abs() < 1e-9);
        assert_eq!(built_in("nbcc-office", 5).unwrap().floors, Some([1, 5]));
        assert_eq!(built_in("drift-h400", 40).unwrap().limit_per_storey_height, Some(0.0025));
        assert!(built_in("comfy", 40).unwrap_err().to_string().contains("nbcc-office"));
    }
}
