//! The serviceability check a design office signs: several criteria at once under the site's
//! climate, each the T-year level of a response over a range of floors against a limit, with its
//! band, its governing floor and a verdict; a strength criterion's annual probability of exceeding
//! its limit against ASCE 7's target. Every floor and criterion is read off the same storms
//! ([`crate::analysis::sampling::annual_sample`]), stratified over the climate as an annual curve is.

mod certified;
mod criteria;

pub use certified::CriterionCertification;
pub use criteria::{
    BUILT_IN, Criterion, CriterionChoice, FailureMode, MAX_CRITERIA, ResolvedCriterion, RiskCategory, Statistic,
    StrengthTarget, built_in,
};

use crate::analysis::answers::hazard::{MAX_SPEED, REFERENCE_PILOT_SHARE, WIND_SPEED, return_level};
use crate::analysis::certification::certified_hazard::PairedStrata;
use crate::analysis::certification::certify::{CertifyOptions, check_reference_storms};
use crate::analysis::responses::response::{Response, ResponseKind};
use crate::analysis::sampling::annual_sample::{Aim, AnnualDesign, AnnualSample, PILOT_SHARE};
use crate::analysis::sampling::draws::{DivergedStorm, Draws, OnDivergence, check_samples, peak_sets_at};
use crate::analysis::sampling::exceedance::check_confidence;
use crate::analysis::sampling::reference_storms::{PairedPeak, PairedRuns, reference_storm_seed};
use crate::analysis::sampling::runner::StormRunner;
use crate::analysis::sampling::strata::{Estimate, StormRows, StratifiedPeaks, WindStrata, pilot};
use crate::error::{Error, Result};
use crate::progress::Observer;
use crate::study::{Order, Study};
use crate::surrogate::Metamodel;
use crate::uncertainty::{InputModel, Marginal, rng_from_seed};
use serde::{Deserialize, Serialize};
use statrs::distribution::{ContinuousCDF, Normal};

/// What a serviceability check is asked.
#[derive(Debug, Clone, PartialEq)]
pub struct ServiceabilityOptions {
    /// The law of the annual maximum storm speed.
    pub climate: Marginal,
    /// The criteria judged, each against its own limit or target.
    pub criteria: Vec<Criterion>,
    /// Storms in all (a quarter of them the pilot), each through every criterion and floor.
    pub samples: usize,
    /// The seed of the storms' inputs, speeds and phases.
    pub seed: u64,
    /// The level of the bands.
    pub confidence: f64,
    /// Certify each criterion's governing floor with this many storms through both the reference
    /// model and the metamodel, shared out over the wind strata as an annual curve's are
    /// ([`crate::analysis::HazardOptions::certify`]).
    pub certify: Option<CertifyOptions>,
}

/// How a criterion came out.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// Every judged floor's band lies within the limit (the strength target).
    Pass,
    /// Some floor's band lies wholly beyond it.
    Fail,
    /// Neither: more storms (or a certified answer) may decide.
    Inconclusive,
}

/// A criterion's T-year level at every judged floor, from the same storms.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct LevelProfile {
    /// The judged floors, bottom up.
    pub floors: Vec<usize>,
    /// The T-year level at each floor; none where the sampled storms do not reach so rare a level.
    pub values: Vec<Option<f64>>,
    /// Where the band's ends cross the level's probability.
    pub lower: Vec<Option<f64>>,
    /// The level where the band's upper end crosses the level's probability, at each floor.
    pub upper: Vec<Option<f64>>,
    /// The limit at each floor (SI).
    pub limits: Vec<f64>,
}

/// A strength criterion's annual probability of exceeding its limit at its most probable floor,
/// against ASCE 7's target.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct StrengthCheck {
    /// The building's risk category.
    pub risk_category: RiskCategory,
    /// The consequence of the failure the limit marks.
    pub failure: FailureMode,
    /// The floor of the largest annual probability.
    pub floor: usize,
    /// The annual probability of exceeding the limit at that floor.
    pub annual_probability: f64,
    /// The lower end of the annual probability's band.
    pub lower: f64,
    /// The upper end of the annual probability's band.
    pub upper: f64,
    /// −Φ⁻¹ of the annual probability; none where it is 0 or 1.
    pub beta: Option<f64>,
    /// ASCE 7-16 Table 1.3-1's annual probability for the category and failure.
    pub target_annual_probability: f64,
    /// −Φ⁻¹ of the target (annual; the table's own indices are for 50 years).
    pub target_beta: f64,
    /// β − target β: positive where the building is more reliable than the target.
    pub margin: Option<f64>,
}

/// How one criterion came out.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct CriterionCheck {
    /// The criterion's name, as the request gave it.
    pub name: String,
    /// The response judged.
    pub response: ResponseKind,
    /// Whether each storm's peak or its RMS is judged.
    pub statistic: Statistic,
    /// The response's SI unit.
    pub unit: String,
    /// The return period (years) whose level is judged.
    pub return_period_years: f64,
    /// The floor of the largest utilisation.
    pub governing_floor: usize,
    /// The T-year level at the governing floor, with its band.
    pub value: Option<f64>,
    /// The level where the band's lower end crosses the level's probability.
    pub lower: Option<f64>,
    /// The level where the band's upper end crosses the level's probability.
    pub upper: Option<f64>,
    /// The limit at the governing floor (SI).
    pub limit: f64,
    /// value / limit at the governing floor; none where the level was not reached.
    pub utilisation: Option<f64>,
    /// Over every judged floor: `pass` where every upper end is within its limit, `fail` where
    /// some lower end is beyond, else `inconclusive`; for a strength criterion the same of the
    /// annual probability's band against the target.
    pub verdict: Verdict,
    /// The T-year level at every judged floor.
    pub profile: LevelProfile,
    /// A strength criterion's annual probability against its target.
    pub strength: Option<StrengthCheck>,
    /// What the reference storms did, when the check was certified: then the governing floor's
    /// level, band and utilisation (and its entry in `profile`) are the certified ones, and the
    /// verdict is judged with them.
    pub certification: Option<CriterionCertification>,
}

/// A serviceability check's answer.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct Serviceability {
    /// The law of the annual maximum storm speed at the 10 m station.
    pub climate: Marginal,
    /// Storms run, each through every criterion and floor.
    pub samples: usize,
    /// Wind strata the storms were drawn in.
    pub strata: usize,
    /// The level of the bands.
    pub confidence: f64,
    /// Each criterion's outcome, in the order asked.
    pub criteria: Vec<CriterionCheck>,
    /// Storms whose free run diverged, counted as exceeding every level.
    pub diverged_storms: usize,
    /// The first few diverged storms with their inputs.
    #[serde(default)]
    pub first_diverged: Vec<DivergedStorm>,
    /// The climate's probability of storms too rare to be run; counted as exceeding.
    pub unsampled_probability: f64,
    /// The wind speeds of the calibration's experiments, lowest and highest (m/s).
    pub calibrated_wind_range: [f64; 2],
    /// The climate's probability of a speed outside them.
    pub climate_beyond_calibrated_range: f64,
}

impl ServiceabilityOptions {
    /// Checks everything but the sampling; errors name the field.
    pub fn resolve(&self, study: &Study) -> Result<Vec<ResolvedCriterion>> {
        check_samples(self.samples)?;
        check_confidence(self.confidence)?;
        if self.criteria.is_empty() || self.criteria.len() > MAX_CRITERIA {
            return Err(Error::invalid("criteria", format!("give 1 to {MAX_CRITERIA} criteria")));
        }
        let resolved = self
            .criteria
            .iter()
            .enumerate()
            .map(|(i, c)| c.resolve(&study.structure, &format!("criteria[{i}]")))
            .collect::<Result<Vec<_>>>()?;
        pilot(&self.strata(), self.samples, PILOT_SHARE, "samples")?;
        if let Some(certify) = &self.certify {
            check_reference_storms(certify.reference_storms, self.samples, "certify.reference_storms")?;
            pilot(&self.strata(), certify.reference_storms, REFERENCE_PILOT_SHARE, "certify.reference_storms")?;
        }
        Ok(resolved)
    }

    /// Strata down to the rarest level asked: a criterion's 1/T or a strength target.
    fn strata(&self) -> WindStrata {
        let targets = self.criteria.iter().flat_map(|c| c.strength.map(|s| s.annual_probability()));
        let smallest = self.criteria.iter().map(|c| 1.0 / c.return_period_years).chain(targets).fold(1e-4, f64::min);
        WindStrata::new(&self.climate, smallest, MAX_SPEED)
    }
}

/// The check of `options.criteria` on a metamodel under `options.climate`, every other input
/// drawn from its law.
pub fn metamodel_serviceability(
    metamodel: &Metamodel,
    study: &Study,
    options: &ServiceabilityOptions,
    runner: &dyn StormRunner,
    observer: &dyn Observer,
) -> Result<Serviceability> {
    let resolved = options.resolve(study)?;
    let calibrated = metamodel.calibrated_range(study, WIND_SPEED)?;
    let peaks_of = |responses: &[Response], rows: &[Vec<f64>], first: usize| {
        let storms: Vec<usize> = (first..first + rows.len()).collect();
        let draws = Draws { study, rows, storms: &storms, seed: options.seed, on_divergence: OnDivergence::Exceed };
        peak_sets_at(metamodel, &draws, responses, runner, observer)
    };
    let order = options.certify.map_or(Order::Reduced, |c| c.order);
    let pairs_of = |response: Response, rows: &[Vec<f64>], first: usize| {
        let runs = PairedRuns { metamodel, study, seed: reference_storm_seed(options.seed), response, order };
        let storms: Vec<usize> = (first..first + rows.len()).collect();
        runner.pairs(&runs, rows, &storms, observer)
    };
    serviceability_check(&study.inputs, &resolved, options, calibrated, peaks_of, pairs_of)
}

/// The check of the `resolved` criteria on storms drawn from `inputs` with the wind speed the
/// climate's: `peaks_of(responses, rows, first)` answers `[row][response]` (`first`: the rows run
/// before, so that every row gets its own storm). Certified, `pairs_of(response, rows, first)`
/// runs rows drawn from the reference storms' seed through both models.
pub fn serviceability_check(
    inputs: &InputModel,
    resolved: &[ResolvedCriterion],
    options: &ServiceabilityOptions,
    calibrated: [f64; 2],
    mut peaks_of: impl FnMut(&[Response], &[Vec<f64>], usize) -> Result<Vec<Vec<f64>>>,
    mut pairs_of: impl FnMut(Response, &[Vec<f64>], usize) -> Result<Vec<PairedPeak>>,
) -> Result<Serviceability> {
    let (responses, columns) = columns_of(resolved);
    let strata = options.strata();
    let rows = StormRows { inputs, wind: inputs.index_of(WIND_SPEED)?, climate: &options.climate, strata: &strata };
    let design = AnnualDesign { rows, samples: options.samples, calibrated };
    let aims = |pilot: &[StratifiedPeaks]| criteria_aims(resolved, &columns, pilot, options.confidence);
    let sample =
        design.draw(&mut rng_from_seed(options.seed), |rows, first| peaks_of(&responses, rows, first), aims)?;
    let mut check = judge(resolved, &columns, &sample, options, &strata, calibrated);
    if let Some(certify) = &options.certify {
        for ((judged, criterion), columns) in check.criteria.iter_mut().zip(resolved).zip(&columns) {
            let at = judged.profile.floors.iter().position(|&f| f == judged.governing_floor).expect("a judged floor");
            let column = &sample.columns[columns[at]];
            let response = criterion.responses[at];
            let seed = reference_storm_seed(options.seed);
            let pairs = |rows: &[Vec<f64>], first: usize| pairs_of(response, rows, first);
            let targets: Vec<f64> = judged.value.into_iter().collect();
            let paired =
                PairedStrata::draw(&design.rows, column, &targets, certify, REFERENCE_PILOT_SHARE, seed, pairs)?;
            certified::certify_governing(judged, at, column, &paired, certify, options.confidence);
        }
    }
    Ok(check)
}

/// Every response the criteria judge, once each, and each criterion's columns among them.
fn columns_of(resolved: &[ResolvedCriterion]) -> (Vec<Response>, Vec<Vec<usize>>) {
    let mut responses: Vec<Response> = Vec::new();
    let columns = resolved
        .iter()
        .map(|c| {
            c.responses
                .iter()
                .map(|r| {
                    responses.iter().position(|known| known == r).unwrap_or_else(|| {
                        responses.push(*r);
                        responses.len() - 1
                    })
                })
                .collect()
        })
        .collect();
    (responses, columns)
}

/// What the allocation aims at: each criterion's T-year level at its governing floor in the pilot,
/// and a strength criterion's limit at its most probable floor.
fn criteria_aims(
    resolved: &[ResolvedCriterion],
    columns: &[Vec<usize>],
    pilot: &[StratifiedPeaks],
    confidence: f64,
) -> Vec<Aim> {
    let mut aims = Vec::new();
    for (criterion, columns) in resolved.iter().zip(columns) {
        let profile = profile(criterion, columns, pilot, confidence);
        let governing = governing(&profile);
        if let Some(level) = profile.values[governing] {
            aims.push((columns[governing], level));
        }
        if criterion.criterion.strength.is_some() {
            let floor = largest(&limit_exceedances(criterion, columns, pilot, confidence), |e| e.probability);
            aims.push((columns[floor], criterion.limits[floor]));
        }
    }
    aims
}

/// The T-year level of each of the criterion's floors.
fn profile(
    criterion: &ResolvedCriterion,
    columns: &[usize],
    sample: &[StratifiedPeaks],
    confidence: f64,
) -> LevelProfile {
    let period = criterion.criterion.return_period_years;
    let levels = columns.iter().map(|&c| {
        let column = &sample[c];
        return_level(&column.finite_peaks(), period, |x| column.exceedance(x, confidence))
    });
    let (mut values, mut lower, mut upper) = (Vec::new(), Vec::new(), Vec::new());
    for level in levels {
        values.push(level.value);
        lower.push(level.lower);
        upper.push(level.upper);
    }
    LevelProfile {
        floors: criterion.responses.iter().filter_map(Response::floor).collect(),
        values,
        lower,
        upper,
        limits: criterion.limits.clone(),
    }
}

/// The position of the largest utilisation (a level not reached counts as the largest).
fn governing(profile: &LevelProfile) -> usize {
    let utilisations: Vec<f64> =
        profile.values.iter().zip(&profile.limits).map(|(v, limit)| v.map_or(f64::INFINITY, |v| v / limit)).collect();
    largest(&utilisations, |u| *u)
}

/// The position of the largest `key` (the first of equals).
fn largest<T>(items: &[T], key: impl Fn(&T) -> f64) -> usize {
    (0..items.len()).fold(0, |best, i| if key(&items[i]) > key(&items[best]) { i } else { best })
}

/// The annual probability of each of the criterion's floors exceeding its limit.
fn limit_exceedances(
    criterion: &ResolvedCriterion,
    columns: &[usize],
    sample: &[StratifiedPeaks],
    confidence: f64,
) -> Vec<Estimate> {
    columns.iter().zip(&criterion.limits).map(|(&c, &limit)| sample[c].exceedance(limit, confidence)).collect()
}

/// A level criterion's verdict over its profile.
fn level_verdict(profile: &LevelProfile) -> Verdict {
    let floors = 0..profile.floors.len();
    verdict(
        floors.clone().any(|i| profile.lower[i].is_some_and(|x| x > profile.limits[i])),
        floors.clone().all(|i| profile.upper[i].is_some_and(|x| x <= profile.limits[i])),
    )
}

/// `pass` where every end that matters is within, `fail` where some is beyond.
fn verdict(beyond_for_sure: bool, within_for_sure: bool) -> Verdict {
    match (beyond_for_sure, within_for_sure) {
        (true, _) => Verdict::Fail,
        (false, true) => Verdict::Pass,
        (false, false) => Verdict::Inconclusive,
    }
}

fn judge(
    resolved: &[ResolvedCriterion],
    columns: &[Vec<usize>],
    sample: &AnnualSample,
    options: &ServiceabilityOptions,
    strata: &WindStrata,
    calibrated: [f64; 2],
) -> Serviceability {
    let confidence = options.confidence;
    let criteria = resolved
        .iter()
        .zip(columns)
        .map(|(criterion, columns)| {
            let profile = profile(criterion, columns, &sample.columns, confidence);
            let at = governing(&profile);
            let limit = profile.limits[at];
            let level_verdict = level_verdict(&profile);
            let (strength, verdict) = match criterion.criterion.strength {
                Some(target) => {
                    let exceedances = limit_exceedances(criterion, columns, &sample.columns, confidence);
                    let worst = largest(&exceedances, |e| e.probability);
                    let p = target.annual_probability();
                    let verdict =
                        verdict(exceedances.iter().any(|e| e.lower > p), exceedances.iter().all(|e| e.upper <= p));
                    (Some(strength_check(target, profile.floors[worst], exceedances[worst])), verdict)
                }
                None => (None, level_verdict),
            };
            let c = &criterion.criterion;
            CriterionCheck {
                name: c.name.clone(),
                response: c.response,
                statistic: c.statistic,
                unit: criterion.responses[0].unit().to_string(),
                return_period_years: c.return_period_years,
                governing_floor: profile.floors[at],
                value: profile.values[at],
                lower: profile.lower[at],
                upper: profile.upper[at],
                limit,
                utilisation: profile.values[at].map(|v| v / limit),
                verdict,
                profile,
                strength,
                certification: None,
            }
        })
        .collect();
    Serviceability {
        climate: options.climate,
        samples: sample.storms,
        strata: strata.count(),
        confidence,
        criteria,
        diverged_storms: sample.diverged,
        first_diverged: sample.first_diverged.clone(),
        unsampled_probability: strata.unsampled(),
        calibrated_wind_range: calibrated,
        climate_beyond_calibrated_range: options.climate.cdf(calibrated[0]) + options.climate.survival(calibrated[1]),
    }
}

fn strength_check(target: StrengthTarget, floor: usize, e: Estimate) -> StrengthCheck {
    let beta = (e.probability > 0.0 && e.probability < 1.0).then(|| -Normal::standard().inverse_cdf(e.probability));
    let target_beta = target.annual_beta();
    StrengthCheck {
        risk_category: target.risk_category,
        failure: target.failure,
        floor,
        annual_probability: e.probability,
        lower: e.lower,
        upper: e.upper,
        beta,
        target_annual_probability: target.annual_probability(),
        target_beta,
        margin: beta.map(|b| b - target_beta),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::annual_probability_of_period;
    use crate::analysis::answers::hazard::tests::{lognormal_scatter_annual, lognormal_scatter_level, toy_inputs};

    /// A response at floor f of f·scale·v·exp(σz): its T-year level is exactly f·scale times the
    /// lognormal scatter's ([`lognormal_scatter_level`], an independent quadrature).
    fn toy_peaks(responses: &[Response], rows: &[Vec<f64>]) -> Vec<Vec<f64>> {
        let scale = |r: &Response| match r {
            Response::Drift { floor } => *floor as f64 * 1e-3,
            Response::Acceleration { floor } => *floor as f64 * 1e-2,
            other => unreachable!("{other:?}"),
        };
        rows.iter().map(|row| responses.iter().map(|r| scale(r) * row[1] * (0.15 * row[0]).exp()).collect()).collect()
    }

    fn criterion(name: &str, response: ResponseKind, floors: [usize; 2], limit: f64) -> Criterion {
        Criterion {
            name: name.into(),
            response,
            statistic: Statistic::Peak,
            return_period_years: 10.0,
            limit: Some(limit),
            limit_per_storey_height: None,
            floors: Some(floors),
            strength: None,
        }
    }

    /// Levels against the quadrature, verdicts on each side of the limit and at it, the governing
    /// floor, the same storms for every floor (levels in the floors' exact ratio), and a strength
    /// criterion's annual probability against the quadrature and ASCE 7's target.
    #[test]
    fn levels_verdicts_and_reliability_of_a_known_law() {
        let climate = Marginal::Gumbel { location: 22.0, scale: 2.2 };
        let x10 = lognormal_scatter_level(&climate, 0.15, annual_probability_of_period(10.0));
        let x1000 = lognormal_scatter_level(&climate, 0.15, 1e-3);
        let mut strength = criterion("strength", ResponseKind::Drift, [3, 3], 3e-3 * x1000);
        strength.strength = Some(StrengthTarget { risk_category: RiskCategory::I, failure: FailureMode::NotSudden });
        let options = ServiceabilityOptions {
            climate,
            criteria: vec![
                criterion("within", ResponseKind::Drift, [1, 3], 2.0 * 3e-3 * x10),
                criterion("beyond", ResponseKind::Acceleration, [2, 2], 0.5 * 2e-2 * x10),
                criterion("at", ResponseKind::Drift, [1, 3], 3e-3 * x10),
                strength,
            ],
            samples: 20_000,
            seed: 7,
            confidence: 0.95,
            certify: None,
        };
        let structure = crate::study::Study::preset("frame40-kn").unwrap().structure;
        let resolved: Vec<ResolvedCriterion> =
            options.criteria.iter().map(|c| c.resolve(&structure, "criteria[0]").unwrap()).collect();
        let peaks_of = |responses: &[Response], rows: &[Vec<f64>], _| Ok(toy_peaks(responses, rows));
        let not_paired =
            |_: Response, _: &[Vec<f64>], _: usize| -> Result<Vec<PairedPeak>> { unreachable!("not certified") };
        let check =
            serviceability_check(&toy_inputs(), &resolved, &options, [15.0, 45.0], peaks_of, not_paired).unwrap();
        let [within, beyond, at, strength] = &check.criteria[..] else { panic!("four criteria") };
        for (i, floor) in [1, 2, 3].into_iter().enumerate() {
            let exact = floor as f64 * 1e-3 * x10;
            let (lo, hi) = (within.profile.lower[i].unwrap(), within.profile.upper[i].unwrap());
            assert!(lo <= exact && exact <= hi, "floor {floor}: {exact} not in [{lo}, {hi}]");
            let ratio = within.profile.values[i].unwrap() / within.profile.values[0].unwrap();
            assert!((ratio - floor as f64).abs() < 1e-12, "floor {floor}: {ratio}");
        }
        assert_eq!((within.governing_floor, within.verdict), (3, Verdict::Pass));
        assert!((within.utilisation.unwrap() - 0.5).abs() < 0.02, "{:?}", within.utilisation);
        assert_eq!((beyond.governing_floor, beyond.verdict), (2, Verdict::Fail));
        assert_eq!(at.verdict, Verdict::Inconclusive, "{at:?}");
        assert_eq!(at.profile.values, within.profile.values, "one column per response, shared");
        let s = strength.strength.as_ref().unwrap();
        let exact = lognormal_scatter_annual(&climate, 0.15, x1000);
        assert!(s.lower <= exact && exact <= s.upper, "{exact} not in [{}, {}]", s.lower, s.upper);
        assert_eq!((s.target_annual_probability, strength.verdict), (1.25e-4, Verdict::Fail));
        assert!(s.margin.unwrap() < 0.0 && (s.target_beta - 3.662).abs() < 1e-3, "{s:?}");
        assert!(check.samples <= 20_000 && check.diverged_storms == 0);
    }

    #[test]
    fn criteria_are_checked_naming_the_field() {
        let structure = crate::study::Study::preset("frame40-kn").unwrap().structure;
        let base = criterion("c", ResponseKind::Drift, [1, 40], 0.01);
        let refused = |c: Criterion| c.resolve(&structure, "criteria[1]").unwrap_err().to_string();
        assert!(refused(Criterion { floors: Some([0, 3]), ..base.clone() }).contains("criteria[1].floors"));
        assert!(refused(Criterion { floors: Some([3, 41]), ..base.clone() }).contains("criteria[1].floors"));
        assert!(refused(Criterion { return_period_years: 0.5, ..base.clone() }).contains("return_period_years"));
        assert!(refused(Criterion { limit: Some(f64::NAN), ..base.clone() }).contains("criteria[1].limit"));
        assert!(refused(Criterion { limit: None, ..base.clone() }).contains("criteria[1].limit"));
        assert!(refused(Criterion { statistic: Statistic::Rms, ..base.clone() }).contains("statistic"));
        let ratio = Criterion { limit: None, limit_per_storey_height: Some(0.0025), ..base.clone() };
        let resolved = ratio.resolve(&structure, "c").unwrap();
        let heights = structure.storey_heights();
        assert!((resolved.limits[0] - heights[0] / 400.0).abs() < 1e-12 && resolved.limits.len() == 40);
        let accel = Criterion { response: ResponseKind::Acceleration, ..ratio };
        assert!(refused(accel).contains("limit_per_storey_height"));
    }
}
