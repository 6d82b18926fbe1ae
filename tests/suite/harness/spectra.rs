//! Spectral estimates of simulated series, for the wind's tests.

use rustfft::FftPlanner;
use rustfft::num_complex::Complex;
use std::f64::consts::PI;

/// Welch estimate of the two-sided cross-spectral density S_xy(ω) in rad/s (so that
/// ∫_{−∞}^{∞} S_xx dω is the variance), Hann windows of `segment` points with 50 % overlap, mean
/// removed per series. Returns (ω_k, S_xy(ω_k)) for k = 1 .. segment/2.
pub fn welch_cross(x: &[f64], y: &[f64], dt: f64, segment: usize) -> Vec<(f64, Complex<f64>)> {
    let mean_x = x.iter().sum::<f64>() / x.len() as f64;
    let mean_y = y.iter().sum::<f64>() / y.len() as f64;
    let window: Vec<f64> = (0..segment).map(|n| 0.5 - 0.5 * (2.0 * PI * n as f64 / segment as f64).cos()).collect();
    let power: f64 = window.iter().map(|w| w * w).sum();
    let fft = FftPlanner::<f64>::new().plan_fft_forward(segment);
    let mut sum = vec![Complex::new(0.0, 0.0); segment / 2 + 1];
    let mut count = 0;
    let mut start = 0;
    while start + segment <= x.len() {
        let mut fx: Vec<Complex<f64>> =
            (0..segment).map(|n| Complex::new((x[start + n] - mean_x) * window[n], 0.0)).collect();
        let mut fy: Vec<Complex<f64>> =
            (0..segment).map(|n| Complex::new((y[start + n] - mean_y) * window[n], 0.0)).collect();
        fft.process(&mut fx);
        fft.process(&mut fy);
        for k in 0..=segment / 2 {
            sum[k] += fx[k].conj() * fy[k];
        }
        count += 1;
        start += segment / 2;
    }
    let scale = dt / (2.0 * PI * power * count as f64);
    (1..=segment / 2).map(|k| (2.0 * PI * k as f64 / (segment as f64 * dt), sum[k] * scale)).collect()
}

/// Averages an estimate over the frequency band [lo, hi).
pub fn band_mean(estimate: &[(f64, f64)], lo: f64, hi: f64) -> f64 {
    let inside: Vec<f64> = estimate.iter().filter(|(w, _)| *w >= lo && *w < hi).map(|(_, s)| *s).collect();
    inside.iter().sum::<f64>() / inside.len() as f64
}

/// Mean and standard error of a set of estimates.
pub fn mean_and_standard_error(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let sd = (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    (mean, sd / n.sqrt())
}
