//! Fragility curves: P(peak > x | v) on a grid of storm speeds with the structural inputs and the
//! storm's phases random, and per threshold the lognormal fragility P = Φ(ln(v/θ)/β) that
//! engineers tabulate, fitted by maximum likelihood on the binomial counts (Baker 2015).

use crate::analysis::certification::certify::{
    Certification, CertifiedCurve, CertifyOptions, MAX_REFERENCE_STORMS, certified_curve, check_reference_storms,
};
use crate::analysis::responses::response::Response;
use crate::analysis::sampling::draws::{DivergedStorm, Draws, OnDivergence, check_samples, name_diverged, peaks_at};
use crate::analysis::sampling::exceedance::check_thresholds;
use crate::analysis::sampling::exceedance::{check_confidence, clopper_pearson};
use crate::analysis::sampling::reference_storms::{PairedPeak, PairedRuns, reference_storm_seed};
use crate::analysis::sampling::runner::StormRunner;
use crate::error::{Error, Result};
use crate::optimise::nelder_mead;
use crate::progress::Observer;
use crate::progress::Silent;
use crate::study::{Order, Study, WIND_SPEED};
use crate::surrogate::Metamodel;
use crate::uncertainty::{InputModel, monte_carlo, rng_from_seed};
use crate::wind::WindLoads;
use serde::{Deserialize, Serialize};
use statrs::distribution::{ContinuousCDF, Normal};

/// Most wind speeds one fragility analysis may list.
pub const MAX_WIND_SPEEDS: usize = 200;

/// What a fragility analysis is asked.
#[derive(Debug, Clone, PartialEq)]
pub struct FragilityOptions {
    /// Storm speeds at the 10 m station (m/s).
    pub wind_speeds: Vec<f64>,
    /// Peak values (m).
    pub thresholds: Vec<f64>,
    /// Storms at each speed; the same structural draws and storm phases at every speed (common
    /// random numbers, so the curves are smooth in v).
    pub samples_per_speed: usize,
    /// The seed of the structural draws and of the storms' phases.
    pub seed: u64,
    /// The level of the bands and of the fits' intervals.
    pub confidence: f64,
    /// Certify every speed's probabilities with this many storms per speed through both models
    /// (the same structural draws and phases at every speed).
    pub certify: Option<CertifyOptions>,
}

impl FragilityOptions {
    /// Checks everything but the sampling; errors name the field.
    pub fn check(&self) -> Result<()> {
        check_thresholds(&self.thresholds)?;
        check_confidence(self.confidence)?;
        if self.wind_speeds.is_empty() || self.wind_speeds.len() > MAX_WIND_SPEEDS {
            return Err(Error::invalid("wind_speeds", format!("must list 1 to {MAX_WIND_SPEEDS} speeds")));
        }
        for &v in &self.wind_speeds {
            WindLoads::check_speed(v).map_err(|e| Error::invalid("wind_speeds", e.to_string()))?;
        }
        check_samples(self.samples_per_speed.saturating_mul(self.wind_speeds.len()))
            .map_err(|e| Error::invalid("samples", e.to_string()))?;
        if self.samples_per_speed < 2 {
            return Err(Error::invalid("samples", "must be at least 2 storms per speed"));
        }
        if let Some(certify) = &self.certify {
            let field = "certify.reference_storms";
            check_reference_storms(certify.reference_storms, self.samples_per_speed, field)?;
            let total = certify.reference_storms.saturating_mul(self.wind_speeds.len());
            if total > MAX_REFERENCE_STORMS {
                let reason = format!("{total} reference storms over every speed; at most {MAX_REFERENCE_STORMS}");
                return Err(Error::invalid(field, reason));
            }
        }
        Ok(())
    }
}

/// The lognormal fragility of one threshold, with asymptotic intervals from the likelihood's
/// curvature.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct LognormalFragility {
    /// θ: the speed at which the threshold is exceeded in half the storms (m/s).
    pub median_speed: f64,
    /// β: the standard deviation of ln v at exceedance.
    pub dispersion: f64,
    /// Intervals at the analysis's confidence; none where the likelihood is flat.
    pub median_speed_ci: Option<[f64; 2]>,
    /// The interval of the dispersion.
    pub dispersion_ci: Option<[f64; 2]>,
}

/// P(peak > threshold | v) at every speed, with its band and fit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct FragilityCurve {
    /// The peak value (in the response's unit).
    pub threshold: f64,
    /// P(peak > threshold | v) at each speed.
    pub probability: Vec<f64>,
    /// Clopper-Pearson band at the analysis's confidence.
    pub lower: Vec<f64>,
    /// The band's upper end at each speed.
    pub upper: Vec<f64>,
    /// Fitted over the speeds where no storm diverged; none when none of them sees both exceeding
    /// and non-exceeding storms. A certified curve's is fitted to its probabilities, each
    /// weighted by its effective number of storms p(1 − p)/Var p.
    pub lognormal: Option<LognormalFragility>,
    /// What the reference storms did at each speed, when the analysis was certified (then
    /// `probability`, `lower` and `upper` are the certified ones).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub certification: Option<Certification>,
}

/// The fragility curves of one response, one per threshold, on a grid of storm speeds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct Fragility {
    /// Storm speeds (m/s).
    pub wind_speeds: Vec<f64>,
    /// One curve per threshold, in the order asked.
    pub curves: Vec<FragilityCurve>,
    /// Storms at each speed (the same structural draws and phases at every speed).
    pub samples_per_speed: usize,
    /// The level of the bands and of the fits' intervals.
    pub confidence: f64,
    /// The wind speeds of the calibration's experiments, lowest and highest (m/s).
    pub calibrated_wind_range: [f64; 2],
    /// Storms whose metamodel free run diverged or had no stable rest, per speed: counted as
    /// exceeding every threshold, and the speed left out of the lognormal fits.
    pub diverged_storms: Vec<usize>,
    /// The first few diverged storms with their inputs.
    #[serde(default)]
    pub first_diverged: Vec<DivergedStorm>,
}

/// `count` draws of `inputs` from `seed`, each held at every speed in turn (speed by speed), and
/// the storm stream of each row: the same draw's at every speed.
fn rows_at_every_speed(
    inputs: &InputModel,
    wind: usize,
    speeds: &[f64],
    count: usize,
    seed: u64,
) -> (Vec<Vec<f64>>, Vec<usize>) {
    let draws = monte_carlo(inputs, count, &mut rng_from_seed(seed));
    let mut rows = Vec::with_capacity(count * speeds.len());
    for &v in speeds {
        rows.extend(draws.iter().map(|x| {
            let mut x = x.clone();
            x[wind] = v;
            x
        }));
    }
    let storms = (0..rows.len()).map(|i| i % count).collect();
    (rows, storms)
}

/// The fragility curves of the peaks `peaks_of` returns for rows (inputs, storm stream); certified,
/// with the storms through both models that `paired_of` returns for rows drawn with the
/// reference storms' seed.
pub fn fragility(
    inputs: &InputModel,
    options: &FragilityOptions,
    calibrated: [f64; 2],
    peaks_of: impl FnOnce(&[Vec<f64>], &[usize]) -> Result<Vec<f64>>,
    paired_of: impl FnOnce(&[Vec<f64>], &[usize]) -> Result<Vec<PairedPeak>>,
) -> Result<Fragility> {
    options.check()?;
    let wind = inputs.index_of(WIND_SPEED)?;
    let n = options.samples_per_speed;
    let (rows, storms) = rows_at_every_speed(inputs, wind, &options.wind_speeds, n, options.seed);
    let peaks = peaks_of(&rows, &storms)?;
    let confidence = options.confidence;
    // Certified, every speed's curve at every threshold, its metamodel storms corrected by its
    // reference storms.
    let certified = match &options.certify {
        None => None,
        Some(certify) => {
            let seed = reference_storm_seed(options.seed);
            let (rows, storms) =
                rows_at_every_speed(inputs, wind, &options.wind_speeds, certify.reference_storms, seed);
            let paired = paired_of(&rows, &storms)?;
            let per_speed: Vec<CertifiedCurve> = peaks
                .chunks(n)
                .zip(paired.chunks(certify.reference_storms))
                .map(|(peaks, paired)| certified_curve(peaks, paired, &options.thresholds, certify.order, confidence))
                .collect();
            Some((certify, per_speed))
        }
    };
    let diverged: Vec<usize> = peaks.chunks(n).map(|p| p.iter().filter(|y| y.is_infinite()).count()).collect();
    let mut first_diverged = Vec::new();
    name_diverged(inputs, &rows, storms.iter().copied(), &peaks, &mut first_diverged);
    // The fit only over the speeds where the metamodel ran every storm: where some diverged it
    // extrapolates, and counting them as exceeding would bend the fitted curve.
    let sound: Vec<usize> = (0..diverged.len()).filter(|&j| diverged[j] == 0).collect();
    let sound_speeds: Vec<f64> = sound.iter().map(|&j| options.wind_speeds[j]).collect();
    let curves = options
        .thresholds
        .iter()
        .enumerate()
        .map(|(i, &x)| match &certified {
            None => {
                let counts: Vec<f64> = peaks.chunks(n).map(|p| p.iter().filter(|&&y| y > x).count() as f64).collect();
                let bands: Vec<(f64, f64)> = counts.iter().map(|&k| clopper_pearson(k, n as f64, confidence)).collect();
                let sound_counts: Vec<f64> = sound.iter().map(|&j| counts[j]).collect();
                FragilityCurve {
                    threshold: x,
                    probability: counts.iter().map(|&k| k / n as f64).collect(),
                    lower: bands.iter().map(|b| b.0).collect(),
                    upper: bands.iter().map(|b| b.1).collect(),
                    lognormal: fit_lognormal(&sound_speeds, &sound_counts, &vec![n as f64; sound.len()], confidence),
                    certification: None,
                }
            }
            Some((certify, per_speed)) => {
                certified_fragility(i, x, per_speed, certify, n, &sound, &sound_speeds, confidence)
            }
        })
        .collect();
    Ok(Fragility {
        wind_speeds: options.wind_speeds.clone(),
        curves,
        samples_per_speed: n,
        confidence: options.confidence,
        calibrated_wind_range: calibrated,
        diverged_storms: diverged,
        first_diverged,
    })
}

/// Threshold `i`'s certified curve, read off every speed's certified curve ([`certified_curve`]),
/// and the lognormal fitted to its probabilities with their effective numbers of storms.
#[allow(clippy::too_many_arguments)]
fn certified_fragility(
    i: usize,
    threshold: f64,
    per_speed: &[CertifiedCurve],
    certify: &CertifyOptions,
    n: usize,
    sound: &[usize],
    sound_speeds: &[f64],
    confidence: f64,
) -> FragilityCurve {
    let column =
        |f: &dyn Fn(&CertifiedCurve) -> &[f64]| -> Vec<f64> { per_speed.iter().map(|speed| f(speed)[i]).collect() };
    let probability = column(&|c| &c.curve.probabilities);
    let (lower, upper) = (column(&|c| &c.curve.lower), column(&|c| &c.curve.upper));
    let variance = column(&|c| &c.variance);
    // Effective storms: p(1 − p)/Var p with the variance the band stands for; n where p is 0 or 1.
    let trials: Vec<f64> = sound
        .iter()
        .map(|&j| {
            let p = probability[j];
            if p > 0.0 && p < 1.0 && variance[j] > 0.0 { p * (1.0 - p) / variance[j] } else { n as f64 }
        })
        .collect();
    let counts: Vec<f64> = sound.iter().zip(&trials).map(|(&j, t)| probability[j] * t).collect();
    let certification = Certification {
        reference_storms: certify.reference_storms,
        order: certify.order,
        metamodel_probabilities: column(&|c| &c.certification.metamodel_probabilities),
        metamodel_lower: column(&|c| &c.certification.metamodel_lower),
        metamodel_upper: column(&|c| &c.certification.metamodel_upper),
        mismatch_rate: column(&|c| &c.certification.mismatch_rate),
        correction: column(&|c| &c.certification.correction),
        correction_lower: column(&|c| &c.certification.correction_lower),
        correction_upper: column(&|c| &c.certification.correction_upper),
    };
    FragilityCurve {
        threshold,
        lognormal: fit_lognormal(sound_speeds, &counts, &trials, confidence),
        probability,
        lower,
        upper,
        certification: Some(certification),
    }
}

/// The maximum-likelihood lognormal fragility through k_j of n_j exceedances at speeds v_j (k and
/// n may be effective counts, not whole): the minimum over (ln θ, ln β) of
/// −Σ k ln Φ(z) + (n − k) ln Φ(−z), z = ln(v/θ)/β, by Nelder-Mead; intervals from the inverse of
/// the negative log-likelihood's Hessian there.
fn fit_lognormal(speeds: &[f64], counts: &[f64], trials: &[f64], confidence: f64) -> Option<LognormalFragility> {
    if counts.iter().all(|&k| k <= 0.0) || counts.iter().zip(trials).all(|(k, n)| k >= n) {
        return None;
    }
    let normal = Normal::standard();
    let log_cdf = |z: f64| normal.cdf(z).max(1e-300).ln();
    let nll = |p: &[f64]| -> f64 {
        let beta = p[1].exp();
        speeds
            .iter()
            .zip(counts.iter().zip(trials))
            .map(|(&v, (&k, &n))| {
                let z = (v.ln() - p[0]) / beta;
                -k * log_cdf(z) - (n - k) * log_cdf(-z)
            })
            .sum()
    };
    // Start at the speed whose fraction is nearest one half.
    let from_half = |j: usize| (counts[j] / trials[j] - 0.5).abs();
    let nearest = (0..counts.len()).min_by(|&a, &b| from_half(a).total_cmp(&from_half(b))).unwrap_or(0);
    let best = nelder_mead(vec![speeds[nearest].ln(), 0.3f64.ln()], nll, &Silent).ok()?.x;
    let (a, b) = (best[0], best[1]);
    if !(a.is_finite() && b.is_finite()) {
        return None;
    }
    // The Hessian by central differences, its inverse the asymptotic covariance of (ln θ, ln β).
    let h = 1e-4;
    let at = |da: f64, db: f64| nll(&[a + da, b + db]);
    let f0 = at(0.0, 0.0);
    let haa = (at(h, 0.0) - 2.0 * f0 + at(-h, 0.0)) / (h * h);
    let hbb = (at(0.0, h) - 2.0 * f0 + at(0.0, -h)) / (h * h);
    let hab = (at(h, h) - at(h, -h) - at(-h, h) + at(-h, -h)) / (4.0 * h * h);
    let det = haa * hbb - hab * hab;
    let z = normal.inverse_cdf(0.5 + confidence / 2.0);
    let interval = |centre: f64, variance: f64| {
        (det > 0.0 && haa > 0.0 && variance > 0.0 && variance.is_finite()).then(|| {
            let half = z * variance.sqrt();
            [(centre - half).exp(), (centre + half).exp()]
        })
    };
    Some(LognormalFragility {
        median_speed: a.exp(),
        dispersion: b.exp(),
        median_speed_ci: interval(a, hbb / det),
        dispersion_ci: interval(b, haa / det),
    })
}

/// The fragility curves of a metamodel's peak `response`.
pub fn metamodel_fragility(
    metamodel: &Metamodel,
    study: &Study,
    response: Response,
    options: &FragilityOptions,
    runner: &dyn StormRunner,
    observer: &dyn Observer,
) -> Result<Fragility> {
    response.check(&study.structure)?;
    let calibrated = metamodel.calibrated_range(study, WIND_SPEED)?;
    let peaks_of = |rows: &[Vec<f64>], storms: &[usize]| {
        let draws = Draws { study, rows, storms, seed: options.seed, on_divergence: OnDivergence::Exceed };
        peaks_at(metamodel, &draws, response, runner, observer)
    };
    let order = options.certify.map_or(Order::Reduced, |c| c.order);
    let runs = PairedRuns { metamodel, study, seed: reference_storm_seed(options.seed), response, order };
    let paired_of = |rows: &[Vec<f64>], storms: &[usize]| runner.pairs(&runs, rows, storms, observer);
    fragility(&study.inputs, options, calibrated, peaks_of, paired_of)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uncertainty::{Input, Marginal};

    /// Inputs z and e, standard normal, and the wind speed; 21 speeds from 20 to 60 m/s, two
    /// thresholds, 2 000 storms per speed, 99 % bands.
    fn toy(certify: Option<CertifyOptions>) -> (InputModel, FragilityOptions) {
        let inputs = InputModel::new(vec![
            Input { name: "z".into(), marginal: Marginal::Normal { mean: 0.0, sd: 1.0 } },
            Input { name: "e".into(), marginal: Marginal::Normal { mean: 0.0, sd: 1.0 } },
            Input { name: WIND_SPEED.into(), marginal: Marginal::Frechet { mean: 30.0, sd: 3.5 } },
        ])
        .unwrap();
        let options = FragilityOptions {
            wind_speeds: (0..=20).map(|i| 20.0 + 2.0 * i as f64).collect(),
            thresholds: vec![30.0, 45.0],
            samples_per_speed: 2000,
            seed: 4,
            confidence: 0.99,
            certify,
        };
        (inputs, options)
    }

    /// peak = v·exp(σ z), z ~ N(0, 1), exceeds x with probability Φ(ln(v/x)/σ): a lognormal
    /// fragility with θ = x and β = σ exactly. The fit's intervals hold both, and each point's band
    /// holds the exact probability.
    #[test]
    fn lognormal_fragility_of_a_lognormal_response_is_recovered() {
        let (inputs, options) = toy(None);
        let sigma = 0.2;
        let peaks_of = |rows: &[Vec<f64>], _: &[usize]| Ok(rows.iter().map(|r| r[2] * (sigma * r[0]).exp()).collect());
        let result =
            fragility(&inputs, &options, [20.0, 50.0], peaks_of, |_, _| unreachable!("not certified")).unwrap();
        let normal = Normal::standard();
        for curve in &result.curves {
            let fit = curve.lognormal.as_ref().unwrap();
            let [lo, hi] = fit.median_speed_ci.unwrap();
            assert!(lo <= curve.threshold && curve.threshold <= hi, "θ {fit:?}");
            let [lo, hi] = fit.dispersion_ci.unwrap();
            assert!(lo <= sigma && sigma <= hi, "β {fit:?}");
            for (j, &v) in result.wind_speeds.iter().enumerate() {
                let exact = normal.cdf((v / curve.threshold).ln() / sigma);
                assert!(curve.lower[j] <= exact && exact <= curve.upper[j], "v = {v}: {exact}");
            }
        }
    }

    /// The same response through a surrogate 5 % low with 3 % scatter of its own: its curves miss
    /// the exact probabilities; certified with 200 reference storms per speed, at least 95 % of
    /// the 42 points' 99 % bands hold them, and the fit's median speed interval holds θ.
    #[test]
    fn certified_fragility_holds_the_reference_whatever_the_surrogates_bias() {
        let (inputs, options) = toy(Some(CertifyOptions { reference_storms: 200, order: Order::Reduced }));
        let sigma = 0.2;
        let reference = |r: &Vec<f64>| r[2] * (sigma * r[0]).exp();
        let surrogate = |r: &Vec<f64>| 0.95 * reference(r) * (0.03 * r[1]).exp();
        let peaks_of = |rows: &[Vec<f64>], _: &[usize]| Ok(rows.iter().map(surrogate).collect());
        let paired_of = |rows: &[Vec<f64>], _: &[usize]| {
            Ok(rows.iter().map(|r| PairedPeak { reference: reference(r), metamodel: surrogate(r) }).collect())
        };
        let mut too_many = options.clone();
        too_many.certify = Some(CertifyOptions { reference_storms: 300, order: Order::Reduced });
        let error = too_many.check().unwrap_err().to_string();
        assert!(error.starts_with("certify.reference_storms") && error.contains("6300"), "{error}");
        let result = fragility(&inputs, &options, [20.0, 50.0], peaks_of, paired_of).unwrap();
        let normal = Normal::standard();
        let (mut held, mut surrogate_held, mut points) = (0, 0, 0);
        for curve in &result.curves {
            let certification = curve.certification.as_ref().unwrap();
            for (j, &v) in result.wind_speeds.iter().enumerate() {
                let exact = normal.cdf((v / curve.threshold).ln() / sigma);
                held += usize::from(curve.lower[j] <= exact && exact <= curve.upper[j]);
                let (lo, hi) = (certification.metamodel_lower[j], certification.metamodel_upper[j]);
                surrogate_held += usize::from(lo <= exact && exact <= hi);
                points += 1;
            }
            let [lo, hi] = curve.lognormal.as_ref().unwrap().median_speed_ci.unwrap();
            assert!(lo <= curve.threshold && curve.threshold <= hi, "θ {:?}", curve.lognormal);
        }
        assert!(held as f64 >= 0.95 * points as f64, "{held} of {points}");
        assert!(surrogate_held * 2 < points, "the surrogate alone holds {surrogate_held} of {points}");
    }

    #[test]
    fn a_threshold_never_reached_has_no_fit() {
        assert!(fit_lognormal(&[20.0, 30.0], &[0.0, 0.0], &[10.0, 10.0], 0.95).is_none());
        assert!(fit_lognormal(&[20.0, 30.0], &[10.0, 10.0], &[10.0, 10.0], 0.95).is_none());
    }
}
