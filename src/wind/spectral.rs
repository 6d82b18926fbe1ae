//! Deodatis' spectral representation of an n-variate stationary Gaussian process with a real
//! cross-spectral matrix (Eqs. 15-17), evaluated by FFT.
//!
//! Component j is v_j(t) = Σ_{m≤j} Σ_l 2 H_jm(ω_ml) √Δω cos(ω_ml t + φ_ml), with
//! ω_ml = lΔω + (m+1)Δω/n and H(ω) the lower Cholesky factor of S(ω). Because the coherence is real,
//! H is real and the phase angles θ_jm reduce to its signs. For each (j, m) the sum over l is one
//! inverse FFT, h_jm(p) = Σ_l B_jm(l) e^{2πilp/M}, modulated by e^{i(m+1)Δω t/n}; the period of the
//! process is T̂ = 2πn/Δω.

use super::StormGrid;
use crate::error::{Error, Result};
use crate::linalg::cholesky_through_column;
use crate::uncertainty::Rng;
use rand::RngExt;
use rustfft::FftPlanner;
use rustfft::num_complex::Complex;
use std::f64::consts::PI;

/// A cross-spectral density evaluated along an arithmetic sequence of frequencies.
pub trait CrossSpectralDensity {
    fn dim(&self) -> usize;
    /// Calls `visit(l, s)` for ω_l = ω₀ + l·Δω, l < count, where `s` is the two-sided CSD in rad/s,
    /// row-major n×n; at least its lower triangle is filled.
    fn sweep(&self, omega0: f64, domega: f64, count: usize, visit: &mut dyn FnMut(usize, &[f64]));
}

/// The frequency discretisation: N lines per component below the cut-off ω_up.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpectralGrid {
    pub lines: usize,
    pub cutoff: f64,
}

impl SpectralGrid {
    /// Δω = ω_up / N.
    pub fn step(&self) -> f64 {
        self.cutoff / self.lines as f64
    }

    /// Period T̂ = 2πn/Δω of an n-variate simulation (Eq. 17).
    pub fn period(&self, n: usize) -> f64 {
        2.0 * PI * n as f64 / self.step()
    }
}

/// Simulates one realization of the process on `storm`'s time grid, generated every
/// `generation_step` seconds (rounded down to an FFT-friendly grid) and interpolated by cubic
/// convolution when that grid differs from the storm's. Returns one series per component.
pub fn simulate(
    csd: &dyn CrossSpectralDensity,
    grid: &SpectralGrid,
    generation_step: f64,
    storm: &StormGrid,
    rng: &mut Rng,
) -> Result<Vec<Vec<f64>>> {
    let n = csd.dim();
    let lines = grid.lines;
    let domega = grid.step();
    if storm.duration > grid.period(n) {
        return Err(Error::invalid(
            "duration_s",
            format!(
                "{} s is longer than the period of the simulated wind ({:.0} s); raise wind.frequencies",
                storm.duration,
                grid.period(n)
            ),
        ));
    }
    let phases: Vec<f64> = (0..n * lines).map(|_| 2.0 * PI * rng.random::<f64>()).collect();

    let fft_len = fft_friendly((2.0 * PI / (domega * generation_step)).ceil().max(2.0 * lines as f64 + 1.0) as usize);
    let dt_g = 2.0 * PI / (fft_len as f64 * domega);
    let direct = (dt_g - storm.time_step).abs() <= 1e-9 * storm.time_step;
    // Coarse instants p = −1 ..= last+1 so that cubic interpolation has neighbours at both ends.
    let (first, count) =
        if direct { (0i64, storm.steps()) } else { (-1i64, (storm.duration / dt_g).floor() as usize + 4) };

    let mut coarse = vec![vec![0.0; count]; n];
    let fft = FftPlanner::<f64>::new().plan_fft_inverse(fft_len);
    let mut buffer = vec![Complex::new(0.0, 0.0); fft_len];
    let mut scratch = vec![Complex::new(0.0, 0.0); fft.get_inplace_scratch_len()];
    let mut factor = vec![0.0; n * n];
    let mut column = vec![0.0; n * lines];
    let mut modulation = vec![Complex::new(0.0, 0.0); count];
    let amplitude = 2.0 * domega.sqrt();

    for m in 0..n {
        let omega0 = (m + 1) as f64 * domega / n as f64;
        // Column m of the Cholesky factor at every ω_ml, stored line-major: column[l·n + j]. Only
        // columns ≤ m are factored: the later ones would cost more than the earlier ones.
        csd.sweep(omega0, domega, lines, &mut |l, s| {
            factor.copy_from_slice(s);
            cholesky_through_column(&mut factor, n, m);
            for j in m..n {
                column[l * n + j] = factor[j * n + m];
            }
        });
        for (q, z) in modulation.iter_mut().enumerate() {
            let t = (first + q as i64) as f64 * dt_g;
            *z = Complex::from_polar(1.0, omega0 * t);
        }
        for j in m..n {
            buffer.iter_mut().for_each(|b| *b = Complex::new(0.0, 0.0));
            for l in 0..lines {
                let h = column[l * n + j];
                buffer[l] = Complex::from_polar(amplitude * h, phases[m * lines + l]);
            }
            fft.process_with_scratch(&mut buffer, &mut scratch);
            for (q, (out, z)) in coarse[j].iter_mut().zip(&modulation).enumerate() {
                let p = (first + q as i64).rem_euclid(fft_len as i64) as usize;
                *out += (buffer[p] * z).re;
            }
        }
    }
    if direct {
        return Ok(coarse);
    }
    Ok(coarse.iter().map(|c| interpolate_cubic(c, dt_g, storm)).collect())
}

/// The smallest length ≥ `n` of the form 2^a 3^b 5^c, on which rustfft is fastest.
fn fft_friendly(n: usize) -> usize {
    let mut best = n.next_power_of_two();
    let mut p5 = 1;
    while p5 < best {
        let mut p35 = p5;
        while p35 < best {
            let mut len = p35;
            while len < n {
                len *= 2;
            }
            best = best.min(len);
            p35 *= 3;
        }
        p5 *= 5;
    }
    best
}

/// Keys' cubic convolution (a = −½) from a coarse series whose first entry is at t = −dt_g.
fn interpolate_cubic(coarse: &[f64], dt_g: f64, storm: &StormGrid) -> Vec<f64> {
    (0..storm.steps())
        .map(|i| {
            let x = i as f64 * storm.time_step / dt_g;
            let p = x.floor();
            let f = x - p;
            let q = p as usize + 1;
            let (y0, y1, y2, y3) = (coarse[q - 1], coarse[q], coarse[q + 1], coarse[q + 2]);
            y1 + 0.5 * f * (y2 - y0 + f * (2.0 * y0 - 5.0 * y1 + 4.0 * y2 - y3 + f * (3.0 * (y1 - y2) + y3 - y0)))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uncertainty::rng_from_seed;

    /// A constant 2×2 spectrum S = [[1, ρ],[ρ, 1]]·s₀ on [0, ω_up).
    struct Flat {
        level: f64,
        rho: f64,
    }

    impl CrossSpectralDensity for Flat {
        fn dim(&self) -> usize {
            2
        }
        fn sweep(&self, _: f64, _: f64, count: usize, visit: &mut dyn FnMut(usize, &[f64])) {
            let s = [self.level, self.level * self.rho, self.level * self.rho, self.level];
            for l in 0..count {
                visit(l, &s);
            }
        }
    }

    /// Over one full period T̂ the scheme is ergodic: the time averages of v_j² and v₁v₂ equal the
    /// discretised targets 2 Σ S Δω exactly, up to rounding, for every realization.
    #[test]
    fn full_period_moments_are_exact() {
        let grid = SpectralGrid { lines: 64, cutoff: 2.0 * PI };
        let period = grid.period(2);
        let fft_len = fft_friendly(256);
        let dt = 2.0 * PI / (fft_len as f64 * grid.step());
        let storm = StormGrid { duration: period - dt, time_step: dt };
        let csd = Flat { level: 0.3, rho: 0.6 };
        let v = simulate(&csd, &grid, dt, &storm, &mut rng_from_seed(4)).unwrap();
        let mean = |f: &dyn Fn(usize) -> f64| (0..storm.steps()).map(f).sum::<f64>() / storm.steps() as f64;
        let target = 2.0 * 0.3 * grid.cutoff;
        let var0 = mean(&|i| v[0][i] * v[0][i]);
        let var1 = mean(&|i| v[1][i] * v[1][i]);
        let cov = mean(&|i| v[0][i] * v[1][i]);
        assert!((var0 / target - 1.0).abs() < 1e-10, "{var0} vs {target}");
        assert!((var1 / target - 1.0).abs() < 1e-10, "{var1} vs {target}");
        assert!((cov / (0.6 * target) - 1.0).abs() < 1e-10, "{cov}");
    }

    /// The FFT evaluation equals the direct double sum of Eq. (15) at arbitrary instants.
    #[test]
    fn fft_equals_direct_summation() {
        let grid = SpectralGrid { lines: 32, cutoff: 2.0 * PI };
        let csd = Flat { level: 1.0, rho: -0.4 };
        let fft_len = fft_friendly(128);
        let dt = 2.0 * PI / (fft_len as f64 * grid.step());
        let storm = StormGrid { duration: 40.0 * dt, time_step: dt };
        let v = simulate(&csd, &grid, dt, &storm, &mut rng_from_seed(11)).unwrap();
        let mut rng = rng_from_seed(11);
        let phases: Vec<f64> = (0..64).map(|_| 2.0 * PI * rng.random::<f64>()).collect();
        let h = [[1.0, 0.0], [-0.4, (1.0f64 - 0.16).sqrt()]];
        let dw = grid.step();
        for (i, t) in (0..storm.steps()).map(|i| (i, i as f64 * dt)) {
            for j in 0..2 {
                let mut sum = 0.0;
                for m in 0..=j {
                    for l in 0..32 {
                        let w = l as f64 * dw + (m + 1) as f64 * dw / 2.0;
                        sum += 2.0 * h[j][m] * dw.sqrt() * (w * t + phases[m * 32 + l]).cos();
                    }
                }
                assert!((v[j][i] - sum).abs() < 1e-10, "t={t} j={j}: {} vs {sum}", v[j][i]);
            }
        }
    }

    #[test]
    fn interpolation_reproduces_cubics_exactly_inside() {
        // Keys' kernel reproduces quadratics exactly.
        let dt_g = 0.1;
        let coarse: Vec<f64> = (0..30)
            .map(|q| {
                let t = (q as f64 - 1.0) * dt_g;
                1.0 + 2.0 * t - 3.0 * t * t
            })
            .collect();
        let storm = StormGrid { duration: 2.0, time_step: 0.01 };
        let fine = interpolate_cubic(&coarse, dt_g, &storm);
        for (i, y) in fine.iter().enumerate() {
            let t = i as f64 * 0.01;
            assert!((y - (1.0 + 2.0 * t - 3.0 * t * t)).abs() < 1e-12);
        }
    }

    #[test]
    fn fft_lengths_are_smooth() {
        assert_eq!(fft_friendly(204_800), 204_800);
        assert_eq!(fft_friendly(20_481), 20_736);
        assert_eq!(fft_friendly(4096), 4096);
    }

    #[test]
    fn storms_longer_than_the_period_are_refused() {
        let grid = SpectralGrid { lines: 16, cutoff: 2.0 * PI };
        let storm = StormGrid { duration: 100.0, time_step: 0.1 };
        let err = simulate(&Flat { level: 1.0, rho: 0.0 }, &grid, 0.1, &storm, &mut rng_from_seed(1)).unwrap_err();
        assert!(err.to_string().contains("period"));
    }
}
