//! Experimental designs over an input model: Latin hypercube (the paper's calibration design) and
//! plain Monte Carlo (validation and exceedance sampling).

use super::InputModel;
use rand::seq::SliceRandom;
use rand::{RngExt, SeedableRng};

/// The generator behind every random number in windmeta: portable and reproducible across platforms
/// (rand's `StdRng` is documented as not portable).
pub type Rng = rand::rngs::Xoshiro256PlusPlus;

/// The generator started from `seed`.
pub fn rng_from_seed(seed: u64) -> Rng {
    Rng::seed_from_u64(seed)
}

/// `count` samples by Latin hypercube: each input's range is cut into `count` equiprobable strata,
/// every stratum is used once, and the strata of different inputs are paired at random.
pub fn latin_hypercube(model: &InputModel, count: usize, rng: &mut Rng) -> Vec<Vec<f64>> {
    let mut samples = vec![vec![0.0; model.len()]; count];
    let mut strata: Vec<usize> = (0..count).collect();
    for (d, input) in model.inputs.iter().enumerate() {
        strata.shuffle(rng);
        for (sample, &stratum) in samples.iter_mut().zip(&strata) {
            let u: f64 = rng.random();
            sample[d] = input.marginal.quantile((stratum as f64 + u) / count as f64);
        }
    }
    samples
}

/// `count` independent samples.
pub fn monte_carlo(model: &InputModel, count: usize, rng: &mut Rng) -> Vec<Vec<f64>> {
    (0..count)
        .map(|_| {
            model
                .inputs
                .iter()
                .map(|input| {
                    // random() is in [0, 1); the open interval keeps quantiles finite.
                    let u: f64 = rng.random();
                    input.marginal.quantile(u.max(f64::MIN_POSITIVE))
                })
                .collect()
        })
        .collect()
}

/// An independent seed for stream `stream` of a run seeded with `seed` (SplitMix64 finaliser), so
/// that sample k's storm is the same whichever thread draws it and however many samples there are.
pub fn stream_seed(seed: u64, stream: u64) -> u64 {
    let mut z = seed ^ stream.wrapping_add(1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uncertainty::{Input, Marginal};

    fn model() -> InputModel {
        InputModel::new(vec![
            Input { name: "u".into(), marginal: Marginal::Uniform { lower: 0.0, upper: 10.0 } },
            Input { name: "v".into(), marginal: Marginal::Frechet { mean: 30.0, sd: 3.5 } },
            Input { name: "c".into(), marginal: Marginal::Constant { value: 7.0 } },
        ])
        .unwrap()
    }

    #[test]
    fn latin_hypercube_fills_every_stratum_once() {
        let m = model();
        let k = 50;
        let samples = latin_hypercube(&m, k, &mut rng_from_seed(1));
        for d in 0..2 {
            let mut seen = vec![0; k];
            for s in &samples {
                let stratum = (m.inputs[d].marginal.cdf(s[d]) * k as f64).floor() as usize;
                seen[stratum.min(k - 1)] += 1;
            }
            assert!(seen.iter().all(|&c| c == 1), "input {d}: {seen:?}");
        }
        assert!(samples.iter().all(|s| s[2] == 7.0));
    }

    #[test]
    fn designs_reproduce_for_a_seed() {
        let a = latin_hypercube(&model(), 10, &mut rng_from_seed(9));
        let b = latin_hypercube(&model(), 10, &mut rng_from_seed(9));
        assert_eq!(a, b);
        let c = monte_carlo(&model(), 10, &mut rng_from_seed(9));
        assert_eq!(c, monte_carlo(&model(), 10, &mut rng_from_seed(9)));
    }

    /// Monte Carlo mean of the Fréchet input within 4 standard errors of 30 m/s.
    #[test]
    fn monte_carlo_has_the_right_mean() {
        let n = 20_000;
        let samples = monte_carlo(&model(), n, &mut rng_from_seed(3));
        let mean = samples.iter().map(|s| s[1]).sum::<f64>() / n as f64;
        assert!((mean - 30.0).abs() < 4.0 * 3.5 / (n as f64).sqrt(), "mean {mean}");
    }
}
