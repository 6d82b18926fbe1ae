//! The reduced-order reference: the retained modal equations (Eq. 3, damper force subtracted),
//! M_m ÿ_m + 2M_m ζ ω_m ẏ_m + M_m ω_m² y_m = Q_m(t) − φ_mᵀ Bᵀ F(B Φ ẏ).
//!
//! Each mode is advanced exactly for a load that is linear within the step (the exponential
//! integrator of Wilson's fast nonlinear analysis): x_{i+1} = E x_i + (Γ₀ − Γ₁) p_i + Γ₁ p_{i+1},
//! with E, Γ₀, Γ₁ from one 4×4 matrix exponential (Van Loan). The damper forces at the new step
//! depend on the new velocities, which are affine in them, so each step ends in the implicit solve
//! of [`super::damper`].

use super::damper::{Dampers, ImplicitDamperSolve};
use super::motion::ModalMotion;
use crate::error::{Error, Result};
use crate::progress::{CHECK_EVERY_STEPS, Observer, check};
use crate::structure::Modes;
use crate::wind::ModalForces;

/// Modal displacement histories y_m(t), one series per retained mode (roof-normalised shapes, so
/// Σ_m y_m is the roof displacement), and the integrator's velocities ẏ_m(t).
#[derive(Debug, Clone)]
pub struct ModalResponse {
    /// Modal displacements y_m (m), `[mode][step]`.
    pub displacements: Vec<Vec<f64>>,
    /// Modal velocities ẏ_m (m/s), `[mode][step]`.
    pub velocities: Vec<Vec<f64>>,
}

impl ModalResponse {
    /// Roof displacement history: the shapes' roof components are 1.
    pub fn roof(&self) -> Vec<f64> {
        let steps = self.displacements.first().map_or(0, Vec::len);
        (0..steps).map(|i| self.displacements.iter().map(|y| y[i]).sum()).collect()
    }

    /// The motion, as the floor accelerations and damper forces are computed from it.
    pub fn motion(self) -> ModalMotion {
        ModalMotion { displacements: self.displacements, velocities: self.velocities }
    }
}

/// Step coefficients of one mode: state transition E and load integrals Γ₀, Γ₁ (2-vectors).
#[derive(Debug, Clone, Copy)]
pub(super) struct StepCoefficients {
    pub(super) e: [[f64; 2]; 2],
    pub(super) gamma0: [f64; 2],
    pub(super) gamma1: [f64; 2],
}

impl StepCoefficients {
    pub(super) fn new(omega: f64, zeta: f64, dt: f64) -> Self {
        let mut z = [[0.0; 4]; 4];
        z[0][1] = dt;
        z[1][0] = -omega * omega * dt;
        z[1][1] = -2.0 * zeta * omega * dt;
        z[1][2] = dt;
        z[2][3] = 1.0;
        let x = expm4(z);
        StepCoefficients {
            e: [[x[0][0], x[0][1]], [x[1][0], x[1][1]]],
            gamma0: [x[0][2], x[1][2]],
            gamma1: [x[0][3], x[1][3]],
        }
    }
}

/// exp(A) of a 4×4 matrix by scaling and squaring of a Taylor series, accurate to rounding for
/// the well-scaled matrices built here.
fn expm4(a: [[f64; 4]; 4]) -> [[f64; 4]; 4] {
    let norm = (0..4).map(|j| (0..4).map(|i| a[i][j].abs()).sum::<f64>()).fold(0.0, f64::max);
    let squarings = if norm > 0.5 { (norm / 0.5).log2().ceil() as i32 } else { 0 };
    let scale = 0.5f64.powi(squarings);
    let mul = |x: &[[f64; 4]; 4], y: &[[f64; 4]; 4]| {
        let mut r = [[0.0; 4]; 4];
        for i in 0..4 {
            for j in 0..4 {
                r[i][j] = (0..4).map(|k| x[i][k] * y[k][j]).sum();
            }
        }
        r
    };
    let scaled = a.map(|row| row.map(|v| v * scale));
    let mut result = [[0.0; 4]; 4];
    let mut term = [[0.0; 4]; 4];
    for i in 0..4 {
        result[i][i] = 1.0;
        term[i][i] = 1.0;
    }
    for k in 1..=20 {
        term = mul(&term, &scaled).map(|row| row.map(|v| v / k as f64));
        for i in 0..4 {
            for j in 0..4 {
                result[i][j] += term[i][j];
            }
        }
    }
    for _ in 0..squarings {
        result = mul(&result, &result);
    }
    result
}

/// Integrates the reduced model from the static equilibrium under the mean load.
///
/// `modes` are the sample's modes (frequencies and generalized masses already scaled), `forces`
/// its modal forces on the storm's grid of step `time_step`.
pub fn integrate_reduced(
    modes: &Modes,
    damping_ratio: f64,
    dampers: &Dampers,
    forces: &ModalForces,
    time_step: f64,
    observer: &dyn Observer,
) -> Result<ModalResponse> {
    let count = modes.count();
    if forces.series.len() != count {
        return Err(Error::invalid("forces", format!("{} modal series for {count} modes", forces.series.len())));
    }
    let steps = forces.series[0].len();
    let coefficients: Vec<StepCoefficients> =
        modes.frequencies.iter().map(|&w| StepCoefficients::new(w, damping_ratio, time_step)).collect();
    let masses = &modes.modal_masses;
    let map = dampers.modal_map(modes.shapes.as_ref());
    let active = dampers.coefficients.iter().any(|&c| c > 0.0);
    let w_inverse: Vec<f64> = (0..count * count)
        .map(|k| if k % (count + 1) == 0 { masses[k / count] / coefficients[k / count].gamma1[1] } else { 0.0 })
        .collect();
    let mut solver = ImplicitDamperSolve::new(w_inverse, map, dampers);

    let mut y: Vec<f64> = (0..count).map(|m| forces.mean[m] / (masses[m] * modes.frequencies[m].powi(2))).collect();
    let mut v = vec![0.0; count];
    let mut load: Vec<f64> = (0..count).map(|m| forces.series[m][0] / masses[m]).collect();
    let mut displacements: Vec<Vec<f64>> = (0..count)
        .map(|m| {
            let mut series = Vec::with_capacity(steps);
            series.push(y[m]);
            series
        })
        .collect();
    let mut velocities: Vec<Vec<f64>> = (0..count)
        .map(|_| {
            let mut series = Vec::with_capacity(steps);
            series.push(0.0);
            series
        })
        .collect();
    let mut known = vec![[0.0; 2]; count];
    let mut a = vec![0.0; count];
    let mut s = vec![0.0; count];
    let mut damper_forces = vec![0.0; dampers.len()];
    let mut modal_damper_force = vec![0.0; count];

    for i in 1..steps {
        if i % CHECK_EVERY_STEPS == 0 {
            check(observer)?;
        }
        for m in 0..count {
            let c = &coefficients[m];
            let next = forces.series[m][i] / masses[m];
            known[m] = std::array::from_fn(|r| {
                c.e[r][0] * y[m] + c.e[r][1] * v[m] + (c.gamma0[r] - c.gamma1[r]) * load[m] + c.gamma1[r] * next
            });
            a[m] = known[m][1];
            // Predictor: the previous step's damper forces.
            s[m] = a[m] - c.gamma1[1] * modal_damper_force[m] / masses[m];
        }
        if active {
            solver.solve(&a, &mut s, &mut damper_forces)?;
            solver.generalized_forces(&damper_forces, &mut modal_damper_force);
        }
        for m in 0..count {
            let c = &coefficients[m];
            let g = modal_damper_force[m] / masses[m];
            y[m] = known[m][0] - c.gamma1[0] * g;
            v[m] = known[m][1] - c.gamma1[1] * g;
            load[m] = forces.series[m][i] / masses[m] - g;
            if !y[m].is_finite() {
                return Err(Error::Numerical(format!("the reduced model diverged at step {i}")));
            }
            displacements[m].push(y[m]);
            velocities[m].push(v[m]);
        }
    }
    Ok(ModalResponse { displacements, velocities })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matrix_exponential_of_a_rotation_generator() {
        // exp([[0, θ], [−θ, 0]]) is a rotation by θ.
        let theta = 3.7;
        let mut a = [[0.0; 4]; 4];
        a[0][1] = theta;
        a[1][0] = -theta;
        let e = expm4(a);
        assert!((e[0][0] - theta.cos()).abs() < 1e-14);
        assert!((e[0][1] - theta.sin()).abs() < 1e-14);
        assert!((e[2][2] - 1.0).abs() < 1e-15);
    }
}
