use super::*;
use crate::analysis::sampling::draws::NAMED_DIVERGED_STORMS;
use crate::uncertainty::Input;
use statrs::distribution::Continuous;

/// peak = v·exp(σ z), z ~ N(0, 1): λ(x) = ∫ Φ(ln(v/x)/σ) f(v) dv, here by Simpson's rule on the
/// climate's quantiles (an independent computation).
pub(in crate::analysis) fn lognormal_scatter_annual(climate: &Marginal, sigma: f64, x: f64) -> f64 {
    // Over ξ = Φ⁻¹(F(v)) from −8 to 8, where φ(ξ) dξ = f(v) dv.
    let normal = Normal::standard();
    let integrand = |xi: f64| normal.pdf(xi) * normal.cdf((climate.from_standard(xi) / x).ln() / sigma);
    crate::uncertainty::simpson(integrand, -8.0, 8.0, 4000)
}

/// The exact level of annual probability `p` of [`lognormal_scatter_annual`], by bisection.
pub(in crate::analysis) fn lognormal_scatter_level(climate: &Marginal, sigma: f64, p: f64) -> f64 {
    let (mut lo, mut hi) = (1.0, 200.0);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if lognormal_scatter_annual(climate, sigma, mid) > p { lo = mid } else { hi = mid }
    }
    0.5 * (lo + hi)
}

/// The toy's inputs: z, standard normal, and the wind speed (Fréchet, mean 30 m/s, sd 3.5 m/s).
pub(in crate::analysis) fn toy_inputs() -> InputModel {
    InputModel::new(vec![
        Input { name: "z".into(), marginal: Marginal::Normal { mean: 0.0, sd: 1.0 } },
        Input { name: WIND_SPEED.into(), marginal: Marginal::Frechet { mean: 30.0, sd: 3.5 } },
    ])
    .unwrap()
}

fn not_paired(_: &[Vec<f64>], _: usize) -> Result<Vec<PairedPeak>> {
    unreachable!("not certified")
}

fn toy_peaks(sigma: f64) -> impl FnMut(&[Vec<f64>], usize) -> Result<Vec<f64>> {
    move |rows: &[Vec<f64>], _| Ok(rows.iter().map(|r| r[1] * (sigma * r[0]).exp()).collect())
}

/// The stratified annual curve of a response with lognormal scatter about the speed, against
/// the quadrature: within four coefficients of variation from 10⁻¹ to 10⁻⁵ a year, each with a
/// coefficient of variation below 0.3 from 20 000 storms (equal allocation gave 0.44 at 10⁻⁵,
/// Neyman's after a pilot below 0.3); the return levels' bands hold the exact levels.
#[test]
fn annual_curve_and_return_levels_match_quadrature_down_to_1e_5() {
    let climate = Marginal::Gumbel { location: 22.0, scale: 2.2 };
    let sigma = 0.15;
    let mut options = HazardOptions {
        climate,
        samples: 20_000,
        seed: 11,
        thresholds: None,
        return_periods: vec![10.0, 100.0, 1e4, 1e5],
        limit: None,
        confidence: 0.95,
        sampling: Sampling::Stratified,
        certify: None,
    };
    // The exact level of each probability, by bisection on the quadrature.
    let level = |p: f64| lognormal_scatter_level(&climate, sigma, p);
    let levels: Vec<f64> = [1e-1, 1e-2, 1e-3, 1e-4, 1e-5].iter().map(|&p| level(p)).collect();
    options.thresholds = Some(levels.clone());
    let curve = hazard_curve(&toy_inputs(), &options, [15.0, 45.0], toy_peaks(sigma), not_paired).unwrap();
    for (i, p) in [1e-1, 1e-2, 1e-3, 1e-4, 1e-5].iter().enumerate() {
        let cov = curve.cov[i].unwrap();
        assert!(cov < 0.3, "p = {p}: cov {cov}");
        let relative = curve.annual_probability[i] / p - 1.0;
        assert!(relative.abs() < 4.0 * cov, "p = {p}: {} (cov {cov})", curve.annual_probability[i]);
    }
    for r in &curve.return_levels {
        let exact = level(1.0 - (-1.0 / r.return_period_years).exp());
        let (lo, hi) = (r.lower.unwrap(), r.upper.unwrap());
        assert!(lo <= exact * 1.01 && exact <= hi * 1.01, "T = {}: {exact} not in [{lo}, {hi}]", r.return_period_years);
    }
    // The rarest level leans on speeds above 45 m/s (the 10⁻⁵ speed is 47.3 m/s); the commonest
    // does not.
    let beyond = &curve.probability_beyond_calibrated_range;
    assert!(beyond[4] > 0.1 * curve.annual_probability[4], "{beyond:?}");
    assert!(beyond[0] < 0.01 * curve.annual_probability[0], "{beyond:?}");
    assert!(curve.samples <= 20_000);
    // The commonest levels: the 1-year one is exceeded with 1 − e⁻¹ = 0.632 a year, the 5-year
    // one with 0.181 (not 1 and 0.2).
    options.thresholds = None;
    options.return_periods = vec![1.0, 5.0];
    let curve = hazard_curve(&toy_inputs(), &options, [15.0, 45.0], toy_peaks(sigma), not_paired).unwrap();
    for r in &curve.return_levels {
        let exact = level(1.0 - (-1.0 / r.return_period_years).exp());
        let (lo, hi) = (r.lower.unwrap(), r.upper.unwrap());
        assert!(lo <= exact && exact <= hi, "T = {}: {exact} not in [{lo}, {hi}]", r.return_period_years);
    }
}

/// Plain Monte Carlo with the same number of storms agrees with the stratified estimate where
/// it can see (10⁻¹, 10⁻²), within the sum of their standard errors times four.
#[test]
fn plain_monte_carlo_agrees_with_the_stratified_estimate() {
    let climate = Marginal::Frechet { mean: 30.0, sd: 3.5 };
    let thresholds = vec![35.0, 45.0];
    let run = |sampling| {
        let options = HazardOptions {
            climate,
            samples: 40_000,
            seed: 5,
            thresholds: Some(thresholds.clone()),
            return_periods: vec![],
            limit: Some(45.0),
            confidence: 0.95,
            sampling,
            certify: None,
        };
        hazard_curve(&toy_inputs(), &options, [20.0, 50.0], toy_peaks(0.1), not_paired).unwrap()
    };
    let (stratified, plain) = (run(Sampling::Stratified), run(Sampling::MonteCarlo));
    for i in 0..2 {
        let sd = |c: &HazardCurve| c.cov[i].unwrap() * c.annual_probability[i];
        let gap = (stratified.annual_probability[i] - plain.annual_probability[i]).abs();
        assert!(gap < 4.0 * (sd(&stratified) + sd(&plain)), "{i}: {stratified:?} {plain:?}");
    }
    let r = plain.reliability.unwrap();
    let beta = r.beta.unwrap();
    assert!((beta + Normal::standard().inverse_cdf(r.annual_probability)).abs() < 1e-12);
    assert!(r.beta_lower.unwrap() < beta && beta < r.beta_upper.unwrap());
}

/// Storms that diverge (here, in a toy, every storm above 40 m/s) are counted and the first
/// five named with the inputs they were run with, in the order they ran.
#[test]
fn diverged_storms_are_counted_and_the_first_named_with_their_inputs() {
    let options = HazardOptions {
        climate: Marginal::Frechet { mean: 30.0, sd: 3.5 },
        samples: 2_000,
        seed: 3,
        thresholds: None,
        return_periods: vec![10.0],
        limit: None,
        confidence: 0.95,
        sampling: Sampling::MonteCarlo,
        certify: None,
    };
    let mut ran = Vec::new();
    let peaks_of = |rows: &[Vec<f64>], first: usize| {
        ran.extend(rows.iter().enumerate().map(|(i, r)| (first + i, r.clone())));
        Ok(rows.iter().map(|r| if r[1] > 40.0 { f64::INFINITY } else { r[1] }).collect())
    };
    let curve = hazard_curve(&toy_inputs(), &options, [20.0, 50.0], peaks_of, not_paired).unwrap();
    let diverged: Vec<_> = ran.iter().filter(|(_, r)| r[1] > 40.0).collect();
    assert!(diverged.len() > NAMED_DIVERGED_STORMS, "{} diverged", diverged.len());
    assert_eq!(curve.diverged_storms, diverged.len());
    let named: Vec<_> =
        curve.first_diverged.iter().map(|d| (d.storm, vec![d.inputs["z"], d.inputs[WIND_SPEED]])).collect();
    let expected: Vec<_> = diverged.iter().take(NAMED_DIVERGED_STORMS).map(|(k, r)| (*k, r.clone())).collect();
    assert_eq!(named, expected);
    let line = crate::analysis::describe_diverged(&curve.first_diverged);
    assert!(line.starts_with(&format!("storm {} (wind_speed = ", expected[0].0)), "{line}");
}

/// A band whose lower end dips to zero over a hundred levels well before it falls for good
/// (wider than a grid step of 20): the return level's lower end is the first level where it
/// falls (the cautious reading), not where bisection alone might land; the monotone estimate's
/// own level is found to the level.
#[test]
fn a_return_levels_ends_are_the_first_crossings_of_a_band_that_is_not_monotone() {
    let levels: Vec<f64> = (0..10_000).map(f64::from).collect();
    let estimate = |x: f64| {
        let probability = (-x / 1_000.0).exp();
        let dipped = (3_001.0..3_101.0).contains(&x);
        Estimate {
            probability,
            lower: if dipped { 0.0 } else { 0.5 * probability },
            upper: probability,
            cov: None,
            beyond: 0.0,
        }
    };
    // 1 − exp(−1/T) = exp(−5) at T = 1 / −ln(1 − e⁻⁵).
    let period = -1.0 / (1.0 - (-5.0f64).exp()).ln();
    let level = return_level(&levels, period, estimate);
    assert_eq!(level.value, Some(5_000.0));
    assert_eq!(level.upper, Some(5_000.0));
    assert_eq!(level.lower, Some(3_001.0), "the first level where the lower end falls");
}

#[test]
fn bad_options_name_the_field() {
    let base = HazardOptions {
        climate: Marginal::Frechet { mean: 30.0, sd: 3.5 },
        samples: 100,
        seed: 1,
        thresholds: None,
        return_periods: vec![50.0],
        limit: None,
        confidence: 0.95,
        sampling: Sampling::Stratified,
        certify: None,
    };
    let cases = [
        ("return_periods", HazardOptions { return_periods: vec![0.5], ..base.clone() }),
        ("return_periods", HazardOptions { return_periods: vec![f64::NAN], ..base.clone() }),
        ("limit", HazardOptions { limit: Some(-1.0), ..base.clone() }),
        ("samples", HazardOptions { samples: 5, ..base.clone() }),
        ("confidence", HazardOptions { confidence: 1.0, ..base.clone() }),
    ];
    for (field, options) in cases {
        let err = hazard_curve(&toy_inputs(), &options, [20.0, 50.0], toy_peaks(0.1), not_paired).unwrap_err();
        assert!(err.to_string().starts_with(field), "{field}: {err}");
    }
}

/// The certified annual curve ([`crate::analysis::certification::certified_hazard`]) of a surrogate
/// whose own curve is biased, against the reference's by quadrature.
mod certified {
    use super::lognormal_scatter_annual;
    use crate::analysis::answers::hazard::{HazardOptions, WIND_SPEED, hazard_curve};
    use crate::analysis::certification::certify::CertifyOptions;
    use crate::analysis::sampling::reference_storms::PairedPeak;
    use crate::analysis::sampling::strata::Sampling;
    use crate::error::Result;
    use crate::study::Order;
    use crate::uncertainty::{Input, InputModel, Marginal};

    const SIGMA: f64 = 0.15;

    /// The reference's peak v·exp(0.15 z) and a surrogate 4 % low with 3 % scatter of its own,
    /// 0.96·v·exp(0.15 z + 0.03 e): its annual curve is biased.
    fn toy_inputs() -> InputModel {
        let normal = Marginal::Normal { mean: 0.0, sd: 1.0 };
        InputModel::new(vec![
            Input { name: "z".into(), marginal: normal },
            Input { name: "e".into(), marginal: normal },
            Input { name: WIND_SPEED.into(), marginal: Marginal::Gumbel { location: 22.0, scale: 2.2 } },
        ])
        .unwrap()
    }

    fn reference(row: &[f64]) -> f64 {
        row[2] * (SIGMA * row[0]).exp()
    }

    fn surrogate(row: &[f64]) -> f64 {
        0.96 * reference(row) * (0.03 * row[1]).exp()
    }

    fn surrogate_peaks(rows: &[Vec<f64>], _: usize) -> Result<Vec<f64>> {
        Ok(rows.iter().map(|r| surrogate(r)).collect())
    }

    fn pairs(rows: &[Vec<f64>], _: usize) -> Result<Vec<PairedPeak>> {
        Ok(rows.iter().map(|r| PairedPeak { reference: reference(r), metamodel: surrogate(r) }).collect())
    }

    /// The level the reference exceeds with annual probability p, by bisection on the quadrature.
    fn reference_level(climate: &Marginal, p: f64) -> f64 {
        let (mut lo, mut hi) = (1.0, 200.0);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if lognormal_scatter_annual(climate, SIGMA, mid) > p { lo = mid } else { hi = mid }
        }
        0.5 * (lo + hi)
    }

    /// The certified annual curve's 95 % band holds the reference's annual probability in at
    /// least 93 % of 400 repetitions, from 0.5 down to 10⁻³ a year (4 000 surrogate storms, 200
    /// reference storms over the strata), where the surrogate alone misses at 0.5 and 0.1.
    /// Measured: 0.99, 1, 1, 1 at 0.5, 0.1, 10⁻², 10⁻³ (the surrogate's own band 0, 0, 0.12,
    /// 0.55); the bands' mean width 0.33, 1.0, 2.3 and 3.4 times the probability (this surrogate
    /// disagrees with the reference about 12 % of the storms at the median level).
    #[test]
    fn the_certified_annual_band_covers_the_reference_whatever_the_surrogates_bias() {
        let climate = Marginal::Gumbel { location: 22.0, scale: 2.2 };
        let levels = [0.5, 0.1, 1e-2, 1e-3];
        let thresholds: Vec<f64> = levels.iter().map(|&p| reference_level(&climate, p)).collect();
        let repetitions = 400;
        let (mut covered, mut surrogate_covered) = ([0usize; 4], [0usize; 4]);
        for seed in 0..repetitions {
            let options = HazardOptions {
                climate,
                samples: 4_000,
                seed,
                thresholds: Some(thresholds.clone()),
                return_periods: vec![2.0, 10.0, 100.0, 1000.0],
                limit: None,
                confidence: 0.95,
                sampling: Sampling::Stratified,
                certify: Some(CertifyOptions { reference_storms: 200, order: Order::Reduced }),
            };
            let curve = hazard_curve(&toy_inputs(), &options, [15.0, 45.0], surrogate_peaks, pairs).unwrap();
            let certification = curve.certification.as_ref().unwrap();
            assert_eq!(
                certification.points.reference_storms,
                certification.reference_storms_per_stratum.iter().sum::<usize>()
            );
            assert!(certification.points.reference_storms <= 200);
            for (i, &p) in levels.iter().enumerate() {
                covered[i] += usize::from(curve.lower[i] <= p && p <= curve.upper[i]);
                let (lo, hi) = (certification.points.metamodel_lower[i], certification.points.metamodel_upper[i]);
                surrogate_covered[i] += usize::from(lo <= p && p <= hi);
            }
        }
        for (i, &p) in levels.iter().enumerate() {
            let coverage = covered[i] as f64 / repetitions as f64;
            assert!(coverage >= 0.93, "p = {p}: coverage {coverage}");
        }
        assert!(surrogate_covered[0] < repetitions as usize / 10 && surrogate_covered[1] < repetitions as usize / 10);
    }
}
