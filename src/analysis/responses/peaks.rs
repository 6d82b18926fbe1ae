//! Summary statistics of sampled peak responses.

use serde::Serialize;

/// Mean, sample standard deviation and quantiles of a set of peaks.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PeakSummary {
    /// The mean peak.
    pub mean: f64,
    /// The sample standard deviation of the peaks.
    pub sd: f64,
    /// (probability, value) pairs.
    pub quantiles: Vec<(f64, f64)>,
}

/// The probabilities reported by default.
pub const REPORTED_PROBABILITIES: [f64; 7] = [0.01, 0.05, 0.25, 0.5, 0.75, 0.95, 0.99];

impl PeakSummary {
    /// The summary of `values` (at least one), its quantiles at the reported probabilities (1, 5,
    /// 25, 50, 75, 95 and 99 %).
    pub fn of(values: &[f64]) -> Self {
        let n = values.len() as f64;
        let mean = values.iter().sum::<f64>() / n;
        let sd = if values.len() > 1 {
            (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt()
        } else {
            0.0
        };
        let mut sorted = values.to_vec();
        sorted.sort_by(f64::total_cmp);
        let quantiles = REPORTED_PROBABILITIES.iter().map(|&p| (p, quantile(&sorted, p))).collect();
        PeakSummary { mean, sd, quantiles }
    }
}

/// Pearson's correlation of two equally long samples.
pub fn pearson(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len() as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let cov: f64 = a.iter().zip(b).map(|(x, y)| (x - ma) * (y - mb)).sum();
    let va: f64 = a.iter().map(|x| (x - ma).powi(2)).sum();
    let vb: f64 = b.iter().map(|y| (y - mb).powi(2)).sum();
    cov / (va * vb).sqrt()
}

/// Quantile of sorted data by linear interpolation between order statistics (Hyndman-Fan type 7,
/// the default of R and NumPy).
pub fn quantile(sorted: &[f64], p: f64) -> f64 {
    let h = (sorted.len() - 1) as f64 * p;
    let lo = h.floor() as usize;
    let hi = (lo + 1).min(sorted.len() - 1);
    sorted[lo] + (h - lo as f64) * (sorted[hi] - sorted[lo])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// numpy.quantile([1, 2, 3, 4, 10], [0.25, 0.5, 0.9]) = [2.0, 3.0, 7.6].
    #[test]
    fn quantiles_match_numpy() {
        let data = [1.0, 2.0, 3.0, 4.0, 10.0];
        assert_eq!(quantile(&data, 0.25), 2.0);
        assert_eq!(quantile(&data, 0.5), 3.0);
        assert!((quantile(&data, 0.9) - 7.6).abs() < 1e-12);
        let s = PeakSummary::of(&data);
        assert_eq!(s.mean, 4.0);
        assert!((s.sd - 12.5f64.sqrt()).abs() < 1e-12);
    }
}
