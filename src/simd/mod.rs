//! Eight f64 lanes as one value, on three instruction sets: AVX-512 (one register), AVX2 (two)
//! and portable arrays, and the dispatch that runs a [`Kernel`] on the widest the processor has.
//! The batched free run and the acceleration sink are written once over [`Vector`] and compiled
//! for each. Arrays of `[f64; 8]` alone were not enough: the compiler scalarised the recursion's
//! state and regrouped it into vectors that straddle two modes, paying lane permutations every step.
//!
//! Every implementation rounds identically (products that are summed are fused multiply-adds, the
//! same operation in hardware and in `f64::mul_add`), so a lane's result does not depend on which
//! one runs.
//!
//! Soundness: a vector value can only be made from an [`Vector::Isa`] value, and the x86 ones
//! (`Avx512Isa`, `Avx2Isa`) only come from detecting their instructions on the running processor.
//! Every method of a vector therefore runs where its instructions exist. Speed is a separate
//! matter: the intrinsics inline only into functions compiled for the features ([`run_widest`]);
//! elsewhere they become calls, correct but many times slower. This is the only module with
//! `unsafe` code.

#![allow(unsafe_code)]

/// Samples per batch: one AVX-512 register of f64, two AVX2 ones.
pub const LANES: usize = 8;

/// One value of every sample of a batch.
pub type Lanes = [f64; LANES];

/// Work written once over the vector type: [`run_widest`] runs it on the widest vectors the
/// processor has, compiled for their instructions.
pub trait Kernel {
    /// What the work returns.
    type Output;
    /// Everything this calls in its loops must be `#[inline(always)]`, so that it is compiled for
    /// V's instructions too (a function that is not inlined keeps the baseline code, and a vector
    /// method that is not inlined becomes a call per operation).
    fn run<V: Vector>(self, isa: V::Isa) -> Self::Output;
}

/// Runs `kernel` on AVX-512 where the processor has it, else on AVX2, else on portable arrays.
pub fn run_widest<K: Kernel>(kernel: K) -> K::Output {
    #[cfg(target_arch = "x86_64")]
    {
        if let Some(isa) = Avx512Isa::detect() {
            // SAFETY: `isa` was detected, so the processor has the features `on_avx512` is
            // compiled for.
            return unsafe { on_avx512(kernel, isa) };
        }
        if let Some(isa) = Avx2Isa::detect() {
            // SAFETY: as above, for `on_avx2`.
            return unsafe { on_avx2(kernel, isa) };
        }
    }
    kernel.run::<Lanes>(())
}

/// # Safety
/// The processor must have AVX-512F and FMA, which `isa` proves.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,fma")]
unsafe fn on_avx512<K: Kernel>(kernel: K, isa: Avx512Isa) -> K::Output {
    kernel.run::<Avx512>(isa)
}

/// # Safety
/// The processor must have AVX2 and FMA, which `isa` proves.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn on_avx2<K: Kernel>(kernel: K, isa: Avx2Isa) -> K::Output {
    kernel.run::<Avx2>(isa)
}

/// Lane-wise arithmetic on eight f64.
pub trait Vector: Copy {
    /// Proof that the instructions the type uses exist here; values are made only from it.
    type Isa: Copy;
    /// `x` in every lane.
    fn splat(isa: Self::Isa, x: f64) -> Self;
    /// The eight values of `x`.
    fn load(isa: Self::Isa, x: &Lanes) -> Self;
    /// Writes the lanes to `to`.
    fn store(self, to: &mut Lanes);
    /// self·b + c, rounded once.
    fn mul_add(self, b: Self, c: Self) -> Self;
    /// Product self·b, lane by lane.
    fn mul(self, b: Self) -> Self;
    /// Absolute value, lane by lane.
    fn abs(self) -> Self;
    /// The larger of the two; where either is NaN, `b` (the x86 rule, one instruction).
    fn max(self, b: Self) -> Self;
}

/// The portable arrays need no instruction beyond the baseline.
impl Vector for Lanes {
    type Isa = ();
    #[inline(always)]
    fn splat(_: (), x: f64) -> Self {
        [x; LANES]
    }
    #[inline(always)]
    fn load(_: (), x: &Lanes) -> Self {
        *x
    }
    #[inline(always)]
    fn store(self, to: &mut Lanes) {
        *to = self;
    }
    #[inline(always)]
    fn mul_add(self, b: Self, c: Self) -> Self {
        let mut out = [0.0; LANES];
        for l in 0..LANES {
            out[l] = self[l].mul_add(b[l], c[l]);
        }
        out
    }
    #[inline(always)]
    fn mul(self, b: Self) -> Self {
        let mut out = [0.0; LANES];
        for l in 0..LANES {
            out[l] = self[l] * b[l];
        }
        out
    }
    #[inline(always)]
    fn abs(self) -> Self {
        self.map(f64::abs)
    }
    #[inline(always)]
    fn max(self, b: Self) -> Self {
        let mut out = [0.0; LANES];
        for l in 0..LANES {
            out[l] = if self[l] > b[l] { self[l] } else { b[l] };
        }
        out
    }
}

#[cfg(target_arch = "x86_64")]
use x86::{Avx2, Avx2Isa, Avx512, Avx512Isa};

#[cfg(target_arch = "x86_64")]
mod x86 {
    use super::{Lanes, Vector};
    use std::arch::x86_64::*;

    /// Proof that the processor has AVX-512F and FMA: only [`Avx512Isa::detect`] makes one.
    #[derive(Clone, Copy)]
    pub struct Avx512Isa(());

    impl Avx512Isa {
        pub fn detect() -> Option<Self> {
            (is_x86_feature_detected!("avx512f") && is_x86_feature_detected!("fma")).then_some(Avx512Isa(()))
        }
    }

    /// Proof that the processor has AVX2 and FMA: only [`Avx2Isa::detect`] makes one.
    #[derive(Clone, Copy)]
    pub struct Avx2Isa(());

    impl Avx2Isa {
        pub fn detect() -> Option<Self> {
            (is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma")).then_some(Avx2Isa(()))
        }
    }

    /// One AVX-512 register; made only with an [`Avx512Isa`].
    #[derive(Clone, Copy)]
    pub struct Avx512(__m512d);

    // SAFETY (every block below): an `Avx512` exists only where an `Avx512Isa` was detected, so
    // AVX-512F and FMA are present; the loads and stores read and write whole `[f64; 8]` through
    // references.
    impl Vector for Avx512 {
        type Isa = Avx512Isa;
        #[inline(always)]
        fn splat(_: Avx512Isa, x: f64) -> Self {
            // SAFETY: an `Avx512` exists only where AVX-512F and FMA were detected.
            Avx512(unsafe { _mm512_set1_pd(x) })
        }
        #[inline(always)]
        fn load(_: Avx512Isa, x: &Lanes) -> Self {
            // SAFETY: an `Avx512` exists only where AVX-512F and FMA were detected.
            Avx512(unsafe { _mm512_loadu_pd(x.as_ptr()) })
        }
        #[inline(always)]
        fn store(self, to: &mut Lanes) {
            // SAFETY: an `Avx512` exists only where AVX-512F and FMA were detected.
            unsafe { _mm512_storeu_pd(to.as_mut_ptr(), self.0) }
        }
        #[inline(always)]
        fn mul_add(self, b: Self, c: Self) -> Self {
            // SAFETY: an `Avx512` exists only where AVX-512F and FMA were detected.
            Avx512(unsafe { _mm512_fmadd_pd(self.0, b.0, c.0) })
        }
        #[inline(always)]
        fn mul(self, b: Self) -> Self {
            // SAFETY: an `Avx512` exists only where AVX-512F and FMA were detected.
            Avx512(unsafe { _mm512_mul_pd(self.0, b.0) })
        }
        #[inline(always)]
        fn abs(self) -> Self {
            // SAFETY: an `Avx512` exists only where AVX-512F and FMA were detected.
            Avx512(unsafe { _mm512_abs_pd(self.0) })
        }
        #[inline(always)]
        fn max(self, b: Self) -> Self {
            // SAFETY: an `Avx512` exists only where AVX-512F and FMA were detected.
            Avx512(unsafe { _mm512_max_pd(self.0, b.0) })
        }
    }

    /// Two AVX2 registers; made only with an [`Avx2Isa`].
    #[derive(Clone, Copy)]
    pub struct Avx2(__m256d, __m256d);

    // SAFETY (every block below): as for `Avx512`, with `Avx2Isa`; `add(4)` stays inside the eight
    // lanes.
    impl Vector for Avx2 {
        type Isa = Avx2Isa;
        #[inline(always)]
        fn splat(_: Avx2Isa, x: f64) -> Self {
            // SAFETY: an `Avx2` exists only where AVX2 and FMA were detected.
            unsafe { Avx2(_mm256_set1_pd(x), _mm256_set1_pd(x)) }
        }
        #[inline(always)]
        fn load(_: Avx2Isa, x: &Lanes) -> Self {
            // SAFETY: an `Avx2` exists only where AVX2 and FMA were detected.
            unsafe { Avx2(_mm256_loadu_pd(x.as_ptr()), _mm256_loadu_pd(x.as_ptr().add(4))) }
        }
        #[inline(always)]
        fn store(self, to: &mut Lanes) {
            // SAFETY: an `Avx2` exists only where AVX2 and FMA were detected.
            unsafe {
                _mm256_storeu_pd(to.as_mut_ptr(), self.0);
                _mm256_storeu_pd(to.as_mut_ptr().add(4), self.1);
            }
        }
        #[inline(always)]
        fn mul_add(self, b: Self, c: Self) -> Self {
            // SAFETY: an `Avx2` exists only where AVX2 and FMA were detected.
            unsafe { Avx2(_mm256_fmadd_pd(self.0, b.0, c.0), _mm256_fmadd_pd(self.1, b.1, c.1)) }
        }
        #[inline(always)]
        fn mul(self, b: Self) -> Self {
            // SAFETY: an `Avx2` exists only where AVX2 and FMA were detected.
            unsafe { Avx2(_mm256_mul_pd(self.0, b.0), _mm256_mul_pd(self.1, b.1)) }
        }
        #[inline(always)]
        fn abs(self) -> Self {
            // SAFETY: an `Avx2` exists only where AVX2 and FMA were detected.
            unsafe {
                let sign = _mm256_set1_pd(-0.0);
                Avx2(_mm256_andnot_pd(sign, self.0), _mm256_andnot_pd(sign, self.1))
            }
        }
        #[inline(always)]
        fn max(self, b: Self) -> Self {
            // SAFETY: an `Avx2` exists only where AVX2 and FMA were detected.
            unsafe { Avx2(_mm256_max_pd(self.0, b.0), _mm256_max_pd(self.1, b.1)) }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn exercise<V: Vector>(isa: V::Isa) -> [Lanes; 4] {
        let a: Lanes = [1.5, -2.0, 0.1, 3.0, -0.0, 7.0, -1e-300, 2.5];
        let b: Lanes = [0.3, 0.7, -0.1, 1e16, 2.0, -3.0, 1e300, 0.4];
        let c: Lanes = [1.0, -1.0, 0.01, -1.0, 0.0, 21.0, 1.0, -1.0];
        let (va, vb, vc) = (V::load(isa, &a), V::load(isa, &b), V::load(isa, &c));
        let mut out = [[0.0; LANES]; 4];
        va.mul_add(vb, vc).store(&mut out[0]);
        va.mul(vb).store(&mut out[1]);
        va.abs().store(&mut out[2]);
        va.max(vb).mul_add(V::splat(isa, 2.0), V::splat(isa, 0.5)).store(&mut out[3]);
        out
    }

    /// The instruction sets agree with the portable arrays bit for bit (the fused multiply-add of
    /// 3·10¹⁶ − 1 keeps the 1 that a separate product would round away).
    #[test]
    fn instruction_sets_agree_bit_for_bit() {
        let portable = exercise::<Lanes>(());
        assert_eq!(portable[0][3], 3.0f64.mul_add(1e16, -1.0));
        let bits = |r: [Lanes; 4]| r.map(|r| r.map(f64::to_bits));
        #[cfg(target_arch = "x86_64")]
        {
            use std::io::Write;
            // Skips are written past the harness's capture, so that they are seen in the run's output.
            match Avx512Isa::detect() {
                Some(isa) => assert_eq!(bits(exercise::<Avx512>(isa)), bits(portable)),
                None => {
                    let _ = writeln!(std::io::stderr(), "AVX-512 comparison SKIPPED: this processor has no AVX-512F");
                }
            }
            match Avx2Isa::detect() {
                Some(isa) => assert_eq!(bits(exercise::<Avx2>(isa)), bits(portable)),
                None => {
                    let _ = writeln!(std::io::stderr(), "AVX2 comparison SKIPPED: this processor has no AVX2 with FMA");
                }
            }
        }
    }
}
