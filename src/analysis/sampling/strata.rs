//! Rare annual probabilities by stratifying the wind speed.
//!
//! A tall building's peak response grows with the storm's mean speed roughly as v², far faster than
//! with any other input, so the storms that exceed a rare threshold are nearly all storms of a rare
//! speed. The climate's upper-tail probability q = 1 − F(v) is cut into strata — [1, 0.5],
//! [0.5, 0.1], then one per decade down to q_min — and each stratum gets the same number of storms,
//! its speeds drawn from the climate conditioned on the stratum and every other input from the
//! input model. The estimate of P(peak > x) is Σ_s w_s k_s/n_s with w_s the stratum's probability,
//! and its variance Σ_s w_s² p̂_s(1 − p̂_s)/n_s: a probability of 10⁻⁵ is estimated from the
//! thousands of storms its decade holds instead of the one storm in 10⁵ plain Monte Carlo would
//! give it. Storms rarer than q_min (one hundredth of the smallest probability asked for) are not
//! run; they are counted as exceeding, which biases an estimate upwards by at most q_min.
//!
//! With one stratum [1, 0] this is plain Monte Carlo, and the band is Clopper-Pearson's.

use super::exceedance::clopper_pearson;
use crate::error::{Error, Result};
use crate::uncertainty::{InputModel, Marginal, Rng, monte_carlo};
use crate::wind::WindLoads;
use rand::RngExt;
use serde::{Deserialize, Serialize};
use statrs::distribution::{ContinuousCDF, Normal};

/// How the wind speeds of an annual analysis are drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(rename_all = "snake_case")]
pub enum Sampling {
    /// Equal numbers of storms per stratum of the climate's tail (the default).
    #[default]
    Stratified,
    /// Plain Monte Carlo from the climate: the check of the stratified estimate.
    MonteCarlo,
}

/// The strata of the climate's upper-tail probability q = 1 − F(v), and their speeds.
#[derive(Debug, Clone, PartialEq)]
pub struct WindStrata {
    /// Falling boundaries in q, from 1 to q_min (0 for plain Monte Carlo).
    pub bounds: Vec<f64>,
}

impl WindStrata {
    /// Strata for probabilities down to `smallest`, q_min = smallest/100, raised where needed so
    /// that no sampled speed exceeds `max_speed`.
    pub fn new(climate: &Marginal, smallest: f64, max_speed: f64) -> Self {
        let mut q_min = (smallest / 100.0).clamp(1e-15, 0.01);
        while climate.upper_quantile(q_min) >= max_speed && q_min < 0.01 {
            q_min *= 10f64.powf(0.25);
        }
        let mut bounds = vec![1.0, 0.5, 0.1];
        while bounds[bounds.len() - 1] / 10.0 > q_min * (1.0 + 1e-9) {
            let next = bounds[bounds.len() - 1] / 10.0;
            bounds.push(next);
        }
        bounds.push(q_min.min(bounds[bounds.len() - 1] / 2.0));
        WindStrata { bounds }
    }

    /// One stratum: plain Monte Carlo.
    pub fn monte_carlo() -> Self {
        WindStrata { bounds: vec![1.0, 0.0] }
    }

    /// The number of strata.
    pub fn count(&self) -> usize {
        self.bounds.len() - 1
    }

    /// The climate's probability of each stratum.
    pub fn weights(&self) -> Vec<f64> {
        self.bounds.windows(2).map(|b| b[0] - b[1]).collect()
    }

    /// The probability no storm represents: storms rarer than the last boundary.
    pub fn unsampled(&self) -> f64 {
        self.bounds[self.bounds.len() - 1]
    }

    /// `counts[s]` speeds in each stratum s in turn: q uniform in the stratum, v = F⁻¹(1 − q).
    pub fn speeds(&self, climate: &Marginal, counts: &[usize], rng: &mut Rng) -> Vec<f64> {
        let mut speeds = Vec::with_capacity(counts.iter().sum());
        for (b, &count) in self.bounds.windows(2).zip(counts) {
            for _ in 0..count {
                let u: f64 = rng.random();
                // (0, 1]: never the stratum's upper boundary q = b[0] = 1, where v is 0.
                let q = b[1] + (b[0] - b[1]) * (1.0 - u);
                speeds.push(climate.upper_quantile(q.max(1e-300)));
            }
        }
        speeds
    }

    /// Neyman's allocation of `budget` storms for the given pilots: n_s ∝ w_s·√(p_s(1 − p_s)), the
    /// allocation of least variance, summed over the targets (a pilot's peaks and a level x of
    /// them) each weighted by 1/P(x)² so that every target's relative error counts alike; p_s from
    /// the pilot as (k + ½)/(n + 1), so that a stratum the pilot saw no exceedance in keeps some
    /// storms.
    pub fn neyman(&self, targets: &[(&StratifiedPeaks, f64)], budget: usize) -> Vec<usize> {
        let weights = self.weights();
        let mut scores = vec![0.0; weights.len()];
        for &(pilot, x) in targets {
            let total = pilot.exceedance_fraction(x).max(f64::MIN_POSITIVE);
            for (s, stratum) in pilot.strata.iter().enumerate() {
                let hits = (stratum.len() - stratum.partition_point(|p| p.0 <= x)) as f64;
                let p = (hits + 0.5) / (stratum.len() as f64 + 1.0);
                scores[s] += weights[s] * (p * (1.0 - p)).sqrt() / total;
            }
        }
        let sum: f64 = scores.iter().sum();
        if sum.is_nan() || sum <= 0.0 {
            // No target: the storms shared equally.
            return vec![budget / weights.len(); weights.len()];
        }
        scores.iter().map(|a| (budget as f64 * a / sum).floor() as usize).collect()
    }
}

/// How an annual analysis draws its storms' inputs: every input from its law, the wind speed
/// from the climate within each stratum.
pub struct StormRows<'a> {
    /// The input model every other input is drawn from.
    pub inputs: &'a InputModel,
    /// The wind speed's position among the inputs.
    pub wind: usize,
    /// The law of the annual maximum storm speed.
    pub climate: &'a Marginal,
    /// The strata of the climate's tail the speeds are drawn in.
    pub strata: &'a WindStrata,
}

impl StormRows<'_> {
    /// `counts[s]` rows in each stratum s in turn, and their speeds.
    pub fn rows(&self, counts: &[usize], rng: &mut Rng) -> Result<(Vec<Vec<f64>>, Vec<f64>)> {
        let speeds = self.strata.speeds(self.climate, counts, rng);
        if let Some(&v) = speeds.iter().find(|v| WindLoads::check_speed(**v).is_err()) {
            return Err(Error::invalid("climate", format!("puts weight on a speed the wind model refuses ({v} m/s)")));
        }
        let mut rows = monte_carlo(self.inputs, speeds.len(), rng);
        for (row, &v) in rows.iter_mut().zip(&speeds) {
            row[self.wind] = v;
        }
        Ok((rows, speeds))
    }
}

/// A pilot's storms per stratum: all of `storms` for one stratum, else one in `share` shared
/// equally, at least two per stratum (errs naming `field` below that).
pub fn pilot(strata: &WindStrata, storms: usize, share: usize, field: &str) -> Result<Vec<usize>> {
    let share = if strata.count() == 1 { 1 } else { share };
    let counts = vec![storms / share / strata.count(); strata.count()];
    if counts[0] < 2 {
        return Err(Error::invalid(
            field,
            format!("must be at least {} for the {} strata", 2 * share * strata.count(), strata.count()),
        ));
    }
    Ok(counts)
}

/// An estimated probability with its error.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// The estimated probability.
    pub probability: f64,
    /// The lower end of its band.
    pub lower: f64,
    /// The upper end of its band.
    pub upper: f64,
    /// Coefficient of variation; none when no sampled storm exceeds.
    pub cov: Option<f64>,
    /// The part of `probability` from storms outside the calibrated speeds.
    pub beyond: f64,
}

/// The peaks of a stratified sample, each stratum's sorted, with which of them came from speeds
/// outside the calibrated range.
pub struct StratifiedPeaks {
    weights: Vec<f64>,
    unsampled: f64,
    /// Per stratum: (peak, outside the calibrated range), by peak.
    strata: Vec<Vec<(f64, bool)>>,
}

impl StratifiedPeaks {
    /// `peaks` and `outside` in the order of [`WindStrata::speeds`] with `counts`.
    pub fn new(strata: &WindStrata, counts: &[usize], peaks: &[f64], outside: &[bool]) -> Self {
        let mut stratified = StratifiedPeaks {
            weights: strata.weights(),
            unsampled: strata.unsampled(),
            strata: vec![Vec::new(); strata.count()],
        };
        stratified.add(counts, peaks, outside);
        stratified
    }

    /// More storms, in the order of [`WindStrata::speeds`] with `counts`.
    pub fn add(&mut self, counts: &[usize], peaks: &[f64], outside: &[bool]) {
        let mut first = 0;
        for (stratum, &count) in self.strata.iter_mut().zip(counts) {
            stratum
                .extend(peaks[first..first + count].iter().copied().zip(outside[first..first + count].iter().copied()));
            stratum.sort_by(|a, b| a.0.total_cmp(&b.0));
            first += count;
        }
    }

    /// The point estimate of P(peak > x), without its band.
    pub(in crate::analysis) fn exceedance_fraction(&self, x: f64) -> f64 {
        let sampled = self.weights.iter().zip(&self.strata).map(|(w, stratum)| {
            w * (stratum.len() - stratum.partition_point(|s| s.0 <= x)) as f64 / stratum.len() as f64
        });
        sampled.sum::<f64>() + self.unsampled
    }

    /// Every finite sampled peak (a diverged storm's is infinite), ascending.
    pub fn finite_peaks(&self) -> Vec<f64> {
        let mut all: Vec<f64> = self.strata.iter().flatten().map(|p| p.0).filter(|p| p.is_finite()).collect();
        all.sort_by(f64::total_cmp);
        all
    }

    /// The climate's probability of each stratum.
    pub(in crate::analysis) fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// The probability of storms too rare to be run, counted as exceeding.
    pub(in crate::analysis) fn unsampled(&self) -> f64 {
        self.unsampled
    }

    /// Stratum `s`'s finite peaks within [lo, hi], ascending, its diverged storms (whose peaks
    /// are infinite) and its number of storms.
    pub(in crate::analysis) fn window(&self, s: usize, lo: f64, hi: f64) -> (&[(f64, bool)], usize, usize) {
        let stratum = &self.strata[s];
        let finite = stratum.partition_point(|p| p.0.is_finite());
        let first = stratum.partition_point(|p| p.0 < lo).min(finite);
        let end = stratum.partition_point(|p| p.0 <= hi).clamp(first, finite);
        (&stratum[first..end], stratum.len() - finite, stratum.len())
    }

    /// P(peak > x) with its band at `confidence`: the sampled strata's part ([`Self::sampled`])
    /// and the unsampled tail, which widens the band by its probability.
    pub fn exceedance(&self, x: f64, confidence: f64) -> Estimate {
        let part = self.sampled(x, confidence);
        let probability = part.probability + self.unsampled;
        Estimate {
            probability,
            lower: part.lower,
            upper: (part.upper + self.unsampled).min(1.0),
            cov: (part.probability > 0.0).then(|| part.variance.sqrt() / probability),
            beyond: part.beyond + self.unsampled,
        }
    }

    /// The sampled strata's part of P(peak > x). Its band is Wilson's at the effective sample size
    /// n* = p̂(1 − p̂)/Var p̂ (Kish's design effect; the fraction's own when no storm exceeds), and
    /// Clopper-Pearson's for one stratum.
    pub(in crate::analysis) fn sampled(&self, x: f64, confidence: f64) -> SampledPart {
        let sampled: f64 = self.weights.iter().sum();
        let (mut p, mut variance, mut beyond, mut kish) = (0.0, 0.0, 0.0, 0.0);
        for (w, stratum) in self.weights.iter().zip(&self.strata) {
            let n = stratum.len() as f64;
            let first = stratum.partition_point(|s| s.0 <= x);
            let hits = (stratum.len() - first) as f64;
            let outside = stratum[first..].iter().filter(|s| s.1).count() as f64;
            let ps = hits / n;
            p += w * ps;
            beyond += w * outside / n;
            variance += w * w * ps * (1.0 - ps) / n;
            kish += (w / sampled).powi(2) / n;
        }
        let share = p / sampled;
        let (lo, hi) = if self.strata.len() == 1 {
            let n = self.strata[0].len() as f64;
            clopper_pearson((share * n).round(), n, confidence)
        } else {
            let effective =
                if variance > 0.0 { share * (1.0 - share) / (variance / sampled.powi(2)) } else { 1.0 / kish };
            wilson(share, effective, confidence)
        };
        SampledPart { probability: p, variance, lower: sampled * lo, upper: sampled * hi, beyond }
    }
}

/// The sampled strata's part of an exceedance probability.
pub(in crate::analysis) struct SampledPart {
    /// The sampled strata's part of the probability.
    pub probability: f64,
    /// The variance of `probability`.
    pub variance: f64,
    /// Its band.
    pub lower: f64,
    /// Its band's upper end.
    pub upper: f64,
    /// The part of `probability` from storms outside the calibrated speeds.
    pub beyond: f64,
}

/// Wilson's score interval for a proportion p̂ from n (effective) trials: closed form, sound for
/// few successes, and free of the incomplete beta function, whose inversion does not converge
/// reliably at the effective sizes of a stratified estimate (10⁸ and more).
fn wilson(p: f64, n: f64, confidence: f64) -> (f64, f64) {
    let z = Normal::standard().inverse_cdf(0.5 + confidence / 2.0);
    let z2n = z * z / n;
    let centre = (p + z2n / 2.0) / (1.0 + z2n);
    let half = z / (1.0 + z2n) * (p * (1.0 - p) / n + z2n / (4.0 * n)).sqrt();
    ((centre - half).max(0.0), (centre + half).min(1.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uncertainty::rng_from_seed;

    /// With the peak equal to the speed, P(peak > x) is the climate's own tail 1 − F(x): the
    /// stratified estimate finds 2·10⁻⁵ and 3·10⁻⁶ to within its stated error from 9 000 storms,
    /// where plain Monte Carlo with as many would see none.
    #[test]
    fn stratified_estimate_reaches_the_far_tail_of_a_known_law() {
        let climate = Marginal::Gumbel { location: 25.0, scale: 2.5 };
        let strata = WindStrata::new(&climate, 1e-6, 150.0);
        assert_eq!(strata.count(), 9, "{:?}", strata.bounds);
        let counts = vec![1000; strata.count()];
        let speeds = strata.speeds(&climate, &counts, &mut rng_from_seed(3));
        let estimate = StratifiedPeaks::new(&strata, &counts, &speeds, &vec![false; speeds.len()]);
        for q in [0.3, 3e-2, 2e-5, 3e-6] {
            let e = estimate.exceedance(climate.upper_quantile(q), 0.95);
            let cov = e.cov.unwrap();
            assert!(cov < 0.1, "q = {q}: cov {cov}");
            assert!((e.probability / q - 1.0).abs() < 4.0 * cov + 0.01, "q = {q}: {}", e.probability);
            assert!(e.lower <= q && q <= e.upper * 1.0001, "q = {q}: [{}, {}]", e.lower, e.upper);
        }
    }

    /// One stratum is plain Monte Carlo: the band is Clopper-Pearson's for k of n.
    #[test]
    fn one_stratum_is_plain_monte_carlo() {
        let strata = WindStrata::monte_carlo();
        let peaks: Vec<f64> = (0..10).map(f64::from).collect();
        let e = StratifiedPeaks::new(&strata, &[10], &peaks, &[false; 10]).exceedance(6.5, 0.95);
        assert_eq!(e.probability, 0.3);
        let (lo, hi) = clopper_pearson(3.0, 10.0, 0.95);
        assert!((e.lower - lo).abs() < 1e-12 && (e.upper - hi).abs() < 1e-12);
    }

    #[test]
    fn strata_stop_below_the_largest_speed() {
        let climate = Marginal::Frechet { mean: 30.0, sd: 3.5 };
        let strata = WindStrata::new(&climate, 1e-9, 150.0);
        assert!(climate.upper_quantile(strata.unsampled()) < 150.0);
        assert!(strata.unsampled() > 1e-11);
    }
}
