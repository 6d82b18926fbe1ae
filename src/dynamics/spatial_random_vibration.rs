//! With linear dampers (exponent 1) the three-dimensional reduced reference is a linear system, and
//! its responses follow in closed form from the loads' spectrum: the modal equations
//! M ÿ + (C + Gᵀ c G) ẏ + K y = Q have the transfer function H(ω) = (K − ω²M + iω(C + Gᵀ c G))⁻¹,
//! a response r = aᵀ y the spectrum S_r = (Hᵀa)ᵀ S_Q conj(Hᵀa), its RMS √λ₀ (λ_k the spectral
//! moments ∫ω^k S_r) and its expected largest excursion over T seconds p·√λ₀ by the standard peak
//! factor of random vibration, p = √(2 ln ν_e T) + 0.5772/√(2 ln ν_e T) (Davenport 1964) with the
//! rate of independent excursions of either sign ν_e = ν·(1.63 δ^0.45 − 0.38) for a narrow band
//! δ < 0.69 and ν otherwise, ν = √(λ₂/λ₀)/π, δ = √(1 − λ₁²/(λ₀λ₂)) (Der Kiureghian 1980: a resonant
//! response's excursions come in clumps, which Davenport's Poisson count takes for independent).
//! The time-domain reference, driven by storms of that spectrum (drag, across-wind force and
//! torque, from the example wind-tunnel data at 30° to x), must agree: RMS within 3 %, mean peaks
//! within 5 %.
//!
//! The tolerances hold the sampling error too: the drag's slow quasi-static sway makes a storm's
//! variance scatter by about 20 % (its loads' integral time scale of some 20 s over 800 s), so 160
//! storms leave about 0.8 % on an RMS; at Δt = 0.05 s (a tenth of the fastest retained period) the
//! exponential integrator stays exact for the loads' linear interpolation and the central
//! differences of the accelerations err by (ωΔt)²/6 < 0.1 % on the modes that carry them.

use super::*;
use crate::progress::Silent;
use crate::structure::Modes;
use crate::structure::spatial::{Dof, SpatialModes, corner_acceleration, dof, frame40_3d, plan_arms, plan_direction};
use crate::uncertainty::rng_from_seed;
use crate::wind::aerodynamic::{Aerodynamics, TunnelData};
use crate::wind::{
    CrossSpectralDensity, DirectionalWind, ModalForces, Projected, ProjectedSpectrum, SpectralGrid, StormGrid,
    TransformWorkspace, WindSite, simulate_coarse,
};
use faer::Mat;
use std::cell::RefCell;
use std::collections::HashMap;
use std::f64::consts::PI;

const DIRECTION_DEG: f64 = 30.0;
const STATION_SPEED: f64 = 30.0;
const DAMPING_RATIO: f64 = 0.02;
/// The dampers add this damping ratio to the first mode.
const ADDED_DAMPING: f64 = 0.03;
const MODES: usize = 6;
const TIME_STEP: f64 = 0.05;
const DURATION: f64 = 900.0;
/// The start of each storm left out: the model starts at rest under the mean load.
const TRANSIENT: f64 = 100.0;
const STORMS: u64 = 160;

/// Columns by (column, ω₀, Δω, buffer length).
type KeptColumns = HashMap<(usize, u64, u64, usize), Vec<f64>>;

/// A spectrum's Cholesky columns kept from the first storm for the next: every storm of the test
/// simulates the same spectrum on the same frequencies, and forming the wake's projected spectrum
/// (80 floor loads onto 6 modes) at each of them is most of a storm's cost otherwise.
struct Kept<'a> {
    spectrum: &'a dyn CrossSpectralDensity,
    columns: RefCell<KeptColumns>,
}

impl CrossSpectralDensity for Kept<'_> {
    fn dim(&self) -> usize {
        self.spectrum.dim()
    }

    fn sweep(&self, omega0: f64, domega: f64, count: usize, visit: &mut dyn FnMut(usize, &[f64])) {
        self.spectrum.sweep(omega0, domega, count, visit);
    }

    fn factor_columns(&self, omega0: f64, domega: f64, m: usize, columns: &mut [f64]) {
        let key = (m, omega0.to_bits(), domega.to_bits(), columns.len());
        let mut kept = self.columns.borrow_mut();
        let stored = kept.entry(key).or_insert_with(|| {
            let mut fresh = columns.to_vec();
            self.spectrum.factor_columns(omega0, domega, m, &mut fresh);
            fresh
        });
        columns.copy_from_slice(stored);
    }
}

/// The modal loads' two independent parts, as cross-spectral densities of the modal forces.
struct ModalLoads<'a> {
    drag: ProjectedSpectrum<'a>,
    wake: Projected<'a>,
    mean: Vec<f64>,
}

/// Response weights over the modes: roof x, roof y, roof twist (rad), then each corner's x and y.
fn response_weights(modes: &Modes, corners: &[[f64; 2]; 4]) -> Vec<Vec<f64>> {
    let roof = 39;
    let at = |d: Dof, m: usize| modes.shapes[(dof(roof, d), m)];
    let count = modes.count();
    let mut weights: Vec<Vec<f64>> =
        [Dof::X, Dof::Y, Dof::Rotation].iter().map(|&d| (0..count).map(|m| at(d, m)).collect()).collect();
    for p in corners {
        weights.push((0..count).map(|m| at(Dof::X, m) - p[1] * at(Dof::Rotation, m)).collect());
        weights.push((0..count).map(|m| at(Dof::Y, m) + p[0] * at(Dof::Rotation, m)).collect());
    }
    weights
}

/// Solves the real 2p × 2p form of (A + iB) b = a (A, B real) by Gaussian elimination with partial
/// pivoting; returns (Re b, Im b).
fn solve_complex(a_matrix: &Mat<f64>, b_matrix: &Mat<f64>, rhs: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let p = rhs.len();
    let n = 2 * p;
    let mut m = vec![vec![0.0; n + 1]; n];
    for i in 0..p {
        for j in 0..p {
            m[i][j] = a_matrix[(i, j)];
            m[i][p + j] = -b_matrix[(i, j)];
            m[p + i][j] = b_matrix[(i, j)];
            m[p + i][p + j] = a_matrix[(i, j)];
        }
        m[i][n] = rhs[i];
    }
    for k in 0..n {
        let pivot = (k..n).max_by(|&x, &y| m[x][k].abs().total_cmp(&m[y][k].abs())).unwrap();
        m.swap(k, pivot);
        let (above, below) = m.split_at_mut(k + 1);
        let pivot_row = &above[k];
        for row in below {
            let factor = row[k] / pivot_row[k];
            row[k..].iter_mut().zip(&pivot_row[k..]).for_each(|(x, p)| *x -= factor * p);
        }
    }
    let mut x = vec![0.0; n];
    for i in (0..n).rev() {
        x[i] = (m[i][n] - (i + 1..n).map(|j| m[i][j] * x[j]).sum::<f64>()) / m[i][i];
    }
    (x[..p].to_vec(), x[p..].to_vec())
}

#[test]
fn linear_three_dimensional_responses_agree_with_random_vibration() {
    let building = frame40_3d([0.0, 0.0]).unwrap();
    let site = WindSite::default();
    let text =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/data/wind-tunnel-example.json")).unwrap();
    let aerodynamics = Aerodynamics::Tunnel(TunnelData::from_json(&text).unwrap());
    let wind = DirectionalWind::new(&site, &building, Some(aerodynamics)).unwrap();
    let modes = SpatialModes::of(&building, MODES).unwrap().modes();
    let (n, count) = (building.floors(), modes.count());

    // Linear dampers adding ADDED_DAMPING to the first mode.
    let unit = Dampers::spatial(&building, &[1.0; 4], 1.0).unwrap();
    let unit_map = unit.modal_map(modes.shapes.as_ref());
    let gram = |a: usize, b: usize| -> f64 { unit_map.iter().map(|row| row[a].1 * row[b].1).sum::<f64>() };
    let coefficient = ADDED_DAMPING * 2.0 * modes.frequencies[0] * modes.modal_masses[0] / gram(0, 0);
    let dampers = Dampers::spatial(&building, &[coefficient; 4], 1.0).unwrap();

    // The modal loads: the drag's speed field and the wake's forces and torques, projected.
    let [cos, sin] = plan_direction(DIRECTION_DEG);
    let drag = wind.drag(DIRECTION_DEG).unwrap();
    let speeds = drag.spectrum(STATION_SPEED);
    let wake = wind.wake(STATION_SPEED, DIRECTION_DEG).unwrap().unwrap();
    let phi = |m: usize, j: usize, d: Dof| modes.shapes[(dof(j, d), m)];
    let on_floor = |m: usize, j: usize, arms: [f64; 3]| {
        arms[0] * phi(m, j, Dof::X) + arms[1] * phi(m, j, Dof::Y) + arms[2] * phi(m, j, Dof::Rotation)
    };
    let centres = &building.centres_of_mass;
    let drag_projection = Mat::from_fn(count, n, |m, j| {
        on_floor(m, j, plan_arms([cos, sin], centres[j])) * 2.0 * drag.exposure[j] * speeds.mean_speeds[j]
    });
    let wake_projection = Mat::from_fn(count, 2 * n, |m, c| {
        if c < n { on_floor(m, c, plan_arms([-sin, cos], centres[c])) } else { phi(m, c - n, Dof::Rotation) }
    });
    let floor_means = drag.mean_forces(STATION_SPEED);
    let mean: Vec<f64> = (0..count)
        .map(|m| (0..n).map(|j| on_floor(m, j, plan_arms([cos, sin], centres[j])) * floor_means[j]).sum())
        .collect();
    let loads = ModalLoads {
        drag: ProjectedSpectrum { field: &speeds, projection: drag_projection },
        wake: Projected { process: &wake, projection: wake_projection },
        mean,
    };

    let plan = building.plans[39];
    let weights = response_weights(&modes, &plan.corners());

    // Frequency domain, on a grid fine enough for the 5 % damped peaks (Δω ≪ ζω₁ ≈ 0.05 rad/s).
    let domega = 5e-4;
    let cutoff = site.cutoff_rad_s;
    let lines = (cutoff / domega) as usize;
    let mut s_q = vec![vec![0.0; count * count]; lines];
    let mut add = |l: usize, s: &[f64]| s_q[l].iter_mut().zip(s).for_each(|(t, v)| *t += v);
    loads.drag.sweep(0.5 * domega, domega, lines, &mut add);
    loads.wake.sweep(0.5 * domega, domega, lines, &mut add);
    let damper_gram = Mat::from_fn(count, count, |a, b| coefficient * gram(a, b));
    // λ₀ … λ₆ of each response's displacement spectrum (two-sided sums); the acceleration's
    // λ_k are the displacement's λ_{k+4}.
    let mut moments = vec![[0.0; 7]; weights.len()];
    for (l, s) in s_q.iter().enumerate() {
        let omega = (l as f64 + 0.5) * domega;
        let stiffness = Mat::from_fn(count, count, |a, b| {
            if a == b { modes.modal_masses[a] * (modes.frequencies[a].powi(2) - omega * omega) } else { 0.0 }
        });
        let damping = Mat::from_fn(count, count, |a, b| {
            omega
                * (damper_gram[(a, b)]
                    + if a == b { 2.0 * DAMPING_RATIO * modes.frequencies[a] * modes.modal_masses[a] } else { 0.0 })
        });
        for (r, a) in weights.iter().enumerate() {
            let (re, im) = solve_complex(&stiffness, &damping, a);
            let quadratic = |x: &[f64]| -> f64 {
                (0..count).map(|i| x[i] * (0..count).map(|j| s[i * count + j] * x[j]).sum::<f64>()).sum()
            };
            let s_r = quadratic(&re) + quadratic(&im);
            for (k, moment) in moments[r].iter_mut().enumerate() {
                *moment += 2.0 * omega.powi(k as i32) * s_r * domega;
            }
        }
    }
    let record = DURATION - TRANSIENT;
    // The mean largest |r| over the record from λ₀, λ₁, λ₂.
    let peak_factor = |[l0, l1, l2]: [f64; 3]| {
        let rate = (l2 / l0).sqrt() / PI;
        let delta = (1.0 - l1 * l1 / (l0 * l2)).max(0.0).sqrt();
        let independent = if delta < 0.69 { rate * (1.63 * delta.powf(0.45) - 0.38) } else { rate };
        let root = (2.0 * (independent * record).ln()).sqrt();
        root + 0.5772 / root
    };

    // Time domain: the reduced reference over STORMS storms.
    let grid = SpectralGrid { lines: site.frequencies, cutoff: site.cutoff_rad_s };
    let storm = StormGrid { duration: DURATION, time_step: TIME_STEP };
    let statics: Vec<f64> = weights
        .iter()
        .map(|a| {
            (0..count).map(|m| a[m] * loads.mean[m] / (modes.modal_masses[m] * modes.frequencies[m].powi(2))).sum()
        })
        .collect();
    let mut workspace = TransformWorkspace::default();
    let first = (TRANSIENT / TIME_STEP) as usize;
    let drag_kept = Kept { spectrum: &loads.drag, columns: RefCell::default() };
    let wake_kept = Kept { spectrum: &loads.wake, columns: RefCell::default() };
    // Per roof response: Σ of the mean squares and of the peaks of the displacement and the
    // acceleration; Σ of the worst corner's mean square resultant acceleration.
    let mut sums = [[0.0; 4]; 3];
    let mut corner_square = 0.0;
    for k in 0..STORMS {
        let rng = &mut rng_from_seed(1000 + k);
        let drag_part = simulate_coarse(&drag_kept, &grid, site.field_generation_step_s, DURATION, &mut workspace, rng)
            .unwrap()
            .on_grid(&storm);
        let wake_part = simulate_coarse(&wake_kept, &grid, site.field_generation_step_s, DURATION, &mut workspace, rng)
            .unwrap()
            .on_grid(&storm);
        let series: Vec<Vec<f64>> = (0..count)
            .map(|m| drag_part[m].iter().zip(&wake_part[m]).map(|(a, b)| loads.mean[m] + a + b).collect())
            .collect();
        let forces = ModalForces { mean: loads.mean.clone(), series };
        let run = integrate_reduced(&modes, DAMPING_RATIO, &dampers, &forces, TIME_STEP, &Silent).unwrap();
        let motion = run.motion();
        let accelerations = SampleModel::new(&modes, DAMPING_RATIO, &dampers).modal_accelerations(&motion, &forces);
        let history = |a: &[f64], histories: &[Vec<f64>]| -> Vec<f64> {
            (first..storm.steps()).map(|t| (0..count).map(|m| a[m] * histories[m][t]).sum()).collect()
        };
        let mut roof_accelerations = Vec::new();
        for (r, sum) in sums.iter_mut().enumerate() {
            let displacement: Vec<f64> =
                history(&weights[r], &motion.displacements).iter().map(|x| x - statics[r]).collect();
            let acceleration = history(&weights[r], &accelerations);
            let mean_square = |x: &[f64]| x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64;
            let peak = |x: &[f64]| x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            sum[0] += mean_square(&displacement);
            sum[1] += peak(&displacement);
            sum[2] += mean_square(&acceleration);
            sum[3] += peak(&acceleration);
            roof_accelerations.push(acceleration);
        }
        let corner = corner_acceleration(
            &plan,
            building.centres_of_mass[39],
            &roof_accelerations[0],
            &roof_accelerations[1],
            &roof_accelerations[2],
            1,
        );
        corner_square += corner.rms * corner.rms;
    }
    let storms = STORMS as f64;
    for (r, name) in ["roof x", "roof y", "roof twist"].iter().enumerate() {
        let l = moments[r];
        let simulated =
            [(sums[r][0] / storms).sqrt(), sums[r][1] / storms, (sums[r][2] / storms).sqrt(), sums[r][3] / storms];
        let expected = [
            l[0].sqrt(),
            peak_factor([l[0], l[1], l[2]]) * l[0].sqrt(),
            l[4].sqrt(),
            peak_factor([l[4], l[5], l[6]]) * l[4].sqrt(),
        ];
        eprintln!("{name}: simulated {simulated:?}, random vibration {expected:?}");
        for (q, (what, tolerance)) in [
            ("displacement RMS", 0.03),
            ("displacement peak", 0.05),
            ("acceleration RMS", 0.03),
            ("acceleration peak", 0.05),
        ]
        .into_iter()
        .enumerate()
        {
            let error = simulated[q] / expected[q] - 1.0;
            assert!(
                error.abs() <= tolerance,
                "{name} {what}: {:.4e} against {:.4e} ({:+.2} %)",
                simulated[q],
                expected[q],
                100.0 * error
            );
        }
    }
    // The worst corner's resultant acceleration: RMS √(σ_x² + σ_y²) of the worst corner.
    let corner_rms = (corner_square / storms).sqrt();
    let expected = (0..4).map(|k| (moments[3 + 2 * k][4] + moments[4 + 2 * k][4]).sqrt()).fold(0.0, f64::max);
    eprintln!("worst corner: simulated RMS {corner_rms:e}, random vibration {expected:e}");
    assert!((corner_rms / expected - 1.0).abs() <= 0.03, "corner resultant RMS {corner_rms:e} against {expected:e}");
    // The torsion is there: the corner's RMS exceeds the centre's.
    let centre = (moments[0][4] + moments[1][4]).sqrt();
    assert!(expected > 1.05 * centre, "corner {expected:e}, centre {centre:e}");
}
