//! Peak profiles: the peak of a response at every floor where it exists, sampled from a metamodel
//! in one pass over the storms (every floor's peak from the same runs), and the profile of a
//! quantile of those peaks with a distribution-free confidence band.

use crate::analysis::responses::peaks::quantile;
use crate::analysis::responses::response::{Response, ResponseKind};
use crate::analysis::sampling::draws::{Draws, OnDivergence, check_samples, peak_sets_at};
use crate::analysis::sampling::exceedance::check_confidence;
use crate::analysis::sampling::runner::StormRunner;
use crate::error::{Error, Result};
use crate::progress::Observer;
use crate::study::Study;
use crate::surrogate::Metamodel;
use crate::uncertainty::{InputModel, monte_carlo, rng_from_seed};
use serde::{Deserialize, Serialize};
use statrs::distribution::{Binomial, DiscreteCDF};

/// The profile of one quantile of a response's peaks up the height.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct PeakProfile {
    /// The response's kind.
    pub response: ResponseKind,
    /// Its unit: m, m/s² or N.
    pub unit: String,
    /// The floors, bottom up (for damper responses, the floors above a damper).
    pub floors: Vec<usize>,
    /// The probability of the quantile, e.g. 0.9 for the peak exceeded by one storm in ten.
    pub quantile: f64,
    /// The quantile of the peaks at each floor (Hyndman-Fan type 7).
    pub values: Vec<f64>,
    /// Distribution-free band at `confidence`: order statistics x_(r) and x_(s) with
    /// P(r ≤ K < s) ≥ confidence, K ~ Binomial(samples, quantile).
    pub lower: Vec<f64>,
    /// The band's upper end at each floor.
    pub upper: Vec<f64>,
    /// The mean peak at each floor.
    pub means: Vec<f64>,
    /// Storms behind each floor's quantile.
    pub samples: usize,
    /// The band's level.
    pub confidence: f64,
}

/// Peaks of a response at every floor where it exists, for each storm.
#[derive(Debug, Clone)]
pub struct ProfileSamples {
    /// The response at each floor where it exists, bottom up.
    pub responses: Vec<Response>,
    /// `peaks[sample][i]`: the peak of `responses[i]` in storm `sample`.
    pub peaks: Vec<Vec<f64>>,
}

/// The responses of kind `kind` at every floor where the building has one, bottom up.
pub fn profile_responses(kind: ResponseKind, study: &Study) -> Result<Vec<Response>> {
    let floors = study.structure.floors();
    let present: Vec<Response> =
        (1..=floors).map(|floor| kind.at_floor(floor)).filter(|r| r.check(&study.structure).is_ok()).collect();
    if present.is_empty() {
        return Err(Error::invalid("response", format!("the structure has no floor with a {}", kind.name())));
    }
    Ok(present)
}

/// Peaks of `kind` at every floor over `samples` storms of the metamodel, inputs drawn from
/// `inputs`; sample k's inputs and storm depend only on (seed, k), as in an exceedance curve, so
/// a floor's peaks are those of the exceedance request of that floor with the same seed.
#[allow(clippy::too_many_arguments)]
pub fn metamodel_profiles(
    metamodel: &Metamodel,
    study: &Study,
    inputs: &InputModel,
    samples: usize,
    seed: u64,
    kind: ResponseKind,
    runner: &dyn StormRunner,
    observer: &dyn Observer,
) -> Result<ProfileSamples> {
    check_samples(samples)?;
    let responses = profile_responses(kind, study)?;
    let rows = monte_carlo(inputs, samples, &mut rng_from_seed(seed));
    let storms: Vec<usize> = (0..samples).collect();
    let draws = Draws { study, rows: &rows, storms: &storms, seed, on_divergence: OnDivergence::Fail };
    let peaks = peak_sets_at(metamodel, &draws, &responses, runner, observer)?;
    Ok(ProfileSamples { responses, peaks })
}

/// Errs unless 0 < p < 1.
pub fn check_quantile(p: f64) -> Result<()> {
    if p > 0.0 && p < 1.0 {
        Ok(())
    } else {
        Err(Error::invalid("quantile", format!("must lie strictly between 0 and 1, got {p}")))
    }
}

impl ProfileSamples {
    /// The profile of the `p` quantile with its band at `confidence`. Errs when the samples are
    /// too few for the band (its lower or upper order statistic would lie outside the sample).
    pub fn quantile_profile(&self, p: f64, confidence: f64) -> Result<PeakProfile> {
        check_quantile(p)?;
        check_confidence(confidence)?;
        let n = self.peaks.len();
        let (r, s) = order_statistics(n, p, confidence)?;
        let mut profile = PeakProfile {
            response: self.responses[0].kind(),
            unit: self.responses[0].unit().to_string(),
            floors: self.responses.iter().filter_map(Response::floor).collect(),
            quantile: p,
            values: Vec::new(),
            lower: Vec::new(),
            upper: Vec::new(),
            means: Vec::new(),
            samples: n,
            confidence,
        };
        for i in 0..self.responses.len() {
            let mut column: Vec<f64> = self.peaks.iter().map(|peaks| peaks[i]).collect();
            column.sort_by(f64::total_cmp);
            profile.values.push(quantile(&column, p));
            profile.lower.push(column[r - 1]);
            profile.upper.push(column[s - 1]);
            profile.means.push(column.iter().sum::<f64>() / n as f64);
        }
        Ok(profile)
    }
}

/// The 1-based ranks (r, s) of the order statistics bounding the `p` quantile of `n` samples at
/// `confidence`: with K ~ Binomial(n, p) the number of samples below the quantile,
/// P(x_(r) ≤ ξ_p < x_(s)) = P(r ≤ K < s); r is the largest rank with P(K < r) ≤ α/2 and s the
/// smallest with P(K ≥ s) ≤ α/2, so the band covers with probability at least `confidence`.
pub fn order_statistics(n: usize, p: f64, confidence: f64) -> Result<(usize, usize)> {
    let binomial = Binomial::new(p, n as u64).map_err(|e| Error::invalid("quantile", e.to_string()))?;
    let tail = (1.0 - confidence) / 2.0;
    // P(K < r) = cdf(r − 1).
    let r = (1..=n).take_while(|&r| binomial.cdf(r as u64 - 1) <= tail).last();
    // P(K ≥ s) = 1 − cdf(s − 1).
    let s = (1..=n).find(|&s| 1.0 - binomial.cdf(s as u64 - 1) <= tail);
    match (r, s) {
        (Some(r), Some(s)) => Ok((r, s)),
        _ => Err(Error::invalid(
            "samples",
            format!("{n} samples are too few for a {confidence} band of the {p} quantile; draw more"),
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Ranks from the binomial tails, checked against a direct sum: for n = 100, p = 0.9 at 95 %
    /// the band is x_(84)..x_(96) (P(K ≤ 83) = 0.0206, P(K ≤ 84) = 0.0399 > 0.025;
    /// P(K ≥ 96) = 0.0237, P(K ≥ 95) = 0.0576, by exact binomial sums).
    #[test]
    fn order_statistics_bound_the_quantile() {
        assert_eq!(order_statistics(100, 0.9, 0.95).unwrap(), (84, 96));
        assert_eq!(order_statistics(101, 0.5, 0.95).unwrap().0 + order_statistics(101, 0.5, 0.95).unwrap().1, 102);
        assert!(order_statistics(10, 0.99, 0.95).unwrap_err().to_string().contains("too few"));
    }

    #[test]
    fn quantile_profile_of_known_peaks() {
        let responses = vec![Response::Drift { floor: 1 }, Response::Drift { floor: 2 }];
        let peaks: Vec<Vec<f64>> = (1..=100).map(|k| vec![k as f64, 2.0 * k as f64]).collect();
        let profile = ProfileSamples { responses, peaks }.quantile_profile(0.9, 0.95).unwrap();
        assert_eq!(profile.floors, vec![1, 2]);
        assert!((profile.values[0] - 90.1).abs() < 1e-12, "{}", profile.values[0]);
        assert_eq!((profile.lower[0], profile.upper[0]), (84.0, 96.0));
        assert_eq!((profile.lower[1], profile.upper[1]), (168.0, 192.0));
        assert!((profile.means[1] - 101.0).abs() < 1e-12);
    }
}
