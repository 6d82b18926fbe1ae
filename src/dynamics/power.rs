//! x^α for the damper law F = c·|v|^α when it is evaluated for every damper at every step of a
//! predicted storm (40 dampers × 90 000 steps per sample), and for the law's secant in every step
//! of the metamodel's free run. `f64::powf` is exact to the last bit and costs some 16 ns; the
//! responses need far less than that exactness. This version is branch-free arithmetic and bit
//! operations only (a range reduction, an atanh series for the logarithm, a Taylor polynomial for
//! the exponential), within 10⁻¹³ of `powf` (tested over 40 decades). The free run waits on each
//! step's power, so its polynomials are evaluated by Estrin's scheme with fused products, the
//! shallowest chain of dependent operations: on a 2-core Xeon with AVX-512, eight lanes at once
//! took 37 ns from argument to result and 22 ns each when four ran side by side, against 85 ns and
//! 45 ns by Horner's rule with separate products (`cargo run --release --example roofline`). No
//! crate offers an f64 power with a stated error that is cheaper than `powf`.

/// 1.5·2⁵²: adding it rounds a double of magnitude below 2⁵¹ to an integer, which then sits in the
/// low bits of the sum's representation.
const ROUNDER: f64 = 6_755_399_441_055_744.0;
/// 2⁵², whose representation with an integer n < 2⁵² in the mantissa bits is 2⁵² + n.
const TWO_52: f64 = 4_503_599_627_370_496.0;

/// 1/n! for n = 0 … 13: the Taylor coefficients of e^r.
const INVERSE_FACTORIALS: [f64; 14] = {
    let mut c = [1.0; 14];
    let mut n = 1;
    while n < 14 {
        c[n] = c[n - 1] / n as f64;
        n += 1;
    }
    c
};

/// x^α for x ≥ 0 and |α| ≤ 2: relative error below 10⁻¹³; 0 for x below the smallest normal
/// double (where x^α < 10⁻⁶¹ for the dampers' α ≥ 0.2). Always inlined, so that a loop over the
/// dampers is vectorized (the compiler left it a call in the acceleration sink).
#[inline(always)]
pub fn power(x: f64, alpha: f64) -> f64 {
    power_lanes([x], alpha)[0]
}

/// [`power`] of every lane, each operation a pass over the lanes, so that the lanes vectorise where
/// one loop over [`power`] of each stays scalar (a recursion that needs a power per step and lane,
/// [`crate::surrogate::DamperLaw`]'s, ran scalar that way). Lane by lane the same operations as
/// [`power`], which is its one-lane case: the same values to the bit.
#[inline(always)]
pub fn power_lanes<const N: usize>(x: [f64; N], alpha: f64) -> [f64; N] {
    use std::array::from_fn;
    let bits: [u64; N] = from_fn(|l| x[l].to_bits());
    // x = m·2^e with m in [1, 2), then m in [√½, √2) so that |s| below is at most 0.172.
    let biased_exponent: [f64; N] = from_fn(|l| f64::from_bits((bits[l] >> 52) | TWO_52.to_bits()) - TWO_52);
    let mantissa: [f64; N] = from_fn(|l| f64::from_bits((bits[l] & 0x000f_ffff_ffff_ffff) | 1f64.to_bits()));
    let high: [bool; N] = from_fn(|l| mantissa[l] > std::f64::consts::SQRT_2);
    let m: [f64; N] = from_fn(|l| if high[l] { 0.5 * mantissa[l] } else { mantissa[l] });
    let e: [f64; N] = from_fn(|l| biased_exponent[l] - 1023.0 + if high[l] { 1.0 } else { 0.0 });
    // ln m = 2·atanh(s), s = (m − 1)/(m + 1): the series to s¹⁷ leaves 2·0.172¹⁹/19 < 10⁻¹⁵.
    // Its polynomial in z = s² by Estrin's scheme (pairs, then pairs of pairs), every product
    // fused: three multiply-adds deep instead of Horner's eight, because the free run waits on
    // each step's power (a chain of dependent operations is what a storm-step costs).
    let s: [f64; N] = from_fn(|l| (m[l] - 1.0) / (m[l] + 1.0));
    let z: [f64; N] = from_fn(|l| s[l] * s[l]);
    let z2: [f64; N] = from_fn(|l| z[l] * z[l]);
    let z4: [f64; N] = from_fn(|l| z2[l] * z2[l]);
    let pair = |low: f64, high: f64, x: &[f64; N]| -> [f64; N] { from_fn(|l| high.mul_add(x[l], low)) };
    let (p0, p1) = (pair(1.0 / 3.0, 1.0 / 5.0, &z), pair(1.0 / 7.0, 1.0 / 9.0, &z));
    let (p2, p3) = (pair(1.0 / 11.0, 1.0 / 13.0, &z), pair(1.0 / 15.0, 1.0 / 17.0, &z));
    let low: [f64; N] = from_fn(|l| p1[l].mul_add(z2[l], p0[l]));
    let high: [f64; N] = from_fn(|l| p3[l].mul_add(z2[l], p2[l]));
    let series: [f64; N] = from_fn(|l| high[l].mul_add(z4[l], low[l]));
    let ln_m: [f64; N] = from_fn(|l| (2.0 * s[l]) * z[l].mul_add(series[l], 1.0));
    let y: [f64; N] = from_fn(|l| alpha * e[l].mul_add(std::f64::consts::LN_2, ln_m[l]));
    // e^y = 2^k·e^r with k = round(y/ln 2), |r| ≤ ln 2 / 2; Taylor to r¹³ leaves 0.347¹⁴/14! < 10⁻¹⁶,
    // by Estrin's scheme too (four multiply-adds deep instead of thirteen).
    let rounded: [f64; N] = from_fn(|l| y[l].mul_add(std::f64::consts::LOG2_E, ROUNDER));
    let r: [f64; N] = from_fn(|l| (ROUNDER - rounded[l]).mul_add(std::f64::consts::LN_2, y[l]));
    let r2: [f64; N] = from_fn(|l| r[l] * r[l]);
    let r4: [f64; N] = from_fn(|l| r2[l] * r2[l]);
    let r8: [f64; N] = from_fn(|l| r4[l] * r4[l]);
    let c = &INVERSE_FACTORIALS;
    // Each a pass over the lanes of its own (an array of arrays made by `from_fn` left a call per
    // lane in the loop).
    let p0 = pair(c[0], c[1], &r);
    let p1 = pair(c[2], c[3], &r);
    let p2 = pair(c[4], c[5], &r);
    let p3 = pair(c[6], c[7], &r);
    let p4 = pair(c[8], c[9], &r);
    let p5 = pair(c[10], c[11], &r);
    let p6 = pair(c[12], c[13], &r);
    let q0: [f64; N] = from_fn(|l| p1[l].mul_add(r2[l], p0[l]));
    let q1: [f64; N] = from_fn(|l| p3[l].mul_add(r2[l], p2[l]));
    let q2: [f64; N] = from_fn(|l| p5[l].mul_add(r2[l], p4[l]));
    let low_half: [f64; N] = from_fn(|l| q1[l].mul_add(r4[l], q0[l]));
    let high_half: [f64; N] = from_fn(|l| p6[l].mul_add(r4[l], q2[l]));
    let taylor: [f64; N] = from_fn(|l| high_half[l].mul_add(r8[l], low_half[l]));
    from_fn(|l| {
        let k_bits = rounded[l].to_bits().wrapping_sub(ROUNDER.to_bits());
        let scale = f64::from_bits(k_bits.wrapping_add(1023) << 52);
        if x[l] < f64::MIN_POSITIVE { 0.0 } else { taylor[l] * scale }
    })
}

/// The damper law's shape sign(v)|v|^α, with [`power`]'s accuracy.
#[inline(always)]
pub fn sign_power(v: f64, alpha: f64) -> f64 {
    power(v.abs(), alpha).copysign(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Against `powf` over 40 decades of x (damper velocities sit between 10⁻⁸ and 1 m/s) and the
    /// exponents a damper law takes.
    #[test]
    fn agrees_with_powf() {
        let mut worst: f64 = 0.0;
        for alpha in [-0.31, 0.2, 0.38, 0.5, 1.0, 1.7, 2.0] {
            for i in 0..200_000 {
                let x = 10f64.powf(-20.0 + 40.0 * i as f64 / 200_000.0) * (1.0 + 1e-3 * (i % 7) as f64);
                let exact = x.powf(alpha);
                worst = worst.max((power(x, alpha) - exact).abs() / exact);
            }
        }
        assert!(worst < 1e-13, "worst relative error {worst:e}");
        assert_eq!(power(0.0, 0.38), 0.0);
        assert_eq!(power(1.0, 0.38), 1.0);
        assert!((power(2.0, 0.5) - std::f64::consts::SQRT_2).abs() < 1e-15);
    }

    /// Eight lanes at once give each lane's [`power`] to the bit, zeros included.
    #[test]
    fn lanes_agree_with_the_scalar_power() {
        for i in 0..20_000 {
            let x: [f64; 8] = std::array::from_fn(|l| {
                if (i + l) % 97 == 0 { 0.0 } else { 10f64.powf(-12.0 + (i * 8 + l) as f64 * 1.5e-4) }
            });
            let lanes = power_lanes(x, -0.31);
            for l in 0..8 {
                assert_eq!(lanes[l].to_bits(), power(x[l], -0.31).to_bits(), "{}", x[l]);
            }
        }
    }
}
