//! The damper law as a NARX term: a mode's velocity put through the dampers' power law.
//!
//! Viscous dampers with F = c·|v|^α, α < 1, damp a small motion more, and a large one less, than
//! any linear model: their equivalent damping falls as the amplitude to the power α − 1. A NARX
//! model of polynomial terms fits the average damping, so it under-predicts the resonant motion of
//! the largest cycles, which is where the peak acceleration is made (on frame40-kn the free run
//! of mode 1 fitted to the storm itself gave 0.972 of the peak roof acceleration with α = 0.38,
//! 1.000 with α = 1). The velocity term D(Δ) = Δ·(Δ² + κ²)^((α−1)/2) of the first difference
//! Δ = y(t − l) − y(t − l − 1) is that law. The knee κ smooths it near Δ = 0, where a damper's
//! velocity is not one mode's (the other modes' velocities cross zero elsewhere) and where the
//! pure law's slope is infinite (which the refinement's sensitivities could not follow). The
//! secant S(Δ) = D(Δ)/Δ carries the law to a mode whose dampers' velocities another mode makes
//! ([`super::narx::DamperTerm::Modulated`]).
//!
//! The power is [`crate::dynamics::power`], arithmetic and bit operations only, so that the
//! calibration's scalar recursions and the batched free run compute the same value on every
//! processor, and the free run's lanes vectorise.

use crate::dynamics::{power, power_lanes};
use serde::{Deserialize, Serialize};

/// The dampers' exponent and, per mode, the knee of its velocity term in that mode's scaled
/// output units.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct DamperLaw {
    /// α of F = c·|v|^α.
    pub exponent: f64,
    /// κ per mode: 0.1 of the root-mean-square first difference of the mode's scaled output
    /// over the selection experiments.
    pub knees: Vec<f64>,
}

/// The knee as a fraction of a mode's root-mean-square first difference (in [`DamperLaw`]'s doc too).
/// At 0.3 the law was nearly linear over most of a 20 m/s storm's first differences (peak
/// acceleration error 5.9 % there, against 3.9 % at 0.1) and extrapolated worse to 60 m/s
/// (displacement 1.1 % against 0.24 %); within the design both gave the same errors (docs/method.md).
pub const KNEE_FRACTION: f64 = 0.1;

impl DamperLaw {
    /// D(Δ) of mode `mode`'s first difference Δ.
    #[inline]
    pub fn value(&self, mode: usize, difference: f64) -> f64 {
        difference * self.secant(mode, difference)
    }

    /// S(Δ) = D(Δ)/Δ of mode `mode`'s first difference Δ.
    #[inline]
    pub fn secant(&self, mode: usize, difference: f64) -> f64 {
        secant(difference, self.knees[mode], self.exponent)
    }

    /// D(Δ) and dD/dΔ of mode `mode`'s first difference Δ, from one power.
    #[inline]
    pub fn value_and_slope(&self, mode: usize, difference: f64) -> (f64, f64) {
        let (knee, alpha) = (self.knees[mode], self.exponent);
        let s = difference.mul_add(difference, knee * knee);
        let factor = power(s, (alpha - 1.0) / 2.0);
        // d/dΔ [Δ s^β] = s^β + 2βΔ² s^(β−1) = s^β (s + (α − 1) Δ²) / s, β = (α − 1)/2.
        (difference * factor, factor * ((alpha - 1.0) * difference).mul_add(difference, s) / s)
    }
}

/// The law's secant S(Δ) = (Δ² + κ²)^((α−1)/2).
#[inline(always)]
fn secant(difference: f64, knee: f64, exponent: f64) -> f64 {
    secant_lanes([difference], knee, exponent)[0]
}

/// S(Δ) of every lane, vectorised (see [`power_lanes`]); lane by lane the value of
/// `secant(Δ, κ, α)`, to the bit, so that Δ·S(Δ) is [`DamperLaw::value`].
#[inline(always)]
pub fn secant_lanes<const N: usize>(difference: [f64; N], knee: f64, exponent: f64) -> [f64; N] {
    let squares = std::array::from_fn(|l| difference[l].mul_add(difference[l], knee * knee));
    power_lanes(squares, (exponent - 1.0) / 2.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// D(Δ) is odd, tends to sgn(Δ)|Δ|^α away from the knee, and its slope is its derivative.
    #[test]
    fn law_and_slope() {
        let law = DamperLaw { exponent: 0.38, knees: vec![1e-3, 0.2] };
        for d in [1e-5, 3e-3, 0.05, 1.0, 40.0] {
            assert_eq!(law.value(0, -d), -law.value(0, d));
            let h = 1e-6 * d;
            let numeric = (law.value(1, d + h) - law.value(1, d - h)) / (2.0 * h);
            let (value, slope) = law.value_and_slope(1, d);
            assert_eq!(value, law.value(1, d));
            assert!((slope - numeric).abs() < 1e-6 * numeric.abs(), "{d}");
        }
        let far = law.value(0, 2.0);
        assert!((far / 2f64.powf(0.38) - 1.0).abs() < 1e-6);
        assert_eq!(law.value(0, 0.0), 0.0);
    }
}
