//! Deodatis' spectral representation of an n-variate stationary Gaussian process with a real
//! cross-spectral matrix (Eqs. 15-17), evaluated by FFT.
//!
//! Component j is v_j(t) = Σ_{m≤j} Σ_l 2 H_jm(ω_ml) √Δω cos(ω_ml t + φ_ml), with
//! ω_ml = lΔω + (m+1)Δω/n and H(ω) the lower Cholesky factor of S(ω). Because the coherence is real,
//! H is real and the phase angles θ_jm reduce to its signs. For each (j, m) the sum over l is one
//! inverse FFT, h_jm(p) = Σ_l B_jm(l) e^{2πilp/M}, modulated by e^{i(m+1)Δω t/n}; the period of the
//! process is T̂ = 2πn/Δω. The transforms, pruned and in single precision, and the sums of their
//! modulated rows are in [`super::pruned`].

use super::StormGrid;
use super::transform::{Bin, TransformWorkspace};
use crate::error::{Error, Result};
use crate::linalg::cholesky_through_column;
use crate::uncertainty::Rng;
use rand::RngExt;
use std::f64::consts::PI;

/// A cross-spectral density evaluated along an arithmetic sequence of frequencies.
pub trait CrossSpectralDensity {
    /// Number of components n.
    fn dim(&self) -> usize;
    /// Calls `visit(l, s)` for ω_l = ω₀ + l·Δω, l < count, where `s` is the two-sided CSD in rad/s,
    /// row-major n×n; at least its lower triangle is filled.
    fn sweep(&self, omega0: f64, domega: f64, count: usize, visit: &mut dyn FnMut(usize, &[f64]));

    /// Column m of the lower Cholesky factor of the CSD at ω_l = ω₀ + l·Δω into
    /// `columns[j·lines + l]`, j ≥ m, for every line l < lines = columns.len() / n (rows above m are
    /// left as they are). By default the CSD of every frequency is factored through column m; a
    /// spectrum that knows its factor gives it directly.
    fn factor_columns(&self, omega0: f64, domega: f64, m: usize, columns: &mut [f64]) {
        let n = self.dim();
        let lines = columns.len() / n;
        let mut factor = vec![0.0; n * n];
        self.sweep(omega0, domega, lines, &mut |l, s| {
            factor.copy_from_slice(s);
            cholesky_through_column(&mut factor, n, m);
            for j in m..n {
                columns[j * lines + l] = factor[j * n + m];
            }
        });
    }
}

/// The frequency discretisation: N lines per component below the cut-off ω_up.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpectralGrid {
    /// Frequency lines N per component.
    pub lines: usize,
    /// Cut-off frequency ω_up (rad/s).
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

/// One realization on its generation grid: `series[j][q]` is component j at t = (q − 1)·step, so
/// that cubic interpolation has a neighbour before t = 0 and two after the end.
#[derive(Debug, Clone)]
pub struct CoarseSeries {
    /// Step of the generation grid (s).
    pub step: f64,
    /// `series[j][q]`: component j at t = (q − 1)·step.
    pub series: Vec<Vec<f64>>,
}

impl CoarseSeries {
    /// Component j at instants first, first + 1, … of a grid of step `time_step`, plus `offset`.
    pub fn interpolate_into(&self, j: usize, time_step: f64, first: usize, offset: f64, out: &mut [f64]) {
        CubicSchedule::new(self.step, time_step).apply(&self.series[j], first, offset, out);
    }

    /// Every component on `storm`'s grid.
    pub fn on_grid(&self, storm: &StormGrid) -> Vec<Vec<f64>> {
        let schedule = CubicSchedule::new(self.step, storm.time_step);
        self.series
            .iter()
            .map(|coarse| {
                let mut out = vec![0.0; storm.steps()];
                schedule.apply(coarse, 0, 0.0, &mut out);
                out
            })
            .collect()
    }
}

/// Keys' cubic convolution weights (a = −½) of the four coarse points around an instant a fraction
/// f ∈ [0, 1) past the second of them.
#[inline(always)]
fn keys_weights(f: f64) -> [f64; 4] {
    [
        0.5 * f * (-1.0 + f * (2.0 - f)),
        0.5 * (2.0 + f * f * (-5.0 + 3.0 * f)),
        0.5 * f * (1.0 + f * (4.0 - 3.0 * f)),
        0.5 * f * f * (f - 1.0),
    ]
}

/// Where the instants of a grid of step `time_step` fall on a generation grid of step dt_g whose
/// first point is at −dt_g: instant i's first coarse neighbour p (coarse point p is at
/// t = (p − 1)·dt_g) and its four cubic-convolution weights. When dt_g is a whole number r of
/// steps (0.1 s over 0.01 s) instant i = r·p + j lies the exact fraction j/r past point p + 1, so
/// r sets of weights serve every instant and no step computes any; otherwise each instant's are
/// computed from i·time_step/dt_g. A weight depends only on its instant, so values do not depend
/// on where a block starts.
#[derive(Debug, Clone, PartialEq)]
pub struct CubicSchedule {
    ratio: f64,
    periodic: Option<Vec<[f64; 4]>>,
}

impl CubicSchedule {
    /// The schedule of a grid of step `time_step` (s) on a generation grid of step `dt_g` (s).
    pub fn new(dt_g: f64, time_step: f64) -> Self {
        let per_step = dt_g / time_step;
        let r = per_step.round();
        let whole = (1.0..=1e6).contains(&r) && (per_step - r).abs() <= 1e-9 * per_step;
        let periodic = whole.then(|| (0..r as usize).map(|j| keys_weights(j as f64 / r)).collect());
        CubicSchedule { ratio: time_step / dt_g, periodic }
    }

    /// `visit(i, p, weights)` for instants first + i, i = 0..len, in order.
    #[inline(always)]
    pub fn for_each(&self, first: usize, len: usize, mut visit: impl FnMut(usize, usize, &[f64; 4])) {
        match &self.periodic {
            Some(weights) => {
                let r = weights.len();
                let (mut p, mut j) = (first / r, first % r);
                for i in 0..len {
                    visit(i, p, &weights[j]);
                    j += 1;
                    if j == r {
                        j = 0;
                        p += 1;
                    }
                }
            }
            None => {
                for i in 0..len {
                    let x = (first + i) as f64 * self.ratio;
                    // x ≥ 0, so truncation is the floor.
                    let p = x as usize;
                    visit(i, p, &keys_weights(x - p as f64));
                }
            }
        }
    }

    /// offset + the interpolated `coarse` at instants first, first + 1, …, into `out`.
    pub fn apply(&self, coarse: &[f64], first: usize, offset: f64, out: &mut [f64]) {
        self.for_each(first, out.len(), |i, p, w| {
            let y = &coarse[p..p + 4];
            out[i] = offset + (w[0] * y[0] + w[1] * y[1] + w[2] * y[2] + w[3] * y[3]);
        });
    }
}

/// `count` draws of e^{iφ} with φ uniform on [0, 2π): points uniform in the unit disc (by rejection
/// from the square, π/4 of the draws kept) projected on the circle. The same law as e^{2πiU} without
/// a sine and a cosine per frequency (they were a tenth of a modal storm's cost). The few points
/// within 10⁻⁶ of the centre are rejected too, which keeps the law rotation-invariant. Every
/// candidate is written and only the kept ones advance, so the processor has no branch to
/// mispredict on a coin flip; the kept points are projected afterwards in one pass the compiler
/// vectorises. Drawn in double precision, kept in the transforms' single.
pub(crate) fn unit_phases(rng: &mut Rng, count: usize) -> Vec<Bin> {
    let mut points = vec![[0.0f64; 2]; count + 1];
    let mut kept = 0;
    while kept < count {
        let x = 2.0 * rng.random::<f64>() - 1.0;
        let y = 2.0 * rng.random::<f64>() - 1.0;
        let r2 = x * x + y * y;
        points[kept] = [x, y];
        kept += usize::from(r2 <= 1.0 && r2 > 1e-12);
    }
    points[..count]
        .iter()
        .map(|[x, y]| {
            let scale = (x * x + y * y).sqrt().recip();
            Bin::new((x * scale) as f32, (y * scale) as f32)
        })
        .collect()
}

/// Simulates one realization of the process on `storm`'s time grid, generated every
/// `generation_step` seconds (rounded down to an FFT-friendly grid) and interpolated by cubic
/// convolution. Returns one series per component.
pub fn simulate(
    csd: &dyn CrossSpectralDensity,
    grid: &SpectralGrid,
    generation_step: f64,
    storm: &StormGrid,
    rng: &mut Rng,
) -> Result<Vec<Vec<f64>>> {
    Ok(simulate_coarse(csd, grid, generation_step, storm.duration, &mut TransformWorkspace::default(), rng)?
        .on_grid(storm))
}

/// Simulates one realization over `duration` seconds on the generation grid only, with the
/// transforms of `workspace`.
pub fn simulate_coarse(
    csd: &dyn CrossSpectralDensity,
    grid: &SpectralGrid,
    generation_step: f64,
    duration: f64,
    workspace: &mut TransformWorkspace,
    rng: &mut Rng,
) -> Result<CoarseSeries> {
    let n = csd.dim();
    let lines = grid.lines;
    let domega = grid.step();
    if duration > grid.period(n) {
        return Err(Error::invalid(
            "duration_s",
            format!(
                "{duration} s is longer than the period of the simulated wind ({:.0} s); raise wind.frequencies",
                grid.period(n)
            ),
        ));
    }
    // e^{iφ_ml}, shared by every component j ≥ m.
    let phases = unit_phases(rng, n * lines);

    let fft_len = fft_friendly((2.0 * PI / (domega * generation_step)).ceil().max(2.0 * lines as f64 + 1.0) as usize);
    let dt_g = 2.0 * PI / (fft_len as f64 * domega);
    // Coarse instants q − 1 for q < count: from −dt_g to two steps past the last instant of any
    // storm grid of this duration (a grid's last instant lies within half a step, ≤ π/(2ω_up), of it).
    let count = ((duration + PI / grid.cutoff) / dt_g).ceil() as usize + 4;

    let mut columns = vec![0.0; n * lines];
    let mut amplitudes = vec![0.0f32; lines];
    let amplitude = 2.0 * domega.sqrt();
    let series = workspace.with(fft_len, lines, n, count, |transform, sum| {
        for m in 0..n {
            let omega0 = (m + 1) as f64 * domega / n as f64;
            // Column m of the Cholesky factor at every ω_ml: columns[j·lines + l].
            csd.factor_columns(omega0, domega, m, &mut columns);
            transform.set_phases(&phases[m * lines..(m + 1) * lines]);
            sum.set_modulation(omega0 * dt_g);
            for (j, column) in columns.chunks_exact(lines).enumerate().skip(m) {
                for (a, h) in amplitudes.iter_mut().zip(column) {
                    *a = (amplitude * h) as f32;
                }
                sum.add(j, transform.transform(&amplitudes));
            }
        }
        sum.series()
    });
    Ok(CoarseSeries { step: dt_g, series })
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uncertainty::rng_from_seed;
    use rustfft::num_complex::Complex;

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
    /// discretised targets 2 Σ S Δω exactly, up to the transforms' single-precision rounding
    /// (a relative 10⁻⁵ leaves an order of magnitude over it), for every realization.
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
        assert!((var0 / target - 1.0).abs() < 1e-5, "{var0} vs {target}");
        assert!((var1 / target - 1.0).abs() < 1e-5, "{var1} vs {target}");
        assert!((cov / (0.6 * target) - 1.0).abs() < 1e-5, "{cov}");
    }

    /// Phases lie on the unit circle and are uniform on it: the first four trigonometric moments
    /// vanish to sampling error (5 standard errors of 1/√(2n)) and the quadrants are equally full.
    #[test]
    fn phases_are_uniform_on_the_circle() {
        let mut rng = rng_from_seed(5);
        let n = 200_000;
        let z: Vec<Complex<f64>> =
            unit_phases(&mut rng, n).iter().map(|z| Complex::new(f64::from(z.re), f64::from(z.im))).collect();
        assert!(z.iter().all(|z| (z.norm() - 1.0).abs() < 1e-7));
        let bound = 5.0 / (2.0 * n as f64).sqrt();
        for k in 1..=4 {
            let moment = z.iter().map(|z| z.powu(k)).sum::<Complex<f64>>() / n as f64;
            assert!(moment.re.abs() < bound && moment.im.abs() < bound, "moment {k}: {moment}");
        }
        let first_quadrant = z.iter().filter(|z| z.re > 0.0 && z.im > 0.0).count() as f64 / n as f64;
        assert!((first_quadrant - 0.25).abs() < 5.0 * (0.25 * 0.75 / n as f64).sqrt(), "{first_quadrant}");
    }

    /// The FFT evaluation equals the direct double sum of Eq. (15) at arbitrary instants, to single
    /// precision's rounding of the sum of the terms' magnitudes.
    #[test]
    fn fft_equals_direct_summation() {
        let grid = SpectralGrid { lines: 32, cutoff: 2.0 * PI };
        let csd = Flat { level: 1.0, rho: -0.4 };
        let fft_len = fft_friendly(128);
        let dt = 2.0 * PI / (fft_len as f64 * grid.step());
        let storm = StormGrid { duration: 40.0 * dt, time_step: dt };
        let v = simulate(&csd, &grid, dt, &storm, &mut rng_from_seed(11)).unwrap();
        let mut rng = rng_from_seed(11);
        let phases = unit_phases(&mut rng, 64);
        let h = [[1.0, 0.0], [-0.4, (1.0f64 - 0.16).sqrt()]];
        let dw = grid.step();
        for (i, t) in (0..storm.steps()).map(|i| (i, i as f64 * dt)) {
            for j in 0..2 {
                let (mut sum, mut magnitudes) = (0.0, 0.0);
                for m in 0..=j {
                    for l in 0..32 {
                        let w = l as f64 * dw + (m + 1) as f64 * dw / 2.0;
                        let phase = phases[m * 32 + l];
                        let phase = Complex::new(f64::from(phase.re), f64::from(phase.im));
                        sum += 2.0 * h[j][m] * dw.sqrt() * (phase * Complex::from_polar(1.0, w * t)).re;
                        magnitudes += 2.0 * f64::abs(h[j][m]) * dw.sqrt();
                    }
                }
                assert!((v[j][i] - sum).abs() < 1e-6 * magnitudes, "t={t} j={j}: {} vs {sum}", v[j][i]);
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
        // A whole number of steps per generation step (periodic weights) and not (computed ones).
        for time_step in [0.01, 0.03] {
            let mut fine = vec![0.0; 67];
            CubicSchedule::new(dt_g, time_step).apply(&coarse, 0, 0.0, &mut fine);
            for (i, y) in fine.iter().enumerate() {
                let t = i as f64 * time_step;
                assert!((y - (1.0 + 2.0 * t - 3.0 * t * t)).abs() < 1e-12, "step {time_step}, instant {i}");
            }
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
