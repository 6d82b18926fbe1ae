//! Annual exceedance probabilities, return levels and reliability indices of a peak response under
//! a wind climate: λ(x) = ∫ P(peak > x | v) f(v) dv with the structural inputs and the storm's
//! phases still random, estimated by stratifying the climate's speed ([`crate::analysis::sampling::strata`]).

use crate::analysis::certification::certified_hazard::{CertifiedPoint, HazardCertification, PairedStrata};
use crate::analysis::certification::certify::{CertifyOptions, check_reference_storms};
use crate::analysis::responses::response::Response;
use crate::analysis::sampling::annual_sample::{AnnualDesign, AnnualSample};
use crate::analysis::sampling::climate::{annual_probability_of_period, period_of_annual_probability};
use crate::analysis::sampling::draws::{DivergedStorm, Draws, OnDivergence, check_samples, peaks_at};
use crate::analysis::sampling::exceedance::check_thresholds;
use crate::analysis::sampling::exceedance::{automatic_thresholds, check_confidence};
use crate::analysis::sampling::reference_storms::{PairedPeak, PairedRuns, reference_storm_seed};
use crate::analysis::sampling::runner::StormRunner;
use crate::analysis::sampling::strata::{Estimate, Sampling, StormRows, StratifiedPeaks, WindStrata, pilot};
use crate::error::{Error, Result};
use crate::progress::Observer;
use crate::study::{Order, Study};
use crate::surrogate::Metamodel;
use crate::uncertainty::{InputModel, Marginal, rng_from_seed};
use serde::{Deserialize, Serialize};
use statrs::distribution::{ContinuousCDF, Normal};

/// The wind input every annual analysis replaces by the climate.
pub use crate::study::WIND_SPEED;

/// Return periods (years) reported when none are asked for.
pub const DEFAULT_RETURN_PERIODS: [f64; 8] = [1.0, 10.0, 50.0, 100.0, 500.0, 700.0, 1000.0, 10000.0];

/// A return period (years) that Neyman's allocation always aims at besides those asked for, so
/// that the common levels keep their precision.
const ALWAYS_TARGETED_PERIOD: f64 = 10.0;

/// Longest return period (years) an analysis may ask for: 10⁻⁶ a year, two decades rarer than
/// the 10⁻⁵ that at most 10⁵ storms resolve with a coefficient of variation below 0.3.
pub const MAX_RETURN_PERIOD: f64 = 1e6;

/// One in this many of a certified analysis's reference storms go to their pilot: more than the
/// metamodel's, for the pilot also measures how far the two models disagree.
pub(in crate::analysis) const REFERENCE_PILOT_SHARE: usize = 2;

/// The largest station speed the wind model admits (m/s).
pub(in crate::analysis) const MAX_SPEED: f64 = 150.0;

/// What an annual analysis is asked.
#[derive(Debug, Clone, PartialEq)]
pub struct HazardOptions {
    /// The law of the annual maximum storm speed.
    pub climate: Marginal,
    /// Storms in all (a quarter of them the pilot, when stratified).
    pub samples: usize,
    /// The seed of the storms' inputs, speeds and phases.
    pub seed: u64,
    /// Peak values at which to report λ; 50 spread over the sampled peaks when absent.
    pub thresholds: Option<Vec<f64>>,
    /// Return periods (years) whose levels are reported.
    pub return_periods: Vec<f64>,
    /// A limit whose annual probability and reliability index are reported.
    pub limit: Option<f64>,
    /// The level of the bands.
    pub confidence: f64,
    /// How the wind speeds are drawn: stratified, or plain Monte Carlo as a check.
    pub sampling: Sampling,
    /// Certify the curve with this many storms through both the reference model and the
    /// metamodel, spread over the wind strata and correcting the curve stratum by stratum (what
    /// they did is the curve's [`HazardCertification`]).
    pub certify: Option<CertifyOptions>,
}

impl HazardOptions {
    /// Checks everything but the sampling; errors name the field.
    pub fn check(&self) -> Result<()> {
        check_samples(self.samples)?;
        check_confidence(self.confidence)?;
        if let Some(thresholds) = &self.thresholds {
            check_thresholds(thresholds)?;
        }
        if self.return_periods.len() > 100
            || self.return_periods.iter().any(|t| !(t.is_finite() && *t >= 1.0 && *t <= MAX_RETURN_PERIOD))
        {
            return Err(Error::invalid(
                "return_periods",
                format!("must be at most 100 numbers of years from 1 to {MAX_RETURN_PERIOD:e}"),
            ));
        }
        if let Some(limit) = self.limit {
            check_thresholds(&[limit])
                .map_err(|_| Error::invalid("limit", "must lie between 0 and 1e9, in the response's unit"))?;
        }
        if let Some(certify) = &self.certify {
            check_reference_storms(certify.reference_storms, self.samples, "certify.reference_storms")?;
            pilot(&self.strata(), certify.reference_storms, REFERENCE_PILOT_SHARE, "certify.reference_storms")?;
        }
        Ok(())
    }

    /// The wind strata the analysis samples.
    fn strata(&self) -> WindStrata {
        match self.sampling {
            Sampling::Stratified => WindStrata::new(&self.climate, self.smallest_probability(), MAX_SPEED),
            Sampling::MonteCarlo => WindStrata::monte_carlo(),
        }
    }

    /// The smallest annual probability the answer must resolve, to the decade the strata need: 1/T
    /// (within 1/(2T²) of the level's 1 − exp(−1/T), and a whole decade where that is a hair below
    /// one, which would add a stratum that no level needs).
    fn smallest_probability(&self) -> f64 {
        self.return_periods.iter().map(|t| 1.0 / t).fold(1e-4, f64::min)
    }
}

/// The response level with a given mean recurrence interval.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct ReturnLevel {
    /// The mean recurrence interval T (years).
    pub return_period_years: f64,
    /// The level whose annual exceedance probability is 1 − exp(−1/T) (≈ 1/T for long periods;
    /// 0.632 for T = 1) (m); none when the sampled peaks do not reach so rare a level.
    pub value: Option<f64>,
    /// Where the band's ends cross that probability.
    pub lower: Option<f64>,
    /// The level where the band's upper end crosses the level's probability.
    pub upper: Option<f64>,
}

/// The annual probability of exceeding a limit and its reliability index β = −Φ⁻¹(P).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct Reliability {
    /// The limit (in the response's unit).
    pub limit: f64,
    /// P(the year's peak > limit).
    pub annual_probability: f64,
    /// The lower end of the annual probability's band.
    pub lower: f64,
    /// The upper end of the annual probability's band.
    pub upper: f64,
    /// The annual probability's coefficient of variation; none where no storm exceeded.
    pub cov: Option<f64>,
    /// None where the probability is 0 or 1 (β infinite).
    pub beta: Option<f64>,
    /// β at the band's ends (the upper probability gives the lower β); none where infinite.
    pub beta_lower: Option<f64>,
    /// β at the band's lower end.
    pub beta_upper: Option<f64>,
}

/// An annual exceedance curve with its band, return levels and what it leans on.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct HazardCurve {
    /// Peak values (m).
    pub thresholds: Vec<f64>,
    /// P(the year's peak > threshold).
    pub annual_probability: Vec<f64>,
    /// The band at `confidence`.
    pub lower: Vec<f64>,
    /// The band's upper end at each threshold.
    pub upper: Vec<f64>,
    /// Coefficient of variation of each probability; none where no storm exceeded.
    pub cov: Vec<Option<f64>>,
    /// Mean recurrence interval −1/ln(1 − P) (years, ≈ 1/P for small P); none where P is 0 or 1.
    pub mri_years: Vec<Option<f64>>,
    /// The levels of the return periods asked for.
    pub return_levels: Vec<ReturnLevel>,
    /// The limit's annual probability and reliability index, when a limit was asked for.
    pub reliability: Option<Reliability>,
    /// The law of the annual maximum storm speed at the 10 m station.
    pub climate: Marginal,
    /// The wind speeds of the calibration's experiments, lowest and highest (m/s).
    pub calibrated_wind_range: [f64; 2],
    /// Per threshold: the part of the annual probability from storms whose speed lies outside the
    /// calibrated range (where the metamodel extrapolates).
    pub probability_beyond_calibrated_range: Vec<f64>,
    /// The climate's probability of a speed outside the calibrated range.
    pub climate_beyond_calibrated_range: f64,
    /// The climate's probability of storms too rare to be run; they are counted as exceeding.
    pub unsampled_probability: f64,
    /// Storms whose metamodel free run diverged or had no stable rest (far outside the calibrated
    /// inputs, as a rule):
    /// counted as exceeding every threshold.
    pub diverged_storms: usize,
    /// The first few diverged storms with their inputs.
    #[serde(default)]
    pub first_diverged: Vec<DivergedStorm>,
    /// Storms run.
    pub samples: usize,
    /// Wind strata the storms were drawn in (1 for plain Monte Carlo).
    pub strata: usize,
    /// How the wind speeds were drawn.
    pub sampling: Sampling,
    /// The level of the bands.
    pub confidence: f64,
    /// What the reference storms did, when the curve was certified (then `annual_probability`,
    /// `lower`, `upper`, the return levels and the reliability are the certified ones).
    pub certification: Option<HazardCertification>,
}

/// The annual curve of the peaks that `peaks_of(rows, first)` returns for input rows drawn from
/// `inputs` with the wind speed replaced by the climate's (`first`: the number of rows run before,
/// so that every row gets its own storm). Stratified, a quarter of the storms go equally to the
/// strata and the rest by Neyman's allocation for the return periods asked for. Certified, the
/// storms through both models that `pairs_of(rows, first)` returns, for rows drawn alike from the
/// reference storms' seed, correct it stratum by stratum (what they did is the curve's
/// [`HazardCertification`]).
pub fn hazard_curve(
    inputs: &InputModel,
    options: &HazardOptions,
    calibrated: [f64; 2],
    mut peaks_of: impl FnMut(&[Vec<f64>], usize) -> Result<Vec<f64>>,
    pairs_of: impl FnMut(&[Vec<f64>], usize) -> Result<Vec<PairedPeak>>,
) -> Result<HazardCurve> {
    options.check()?;
    let strata = options.strata();
    let draws = StormRows { inputs, wind: inputs.index_of(WIND_SPEED)?, climate: &options.climate, strata: &strata };
    let design = AnnualDesign { rows: draws, samples: options.samples, calibrated };
    let one_column = |rows: &[Vec<f64>], first: usize| -> Result<Vec<Vec<f64>>> {
        Ok(peaks_of(rows, first)?.into_iter().map(|peak| vec![peak]).collect())
    };
    let aims = |columns: &[StratifiedPeaks]| targets(&columns[0], options).into_iter().map(|x| (0, x)).collect();
    let AnnualSample { columns, storms: run, diverged, first_diverged } =
        design.draw(&mut rng_from_seed(options.seed), one_column, aims)?;
    let draws = design.rows;
    let sample = columns.into_iter().next().expect("one column");
    let paired = match &options.certify {
        Some(certify) => {
            let seed = reference_storm_seed(options.seed);
            let targets = targets(&sample, options);
            Some(PairedStrata::draw(&draws, &sample, &targets, certify, REFERENCE_PILOT_SHARE, seed, pairs_of)?)
        }
        None => None,
    };
    let confidence = options.confidence;
    let peaks = sample.finite_peaks();
    let thresholds = options.thresholds.clone().unwrap_or_else(|| automatic_thresholds(&peaks, 50));
    let certified = |x: f64| paired.as_ref().map(|paired| paired.exceedance(&sample, x, confidence));
    let estimate = |x: f64| certified(x).map_or_else(|| sample.exceedance(x, confidence), |point| point.estimate);
    let estimates: Vec<Estimate> = thresholds.iter().map(|&x| estimate(x)).collect();
    let certification = paired.as_ref().map(|paired| {
        let points: Vec<CertifiedPoint> = thresholds.iter().filter_map(|&x| certified(x)).collect();
        paired.certification(&points)
    });
    let levels = paired.as_ref().map_or(peaks, |paired| paired.levels_with(&sample));
    let return_levels = options.return_periods.iter().map(|&t| return_level(&levels, t, estimate)).collect();
    let reliability = options.limit.map(|limit| reliability(limit, estimate(limit)));
    let climate = &options.climate;
    Ok(HazardCurve {
        annual_probability: estimates.iter().map(|e| e.probability).collect(),
        lower: estimates.iter().map(|e| e.lower).collect(),
        upper: estimates.iter().map(|e| e.upper).collect(),
        cov: estimates.iter().map(|e| e.cov).collect(),
        mri_years: estimates.iter().map(|e| period_of_annual_probability(e.probability)).collect(),
        probability_beyond_calibrated_range: estimates.iter().map(|e| e.beyond).collect(),
        thresholds,
        return_levels,
        reliability,
        climate: *climate,
        calibrated_wind_range: calibrated,
        climate_beyond_calibrated_range: climate.cdf(calibrated[0]) + climate.survival(calibrated[1]),
        unsampled_probability: strata.unsampled(),
        diverged_storms: diverged,
        first_diverged,
        samples: run,
        strata: strata.count(),
        sampling: options.sampling,
        confidence,
        certification,
    })
}

/// Levels scanned for a return level's first crossing before bisecting ([`return_level`]).
const RETURN_LEVEL_GRID: usize = 512;

/// The levels an allocation aims at: the metamodel's return levels asked for, its 10-year one
/// and the limit.
fn targets(sample: &StratifiedPeaks, options: &HazardOptions) -> Vec<f64> {
    let all = sample.finite_peaks();
    let estimate = |x: f64| sample.exceedance(x, options.confidence);
    let periods = options.return_periods.iter().chain(std::iter::once(&ALWAYS_TARGETED_PERIOD));
    periods.filter_map(|&t| return_level(&all, t, estimate).value).chain(options.limit).collect()
}

/// The return level of period T: the first of the ascending `levels` where the estimate falls to
/// 1 − exp(−1/T), and where each end of the band does. A certified band's ends need not fall
/// monotonically (a stratum's mismatch widens the band at some levels and not at the next), and
/// the first crossing is the cautious one; so the levels are scanned on a grid of at most
/// [`RETURN_LEVEL_GRID`] first, then bisected within the grid step where the first crossing lies
/// (a dip narrower than a grid step may be missed).
pub(in crate::analysis) fn return_level(
    levels: &[f64],
    period: f64,
    estimate: impl Fn(f64) -> Estimate,
) -> ReturnLevel {
    let target = annual_probability_of_period(period);
    let crossing = |end: fn(&Estimate) -> f64| {
        let above = |x: f64| end(&estimate(x)) > target;
        let step = levels.len().div_ceil(RETURN_LEVEL_GRID).max(1);
        let mut grid = (0..levels.len()).step_by(step).chain(levels.len().checked_sub(1));
        let first_below = grid.find(|&i| !above(levels[i]))?;
        let from = first_below.saturating_sub(step - 1);
        let i = from + levels[from..first_below].partition_point(|&x| above(x));
        levels.get(i).copied()
    };
    ReturnLevel {
        return_period_years: period,
        value: crossing(|e| e.probability),
        lower: crossing(|e| e.lower),
        upper: crossing(|e| e.upper),
    }
}

fn reliability(limit: f64, e: Estimate) -> Reliability {
    let beta = |p: f64| -> Option<f64> {
        (p > 0.0 && p < 1.0).then(|| -Normal::standard().inverse_cdf(p)).filter(|b| b.is_finite())
    };
    Reliability {
        limit,
        annual_probability: e.probability,
        lower: e.lower,
        upper: e.upper,
        cov: e.cov,
        beta: beta(e.probability),
        beta_lower: beta(e.upper),
        beta_upper: beta(e.lower),
    }
}

/// The annual curve of a metamodel's peak `response`; the climate replaces the metamodel's own
/// wind-speed marginal, every other input keeps its law.
pub fn metamodel_hazard(
    metamodel: &Metamodel,
    study: &Study,
    response: Response,
    options: &HazardOptions,
    runner: &dyn StormRunner,
    observer: &dyn Observer,
) -> Result<HazardCurve> {
    response.check(&study.structure)?;
    let calibrated = metamodel.calibrated_range(study, WIND_SPEED)?;
    let peaks_of = |rows: &[Vec<f64>], first: usize| {
        let storms: Vec<usize> = (first..first + rows.len()).collect();
        let draws = Draws { study, rows, storms: &storms, seed: options.seed, on_divergence: OnDivergence::Exceed };
        peaks_at(metamodel, &draws, response, runner, observer)
    };
    let order = options.certify.map_or(Order::Reduced, |c| c.order);
    let runs = PairedRuns { metamodel, study, seed: reference_storm_seed(options.seed), response, order };
    let pairs_of = |rows: &[Vec<f64>], first: usize| {
        let storms: Vec<usize> = (first..first + rows.len()).collect();
        runner.pairs(&runs, rows, &storms, observer)
    };
    hazard_curve(&study.inputs, options, calibrated, peaks_of, pairs_of)
}

#[cfg(test)]
pub(in crate::analysis) mod tests;
