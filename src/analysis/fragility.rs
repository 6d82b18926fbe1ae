//! Fragility curves: P(peak > x | v) on a grid of storm speeds with the structural inputs and the
//! storm's phases random, and per threshold the lognormal fragility P = Φ(ln(v/θ)/β) that
//! engineers tabulate, fitted by maximum likelihood on the binomial counts (Baker 2015).

use super::exceedance::{check_confidence, clopper_pearson};
use super::hazard::WIND_SPEED;
use super::sampling::{DivergedStorm, check_samples, name_diverged};
use super::{Draws, OnDivergence, Response, check_thresholds, peaks_at};
use crate::error::{Error, Result};
use crate::optimise::nelder_mead;
use crate::progress::Observer;
use crate::progress::Silent;
use crate::study::Study;
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
    pub seed: u64,
    pub confidence: f64,
}

impl FragilityOptions {
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
    pub dispersion_ci: Option<[f64; 2]>,
}

/// P(peak > threshold | v) at every speed, with its band and fit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct FragilityCurve {
    pub threshold: f64,
    pub probability: Vec<f64>,
    /// Clopper-Pearson band at the analysis's confidence.
    pub lower: Vec<f64>,
    pub upper: Vec<f64>,
    /// Fitted over the speeds where no storm diverged; none when none of them sees both exceeding
    /// and non-exceeding storms.
    pub lognormal: Option<LognormalFragility>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct Fragility {
    /// Storm speeds (m/s).
    pub wind_speeds: Vec<f64>,
    pub curves: Vec<FragilityCurve>,
    pub samples_per_speed: usize,
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

/// The fragility curves of the peaks `peaks_of` returns for rows (inputs, storm stream).
pub fn fragility(
    inputs: &InputModel,
    options: &FragilityOptions,
    calibrated: [f64; 2],
    peaks_of: impl FnOnce(&[Vec<f64>], &[usize]) -> Result<Vec<f64>>,
) -> Result<Fragility> {
    options.check()?;
    let wind = inputs.index_of(WIND_SPEED)?;
    let n = options.samples_per_speed;
    let draws = monte_carlo(inputs, n, &mut rng_from_seed(options.seed));
    let mut rows = Vec::with_capacity(n * options.wind_speeds.len());
    for &v in &options.wind_speeds {
        rows.extend(draws.iter().map(|x| {
            let mut x = x.clone();
            x[wind] = v;
            x
        }));
    }
    let storms: Vec<usize> = (0..rows.len()).map(|i| i % n).collect();
    let peaks = peaks_of(&rows, &storms)?;
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
        .map(|&x| {
            let counts: Vec<usize> = peaks.chunks(n).map(|p| p.iter().filter(|&&y| y > x).count()).collect();
            let bands: Vec<(f64, f64)> =
                counts.iter().map(|&k| clopper_pearson(k as f64, n as f64, options.confidence)).collect();
            FragilityCurve {
                threshold: x,
                probability: counts.iter().map(|&k| k as f64 / n as f64).collect(),
                lower: bands.iter().map(|b| b.0).collect(),
                upper: bands.iter().map(|b| b.1).collect(),
                lognormal: fit_lognormal(
                    &sound_speeds,
                    &sound.iter().map(|&j| counts[j]).collect::<Vec<_>>(),
                    n,
                    options.confidence,
                ),
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

/// The maximum-likelihood lognormal fragility through k_j of n exceedances at speeds v_j: the
/// minimum over (ln θ, ln β) of −Σ k ln Φ(z) + (n − k) ln Φ(−z), z = ln(v/θ)/β, by Nelder-Mead;
/// intervals from the inverse of the negative log-likelihood's Hessian there.
fn fit_lognormal(speeds: &[f64], counts: &[usize], n: usize, confidence: f64) -> Option<LognormalFragility> {
    if counts.iter().all(|&k| k == 0) || counts.iter().all(|&k| k == n) {
        return None;
    }
    let normal = Normal::standard();
    let log_cdf = |z: f64| normal.cdf(z).max(1e-300).ln();
    let nll = |p: &[f64]| -> f64 {
        let beta = p[1].exp();
        speeds
            .iter()
            .zip(counts)
            .map(|(&v, &k)| {
                let z = (v.ln() - p[0]) / beta;
                -(k as f64) * log_cdf(z) - (n - k) as f64 * log_cdf(-z)
            })
            .sum()
    };
    // Start at the speed whose fraction is nearest one half.
    let nearest = counts
        .iter()
        .enumerate()
        .min_by(|a, b| (*a.1 as f64 - n as f64 / 2.0).abs().total_cmp(&(*b.1 as f64 - n as f64 / 2.0).abs()))
        .map_or(0, |(j, _)| j);
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
    observer: &dyn Observer,
) -> Result<Fragility> {
    response.check(&study.structure)?;
    let calibrated = metamodel.calibrated_range(study, WIND_SPEED)?;
    fragility(&study.inputs, options, calibrated, |rows, storms| {
        let draws = Draws { study, rows, storms, seed: options.seed, on_divergence: OnDivergence::Exceed };
        peaks_at(metamodel, &draws, response, observer)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uncertainty::{Input, Marginal};

    /// peak = v·exp(σ z), z ~ N(0, 1), exceeds x with probability Φ(ln(v/x)/σ): a lognormal
    /// fragility with θ = x and β = σ exactly. The fit's intervals hold both, and each point's band
    /// holds the exact probability.
    #[test]
    fn lognormal_fragility_of_a_lognormal_response_is_recovered() {
        let inputs = InputModel::new(vec![
            Input { name: "z".into(), marginal: Marginal::Normal { mean: 0.0, sd: 1.0 } },
            Input { name: WIND_SPEED.into(), marginal: Marginal::Frechet { mean: 30.0, sd: 3.5 } },
        ])
        .unwrap();
        let sigma = 0.2;
        let options = FragilityOptions {
            wind_speeds: (0..=20).map(|i| 20.0 + 2.0 * i as f64).collect(),
            thresholds: vec![30.0, 45.0],
            samples_per_speed: 2000,
            seed: 4,
            confidence: 0.99,
        };
        let result = fragility(&inputs, &options, [20.0, 50.0], |rows, _| {
            Ok(rows.iter().map(|r| r[1] * (sigma * r[0]).exp()).collect())
        })
        .unwrap();
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

    #[test]
    fn a_threshold_never_reached_has_no_fit() {
        assert!(fit_lognormal(&[20.0, 30.0], &[0, 0], 10, 0.95).is_none());
        assert!(fit_lognormal(&[20.0, 30.0], &[10, 10], 10, 0.95).is_none());
    }
}
