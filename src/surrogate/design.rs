//! The calibration's experimental design: a Latin hypercube over the input model, and optionally
//! wider in the wind speed so the metamodel is calibrated, not extrapolated, where rare annual
//! answers are decided.
//!
//! A design of the input model alone spans its own spread of wind speeds: with 200 experiments of
//! the paper's Fréchet (mean 30, sd 3.5 m/s), about 24 to 45 m/s. A climate's 10 000-year speed can
//! lie well beyond. Asked to cover [lower, upper], the design draws the wind speed from the
//! defensive mixture g = ½ f + ½ U(lower, upper) of the input marginal f and the uniform law on the
//! range (Hesterberg 1995), still stratified as a Latin hypercube in g's probability scale: half
//! the experiments where the input model puts them, half spread evenly over the range.
//!
//! The expansions must stay those of the input model: a polynomial chaos expansion is the
//! projection onto polynomials orthonormal under f, and least squares on points drawn from g
//! estimates the projection under g instead. Weighting experiment k by w_k = f(v_k)/g(v_k) makes
//! the weighted least-squares problem an importance-sampling estimate of the projection under f
//! (the weighted-least-squares design of Cohen & Migliorati 2017); the mixture keeps w ≤ 2, so no
//! experiment dominates, while the experiments at high speeds anchor the high-degree terms there.

use super::options::{CalibrationOptions, WindCoverage};
use crate::error::{Error, Result};
use crate::study::{Study, WIND_SPEED};
use crate::uncertainty::{Marginal, latin_hypercube, rng_from_seed};

impl WindCoverage {
    /// The mixture's density g(v) = ½ f(v) + ½ u(v), u the uniform density on the range.
    fn density(&self, marginal: &Marginal, v: f64) -> f64 {
        let uniform = if (self.lower..=self.upper).contains(&v) { 1.0 / (self.upper - self.lower) } else { 0.0 };
        0.5 * marginal.pdf(v) + 0.5 * uniform
    }

    /// The mixture's quantile, by bisection between brackets where its cdf is below and above `u`.
    fn quantile(&self, marginal: &Marginal, u: f64) -> f64 {
        let cdf = |v: f64| 0.5 * marginal.cdf(v) + 0.5 * ((v - self.lower) / (self.upper - self.lower)).clamp(0.0, 1.0);
        let at = marginal.quantile(u);
        let (mut low, mut high) = (at.min(self.lower), at.max(self.upper));
        for _ in 0..200 {
            let middle = 0.5 * (low + high);
            if middle <= low || middle >= high {
                break;
            }
            if cdf(middle) < u { low = middle } else { high = middle }
        }
        0.5 * (low + high)
    }
}

/// The experiments' physical inputs and the weights of their least-squares fits (mean 1).
#[derive(Debug, Clone, PartialEq)]
pub struct Design {
    /// Physical inputs of each experiment, in the input model's order.
    pub points: Vec<Vec<f64>>,
    /// Weight of each experiment in the least-squares fits (mean 1).
    pub weights: Vec<f64>,
}

/// The design: a function of the input model and the options alone, so a stored metamodel can say
/// where it was calibrated.
pub fn design(study: &Study, options: &CalibrationOptions) -> Result<Design> {
    let mut points = latin_hypercube(&study.inputs, options.experiments, &mut rng_from_seed(options.seed));
    let Some(coverage) = options.cover_wind_speeds else {
        return Ok(Design { weights: vec![1.0; points.len()], points });
    };
    coverage.check()?;
    let index = study.inputs.index_of(WIND_SPEED)?;
    let marginal = *study.inputs.marginal(WIND_SPEED)?;
    if matches!(marginal, Marginal::Constant { .. }) {
        return Err(Error::invalid("cover_wind_speeds", "the study holds wind_speed fixed; there is nothing to cover"));
    }
    let (low, high) = marginal.support();
    if !(low <= coverage.lower && coverage.upper <= high) {
        return Err(Error::invalid(
            "cover_wind_speeds",
            format!("[{}, {}] m/s leaves the wind speed's support [{low}, {high}]", coverage.lower, coverage.upper),
        ));
    }
    // The hypercube's stratum of each experiment carried over to the mixture: u = F(v), v' = G⁻¹(u).
    let mut weights = Vec::with_capacity(points.len());
    for point in &mut points {
        let v = coverage.quantile(&marginal, marginal.cdf(point[index]));
        point[index] = v;
        weights.push(marginal.pdf(v) / coverage.density(&marginal, v));
    }
    let mean = weights.iter().sum::<f64>() / weights.len() as f64;
    weights.iter_mut().for_each(|w| *w /= mean);
    Ok(Design { points, weights })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn study() -> Study {
        Study::preset("frame40-kn").unwrap()
    }

    fn covering(lower: f64, upper: f64) -> CalibrationOptions {
        CalibrationOptions {
            experiments: 2000,
            cover_wind_speeds: Some(WindCoverage { lower, upper }),
            ..CalibrationOptions::default()
        }
    }

    /// Without coverage the design is the plain hypercube, every weight 1.
    #[test]
    fn plain_design_is_the_hypercube() {
        let options = CalibrationOptions { experiments: 50, ..CalibrationOptions::default() };
        let d = design(&study(), &options).unwrap();
        let plain = latin_hypercube(&study().inputs, 50, &mut rng_from_seed(options.seed));
        assert_eq!(d.points, plain);
        assert!(d.weights.iter().all(|&w| w == 1.0));
    }

    /// The covering design puts half its experiments on the range evenly (the mixture's uniform
    /// half: 1000 ± 3·√(2000·¼) experiments above the input model's own 99.9 % speed share the
    /// range beyond it), and the weights recover the input model's moments: the weighted mean and
    /// standard deviation of the speeds are the Fréchet's 30 and 3.5 m/s within sampling error.
    #[test]
    fn covering_design_spans_the_range_and_weights_restore_the_input_model() {
        let study = study();
        let index = study.inputs.index_of(WIND_SPEED).unwrap();
        let d = design(&study, &covering(30.0, 75.0)).unwrap();
        let speeds: Vec<f64> = d.points.iter().map(|x| x[index]).collect();
        let marginal = study.inputs.marginal(WIND_SPEED).unwrap();
        let beyond = marginal.upper_quantile(1e-3);
        let far = speeds.iter().filter(|&&v| v > beyond).count() as f64;
        let expected = 0.5 * 2000.0 * (75.0 - beyond) / 45.0 + 0.5 * 2000.0 * 1e-3;
        assert!((far - expected).abs() < 3.0 * (2000.0 * 0.25f64).sqrt(), "{far} beyond {beyond}, expected {expected}");
        assert!(speeds.iter().cloned().fold(0.0, f64::max) > 74.0);
        assert!(
            d.weights.iter().all(|&w| w > 0.0 && w < 2.2),
            "weights of the mixture are at most 2 before normalising"
        );
        let mean = d.weights.iter().zip(&speeds).map(|(w, v)| w * v).sum::<f64>() / 2000.0;
        let var = d.weights.iter().zip(&speeds).map(|(w, v)| w * (v - mean).powi(2)).sum::<f64>() / 2000.0;
        assert!((mean - 30.0).abs() < 0.1, "weighted mean {mean}");
        assert!((var.sqrt() - 3.5).abs() < 0.15, "weighted sd {}", var.sqrt());
        // The other inputs keep their hypercube.
        let plain = latin_hypercube(&study.inputs, 2000, &mut rng_from_seed(1));
        assert!(d.points.iter().zip(&plain).all(|(a, b)| (0..a.len()).all(|i| i == index || a[i] == b[i])));
    }

    #[test]
    fn coverage_is_checked() {
        let study = study();
        for (lower, upper, says) in [
            (40.0, 30.0, "must be below upper"),
            (0.0, 30.0, "must be speeds"),
            (30.0, f64::NAN, "must be speeds"),
            (30.0, 200.0, "must be speeds"),
        ] {
            let error = design(&study, &covering(lower, upper)).unwrap_err().to_string();
            assert!(error.contains("cover_wind_speeds") && error.contains(says), "{error}");
        }
        let mut held = study.clone();
        held.inputs = held.inputs.with_fixed("wind_speed", 30.0).unwrap();
        assert!(design(&held, &covering(30.0, 60.0)).unwrap_err().to_string().contains("holds wind_speed fixed"));
    }
}
