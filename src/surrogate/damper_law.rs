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
//! pure law's slope is infinite (which the refinement's sensitivities could not follow).
//!
//! The power is formed by [`log2`] and [`exp2`] from fused multiply-adds and divisions only, so that
//! the calibration's scalar recursions and the batched free run compute the same value on every
//! processor, and the free run's lanes vectorise (a libm `powf` per lane and step tripled its cost).

use serde::{Deserialize, Serialize};

/// The dampers' exponent and, per mode, the knee of its velocity term in that mode's scaled
/// output units.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
pub struct DamperLaw {
    /// α of F = c·|v|^α.
    pub exponent: f64,
    /// κ per mode: [`KNEE_FRACTION`] of the root-mean-square first difference of the mode's
    /// scaled output over the selection experiments.
    pub knees: Vec<f64>,
}

/// The knee as a fraction of a mode's root-mean-square first difference.
pub const KNEE_FRACTION: f64 = 0.3;

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
pub fn secant(difference: f64, knee: f64, exponent: f64) -> f64 {
    power(difference.mul_add(difference, knee * knee), (exponent - 1.0) / 2.0)
}

/// x^p for a positive normal x, as 2^(p·log2 x); relative error below 1e-13 where p·log2 x is of
/// order ten (tested against `powf`).
#[inline(always)]
fn power(x: f64, p: f64) -> f64 {
    exp2(p * log2(x))
}

/// 1/(2k + 1) for k = 8 down to 0: the series of atanh(s)/s in s².
const ATANH_SERIES: [f64; 9] =
    [1.0 / 17.0, 1.0 / 15.0, 1.0 / 13.0, 1.0 / 11.0, 1.0 / 9.0, 1.0 / 7.0, 1.0 / 5.0, 1.0 / 3.0, 1.0];

/// (ln 2)ⁿ/n! for n = 13 down to 0: the series of 2^r.
const EXP2_SERIES: [f64; 14] = {
    let mut c = [1.0; 14];
    let mut n = 1;
    while n < 14 {
        c[13 - n] = c[14 - n] * std::f64::consts::LN_2 / n as f64;
        n += 1;
    }
    c
};

/// log2 of a positive normal x: x = m·2^e with m in [√½, √2), ln m = 2 atanh s, s = (m − 1)/(m + 1),
/// |s| ≤ 0.172, by its series to s¹⁷ (truncation below 2e-15).
#[inline(always)]
fn log2(x: f64) -> f64 {
    let bits = x.to_bits();
    let mut exponent = ((bits >> 52) & 0x7ff) as i64 - 1023;
    let mut mantissa = f64::from_bits((bits & 0x000f_ffff_ffff_ffff) | 0x3ff0_0000_0000_0000);
    if mantissa > std::f64::consts::SQRT_2 {
        mantissa *= 0.5;
        exponent += 1;
    }
    let s = (mantissa - 1.0) / (mantissa + 1.0);
    let s2 = s * s;
    let series = ATANH_SERIES.iter().fold(0.0f64, |sum, c| sum.mul_add(s2, *c));
    (2.0 * s * series).mul_add(std::f64::consts::LOG2_E, exponent as f64)
}

/// 2^y: y = k + r with r in [−½, ½], 2^r by its Taylor series to degree 13 (truncation below
/// 1e-16), times 2^k by the exponent bits. Beyond ±1000 the result saturates, which the free run's
/// divergence bound meets long before.
#[inline(always)]
fn exp2(y: f64) -> f64 {
    let y = y.clamp(-1000.0, 1000.0);
    let k = y.round();
    let r = y - k;
    let series = EXP2_SERIES.iter().fold(0.0f64, |sum, c| sum.mul_add(r, *c));
    series * f64::from_bits(((k as i64 + 1023) as u64) << 52)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The power by log2 and exp2 equals `powf` to 1e-13 over the range the free run meets
    /// (Δ² + κ² from 1e-12 to 1e6, exponents of dampers from 0.2 to 2).
    #[test]
    fn power_equals_powf() {
        let mut worst = 0.0f64;
        for i in 0..=400 {
            let x = 10f64.powf(-12.0 + 18.0 * i as f64 / 400.0) * (1.0 + 0.37 * (i % 7) as f64);
            for alpha in [0.2, 0.38, 0.5, 0.75, 1.0, 1.5, 2.0] {
                for p in [(alpha - 1.0) / 2.0, (alpha - 3.0) / 2.0] {
                    let exact = x.powf(p);
                    worst = worst.max((power(x, p) - exact).abs() / exact);
                }
            }
        }
        assert!(worst < 1e-13, "worst relative error {worst:e}");
        assert_eq!(log2(1.0), 0.0);
        assert_eq!(exp2(0.0), 1.0);
    }

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
