//! The published model against closed forms and an independent computation of its formulas, the
//! wind-tunnel file against the closed forms it was written from, and the floors' simulated loads
//! against their target spectra.

use super::*;
use crate::linalg::cholesky_through_column;
use crate::structure::spatial::{Dof, SpatialModes, frame40_3d};
use crate::uncertainty::rng_from_seed;
use crate::wind::{CrossSpectralDensity, SpectralGrid, TransformWorkspace, simulate_coarse};
use rustfft::FftPlanner;
use rustfft::num_complex::Complex;
use std::f64::consts::PI;

/// ∫ F d(ln n) of one peak 4κ(1 + 0.6β)β/π · x²/((1 − x²)² + 4β²x²): with u = x² the integral is
/// ½∫du/(u² − 2(1 − 2β²)u + 1), which gives κ(1 + 0.6β)(π/2 + asin(1 − 2β²))/(π√(1 − β²)).
fn peak_area(kappa: f64, beta: f64) -> f64 {
    kappa * (1.0 + 0.6 * beta) * (PI / 2.0 + (1.0 - 2.0 * beta * beta).asin()) / (PI * (1.0 - beta * beta).sqrt())
}

#[test]
fn the_published_across_wind_spectrum_has_the_area_of_its_peaks() {
    for r in [0.5, 1.0, 2.0, 3.0, 4.0] {
        let model = AcrossWindModel::new(r);
        let expected: f64 = model.peaks().iter().map(|&[kappa, _, beta]| peak_area(kappa, beta)).sum();
        // The numerical area stops at n = 10⁻⁴ and 10², beyond which the spectrum (∝ n² below,
        // ∝ n⁻² above) holds F/2 at each end.
        let tails = 0.5 * (model.value(1e-4) + model.value(1e2));
        let area = NormalisedSpectrum::AcrossWind(model).area();
        assert!(
            (area + tails - expected).abs() <= 1e-7 * expected,
            "r = {r}: area {area} + {tails}, closed form {expected}"
        );
        // The model's own invariant: about κ₁ (+ κ₂), the shape of a normalised f·S/σ².
        assert!((0.8..0.95).contains(&area), "r = {r}: area {area}");
    }
}

/// Values of the codes' formulas computed by an independent implementation (Python, from the
/// Thai DPT 1311-50 transcription; see [`published`]), printed to five significant figures: not
/// published values, which no source readable here prints, but a second reading of the formulas.
#[test]
fn published_spectra_match_an_independent_computation_of_the_formulas() {
    let across = [
        (1.0, [0.18977, 0.98934, 0.10296], 0.1572, 0.0502),
        (2.0, [0.68266, 0.24784, 0.05370], 0.2216, 0.1209),
        (3.0, [0.37671, 0.12256, 0.06111], 0.2424, 0.2177),
    ];
    for (r, values, across_rms, torsion_rms) in across {
        let model = AcrossWindModel::new(r);
        for (n, expected) in [0.05, 0.1, 0.2].into_iter().zip(values) {
            let value = model.value(n);
            assert!((value - expected).abs() <= 1e-4 * expected + 5e-6, "r = {r}, n = {n}: {value} against {expected}");
        }
        let (l, t) = (AcrossWindModel::rms_coefficient(r), TorsionModel::rms_coefficient(r));
        assert!((l - across_rms).abs() <= 6e-5, "C'_L at r = {r}: {l}");
        assert!((t - torsion_rms).abs() <= 6e-5, "C'_T at r = {r}: {t}");
    }
    // F_T at U* = 2, 4.5, 5, 6, 8, 10 (the codes' common factor cancels in the ratios).
    let torsion = [
        (1.0, [0.019715, 0.138048, 0.146526, 0.162447, 0.245286, 0.337664]),
        (2.0, [0.012041, 0.387924, 0.255452, 0.123976, 0.148734, 0.171294]),
        (3.0, [0.008665, 0.536463, 0.359838, 0.180298, 0.208214, 0.232811]),
    ];
    for (r, values) in torsion {
        let model = TorsionModel::new(r);
        for (u, expected) in
            [2.0, 5.0, 6.0, 8.0, 10.0].into_iter().zip([values[0], values[2], values[3], values[4], values[5]])
        {
            let ratio = model.law(u) / model.law(4.5);
            let expected_ratio = expected / values[1];
            assert!(
                (ratio - expected_ratio).abs() <= 2e-4 * expected_ratio,
                "r = {r}, U* = {u}: ratio {ratio} against {expected_ratio}"
            );
        }
        // The spectrum's argument is n = f·B/U_H: U* = 1/(n√r).
        let n = 1.0 / (8.0 * r.sqrt());
        assert!((model.value(n) / model.law(8.0) - 1.0).abs() < 1e-12);
    }
}

#[test]
fn the_published_model_refuses_side_ratios_it_does_not_hold_for() {
    for r in [0.1, 6.0, f64::NAN, -1.0] {
        let error = WakeLoads::published(r).unwrap_err().to_string();
        assert!(error.contains("aerodynamics.side_ratio"), "{error}");
    }
    // Wind along x on a 24.4 × 48.8 m plan (x by y) faces the depth: D/B = 0.5; along y, 2.
    let (loads, facing) = Aerodynamics::Published.at(0.0, 24.4, 48.8).unwrap();
    assert_eq!((facing, loads.across_coefficient), (48.8, AcrossWindModel::rms_coefficient(0.5)));
    let (loads, facing) = Aerodynamics::Published.at(100.0, 24.4, 48.8).unwrap();
    assert_eq!((facing, loads.across_coefficient), (24.4, AcrossWindModel::rms_coefficient(2.0)));
}

/// The peaks `scripts/wind-tunnel-example.py` wrote the example file's spectra from: (n_s, β) of the
/// across-wind and torsional spectra at 0° and at 90°.
const EXAMPLE_PEAKS: [[(f64, f64); 2]; 2] = [[(0.10, 0.25), (0.15, 0.40)], [(0.09, 0.30), (0.15, 0.40)]];

fn example() -> TunnelData {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/data/wind-tunnel-example.json"))
        .expect("the example wind-tunnel file");
    TunnelData::from_json(&text).unwrap()
}

/// The script's peak, F(n) = 4(1 + 0.6β)β/π · x²/((1 − x²)² + 4β²x²), x = n/n_s.
fn peak(n: f64, shedding: f64, beta: f64) -> f64 {
    let x2 = (n / shedding).powi(2);
    4.0 * (1.0 + 0.6 * beta) * beta / PI * x2 / ((1.0 - x2).powi(2) + 4.0 * beta * beta * x2)
}

#[test]
fn the_example_tunnel_file_holds_its_closed_form_spectra() {
    let data = example();
    assert_eq!(data.directions(), vec![0.0, 90.0]);
    for (k, direction) in [0.0, 90.0].into_iter().enumerate() {
        let loads = data.at(direction).unwrap();
        for (spectrum, (shedding, beta)) in [&loads.across, &loads.torsion].into_iter().zip(EXAMPLE_PEAKS[k]) {
            // At the table's points to its six significant figures (of n and of F: the slope of
            // F, at most 2 in ln-ln, doubles n's rounding); between them (30 a decade, log-log)
            // within 3 % on the peak's shoulders (less than a simulation's sampling error).
            for i in 0..=600 {
                let n = 10f64.powf(-3.0 + i as f64 / 150.0);
                let (value, exact) = (spectrum.value(n), peak(n, shedding, beta));
                let tolerance = if i % 5 == 0 { 2e-5 } else { 3e-2 };
                assert!(
                    (value - exact).abs() <= tolerance * exact + 1e-12,
                    "{direction}°, n = {n}: {value} against {exact}"
                );
            }
            // The table's area: the closed form's but for the power-law interpolation's shortfall
            // between points on the peak (0.5 % here) and the tails beyond n = 10⁻³ and 10 (< 10⁻⁴).
            let area = spectrum.area();
            assert!((area / peak_area(1.0, beta) - 1.0).abs() < 1e-2, "{direction}°: area {area}");
        }
    }
}

#[test]
fn tunnel_directions_are_interpolated_around_the_circle() {
    let data = example();
    let halfway = data.at(45.0).unwrap();
    assert!((halfway.across_coefficient - 0.175).abs() < 1e-12);
    // The coherence at n = 0.1: 0.3 at 0°; at 90° halfway in ln n from 0.1 (n = 0.01) to 0.4 (n = 1).
    assert!((halfway.coherence.value(0.1) - 0.5 * (0.3 + 0.25)).abs() < 1e-12);
    let n = 0.1;
    let expected = 0.5 * (data.at(0.0).unwrap().across.value(n) + data.at(90.0).unwrap().across.value(n));
    assert!((halfway.across.value(n) - expected).abs() < 1e-12 * expected);
    // 315° lies 5/6 of the way from 90° to 360°.
    let t = (315.0 - 90.0) / 270.0;
    let back = data.at(-45.0).unwrap();
    assert!((back.torsion_coefficient - ((1.0 - t) * 0.06 + t * 0.05)).abs() < 1e-12);
}

#[test]
fn a_bad_tunnel_file_is_refused_by_the_field_at_fault() {
    let valid =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/data/wind-tunnel-example.json")).unwrap();
    let mut json: serde_json::Value = serde_json::from_str(&valid).unwrap();
    let cases: [(&str, serde_json::Value, &str); 6] = [
        ("/reference_breadth_m", serde_json::json!(-3.0), "reference_breadth_m"),
        ("/directions/1/wind_direction_deg", serde_json::json!(0.0), "directions"),
        (
            "/directions/0/across_wind/rms_coefficient",
            serde_json::json!(-0.1),
            "directions[0].across_wind.rms_coefficient",
        ),
        (
            "/directions/1/torsion/reduced_frequencies/3",
            serde_json::json!(0.0),
            "directions[1].torsion.reduced_frequencies[3]",
        ),
        ("/directions/0/coherence", serde_json::json!(1.5), "directions[0].coherence"),
        ("/directions/1/wind_direction_deg", serde_json::json!(400.0), "directions[1].wind_direction_deg"),
    ];
    for (pointer, value, field) in cases {
        let original = json.pointer(pointer).unwrap().clone();
        *json.pointer_mut(pointer).unwrap() = value;
        let error = TunnelData::from_json(&json.to_string()).unwrap_err().to_string();
        assert!(error.contains(field), "{pointer}: {error}");
        *json.pointer_mut(pointer).unwrap() = original;
    }
    assert!(
        TunnelData::from_json("{\"reference_breadth_m\": 1}").unwrap_err().to_string().contains("not a wind-tunnel")
    );
    assert!(TunnelData::from_json(&json.to_string()).is_ok());
}

/// The example data at 0° on `frame40-3d`'s floors, 30 m/s at the roof.
fn example_field() -> (WakeField, Vec<f64>) {
    let building = frame40_3d([0.0, 0.0]).unwrap();
    let heights = building.floor_elevations.clone();
    let storeys: Vec<f64> = heights.iter().scan(0.0, |below, &z| Some(z - std::mem::replace(below, z))).collect();
    let loads = example().at(0.0).unwrap();
    let geometry = WakeGeometry {
        heights: &heights,
        storey_heights: &storeys,
        breadth: 24.4,
        roof_speed: 30.0,
        air_density: 1.25,
    };
    (WakeField::new(&loads, geometry).unwrap(), heights)
}

#[test]
fn the_base_loads_have_the_spectra_of_their_coefficients() {
    let (field, heights) = example_field();
    let loads = example().at(0.0).unwrap();
    let n = field.floors();
    let height = heights[n - 1];
    let q = 0.5 * 1.25 * 30.0 * 30.0;
    let (sigma_m, sigma_t) =
        (loads.across_coefficient * q * 24.4 * height * height, loads.torsion_coefficient * q * 24.4 * 24.4 * height);
    let (area_l, area_t) = (loads.across.area(), loads.torsion.area());
    for frequency in [0.02, 0.1, 0.123, 0.3, 0.7] {
        let reduced = frequency * 24.4 / 30.0;
        let moment: f64 = (0..n)
            .flat_map(|j| (0..n).map(move |k| (j, k)))
            .map(|(j, k)| heights[j] * heights[k] * field.one_sided(j, k, frequency))
            .sum();
        let expected = sigma_m * sigma_m * loads.across.value(reduced) / (area_l * frequency);
        assert!((moment / expected - 1.0).abs() < 1e-10, "base moment at {frequency} Hz: {moment} against {expected}");
        let torque: f64 = (0..n)
            .flat_map(|j| (0..n).map(move |k| (j, k)))
            .map(|(j, k)| field.one_sided(n + j, n + k, frequency))
            .sum();
        let expected = sigma_t * sigma_t * loads.torsion.value(reduced) / (area_t * frequency);
        assert!((torque / expected - 1.0).abs() < 1e-10, "base torque at {frequency} Hz: {torque} against {expected}");
    }
}

#[test]
fn the_closed_form_factor_is_the_cholesky_factor() {
    let (field, _) = example_field();
    let size = field.dim();
    let (omega0, domega, lines) = (0.3, 0.7, 4);
    let mut matrices = Vec::new();
    field.sweep(omega0, domega, lines, &mut |_, s| matrices.push(s.to_vec()));
    for m in [0, 7, 39, 40, 41, 79] {
        let mut columns = vec![f64::NAN; size * lines];
        field.factor_columns(omega0, domega, m, &mut columns);
        for (l, s) in matrices.iter().enumerate() {
            let mut factor = s.clone();
            cholesky_through_column(&mut factor, size, m);
            let scale = s.iter().fold(0.0f64, |a, b| a.max(b.abs())).sqrt();
            for j in m..size {
                let (have, want) = (columns[j * lines + l], factor[j * size + m]);
                assert!((have - want).abs() <= 1e-9 * scale, "column {m}, row {j}, line {l}: {have} against {want}");
            }
        }
    }
}

/// Band powers of two generalised forces and of their co-spectrum, simulated through the floors
/// and projected on the first y sway and the first twist of `frame40-3d`, against the integrals of
/// their target spectra. Each tolerance is four standard errors of a Gaussian process's estimate
/// over the simulated duration, √(∫ G² df / T) (for the co-spectrum, √(∫ G_yy G_θθ df / T)): the
/// spectral representation's fixed amplitudes scatter less than that.
#[test]
fn simulated_wake_loads_have_the_target_spectra_and_cross_spectrum() {
    let (field, _) = example_field();
    let n = field.floors();
    let building = frame40_3d([0.0, 0.0]).unwrap();
    let modes = SpatialModes::of(&building, 6).unwrap();
    let first = |d: usize| (0..modes.count()).find(|&m| modes.shares[m][d] > 0.99).unwrap();
    // The across-wind force of wind along x pushes along y; the torque twists.
    let weights: Vec<Vec<f64>> = [first(1), first(2)]
        .iter()
        .map(|&m| (0..n).map(|j| modes.at(m, j, Dof::Y)).chain((0..n).map(|j| modes.at(m, j, Dof::Rotation))).collect())
        .collect();
    let grid = SpectralGrid { lines: 1024, cutoff: 2.0 * PI * 0.8 };
    let (duration, storms, step) = (1200.0, 12, 0.25);
    let bands = [(0.03, 0.12), (0.12, 0.3), (0.3, 0.7)];
    // Estimates: [band][pair] with pairs yy, θθ, yθ.
    let mut estimates = [[0.0; 3]; 3];
    let mut record_length = 0.0;
    let mut workspace = TransformWorkspace::default();
    let mut planner = FftPlanner::new();
    for storm in 0..storms {
        let coarse = simulate_coarse(&field, &grid, step, duration, &mut workspace, &mut rng_from_seed(storm)).unwrap();
        let samples = coarse.series[0].len() - 1;
        let dt = coarse.step;
        record_length += samples as f64 * dt;
        let spectra: Vec<Vec<Complex<f64>>> = weights
            .iter()
            .map(|w| {
                let mut x: Vec<Complex<f64>> = (1..=samples)
                    .map(|q| Complex::new((0..2 * n).map(|c| w[c] * coarse.series[c][q]).sum(), 0.0))
                    .collect();
                planner.plan_fft_forward(samples).process(&mut x);
                x
            })
            .collect();
        for (b, &(low, high)) in bands.iter().enumerate() {
            let lines = spectra[0].iter().zip(&spectra[1]).enumerate().take(samples / 2).skip(1);
            for (k, (&y, &t)) in lines {
                let f = k as f64 / (samples as f64 * dt);
                if f < low || f >= high {
                    continue;
                }
                let scale = 2.0 / (samples as f64).powi(2);
                estimates[b][0] += scale * y.norm_sqr();
                estimates[b][1] += scale * t.norm_sqr();
                estimates[b][2] += scale * (y * t.conj()).re;
            }
        }
    }
    let storms = storms as f64;
    // Targets: Gᵀ of the two weight vectors on a fine grid, one-sided G(f) = 4π S(2πf).
    let df = 2e-4;
    for (b, &(low, high)) in bands.iter().enumerate() {
        let points = ((high - low) / df).round() as usize;
        let mut integrals = [0.0; 3];
        let mut squares = [0.0; 3];
        field.sweep(2.0 * PI * (low + 0.5 * df), 2.0 * PI * df, points, &mut |_, s| {
            let size = 2 * n;
            let g = |a: &[f64], b: &[f64]| -> f64 {
                4.0 * PI * (0..size).map(|i| a[i] * (0..size).map(|j| s[i * size + j] * b[j]).sum::<f64>()).sum::<f64>()
            };
            let (yy, tt, yt) = (g(&weights[0], &weights[0]), g(&weights[1], &weights[1]), g(&weights[0], &weights[1]));
            integrals.iter_mut().zip([yy, tt, yt]).for_each(|(i, v)| *i += v * df);
            squares.iter_mut().zip([yy * yy, tt * tt, yy * tt]).for_each(|(i, v)| *i += v * df);
        });
        for pair in 0..3 {
            let estimate = estimates[b][pair] / storms;
            let error = (squares[pair] / record_length).sqrt();
            let tolerance = 4.0 * error;
            assert!(
                (estimate - integrals[pair]).abs() <= tolerance,
                "band {low}-{high} Hz, pair {pair}: simulated {estimate:e}, target {:e} ± {tolerance:e}",
                integrals[pair]
            );
        }
        // The co-spectrum is there: the example's coherence 0.3 makes it a sizeable share.
        assert!(integrals[2] > 0.05 * (integrals[0] * integrals[1]).sqrt(), "band {low}-{high}: {integrals:?}");
    }
}
