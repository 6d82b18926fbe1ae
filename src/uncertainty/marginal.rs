//! One-dimensional distributions by the parameters an engineer states (mean and standard deviation
//! where that is how the paper gives them), with quantiles and the map to a standard variable.

use crate::error::{Error, Result, require_finite, require_positive};
use serde::{Deserialize, Serialize};
use statrs::distribution::{ContinuousCDF, Normal};
use statrs::function::gamma::gamma;

/// A marginal distribution.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(tag = "distribution", rename_all = "snake_case", deny_unknown_fields)]
pub enum Marginal {
    /// Normal, given by its mean and standard deviation.
    Normal {
        /// Mean, in the input's unit.
        mean: f64,
        /// Standard deviation, in the input's unit.
        sd: f64,
    },
    /// Lognormal given by the mean and standard deviation of the variable itself.
    Lognormal {
        /// Mean of the variable (not of its logarithm).
        mean: f64,
        /// Standard deviation of the variable (not of its logarithm).
        sd: f64,
    },
    /// Uniform between two bounds.
    Uniform {
        /// Lower bound.
        lower: f64,
        /// Upper bound, above `lower`.
        upper: f64,
    },
    /// Fréchet (extreme value type II, location 0) given by its mean and standard deviation.
    Frechet {
        /// Mean, in the input's unit.
        mean: f64,
        /// Standard deviation, at most the mean.
        sd: f64,
    },
    /// Gumbel (extreme value type I): F(x) = exp(−exp(−(x − location)/scale)).
    Gumbel {
        /// Location μ: the mode.
        location: f64,
        /// Scale β, positive.
        scale: f64,
    },
    /// Weibull (location 0) given by its mean and standard deviation.
    Weibull {
        /// Mean, in the input's unit.
        mean: f64,
        /// Standard deviation, in the input's unit.
        sd: f64,
    },
    /// Not random: always `value`.
    Constant {
        /// The value held.
        value: f64,
    },
}

/// The standard variable a marginal maps to, which fixes the orthonormal polynomial family.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(rename_all = "snake_case")]
pub enum StandardSpace {
    /// ξ ~ N(0, 1): Hermite polynomials.
    Gaussian,
    /// ξ ~ U(−1, 1): Legendre polynomials.
    Uniform,
    /// Not random: no polynomial direction.
    Fixed,
}

fn std_normal() -> Normal {
    Normal::standard()
}

impl Marginal {
    /// Checks the parameters; `field` names the input in messages.
    pub fn check(&self, field: &str) -> Result<()> {
        match *self {
            Marginal::Normal { mean, sd } => {
                require_finite(&format!("{field}.mean"), mean)?;
                require_positive(&format!("{field}.sd"), sd)?;
            }
            Marginal::Lognormal { mean, sd } | Marginal::Frechet { mean, sd } | Marginal::Weibull { mean, sd } => {
                require_positive(&format!("{field}.mean"), mean)?;
                require_positive(&format!("{field}.sd"), sd)?;
                let (family, largest) = match self {
                    Marginal::Frechet { .. } => ("Fréchet", 1.0),
                    Marginal::Weibull { .. } => ("Weibull", WEIBULL_MAX_COV),
                    _ => ("lognormal", f64::INFINITY),
                };
                if sd / mean > largest {
                    return Err(Error::invalid(
                        format!("{field}.sd"),
                        format!("a {family} coefficient of variation above {largest} is not supported"),
                    ));
                }
            }
            Marginal::Gumbel { location, scale } => {
                require_finite(&format!("{field}.location"), location)?;
                require_positive(&format!("{field}.scale"), scale)?;
            }
            Marginal::Uniform { lower, upper } => {
                require_finite(&format!("{field}.lower"), lower)?;
                require_finite(&format!("{field}.upper"), upper)?;
                if upper <= lower {
                    return Err(Error::invalid(
                        format!("{field}.upper"),
                        format!("must exceed lower ({lower}), got {upper}"),
                    ));
                }
            }
            Marginal::Constant { value } => {
                require_finite(&format!("{field}.value"), value)?;
            }
        }
        Ok(())
    }

    /// Mean of the distribution.
    pub fn mean(&self) -> f64 {
        match *self {
            Marginal::Normal { mean, .. }
            | Marginal::Lognormal { mean, .. }
            | Marginal::Frechet { mean, .. }
            | Marginal::Weibull { mean, .. } => mean,
            Marginal::Gumbel { location, scale } => location + EULER_GAMMA * scale,
            Marginal::Uniform { lower, upper } => 0.5 * (lower + upper),
            Marginal::Constant { value } => value,
        }
    }

    /// The closed support [lower, upper] (infinite ends allowed).
    pub fn support(&self) -> (f64, f64) {
        match *self {
            Marginal::Normal { .. } | Marginal::Gumbel { .. } => (f64::NEG_INFINITY, f64::INFINITY),
            Marginal::Lognormal { .. } | Marginal::Frechet { .. } | Marginal::Weibull { .. } => (0.0, f64::INFINITY),
            Marginal::Uniform { lower, upper } => (lower, upper),
            Marginal::Constant { value } => (value, value),
        }
    }

    /// Whether `x` is a value this marginal can take (open at 0 for the positive families).
    pub fn contains(&self, x: f64) -> bool {
        match *self {
            Marginal::Lognormal { .. } | Marginal::Frechet { .. } | Marginal::Weibull { .. } => {
                x > 0.0 && x.is_finite()
            }
            _ => {
                let (lo, hi) = self.support();
                x.is_finite() && x >= lo && x <= hi
            }
        }
    }

    /// The standard variable this marginal maps to.
    pub fn standard_space(&self) -> StandardSpace {
        match self {
            Marginal::Normal { .. }
            | Marginal::Lognormal { .. }
            | Marginal::Frechet { .. }
            | Marginal::Gumbel { .. }
            | Marginal::Weibull { .. } => StandardSpace::Gaussian,
            Marginal::Uniform { .. } => StandardSpace::Uniform,
            Marginal::Constant { .. } => StandardSpace::Fixed,
        }
    }

    /// Lognormal parameters (λ, ζ) of ln X.
    fn lognormal_parameters(mean: f64, sd: f64) -> (f64, f64) {
        let zeta2 = (1.0 + (sd / mean).powi(2)).ln();
        (mean.ln() - 0.5 * zeta2, zeta2.sqrt())
    }

    /// Quantile function, p in (0, 1).
    pub fn quantile(&self, p: f64) -> f64 {
        match *self {
            Marginal::Normal { mean, sd } => mean + sd * std_normal().inverse_cdf(p),
            Marginal::Lognormal { mean, sd } => {
                let (lambda, zeta) = Self::lognormal_parameters(mean, sd);
                (lambda + zeta * std_normal().inverse_cdf(p)).exp()
            }
            Marginal::Uniform { lower, upper } => lower + p * (upper - lower),
            Marginal::Frechet { mean, sd } => {
                let (shape, scale) = frechet_parameters(mean, sd);
                scale * (-p.ln()).powf(-1.0 / shape)
            }
            Marginal::Gumbel { location, scale } => location - scale * (-p.ln()).ln(),
            Marginal::Weibull { mean, sd } => {
                let (shape, scale) = weibull_parameters(mean, sd);
                scale * (-(-p).ln_1p()).powf(1.0 / shape)
            }
            Marginal::Constant { value } => value,
        }
    }

    /// The lower and upper tail probabilities (F(x), 1 − F(x)) of the families whose far tails need
    /// their own digits, each computed without cancellation.
    fn tails(&self, x: f64) -> Option<(f64, f64)> {
        // F = exp(−t): the upper tail is −expm1(−t).
        let maximum_type = |t: f64| ((-t).exp(), -(-t).exp_m1());
        match *self {
            Marginal::Frechet { mean, sd } => {
                let (shape, scale) = frechet_parameters(mean, sd);
                Some(if x <= 0.0 { (0.0, 1.0) } else { maximum_type((x / scale).powf(-shape)) })
            }
            Marginal::Gumbel { location, scale } => Some(maximum_type((-(x - location) / scale).exp())),
            Marginal::Weibull { mean, sd } => {
                // 1 − F = exp(−t).
                let (shape, scale) = weibull_parameters(mean, sd);
                let t = (x.max(0.0) / scale).powf(shape);
                Some((-(-t).exp_m1(), (-t).exp()))
            }
            _ => None,
        }
    }

    /// 1 − F(x), exact in the far upper tail where 1 − cdf(x) would cancel.
    pub fn survival(&self, x: f64) -> f64 {
        match (self.tails(x), self) {
            (Some((_, upper)), _) => upper,
            (None, Marginal::Normal { .. }) => std_normal().cdf(-self.to_standard(x)),
            (None, Marginal::Lognormal { .. }) if x > 0.0 => std_normal().cdf(-self.to_standard(x)),
            _ => 1.0 - self.cdf(x),
        }
    }

    /// The quantile of upper-tail probability q: F⁻¹(1 − q), exact for tiny q.
    pub fn upper_quantile(&self, q: f64) -> f64 {
        match *self {
            Marginal::Frechet { mean, sd } => {
                let (shape, scale) = frechet_parameters(mean, sd);
                scale * (-(-q).ln_1p()).powf(-1.0 / shape)
            }
            Marginal::Gumbel { location, scale } => location - scale * (-(-q).ln_1p()).ln(),
            Marginal::Weibull { mean, sd } => {
                let (shape, scale) = weibull_parameters(mean, sd);
                scale * (-q.ln()).powf(1.0 / shape)
            }
            Marginal::Normal { .. } | Marginal::Lognormal { .. } => self.from_standard(-std_normal().inverse_cdf(q)),
            _ => self.quantile(1.0 - q),
        }
    }

    /// Probability density function.
    pub fn pdf(&self, x: f64) -> f64 {
        let phi = |z: f64| (-0.5 * z * z).exp() / (2.0 * std::f64::consts::PI).sqrt();
        match *self {
            Marginal::Normal { mean, sd } => phi((x - mean) / sd) / sd,
            Marginal::Lognormal { mean, sd } if x > 0.0 => {
                let (lambda, zeta) = Self::lognormal_parameters(mean, sd);
                phi((x.ln() - lambda) / zeta) / (x * zeta)
            }
            Marginal::Uniform { lower, upper } if (lower..=upper).contains(&x) => 1.0 / (upper - lower),
            Marginal::Frechet { mean, sd } if x > 0.0 => {
                let (shape, scale) = frechet_parameters(mean, sd);
                let t = (x / scale).powf(-shape);
                shape / x * t * (-t).exp()
            }
            Marginal::Gumbel { location, scale } => {
                let t = (-(x - location) / scale).exp();
                t * (-t).exp() / scale
            }
            Marginal::Weibull { mean, sd } if x > 0.0 => {
                let (shape, scale) = weibull_parameters(mean, sd);
                let t = (x / scale).powf(shape);
                shape / x * t * (-t).exp()
            }
            _ => 0.0,
        }
    }

    /// Cumulative distribution function.
    pub fn cdf(&self, x: f64) -> f64 {
        match *self {
            Marginal::Normal { mean, sd } => std_normal().cdf((x - mean) / sd),
            Marginal::Lognormal { mean, sd } => {
                if x <= 0.0 {
                    return 0.0;
                }
                let (lambda, zeta) = Self::lognormal_parameters(mean, sd);
                std_normal().cdf((x.ln() - lambda) / zeta)
            }
            Marginal::Uniform { lower, upper } => ((x - lower) / (upper - lower)).clamp(0.0, 1.0),
            Marginal::Frechet { .. } | Marginal::Gumbel { .. } | Marginal::Weibull { .. } => {
                self.tails(x).map_or(0.0, |(lower, _)| lower)
            }
            Marginal::Constant { value } => {
                if x < value {
                    0.0
                } else {
                    1.0
                }
            }
        }
    }

    /// The isoprobabilistic map x → ξ onto the marginal's standard variable.
    pub fn to_standard(&self, x: f64) -> f64 {
        match *self {
            Marginal::Normal { mean, sd } => (x - mean) / sd,
            Marginal::Lognormal { mean, sd } => {
                let (lambda, zeta) = Self::lognormal_parameters(mean, sd);
                (x.ln() - lambda) / zeta
            }
            Marginal::Uniform { lower, upper } => 2.0 * (x - lower) / (upper - lower) - 1.0,
            // Φ⁻¹(F(x)) computed from the smaller tail so that the far tails keep their digits.
            Marginal::Frechet { .. } | Marginal::Gumbel { .. } | Marginal::Weibull { .. } => {
                let (lower, upper) = self.tails(x).expect("an extreme-value family has tails");
                if upper < 0.5 { -std_normal().inverse_cdf(upper) } else { std_normal().inverse_cdf(lower) }
            }
            Marginal::Constant { .. } => 0.0,
        }
    }

    /// The inverse map ξ → x.
    pub fn from_standard(&self, xi: f64) -> f64 {
        match *self {
            Marginal::Normal { mean, sd } => mean + sd * xi,
            Marginal::Lognormal { mean, sd } => {
                let (lambda, zeta) = Self::lognormal_parameters(mean, sd);
                (lambda + zeta * xi).exp()
            }
            Marginal::Uniform { lower, upper } => lower + 0.5 * (xi + 1.0) * (upper - lower),
            Marginal::Frechet { mean, sd } => {
                let (shape, scale) = frechet_parameters(mean, sd);
                // −ln F = −ln Φ(ξ), from the upper tail when ξ > 0.
                let minus_ln_p = if xi > 0.0 { -(-std_normal().cdf(-xi)).ln_1p() } else { -std_normal().cdf(xi).ln() };
                scale * minus_ln_p.powf(-1.0 / shape)
            }
            Marginal::Gumbel { .. } | Marginal::Weibull { .. } => {
                if xi > 0.0 {
                    self.upper_quantile(std_normal().cdf(-xi))
                } else {
                    self.quantile(std_normal().cdf(xi))
                }
            }
            Marginal::Constant { value } => value,
        }
    }
}

/// Euler-Mascheroni constant: the mean of the standard Gumbel law.
const EULER_GAMMA: f64 = 0.577_215_664_901_532_9;

/// Largest Weibull coefficient of variation accepted (shape 0.2; wider laws overflow Γ).
const WEIBULL_MAX_COV: f64 = 15.0;

/// The shape at which a family's squared coefficient of variation, falling in the shape on
/// [lo, hi], equals `cov2`: bisection down to adjacent floating-point numbers (about 60 halvings;
/// it runs for every sample drawn, so it stops there).
fn shape_for_cov(cov2: f64, cov2_of: impl Fn(f64) -> f64, (mut lo, mut hi): (f64, f64)) -> f64 {
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if cov2_of(mid) > cov2 { lo = mid } else { hi = mid }
    }
    0.5 * (lo + hi)
}

/// Shape k and scale s of a Weibull law with the given mean and standard deviation:
/// mean = s Γ(1 + 1/k), var = s² (Γ(1 + 2/k) − Γ(1 + 1/k)²).
pub fn weibull_parameters(mean: f64, sd: f64) -> (f64, f64) {
    let cov2_of = |k: f64| {
        let g1 = gamma(1.0 + 1.0 / k);
        gamma(1.0 + 2.0 / k) / (g1 * g1) - 1.0
    };
    let shape = shape_for_cov((sd / mean).powi(2), cov2_of, (0.2, 1.0e4));
    (shape, mean / gamma(1.0 + 1.0 / shape))
}

/// Shape k and scale s of a Fréchet law with location 0 and the given mean and standard deviation:
/// mean = s Γ(1 − 1/k), var = s² (Γ(1 − 2/k) − Γ(1 − 1/k)²). The coefficient of variation falls
/// monotonically in k, so bisection on k finds it.
pub fn frechet_parameters(mean: f64, sd: f64) -> (f64, f64) {
    let cov2_of = |k: f64| {
        let g1 = gamma(1.0 - 1.0 / k);
        gamma(1.0 - 2.0 / k) / (g1 * g1) - 1.0
    };
    let shape = shape_for_cov((sd / mean).powi(2), cov2_of, (2.0 + 1e-9, 1.0e4));
    (shape, mean / gamma(1.0 - 1.0 / shape))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The paper's wind speed: Fréchet with mean 30 and sd 3.5 m/s; the moments of the fitted law
    /// are recomputed from Γ independently of the bisection (shape ≈ 11.79 per the method notes).
    #[test]
    fn frechet_moments_are_reproduced() {
        let (k, s) = frechet_parameters(30.0, 3.5);
        let mean = s * gamma(1.0 - 1.0 / k);
        let var = s * s * (gamma(1.0 - 2.0 / k) - gamma(1.0 - 1.0 / k).powi(2));
        assert!((mean - 30.0).abs() < 1e-9);
        assert!((var.sqrt() - 3.5).abs() < 1e-9);
        assert!((k - 11.79).abs() < 0.01, "shape {k}");
    }

    #[test]
    fn maps_round_trip_and_match_cdfs() {
        let marginals = [
            Marginal::Normal { mean: 1.0, sd: 2.0 },
            Marginal::Lognormal { mean: 210e9, sd: 15e9 },
            Marginal::Uniform { lower: 0.0, upper: 100.0 },
            Marginal::Frechet { mean: 30.0, sd: 3.5 },
            Marginal::Gumbel { location: 25.0, scale: 2.5 },
            Marginal::Weibull { mean: 30.0, sd: 3.5 },
        ];
        for m in marginals {
            for p in [1e-6, 0.01, 0.3, 0.5, 0.9, 0.999, 1.0 - 1e-9] {
                let x = m.quantile(p);
                assert!((m.cdf(x) - p).abs() < 1e-9 * p.max(1e-3), "{m:?} p={p}");
                let xi = m.to_standard(x);
                let back = m.from_standard(xi);
                assert!((back / x - 1.0).abs() < 1e-8 || (back - x).abs() < 1e-9, "{m:?} x={x} back={back}");
                // Same probability in the standard space: Φ(ξ) = F(x) or (ξ+1)/2 = F(x).
                let q = match m.standard_space() {
                    StandardSpace::Gaussian => std_normal().cdf(xi),
                    _ => 0.5 * (xi + 1.0),
                };
                assert!((q - p).abs() < 1e-7 * p.max(1e-3), "{m:?} p={p} q={q}");
            }
        }
    }

    /// Weibull moments recomputed from Γ; Gumbel's mean is location + γ·scale and its quantiles
    /// the closed form (scipy.stats.gumbel_r(25, 2.5).isf(1e-5) = 53.7823...).
    #[test]
    fn weibull_and_gumbel_match_closed_forms() {
        let (k, s) = weibull_parameters(30.0, 3.5);
        let mean = s * gamma(1.0 + 1.0 / k);
        let var = s * s * (gamma(1.0 + 2.0 / k) - gamma(1.0 + 1.0 / k).powi(2));
        assert!((mean - 30.0).abs() < 1e-9 && (var.sqrt() - 3.5).abs() < 1e-9, "{mean} {var}");
        let g = Marginal::Gumbel { location: 25.0, scale: 2.5 };
        assert!((g.mean() - (25.0 + 2.5 * 0.5772156649)).abs() < 1e-9);
        let x = g.upper_quantile(1e-5);
        assert!((x - (25.0 - 2.5 * (-(-1e-5f64).ln_1p()).ln())).abs() < 1e-12);
        assert!((g.survival(x) / 1e-5 - 1.0).abs() < 1e-10, "{}", g.survival(x));
    }

    /// The skewed families of wind speeds and stiffnesses.
    const SKEWED: [Marginal; 4] = [
        Marginal::Frechet { mean: 30.0, sd: 3.5 },
        Marginal::Gumbel { location: 25.0, scale: 2.5 },
        Marginal::Weibull { mean: 30.0, sd: 3.5 },
        Marginal::Lognormal { mean: 1.0, sd: 0.2 },
    ];

    /// The density integrates to the distribution function (Simpson's rule over [a, b]).
    #[test]
    fn densities_integrate_to_the_cdf() {
        for m in SKEWED {
            let (a, b) = (m.quantile(0.01), m.quantile(0.99));
            let integral = crate::uncertainty::simpson(|x| m.pdf(x), a, b, 2000);
            assert!((integral - 0.98).abs() < 1e-6, "{m:?}: {integral}");
        }
    }

    #[test]
    fn upper_quantiles_keep_their_digits_in_the_far_tail() {
        for m in SKEWED.into_iter().chain([Marginal::Normal { mean: 1.0, sd: 2.0 }]) {
            for q in [1e-3, 1e-7, 1e-12] {
                let x = m.upper_quantile(q);
                assert!((m.survival(x) / q - 1.0).abs() < 1e-6, "{m:?} q={q}: {}", m.survival(x));
            }
        }
    }

    #[test]
    fn lognormal_parameters_reproduce_mean_and_sd() {
        let (lambda, zeta) = Marginal::lognormal_parameters(0.015, 0.005);
        let mean = (lambda + 0.5 * zeta * zeta).exp();
        let var = (zeta * zeta).exp_m1() * mean * mean;
        assert!((mean - 0.015).abs() < 1e-15);
        assert!((var.sqrt() - 0.005).abs() < 1e-15);
    }

    #[test]
    fn invalid_parameters_name_the_field() {
        let err = Marginal::Lognormal { mean: -1.0, sd: 1.0 }.check("inputs.mass_factor").unwrap_err();
        assert!(err.to_string().starts_with("inputs.mass_factor.mean"));
        let err = Marginal::Uniform { lower: 1.0, upper: 1.0 }.check("x").unwrap_err();
        assert!(err.to_string().starts_with("x.upper"));
        assert!(Marginal::Normal { mean: 0.0, sd: f64::NAN }.check("x").is_err());
    }
}
