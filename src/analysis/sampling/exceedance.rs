//! The exceedance estimator of a sample of peaks: P(peak > x) over a threshold grid with exact
//! binomial (Clopper-Pearson) confidence bands, the checks of thresholds and confidence levels
//! that every analysis shares, and the largest gap between two samples' curves. The sampling
//! that feeds it is in [`super::draws`]; the answer a user asks for, `metamodel_exceedance`, is
//! in the answers room.

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};
use statrs::distribution::{Beta, ContinuousCDF};

/// An empirical exceedance curve with its band.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct ExceedanceCurve {
    /// The peak values (in the response's unit) at which the curve is evaluated.
    pub thresholds: Vec<f64>,
    /// Fraction of samples whose peak exceeds each threshold.
    pub probabilities: Vec<f64>,
    /// Clopper-Pearson band at `confidence`.
    pub lower: Vec<f64>,
    /// The band's upper end at each threshold.
    pub upper: Vec<f64>,
    /// Storms whose peaks the curve counts.
    pub samples: usize,
    /// The band's level.
    pub confidence: f64,
}

/// `count` thresholds evenly spread from the smallest to the largest peak.
pub fn automatic_thresholds(peaks: &[f64], count: usize) -> Vec<f64> {
    let lo = peaks.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = peaks.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if count < 2 || hi <= lo {
        return vec![lo];
    }
    (0..count).map(|i| lo + (hi - lo) * i as f64 / (count - 1) as f64).collect()
}

/// Exact binomial (Clopper-Pearson) interval for k successes in n trials; k and n may be
/// effective counts, not whole (a stratified estimate's, by Korn & Graubard).
pub(in crate::analysis) fn clopper_pearson(k: f64, n: f64, confidence: f64) -> (f64, f64) {
    let alpha = 1.0 - confidence;
    let lower = if k <= 0.0 { 0.0 } else { Beta::new(k, n - k + 1.0).map_or(0.0, |b| b.inverse_cdf(alpha / 2.0)) };
    let upper = if k >= n { 1.0 } else { Beta::new(k + 1.0, n - k).map_or(1.0, |b| b.inverse_cdf(1.0 - alpha / 2.0)) };
    (lower, upper)
}

/// Errs unless 0 < `confidence` < 1, naming the field `confidence`.
pub fn check_confidence(confidence: f64) -> Result<()> {
    if confidence > 0.0 && confidence < 1.0 {
        Ok(())
    } else {
        Err(Error::invalid("confidence", format!("must lie strictly between 0 and 1, got {confidence}")))
    }
}

/// The exceedance curve of `peaks` at `thresholds`.
pub fn exceedance_curve(peaks: &[f64], thresholds: &[f64], confidence: f64) -> ExceedanceCurve {
    let n = peaks.len();
    let mut sorted = peaks.to_vec();
    sorted.sort_by(f64::total_cmp);
    let mut probabilities = Vec::with_capacity(thresholds.len());
    let mut lower = Vec::with_capacity(thresholds.len());
    let mut upper = Vec::with_capacity(thresholds.len());
    for &x in thresholds {
        let exceeding = n - sorted.partition_point(|&p| p <= x);
        let (lo, hi) = clopper_pearson(exceeding as f64, n as f64, confidence);
        probabilities.push(exceeding as f64 / n as f64);
        lower.push(lo);
        upper.push(hi);
    }
    ExceedanceCurve { thresholds: thresholds.to_vec(), probabilities, lower, upper, samples: n, confidence }
}

/// Largest vertical gap between the empirical exceedance curves of two samples (the two-sample
/// Kolmogorov-Smirnov statistic), over every threshold.
pub fn max_exceedance_gap(a: &[f64], b: &[f64]) -> f64 {
    let mut all: Vec<f64> = a.iter().chain(b).copied().collect();
    all.sort_by(f64::total_cmp);
    let (mut sa, mut sb) = (a.to_vec(), b.to_vec());
    sa.sort_by(f64::total_cmp);
    sb.sort_by(f64::total_cmp);
    all.iter()
        .map(|&x| {
            let pa = (sa.len() - sa.partition_point(|&p| p <= x)) as f64 / sa.len() as f64;
            let pb = (sb.len() - sb.partition_point(|&p| p <= x)) as f64 / sb.len() as f64;
            (pa - pb).abs()
        })
        .fold(0.0, f64::max)
}

/// Most thresholds a request may list.
pub const MAX_THRESHOLDS: usize = 10_000;
/// Largest threshold, in the response's unit (m, m/s² or N): peaks are absolute values, so
/// thresholds are non-negative, and no displacement, acceleration or damper force comes near 10⁹
/// of its unit; the bound only keeps absurd values out.
pub const MAX_THRESHOLD: f64 = 1e9;

/// Errs unless `thresholds` holds 1 to [`MAX_THRESHOLDS`] values in [0, [`MAX_THRESHOLD`]].
pub fn check_thresholds(thresholds: &[f64]) -> Result<()> {
    if thresholds.is_empty()
        || thresholds.len() > MAX_THRESHOLDS
        || thresholds.iter().any(|x| !(0.0..=MAX_THRESHOLD).contains(x))
    {
        return Err(Error::invalid(
            "thresholds",
            format!("must be 1 to {MAX_THRESHOLDS} numbers between 0 and {MAX_THRESHOLD:e}, in the response's unit"),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn curve_counts_exceedances() {
        let peaks = [1.0, 2.0, 3.0, 4.0];
        let c = exceedance_curve(&peaks, &[0.5, 2.0, 2.5, 4.0], 0.95);
        assert_eq!(c.probabilities, vec![1.0, 0.5, 0.5, 0.0]);
        assert!(c.lower.iter().zip(&c.probabilities).all(|(l, p)| l <= p));
        assert!(c.upper.iter().zip(&c.probabilities).all(|(u, p)| u >= p));
    }

    /// Clopper-Pearson for 3 of 10 at 95 %: (0.06674, 0.65245) (scipy.stats.binomtest(3, 10).proportion_ci()).
    #[test]
    fn clopper_pearson_matches_scipy() {
        let (lo, hi) = clopper_pearson(3.0, 10.0, 0.95);
        assert!((lo - 0.066739).abs() < 1e-5, "{lo}");
        assert!((hi - 0.652453).abs() < 1e-5, "{hi}");
        assert_eq!(clopper_pearson(0.0, 10.0, 0.95).0, 0.0);
        assert_eq!(clopper_pearson(10.0, 10.0, 0.95).1, 1.0);
    }

    #[test]
    fn gap_is_the_two_sample_ks_statistic() {
        assert_eq!(max_exceedance_gap(&[1.0, 2.0, 3.0], &[1.0, 2.0, 3.0]), 0.0);
        assert!((max_exceedance_gap(&[1.0, 2.0, 3.0, 4.0], &[3.5, 5.0, 6.0, 7.0]) - 0.75).abs() < 1e-12);
    }
}
