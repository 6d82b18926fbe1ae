//! The wind climate: the law of the annual maximum of the storm mean wind speed at the 10 m
//! station. It turns what one storm does into what a year does: the building's peak in a year is
//! taken as its peak in the year's strongest storm, so P(annual peak > x) = ∫ P(peak > x | v) f(v) dv.

use crate::error::{Error, Result};
use crate::surrogate::WindCoverage;
use crate::uncertainty::Marginal;
use serde::{Deserialize, Deserializer, Serialize};
use std::collections::BTreeMap;

/// A climate as a client states it: a marginal of the annual maximum speed (`gumbel` by `location`
/// and `scale`; `frechet`, `weibull`, `lognormal` by `mean` and `sd`; any other marginal), or the
/// speeds of two or more return periods, through which a Gumbel law is drawn.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(untagged)]
pub enum ClimateSpec {
    /// The speeds of two or more return periods, through which a Gumbel law is drawn.
    ReturnPeriodSpeeds(ReturnPeriodSpeeds),
    /// The law of the annual maximum speed itself.
    Marginal(Marginal),
}

// A type of its own rather than an inline variant: an inline map inside `oneOf` is dropped by
// openapi-python-client as a duplicate model, and a named schema is generated once.
/// A climate given by the speeds of two or more return periods, through which a Gumbel law is drawn.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct ReturnPeriodSpeeds {
    /// Speeds (m/s) by return period in years, e.g. `{"50": 32.0, "700": 40.0}`.
    #[cfg_attr(feature = "openapi", schema(schema_with = return_period_speeds_schema))]
    pub return_period_speeds: BTreeMap<String, f64>,
}

/// Two or more speeds (m/s) by return period.
#[cfg(feature = "openapi")]
fn return_period_speeds_schema() -> utoipa::openapi::Object {
    use utoipa::openapi::{ObjectBuilder, Type};
    let years = ObjectBuilder::new().schema_type(Type::String).pattern(Some(r"^[0-9]+(\.[0-9]+)?$"));
    ObjectBuilder::new()
        .schema_type(Type::Object)
        .property_names(Some(years))
        .description(Some(
            "Speeds (m/s) by return period in years, e.g. `{\"50\": 32.0, \"700\": 40.0}`: the periods are \
             numbers of years from 1, and the speeds grow with them. The T-year speed is exceeded in a \
             year with probability 1 − exp(−1/T).",
        ))
        .min_properties(Some(2))
        .additional_properties(Some(ObjectBuilder::new().schema_type(Type::Number).exclusive_minimum(Some(0.0))))
        .build()
}

impl<'de> Deserialize<'de> for ClimateSpec {
    /// By the presence of `return_period_speeds`, so that a malformed marginal is reported as such
    /// rather than as "no variant matched".
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> std::result::Result<Self, D::Error> {
        use serde::de::Error as _;
        let value = serde_json::Value::deserialize(deserializer)?;
        match value.get("return_period_speeds") {
            Some(speeds) => {
                if value.as_object().is_some_and(|o| o.len() > 1) {
                    return Err(D::Error::custom("`return_period_speeds` takes no other field"));
                }
                let speeds = BTreeMap::<String, f64>::deserialize(speeds).map_err(D::Error::custom)?;
                Ok(ClimateSpec::ReturnPeriodSpeeds(ReturnPeriodSpeeds { return_period_speeds: speeds }))
            }
            None => Marginal::deserialize(value).map(ClimateSpec::Marginal).map_err(D::Error::custom),
        }
    }
}

/// The largest station speed the wind model admits (m/s): a climate must put less than 10⁻⁶ a
/// year beyond it.
const MAX_SPEED: f64 = 150.0;

impl ClimateSpec {
    /// The law of the annual maximum speed; errors name the field under `field`.
    pub fn resolve(&self, field: &str) -> Result<Marginal> {
        let marginal = match self {
            ClimateSpec::Marginal(marginal) => {
                marginal.check(field)?;
                *marginal
            }
            ClimateSpec::ReturnPeriodSpeeds(ReturnPeriodSpeeds { return_period_speeds }) => {
                gumbel_through(return_period_speeds, &format!("{field}.return_period_speeds"))?
            }
        };
        if marginal.cdf(0.0) > 1e-9 {
            return Err(Error::invalid(field, "a wind speed cannot be negative: the law puts weight below 0 m/s"));
        }
        if marginal.upper_quantile(1e-6).partial_cmp(&MAX_SPEED) != Some(std::cmp::Ordering::Less) {
            return Err(Error::invalid(field, format!("puts a probability above 10⁻⁶ beyond {MAX_SPEED} m/s")));
        }
        Ok(marginal)
    }
}

/// The law a request's climate names, or the metamodel's own wind-speed law when it names none.
pub fn climate_or_own(spec: Option<&ClimateSpec>, study: &crate::study::Study) -> Result<Marginal> {
    match spec {
        Some(spec) => spec.resolve("climate"),
        None => Ok(*study.inputs.marginal(crate::study::WIND_SPEED)?),
    }
}

/// A calibration asked to cover a climate: its design spans the speeds from the climate's 1-year
/// speed (exceeded with 1 − e⁻¹ a year: where a comfort check starts) to the speed exceeded with
/// `annual_probability` a year (see
/// [`crate::surrogate::design`] for how the expansions stay the input model's).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(deny_unknown_fields)]
pub struct ClimateCoverage {
    /// The climate whose speeds the calibration must cover.
    pub climate: ClimateSpec,
    /// The rarest annual exceedance probability the answers must reach (10⁻⁵: the 100 000-year speed).
    #[serde(default = "rarest_default")]
    #[cfg_attr(feature = "openapi", schema(minimum = 1e-8, maximum = 0.1, default = 1e-5))]
    pub annual_probability: f64,
}

fn rarest_default() -> f64 {
    1e-5
}

impl ClimateCoverage {
    /// The speeds to cover; errors name the field under `field`.
    pub fn wind_speeds(&self, field: &str) -> Result<WindCoverage> {
        let p = self.annual_probability;
        if !(1e-8..=0.1).contains(&p) {
            return Err(Error::invalid(
                format!("{field}.annual_probability"),
                format!("must lie in [1e-8, 0.1], got {p}"),
            ));
        }
        let law = self.climate.resolve(&format!("{field}.climate"))?;
        let one_year = law.upper_quantile(annual_probability_of_period(1.0));
        let coverage = WindCoverage { lower: one_year, upper: law.upper_quantile(p) };
        coverage.check()?;
        Ok(coverage)
    }
}

/// The annual probability that the level of return period T (years) is exceeded: 1 − exp(−1/T), the
/// chance of at least one exceedance in a year when they come at a rate of 1/T a year. About 1/T
/// for long periods; 0.632 for T = 1, so that 1-year levels exist.
pub fn annual_probability_of_period(years: f64) -> f64 {
    -(-1.0 / years).exp_m1()
}

/// The return period (years) of an annual exceedance probability p, the inverse of
/// [`annual_probability_of_period`]: −1/ln(1 − p); none outside (0, 1).
pub fn period_of_annual_probability(probability: f64) -> Option<f64> {
    (probability > 0.0 && probability < 1.0).then(|| -1.0 / (-probability).ln_1p())
}

/// The Gumbel law through speeds v_T of return periods T: v = location + scale·y with the reduced
/// variate y = −ln(−ln F(v_T)) = ln T (F(v_T) = exp(−1/T): see [`annual_probability_of_period`]),
/// by least squares (exact through two points).
fn gumbel_through(speeds: &BTreeMap<String, f64>, field: &str) -> Result<Marginal> {
    let mut points = Vec::with_capacity(speeds.len());
    for (years, &speed) in speeds {
        let period: f64 = years.trim().parse().ok().filter(|t: &f64| t.is_finite() && *t >= 1.0).ok_or_else(|| {
            Error::invalid(format!("{field}.{years}"), "a return period is a number of years, at least 1")
        })?;
        if !(speed.is_finite() && speed > 0.0 && speed < MAX_SPEED) {
            return Err(Error::invalid(format!("{field}.{years}"), format!("must lie in (0, {MAX_SPEED}) m/s")));
        }
        points.push((period.ln(), speed));
    }
    if points.len() < 2 {
        return Err(Error::invalid(field, "needs the speeds of at least two return periods"));
    }
    let n = points.len() as f64;
    let (my, mv) = (points.iter().map(|p| p.0).sum::<f64>() / n, points.iter().map(|p| p.1).sum::<f64>() / n);
    let syy: f64 = points.iter().map(|p| (p.0 - my).powi(2)).sum();
    let syv: f64 = points.iter().map(|p| (p.0 - my) * (p.1 - mv)).sum();
    let scale = syv / syy;
    if !(scale.is_finite() && scale > 0.0) {
        return Err(Error::invalid(field, "speeds must grow with the return period"));
    }
    Ok(Marginal::Gumbel { location: mv - scale * my, scale })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two points: the law passes through both (1 − F(v_T) = 1 − exp(−1/T)), a 1-year speed too.
    #[test]
    fn gumbel_through_two_return_period_speeds_passes_through_them() {
        for (speeds, points) in [
            (r#"{"50": 32.0, "700": 40.0}"#, [(50.0_f64, 32.0), (700.0, 40.0)]),
            (r#"{"1": 21.0, "50": 30.0}"#, [(1.0, 21.0), (50.0, 30.0)]),
        ] {
            let spec: ClimateSpec = serde_json::from_str(&format!(r#"{{"return_period_speeds": {speeds}}}"#)).unwrap();
            let law = spec.resolve("climate").unwrap();
            for (t, v) in points {
                let exact = 1.0 - (-1.0 / t).exp();
                assert!((law.survival(v) / exact - 1.0).abs() < 1e-10, "T = {t}: {}", law.survival(v));
                assert!((period_of_annual_probability(law.survival(v)).unwrap() / t - 1.0).abs() < 1e-10);
            }
        }
        // The 50-year speed is exceeded with 1 − e^(−1/50) = 0.019801, not 0.02.
        assert!((annual_probability_of_period(50.0) - 0.0198013267).abs() < 1e-10);
        assert!((annual_probability_of_period(1.0) - 0.6321205588).abs() < 1e-10);
    }

    /// Gumbel(25, 2.5): 1-year speed 25, 10⁻⁵ speed 25 − 2.5·ln(−ln(1 − 10⁻⁵)) = 53.78.
    #[test]
    fn coverage_runs_from_the_one_year_speed_to_the_rarest_speed() {
        let coverage: ClimateCoverage =
            serde_json::from_str(r#"{"climate": {"distribution": "gumbel", "location": 25, "scale": 2.5}}"#).unwrap();
        let speeds = coverage.wind_speeds("cover_climate").unwrap();
        // The 1-year speed of a Gumbel law is its location (reduced variate ln 1 = 0).
        assert!((speeds.lower - 25.0).abs() < 1e-9, "{speeds:?}");
        assert!((speeds.upper - (25.0 - 2.5 * (-(-1e-5f64).ln_1p()).ln())).abs() < 1e-6, "{speeds:?}");
        let rare = ClimateCoverage { annual_probability: 0.5, ..coverage };
        assert!(
            rare.wind_speeds("cover_climate").unwrap_err().to_string().starts_with("cover_climate.annual_probability")
        );
    }

    #[test]
    fn a_marginal_is_a_climate_and_bad_ones_name_the_field() {
        let spec: ClimateSpec =
            serde_json::from_str(r#"{"distribution": "gumbel", "location": 25, "scale": 2.5}"#).unwrap();
        assert_eq!(spec.resolve("climate").unwrap(), Marginal::Gumbel { location: 25.0, scale: 2.5 });
        let err = serde_json::from_str::<ClimateSpec>(r#"{"distribution": "gumbel", "location": 25}"#).unwrap_err();
        assert!(err.to_string().contains("scale"), "{err}");
        let bad = [
            r#"{"return_period_speeds": {"50": 32.0}}"#,
            r#"{"return_period_speeds": {"50": 40.0, "700": 32.0}}"#,
            r#"{"return_period_speeds": {"0.5": 20.0, "700": 32.0}}"#,
            r#"{"return_period_speeds": {"50": -1.0, "700": 32.0}}"#,
            r#"{"distribution": "normal", "mean": 30, "sd": 10}"#,
            r#"{"distribution": "gumbel", "location": 100, "scale": 20}"#,
        ];
        for text in bad {
            let spec: ClimateSpec = serde_json::from_str(text).unwrap();
            let err = spec.resolve("climate").unwrap_err();
            assert!(err.to_string().starts_with("climate"), "{text}: {err}");
        }
    }
}
