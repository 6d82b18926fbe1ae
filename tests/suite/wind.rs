//! The simulated wind against its targets, and the two modal-force paths against each other.
//!
//! Tolerances: where a full period of the simulation is available, Deodatis' scheme is ergodic and
//! the check is deterministic up to the discretisation of the spectrum (1 %). Elsewhere estimates
//! come from several fixed-seed 900 s storms; each band's estimate must lie within four standard
//! errors (computed from the storms themselves) of its target, and the standard error itself must be
//! small enough (≤ 5 %) that the comparison has power.

use crate::harness::spectra::{band_mean, mean_and_standard_error, welch_cross};
use windmeta::study::Study;
use windmeta::uncertainty::rng_from_seed;
use windmeta::wind::{CrossSpectralDensity, FieldSpectrum, ProjectedSpectrum, SpectralGrid, StormGrid, simulate};

const SPEED: f64 = 30.0;
const STORMS: u64 = 12;
const BANDS: [(f64, f64); 4] = [(0.25, 0.75), (0.75, 1.5), (1.5, 3.0), (3.0, 5.5)];

fn study() -> Study {
    Study::preset("frame40").unwrap()
}

fn grid(p: &Study) -> SpectralGrid {
    SpectralGrid { lines: p.wind.site.frequencies, cutoff: p.wind.site.cutoff_rad_s }
}

/// 2∫₀^{ω_up} S_Q,mm dω by the midpoint rule on a grid 100× finer than the simulation's.
fn modal_variance_targets(p: &Study, projection: &ProjectedSpectrum) -> Vec<f64> {
    let modes = projection.dim();
    let points = 100 * p.wind.site.frequencies;
    let h = p.wind.site.cutoff_rad_s / points as f64;
    let mut sums = vec![0.0; modes];
    projection.sweep(0.5 * h, h, points, &mut |_, s| {
        for m in 0..modes {
            sums[m] += 2.0 * s[m * modes + m] * h;
        }
    });
    sums
}

fn projection<'a>(p: &Study, field: &'a FieldSpectrum) -> ProjectedSpectrum<'a> {
    let mean_forces_gain: Vec<f64> = p.wind.exposure.iter().zip(&field.mean_speeds).map(|(e, v)| 2.0 * e * v).collect();
    let shapes = &p.modes.shapes;
    ProjectedSpectrum {
        field,
        projection: faer::Mat::from_fn(shapes.ncols(), shapes.nrows(), |m, j| shapes[(j, m)] * mean_forces_gain[j]),
    }
}

/// The discretised target of Deodatis' scheme: Σ_{m′≤m} Σ_l 2 H_mm′(ω_m′l)² Δω, with H the
/// Cholesky factor of S_Q (by faer, independently of the simulation's own factorisation).
fn modal_variance_discrete(p: &Study, projection: &ProjectedSpectrum) -> Vec<f64> {
    let modes = projection.dim();
    let g = grid(p);
    let dw = g.step();
    let mut sums = vec![0.0; modes];
    for column in 0..modes {
        let omega0 = (column + 1) as f64 * dw / modes as f64;
        projection.sweep(omega0, dw, g.lines, &mut |_, s| {
            let matrix = faer::Mat::from_fn(modes, modes, |i, j| s[i.max(j) * modes + i.min(j)]);
            let l = matrix.llt(faer::Side::Lower).unwrap();
            for (m, sum) in sums.iter_mut().enumerate().skip(column) {
                *sum += 2.0 * l.L()[(m, column)].powi(2) * dw;
            }
        });
    }
    sums
}

/// Over its full period T̂ = 2π·3/Δω = 6144 s Deodatis' scheme is ergodic: the fast path's sample
/// variance of each modal force equals the discretised target for any seed, to rounding plus the
/// spectral table's interpolation error (< 10⁻⁷, src/wind/modal.rs). That
/// target differs from the continuous 2∫S_Q dω by the scheme's offset Riemann sum, about
/// Δω/(6ω_c) ≈ 1 % for a spectral width ω_c ≈ 0.06 rad/s; 2 % bounds it.
#[test]
fn fast_path_variance_over_its_period_matches_the_target() {
    let p = study();
    let dt = 0.1;
    let period = grid(&p).period(3);
    let storm = StormGrid::new(period - dt, dt, &p.wind.site).unwrap();
    let forces = p.modal_wind.forces(SPEED, &storm, &mut rng_from_seed(5)).unwrap();
    let field = p.wind.spectrum(SPEED);
    let projected = projection(&p, &field);
    let discrete = modal_variance_discrete(&p, &projected);
    let continuous = modal_variance_targets(&p, &projected);
    for m in 0..3 {
        let q = &forces.series[m];
        let var = q.iter().map(|x| (x - forces.mean[m]).powi(2)).sum::<f64>() / q.len() as f64;
        assert!((var / discrete[m] - 1.0).abs() < 1e-7, "mode {}: {var:e} vs discrete {:e}", m + 1, discrete[m]);
        assert!((var / continuous[m] - 1.0).abs() < 0.02, "mode {}: {var:e} vs continuous {:e}", m + 1, continuous[m]);
    }
}

/// Floor speeds of the full field: PSD (Eq. 19) and co-coherence (Eq. 22) against the targets.
#[test]
fn full_field_spectra_and_coherence_match_the_targets() {
    let p = study();
    let dt = p.wind.site.field_generation_step_s;
    let storm = StormGrid::new(900.0, dt, &p.wind.site).unwrap();
    let field = p.wind.spectrum(SPEED);
    let realizations: Vec<Vec<Vec<f64>>> = (0..STORMS)
        .map(|seed| simulate(&field, &grid(&p), dt, &storm, &mut rng_from_seed(100 + seed)).unwrap())
        .collect();
    for floor in [9, 39] {
        for (lo, hi) in BANDS {
            let ratios: Vec<f64> = realizations
                .iter()
                .map(|v| {
                    let est: Vec<(f64, f64)> =
                        welch_cross(&v[floor], &v[floor], dt, 1024).into_iter().map(|(w, s)| (w, s.re)).collect();
                    let target: Vec<(f64, f64)> = est.iter().map(|&(w, _)| (w, field.psd(floor, w))).collect();
                    band_mean(&est, lo, hi) / band_mean(&target, lo, hi)
                })
                .collect();
            let (mean, se) = mean_and_standard_error(&ratios);
            assert!(se < 0.05, "floor {} band [{lo}, {hi}): standard error {se}", floor + 1);
            assert!((mean - 1.0).abs() < 4.0 * se, "floor {} band [{lo}, {hi}): PSD ratio {mean} ± {se}", floor + 1);
        }
    }
    for (j, k) in [(9, 10), (9, 14)] {
        for (lo, hi) in BANDS {
            let differences: Vec<f64> = realizations
                .iter()
                .map(|v| {
                    let sjk = welch_cross(&v[j], &v[k], dt, 1024);
                    let sjj = welch_cross(&v[j], &v[j], dt, 1024);
                    let skk = welch_cross(&v[k], &v[k], dt, 1024);
                    let coherence: Vec<(f64, f64)> =
                        (0..sjk.len()).map(|i| (sjk[i].0, sjk[i].1.re / (sjj[i].1.re * skk[i].1.re).sqrt())).collect();
                    let target: Vec<(f64, f64)> =
                        coherence.iter().map(|&(w, _)| (w, field.coherence(j, k, w))).collect();
                    band_mean(&coherence, lo, hi) - band_mean(&target, lo, hi)
                })
                .collect();
            let (mean, se) = mean_and_standard_error(&differences);
            assert!(se < 0.05, "floors {}-{} band [{lo}, {hi}): standard error {se}", j + 1, k + 1);
            assert!(
                mean.abs() < 4.0 * se.max(0.005),
                "floors {}-{} band [{lo}, {hi}): coherence off by {mean} ± {se}",
                j + 1,
                k + 1
            );
        }
    }
}

/// Modal forces projected from the full field and simulated directly: the same variances (against
/// the quadrature target) and the same spectra, on the production grid (Δt = 0.01 s), where the
/// field is generated every 0.1 s and interpolated while the fast path is generated directly.
#[test]
fn modal_fast_path_equals_the_projected_field_in_law() {
    let p = study();
    let dt = 0.01;
    let storm = StormGrid::new(900.0, dt, &p.wind.site).unwrap();
    let shapes = p.modes.shapes.as_ref();
    let projected: Vec<_> = (0..STORMS)
        .map(|seed| p.wind.floor_forces(SPEED, &storm, &mut rng_from_seed(200 + seed)).unwrap().project(shapes))
        .collect();
    let direct: Vec<_> =
        (0..STORMS).map(|seed| p.modal_wind.forces(SPEED, &storm, &mut rng_from_seed(300 + seed)).unwrap()).collect();
    let field = p.wind.spectrum(SPEED);
    let targets = modal_variance_targets(&p, &projection(&p, &field));
    for (m, target) in targets.iter().enumerate() {
        let variances = |runs: &[windmeta::wind::ModalForces]| -> Vec<f64> {
            runs.iter()
                .map(|f| {
                    f.series[m].iter().map(|x| (x - f.mean[m]).powi(2)).sum::<f64>() / f.series[m].len() as f64 / target
                })
                .collect()
        };
        let (field_mean, field_se) = mean_and_standard_error(&variances(&projected));
        let (fast_mean, fast_se) = mean_and_standard_error(&variances(&direct));
        for (name, mean, se) in [("field", field_mean, field_se), ("fast", fast_mean, fast_se)] {
            assert!((mean - 1.0).abs() < 4.0 * se.max(0.01), "mode {} {name}: variance ratio {mean} ± {se}", m + 1);
        }
        let joint = (field_se.powi(2) + fast_se.powi(2)).sqrt();
        assert!((field_mean - fast_mean).abs() < 4.0 * joint.max(0.01), "mode {}: {field_mean} vs {fast_mean}", m + 1);
        // Both paths use the exact mean modal force.
        assert!((projected[0].mean[m] / direct[0].mean[m] - 1.0).abs() < 1e-12);
        for (lo, hi) in BANDS {
            let band = |runs: &[windmeta::wind::ModalForces]| -> Vec<f64> {
                runs.iter()
                    .map(|f| {
                        let est: Vec<(f64, f64)> = welch_cross(&f.series[m], &f.series[m], dt, 10240)
                            .into_iter()
                            .map(|(w, s)| (w, s.re))
                            .collect();
                        band_mean(&est, lo, hi)
                    })
                    .collect()
            };
            let (a, sa) = mean_and_standard_error(&band(&projected));
            let (b, sb) = mean_and_standard_error(&band(&direct));
            let joint = (sa.powi(2) + sb.powi(2)).sqrt();
            assert!(joint < 0.08 * b, "mode {} band [{lo}, {hi}): too noisy ({joint} of {b})", m + 1);
            assert!(
                (a - b).abs() < 4.0 * joint,
                "mode {} band [{lo}, {hi}): field {a:e} vs fast {b:e} (± {joint:e})",
                m + 1
            );
        }
    }
}
