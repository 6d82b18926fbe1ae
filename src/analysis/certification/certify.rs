//! Certified exceedance probabilities: the metamodel's curve corrected by storms run through both
//! the reference model and the metamodel, so that the answer is unbiased for the reference model
//! whatever the metamodel's error, and its band carries that error.
//!
//! With M storms through the metamodel alone and N others through both models, for a threshold t
//! and the indicators I_L, I_H that the metamodel's and the reference's peaks exceed it,
//!
//!   P̂(t) = (1/M) Σ_M I_L + (1/N) Σ_N (I_H − I_L),
//!
//! whose variance is p_L(1 − p_L)/M + [q − (p_H − p_L)²]/N with q = P(I_H ≠ I_L) (the control-
//! variate form of Peherstorfer, Willcox & Gunzburger, SIAM Review 2018). The correction is a
//! difference of paired proportions, which a plain normal interval undercovers when mismatches
//! are few; its band is Bonett & Price's adjusted Wald interval (Statistics in Medicine 2012: one
//! pseudo-count in each discordant cell), the metamodel's part Agresti & Coull's, their variances
//! summed. The unit tests measure the coverage.

use crate::analysis::responses::response::Response;
use crate::analysis::sampling::exceedance::{ExceedanceCurve, clopper_pearson, exceedance_curve};
use crate::analysis::sampling::reference_storms::{PairedPeak, PairedRuns, reference_rows, reference_storm_seed};
use crate::analysis::sampling::runner::StormRunner;
use crate::error::{Error, Result};
use crate::progress::Observer;
use crate::study::{Order, Study};
use crate::surrogate::Metamodel;
use crate::uncertainty::InputModel;
use serde::{Deserialize, Serialize};
use statrs::distribution::{ContinuousCDF, Normal};

/// Most reference storms one certified request may run (each costs a reference integration).
pub const MAX_REFERENCE_STORMS: usize = 5_000;

/// What a request asks of its certification.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(deny_unknown_fields)]
pub struct CertifyOptions {
    /// Storms run through both the reference model and the metamodel (1 to 5 000, at most the
    /// request's storms); each costs a reference integration (at full size about 0.08 s of one
    /// core reduced order, run eight at a time in vector lanes; 1.7 s full order).
    #[cfg_attr(feature = "openapi", schema(minimum = 1, maximum = 5000))]
    #[serde(deserialize_with = "crate::count::count")]
    pub reference_storms: usize,
    /// The reference model: the retained modes, as calibrated (`reduced`), or every floor
    /// (`full`), for users who distrust the modal cut.
    #[serde(default = "reduced")]
    pub order: Order,
}

fn reduced() -> Order {
    Order::Reduced
}

/// The exceedance curve of `metamodel_peaks` (the metamodel's own storms, drawn with `seed`) at
/// `thresholds`: plain, or certified when `certify` asks, its reference storms drawn from `inputs`
/// with a seed apart from the metamodel's and run by `runner`, and what they did.
#[allow(clippy::too_many_arguments)]
pub fn certify_exceedance(
    metamodel: &Metamodel,
    study: &Study,
    inputs: &InputModel,
    metamodel_peaks: &[f64],
    thresholds: &[f64],
    certify: Option<&CertifyOptions>,
    seed: u64,
    response: Response,
    confidence: f64,
    runner: &dyn StormRunner,
    observer: &dyn Observer,
) -> Result<(ExceedanceCurve, Option<Certification>)> {
    let Some(options) = certify else {
        return Ok((exceedance_curve(metamodel_peaks, thresholds, confidence), None));
    };
    check_reference_storms(options.reference_storms, metamodel_peaks.len(), "certify.reference_storms")?;
    let storms = options.reference_storms;
    let runs = PairedRuns { metamodel, study, seed: reference_storm_seed(seed), response, order: options.order };
    let (rows, streams) = reference_rows(inputs, storms, runs.seed);
    let paired = runner.pairs(&runs, &rows, &streams, observer)?;
    let CertifiedCurve { curve, certification, .. } =
        certified_curve(metamodel_peaks, &paired, thresholds, options.order, confidence);
    Ok((curve, Some(certification)))
}

/// What the reference storms did to a curve, point by point: threshold by threshold on an
/// exceedance curve, speed by speed on a fragility curve.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct Certification {
    /// Storms run through both the reference model and the metamodel.
    pub reference_storms: usize,
    /// The reference model they were run through.
    pub order: Order,
    /// The metamodel's own exceedance probabilities (its storms alone), with their
    /// Clopper-Pearson band at the curve's confidence: what an uncertified answer would say.
    pub metamodel_probabilities: Vec<f64>,
    /// The lower end of the metamodel's own band.
    pub metamodel_lower: Vec<f64>,
    /// The upper end of the metamodel's own band.
    pub metamodel_upper: Vec<f64>,
    /// Fraction of the reference storms where the two models fall on different sides of the
    /// threshold, the metamodel's peaks scaled by the factor the pairs show.
    pub mismatch_rate: Vec<f64>,
    /// All that was added to the metamodel's probability: the scaling of its peaks and the mean
    /// over the reference storms of I_H − I_L of the scaled peaks.
    pub correction: Vec<f64>,
    /// The correction's band at the curve's confidence.
    pub correction_lower: Vec<f64>,
    /// The upper end of the correction's band.
    pub correction_upper: Vec<f64>,
}

/// Errs unless 1 ≤ `storms` ≤ [`MAX_REFERENCE_STORMS`] and no more than the request's `samples`.
pub fn check_reference_storms(storms: usize, samples: usize, field: &str) -> Result<()> {
    if storms == 0 || storms > MAX_REFERENCE_STORMS {
        return Err(Error::invalid(field, format!("must be between 1 and {MAX_REFERENCE_STORMS}, got {storms}")));
    }
    if storms > samples {
        return Err(Error::invalid(
            field,
            format!("{storms} reference storms is more than the request's {samples} metamodel storms"),
        ));
    }
    Ok(())
}

/// A certified curve, what its correction was, and the variance its band stands for at each
/// threshold (the adjusted estimators' summed, before the band is clipped to [0, 1]).
pub struct CertifiedCurve {
    /// The certified curve with its band.
    pub curve: ExceedanceCurve,
    /// What the reference storms did to it, threshold by threshold.
    pub certification: Certification,
    /// The variance the band stands for at each threshold.
    pub variance: Vec<f64>,
}

/// The certified curve at `thresholds` from the metamodel's own peaks and the paired storms, with
/// what the correction was.
///
/// A metamodel whose peaks run a few per cent off the reference's disagrees with it on every storm
/// near a threshold, and each disagreement widens the band. So the metamodel's peaks are first
/// scaled by the factor its pairs show (the median ratio of the two models' peaks), and the pairs
/// correct what the scaled peaks still get wrong:
/// P̂ = Σ_h (n_h/N)·P_M(c_h·L > t) + (1/N)·Σ_i (I_H,i − 1[c_h(i)·L_i > t]). Each half h of the
/// pairs is corrected with a factor the other half chose, which keeps every term unbiased for the
/// reference whatever the factor.
pub fn certified_curve(
    metamodel_peaks: &[f64],
    paired: &[PairedPeak],
    thresholds: &[f64],
    order: Order,
    confidence: f64,
) -> CertifiedCurve {
    let z = Normal::standard().inverse_cdf(0.5 + confidence / 2.0);
    let (m, n) = (metamodel_peaks.len() as f64, paired.len() as f64);
    let mut sorted = metamodel_peaks.to_vec();
    sorted.sort_by(f64::total_cmp);
    let exceeding = |t: f64| (sorted.len() - sorted.partition_point(|&p| p <= t)) as f64;
    let halves = CrossFitted::new(paired);
    let mut curve = ExceedanceCurve {
        thresholds: thresholds.to_vec(),
        probabilities: Vec::with_capacity(thresholds.len()),
        lower: Vec::with_capacity(thresholds.len()),
        upper: Vec::with_capacity(thresholds.len()),
        samples: metamodel_peaks.len(),
        confidence,
    };
    let mut variance = Vec::with_capacity(thresholds.len());
    let mut certification = Certification {
        reference_storms: paired.len(),
        order,
        metamodel_probabilities: Vec::with_capacity(thresholds.len()),
        metamodel_lower: Vec::with_capacity(thresholds.len()),
        metamodel_upper: Vec::with_capacity(thresholds.len()),
        mismatch_rate: Vec::with_capacity(thresholds.len()),
        correction: Vec::with_capacity(thresholds.len()),
        correction_lower: Vec::with_capacity(thresholds.len()),
        correction_upper: Vec::with_capacity(thresholds.len()),
    };
    for &t in thresholds {
        // The scaled metamodel's probability, each half's factor weighted by the half's pairs.
        let scaled = (0..2).map(|h| halves.share(h) * exceeding(t / halves.factor[h]) / m).sum::<f64>();
        let (only_reference, only_metamodel) = paired.iter().enumerate().fold((0.0, 0.0), |(h, l), (i, pair)| {
            match (pair.reference > t, halves.scaled(i, pair.metamodel) > t) {
                (true, false) => (h + 1.0, l),
                (false, true) => (h, l + 1.0),
                _ => (h, l),
            }
        });
        let metamodel = AdjustedProportion::agresti_coull(scaled * m, m, z);
        let correction = AdjustedDifference::bonett_price(only_reference, only_metamodel, n);
        variance.push(metamodel.variance + correction.variance);
        let half_width = z * (metamodel.variance + correction.variance).sqrt();
        let centre = metamodel.centre + correction.centre;
        let estimate = scaled + (only_reference - only_metamodel) / n;
        curve.probabilities.push(estimate.clamp(0.0, 1.0));
        curve.lower.push((centre - half_width).clamp(0.0, 1.0));
        curve.upper.push((centre + half_width).clamp(0.0, 1.0));
        // What the metamodel alone says, and all that was added to it: the scaling and the pairs.
        let alone = exceeding(t) / m;
        let (metamodel_lower, metamodel_upper) = clopper_pearson(alone * m, m, confidence);
        let correction_half_width = z * correction.variance.sqrt();
        let scaling = scaled - alone;
        certification.metamodel_probabilities.push(alone);
        certification.metamodel_lower.push(metamodel_lower);
        certification.metamodel_upper.push(metamodel_upper);
        certification.mismatch_rate.push((only_reference + only_metamodel) / n);
        certification.correction.push(estimate - alone);
        certification.correction_lower.push((scaling + correction.centre - correction_half_width).max(-1.0));
        certification.correction_upper.push((scaling + correction.centre + correction_half_width).min(1.0));
    }
    CertifiedCurve { curve, certification, variance }
}

/// The paired storms in two halves (even and odd places) and the factor on the metamodel's peaks
/// each half is corrected with: exp of the median ln(H/L) over the *other* half's pairs where both
/// peaks are finite and positive (1 where it has none).
struct CrossFitted {
    factor: [f64; 2],
    /// Pairs in each half.
    pairs: [usize; 2],
}

impl CrossFitted {
    fn new(paired: &[PairedPeak]) -> Self {
        let log_ratios = |half: usize| -> Vec<f64> {
            paired
                .iter()
                .skip(half)
                .step_by(2)
                .filter(|p| {
                    p.reference > 0.0 && p.metamodel > 0.0 && p.reference.is_finite() && p.metamodel.is_finite()
                })
                .map(|p| (p.reference / p.metamodel).ln())
                .collect()
        };
        let factor_from = |half: usize| median(log_ratios(half)).map_or(1.0, f64::exp);
        CrossFitted { factor: [factor_from(1), factor_from(0)], pairs: [paired.len().div_ceil(2), paired.len() / 2] }
    }

    /// The share of the pairs in half `h`.
    fn share(&self, h: usize) -> f64 {
        self.pairs[h] as f64 / (self.pairs[0] + self.pairs[1]).max(1) as f64
    }

    /// Pair `i`'s metamodel peak scaled by its half's factor.
    fn scaled(&self, i: usize, peak: f64) -> f64 {
        self.factor[i % 2] * peak
    }
}

/// The median of `values`, None when empty.
fn median(mut values: Vec<f64>) -> Option<f64> {
    values.sort_by(f64::total_cmp);
    let n = values.len();
    (n > 0).then(|| if n % 2 == 1 { values[n / 2] } else { (values[n / 2 - 1] + values[n / 2]) / 2.0 })
}

/// A proportion's adjusted centre and the variance of its estimate.
struct AdjustedProportion {
    centre: f64,
    variance: f64,
}

impl AdjustedProportion {
    /// Agresti & Coull: z²/2 successes and z²/2 failures added.
    fn agresti_coull(successes: f64, trials: f64, z: f64) -> Self {
        let trials = trials + z * z;
        let centre = (successes + z * z / 2.0) / trials;
        AdjustedProportion { centre, variance: centre * (1.0 - centre) / trials }
    }
}

/// A difference of paired proportions, adjusted.
pub(super) struct AdjustedDifference {
    /// The adjusted difference, the centre of its band.
    pub centre: f64,
    /// The variance of the adjusted difference.
    pub variance: f64,
}

impl AdjustedDifference {
    /// Bonett & Price: one pseudo-count added to each discordant cell and two to the pairs, so
    /// that no mismatch among few pairs still leaves the band its width.
    pub(super) fn bonett_price(only_first: f64, only_second: f64, pairs: f64) -> Self {
        let (first, second) = ((only_first + 1.0) / (pairs + 2.0), (only_second + 1.0) / (pairs + 2.0));
        let centre = first - second;
        AdjustedDifference { centre, variance: (first + second - centre * centre) / (pairs + 2.0) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uncertainty::{Rng, rng_from_seed};
    use rand::RngExt;

    /// The reference's peak exp(0.3 z) and a surrogate 4 % low with 3 % scatter of its own: the
    /// surrogate's curve is biased, the reference's exceedance probability at t is Φ̄(ln t / 0.3).
    fn toy_storms(rng: &mut Rng, count: usize) -> Vec<PairedPeak> {
        let normal = Normal::standard();
        let mut draw = || normal.inverse_cdf(rng.random::<f64>().max(f64::MIN_POSITIVE));
        (0..count)
            .map(|_| {
                let (z, e) = (draw(), draw());
                let reference = (0.3 * z).exp();
                PairedPeak { reference, metamodel: 0.96 * reference * (0.03 * e).exp() }
            })
            .collect()
    }

    /// The 95 % band holds the reference's probability in at least 93 % of 400 repetitions, from
    /// 0.5 down to 10⁻³ (10 000 surrogate storms, 200 paired), where the surrogate alone is off by
    /// far more than its own band. Measured: 0.975, 0.9925, 1 and 1 at 0.5, 0.1, 10⁻², 10⁻³, with
    /// mean widths 0.12, 0.44, 2.5 and 15 times the probability.
    #[test]
    fn the_band_covers_the_reference_probability_whatever_the_surrogates_bias() {
        let normal = Normal::standard();
        let levels = [0.5, 0.1, 0.01, 1e-3];
        let thresholds: Vec<f64> = levels.iter().map(|&p| (0.3 * normal.inverse_cdf(1.0 - p)).exp()).collect();
        let mut rng = rng_from_seed(7);
        let mut covered = [0usize; 4];
        let mut surrogate_covered = [0usize; 4];
        let repetitions = 400;
        for _ in 0..repetitions {
            let metamodel: Vec<f64> = toy_storms(&mut rng, 10_000).iter().map(|p| p.metamodel).collect();
            let paired = toy_storms(&mut rng, 200);
            let curve = certified_curve(&metamodel, &paired, &thresholds, Order::Reduced, 0.95).curve;
            let plain = crate::analysis::sampling::exceedance::exceedance_curve(&metamodel, &thresholds, 0.95);
            for (i, &p) in levels.iter().enumerate() {
                covered[i] += usize::from(curve.lower[i] <= p && p <= curve.upper[i]);
                surrogate_covered[i] += usize::from(plain.lower[i] <= p && p <= plain.upper[i]);
            }
        }
        for (i, &p) in levels.iter().enumerate() {
            let coverage = covered[i] as f64 / repetitions as f64;
            assert!(coverage >= 0.93, "p = {p}: coverage {coverage}");
        }
        // The surrogate's own band misses at 0.5 and 0.1 (so the test has something to certify).
        assert!(surrogate_covered[0] < repetitions / 10 && surrogate_covered[1] < repetitions / 10);
    }

    /// Hand counts: 10 surrogate storms of which 3 exceed, 5 pairs with one storm exceeding only
    /// in the reference: 0.3 + 1/5; the mismatch rate 1/5. Each half's median ratio H/L is 1 (the
    /// even places' ratios are 4, 1 and 1), so no peak is scaled.
    #[test]
    fn the_estimate_adds_the_mean_disagreement() {
        let metamodel = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 1.5, 1.6, 1.7];
        let pair = |reference, metamodel| PairedPeak { reference, metamodel };
        let paired = [pair(2.0, 0.5), pair(0.2, 0.2), pair(3.0, 3.0), pair(0.1, 0.1), pair(0.4, 0.4)];
        let CertifiedCurve { curve, certification, .. } =
            certified_curve(&metamodel, &paired, &[1.0], Order::Reduced, 0.95);
        assert!((curve.probabilities[0] - 0.5).abs() < 1e-12);
        assert_eq!(certification.metamodel_probabilities, vec![0.3]);
        assert_eq!(certification.mismatch_rate, vec![0.2]);
        assert!((certification.correction[0] - 0.2).abs() < 1e-12);
        assert!(curve.lower[0] < 0.5 && 0.5 < curve.upper[0]);
    }

    /// A surrogate uniformly 4 % low disagrees with the reference near every threshold; scaled by
    /// the factor the other half of the pairs shows, it agrees on every pair, and the certified
    /// probability is the scaled surrogate's: the reference's own fraction over the same storms.
    #[test]
    fn a_surrogate_off_by_a_factor_is_scaled_before_it_is_corrected() {
        let mut rng = rng_from_seed(3);
        let storms = toy_storms(&mut rng, 2_000);
        let low: Vec<PairedPeak> = storms.iter().map(|p| PairedPeak { metamodel: 0.96 * p.reference, ..*p }).collect();
        let metamodel: Vec<f64> = low.iter().map(|p| p.metamodel).collect();
        let thresholds = [0.8, 1.0, 1.3];
        let CertifiedCurve { curve, certification, .. } =
            certified_curve(&metamodel, &low[..200], &thresholds, Order::Reduced, 0.95);
        for (i, &t) in thresholds.iter().enumerate() {
            let reference = storms.iter().filter(|p| p.reference > t).count() as f64 / 2_000.0;
            assert_eq!(certification.mismatch_rate[i], 0.0, "t = {t}");
            assert!((curve.probabilities[i] - reference).abs() < 1e-12, "t = {t}");
            let alone = certification.metamodel_probabilities[i];
            assert!((alone + certification.correction[i] - curve.probabilities[i]).abs() < 1e-12);
        }
    }

    #[test]
    fn reference_storms_are_bounded_by_the_contract_and_the_request() {
        assert!(check_reference_storms(200, 10_000, "certify.reference_storms").is_ok());
        for (storms, samples) in [(0, 100), (MAX_REFERENCE_STORMS + 1, 1_000_000), (300, 200)] {
            let error = check_reference_storms(storms, samples, "certify.reference_storms").unwrap_err();
            assert!(error.to_string().contains("certify.reference_storms"), "{error}");
        }
    }
}
