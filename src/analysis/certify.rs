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

use super::Response;
use super::exceedance::{ExceedanceCurve, clopper_pearson, exceedance_curve};
use super::plot::exceedance_svg;
use super::reference_storms::{PairedPeak, PairedRuns, ReferenceRunner, reference_storm_seed};
use crate::error::{Error, Result};
use crate::progress::Observer;
use crate::study::{Order, Study};
use crate::surrogate::Metamodel;
use crate::uncertainty::{InputModel, monte_carlo, rng_from_seed};
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
    /// request's storms); each costs a reference integration (at full size about 0.26 s of one
    /// core reduced order, 1.9 s full order).
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
    runner: &dyn ReferenceRunner,
    observer: &dyn Observer,
) -> Result<(ExceedanceCurve, Option<Certification>)> {
    let Some(options) = certify else {
        return Ok((exceedance_curve(metamodel_peaks, thresholds, confidence), None));
    };
    check_reference_storms(options.reference_storms, metamodel_peaks.len(), "certify.reference_storms")?;
    let storms = options.reference_storms;
    let runs = PairedRuns { metamodel, study, seed: reference_storm_seed(seed), response, order: options.order };
    let rows = monte_carlo(inputs, storms, &mut rng_from_seed(runs.seed));
    let streams: Vec<usize> = (0..storms).collect();
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
    pub metamodel_lower: Vec<f64>,
    pub metamodel_upper: Vec<f64>,
    /// Fraction of the reference storms where the two models fall on different sides of the
    /// threshold.
    pub mismatch_rate: Vec<f64>,
    /// Mean over the reference storms of I_H − I_L, added to the metamodel's probability.
    pub correction: Vec<f64>,
    /// The correction's band at the curve's confidence.
    pub correction_lower: Vec<f64>,
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
    pub curve: ExceedanceCurve,
    pub certification: Certification,
    pub variance: Vec<f64>,
}

/// The certified curve at `thresholds` from the metamodel's own peaks and the paired storms, with
/// what the correction was.
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
        let exceeding = (sorted.len() - sorted.partition_point(|&p| p <= t)) as f64;
        let (only_reference, only_metamodel) =
            paired.iter().fold((0.0, 0.0), |(h, l), pair| match (pair.reference > t, pair.metamodel > t) {
                (true, false) => (h + 1.0, l),
                (false, true) => (h, l + 1.0),
                _ => (h, l),
            });
        let metamodel = AdjustedProportion::agresti_coull(exceeding, m, z);
        let correction = AdjustedDifference::bonett_price(only_reference, only_metamodel, n);
        variance.push(metamodel.variance + correction.variance);
        let half_width = z * (metamodel.variance + correction.variance).sqrt();
        let centre = metamodel.centre + correction.centre;
        let estimate = exceeding / m + (only_reference - only_metamodel) / n;
        curve.probabilities.push(estimate.clamp(0.0, 1.0));
        curve.lower.push((centre - half_width).clamp(0.0, 1.0));
        curve.upper.push((centre + half_width).clamp(0.0, 1.0));
        let correction_half_width = z * correction.variance.sqrt();
        let (metamodel_lower, metamodel_upper) = clopper_pearson(exceeding, m, confidence);
        certification.metamodel_probabilities.push(exceeding / m);
        certification.metamodel_lower.push(metamodel_lower);
        certification.metamodel_upper.push(metamodel_upper);
        certification.mismatch_rate.push((only_reference + only_metamodel) / n);
        certification.correction.push((only_reference - only_metamodel) / n);
        certification.correction_lower.push((correction.centre - correction_half_width).max(-1.0));
        certification.correction_upper.push((correction.centre + correction_half_width).min(1.0));
    }
    CertifiedCurve { curve, certification, variance }
}

/// The figure of an exceedance curve labelled `label`; a certified one beside the metamodel's own
/// curve with its band, as an uncertified answer would have drawn it.
pub fn exceedance_figure(curve: &ExceedanceCurve, certification: Option<&Certification>, label: &str) -> String {
    let Some(c) = certification else { return exceedance_svg(&[("PC-NARX", curve)], label) };
    let metamodel = ExceedanceCurve {
        probabilities: c.metamodel_probabilities.clone(),
        lower: c.metamodel_lower.clone(),
        upper: c.metamodel_upper.clone(),
        ..curve.clone()
    };
    exceedance_svg(&[("PC-NARX", &metamodel), ("certified", curve)], label)
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
    pub centre: f64,
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
    /// far more than its own band. Measured: 0.965, 0.9725, 1 and 1 at 0.5, 0.1, 10⁻², 10⁻³; a
    /// plain normal interval from the same draws 0.96, 0.92, 0.52 and 0.665.
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
            let plain = super::super::exceedance::exceedance_curve(&metamodel, &thresholds, 0.95);
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

    /// Hand counts: 10 surrogate storms of which 3 exceed, 4 pairs with one storm exceeding only
    /// in the reference: 0.3 + 1/4; the mismatch rate 1/4.
    #[test]
    fn the_estimate_adds_the_mean_disagreement() {
        let metamodel = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 1.5, 1.6, 1.7];
        let pair = |reference, metamodel| PairedPeak { reference, metamodel };
        let paired = [pair(2.0, 0.5), pair(0.2, 0.3), pair(3.0, 3.0), pair(0.1, 0.1)];
        let CertifiedCurve { curve, certification, .. } =
            certified_curve(&metamodel, &paired, &[1.0], Order::Reduced, 0.95);
        assert!((curve.probabilities[0] - 0.55).abs() < 1e-12);
        assert_eq!(certification.metamodel_probabilities, vec![0.3]);
        assert_eq!(certification.mismatch_rate, vec![0.25]);
        assert_eq!(certification.correction, vec![0.25]);
        assert!(curve.lower[0] < 0.55 && 0.55 < curve.upper[0]);
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
