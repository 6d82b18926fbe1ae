//! The full-order reference: every floor's equation (Eq. 1) with classical modal damping,
//! M ü + C u̇ + K u + Bᵀ F(B u̇) = f(t), by Newmark's constant average acceleration.
//!
//! In the new velocities s the step reads A s = r − Bᵀ F(B s) with A = 2M/Δt + C + ΔtK/2, so it ends
//! in the same implicit damper solve as the reduced model with W = A⁻¹. A different discretisation
//! from the modal exponential integrator, so the two check each other.

use super::damper::{Dampers, ImplicitDamperSolve};
use crate::error::{Error, Result};
use crate::linalg::{cholesky, cholesky_solve, multiply_into};
use crate::progress::{CHECK_EVERY_STEPS, Observer, check};
use crate::structure::{Modes, Structure};
use crate::wind::FloorForces;
use faer::Mat;

/// The motion of every floor, `[floor][step]`: displacements (m), and Newmark's own velocities
/// (m/s) and accelerations (m/s²), which satisfy the equations of motion at every step; no
/// history is differenced.
#[derive(Debug, Clone)]
pub struct FloorResponse {
    /// Floor displacements (m).
    pub displacements: Vec<Vec<f64>>,
    /// Floor velocities (m/s).
    pub velocities: Vec<Vec<f64>>,
    /// Floor accelerations (m/s²).
    pub accelerations: Vec<Vec<f64>>,
}

/// M, C and K of one sample, row-major.
#[derive(Debug, Clone)]
pub struct FullSystem {
    /// Degrees of freedom n: one per floor of a plane frame, three of a three-dimensional building.
    pub size: usize,
    /// Mass matrix M (kg), n×n.
    pub mass: Vec<f64>,
    /// Damping matrix C (N·s/m), n×n.
    pub damping: Vec<f64>,
    /// Stiffness matrix K (N/m), n×n.
    pub stiffness: Vec<f64>,
}

impl FullSystem {
    /// K = κ K₀, M = μ M₀ and the classical damping C = M Φ diag(2ζω_n/M_n) Φᵀ M over all modes,
    /// which gives every mode the ratio ζ. `all_modes` are the nominal structure's N modes.
    pub fn new(
        structure: &Structure,
        all_modes: &Modes,
        stiffness_factor: f64,
        mass_factor: f64,
        damping_ratio: f64,
    ) -> Self {
        Self::from_matrices(
            &structure.mass,
            &structure.stiffness,
            all_modes,
            stiffness_factor,
            mass_factor,
            damping_ratio,
        )
    }

    /// The same from the nominal mass and stiffness matrices over any degrees of freedom (a
    /// plane frame's floors, a three-dimensional building's sway and twist) and their N modes.
    pub fn from_matrices(
        nominal_mass: &Mat<f64>,
        nominal_stiffness: &Mat<f64>,
        all_modes: &Modes,
        stiffness_factor: f64,
        mass_factor: f64,
        damping_ratio: f64,
    ) -> Self {
        let n = nominal_mass.nrows();
        let modes = all_modes.scaled(stiffness_factor, mass_factor);
        let mass: Vec<f64> = (0..n * n).map(|k| mass_factor * nominal_mass[(k / n, k % n)]).collect();
        let stiffness: Vec<f64> = (0..n * n).map(|k| stiffness_factor * nominal_stiffness[(k / n, k % n)]).collect();
        // M φ_r for every mode r, then C = Σ_r (2ζω_r/M_r) (Mφ_r)(Mφ_r)ᵀ.
        let mut damping = vec![0.0; n * n];
        for r in 0..modes.count() {
            let m_phi: Vec<f64> =
                (0..n).map(|i| (0..n).map(|k| mass[i * n + k] * modes.shapes[(k, r)]).sum()).collect();
            let weight = 2.0 * damping_ratio * modes.frequencies[r] / modes.modal_masses[r];
            for i in 0..n {
                for j in 0..n {
                    damping[i * n + j] += weight * m_phi[i] * m_phi[j];
                }
            }
        }
        FullSystem { size: n, mass, damping, stiffness }
    }
}

/// Integrates the full-order model from the static equilibrium under the mean load.
pub fn integrate_full(
    system: &FullSystem,
    dampers: &Dampers,
    forces: &FloorForces,
    time_step: f64,
    observer: &dyn Observer,
) -> Result<FloorResponse> {
    let n = system.size;
    let dt = time_step;
    if forces.series.len() != n {
        return Err(Error::invalid("forces", format!("{} floor series for {n} floors", forces.series.len())));
    }
    let steps = forces.series[0].len();
    let mut a_eff: Vec<f64> =
        (0..n * n).map(|k| 2.0 / dt * system.mass[k] + system.damping[k] + 0.5 * dt * system.stiffness[k]).collect();
    let mut solver = ImplicitDamperSolve::new(a_eff.clone(), dampers.floor_weights.clone(), dampers);
    if !cholesky(&mut a_eff, n) {
        return Err(Error::Numerical("the Newmark iteration matrix is not positive definite".into()));
    }
    let mut k_factor = system.stiffness.clone();
    let mut m_factor = system.mass.clone();
    if !cholesky(&mut k_factor, n) || !cholesky(&mut m_factor, n) {
        return Err(Error::Numerical("stiffness or mass lost positive definiteness".into()));
    }
    // Static equilibrium under the mean load, at rest; the initial acceleration balances the rest.
    let mut u = forces.mean.clone();
    cholesky_solve(&k_factor, n, &mut u);
    let mut v = vec![0.0; n];
    let mut acc: Vec<f64> = (0..n).map(|j| forces.series[j][0] - forces.mean[j]).collect();
    cholesky_solve(&m_factor, n, &mut acc);

    let active = dampers.coefficients.iter().any(|&c| c > 0.0);
    let histories = |start: &[f64]| -> Vec<Vec<f64>> {
        start
            .iter()
            .map(|&x| {
                let mut series = Vec::with_capacity(steps);
                series.push(x);
                series
            })
            .collect()
    };
    let (mut displacements, mut velocities, mut accelerations) = (histories(&u), histories(&v), histories(&acc));
    let (mut rhs, mut work, mut predicted) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let mut s = vec![0.0; n];
    let mut correction = vec![0.0; n];
    let mut damper_forces = vec![0.0; dampers.len()];
    for i in 1..steps {
        if i % CHECK_EVERY_STEPS == 0 {
            check(observer)?;
        }
        // r = f_{i+1} + M(2u̇/Δt + ü) − K(u + Δt u̇/2).
        for j in 0..n {
            work[j] = 2.0 / dt * v[j] + acc[j];
        }
        multiply_into(&mut rhs, &system.mass, &work);
        for j in 0..n {
            work[j] = u[j] + 0.5 * dt * v[j];
        }
        multiply_into(&mut predicted, &system.stiffness, &work);
        for j in 0..n {
            rhs[j] += forces.series[j][i] - predicted[j];
        }
        cholesky_solve(&a_eff, n, &mut rhs);
        let a = &rhs;
        if active {
            // Predictor: the previous step's damper correction a − s.
            for j in 0..n {
                s[j] = a[j] - correction[j];
            }
            solver.solve(a, &mut s, &mut damper_forces)?;
            for j in 0..n {
                correction[j] = a[j] - s[j];
            }
        } else {
            s.copy_from_slice(a);
        }
        for j in 0..n {
            let new_acc = 2.0 / dt * (s[j] - v[j]) - acc[j];
            u[j] += 0.5 * dt * (v[j] + s[j]);
            v[j] = s[j];
            acc[j] = new_acc;
            if !u[j].is_finite() {
                return Err(Error::Numerical(format!("the full-order model diverged at step {i}")));
            }
            displacements[j].push(u[j]);
            velocities[j].push(v[j]);
            accelerations[j].push(acc[j]);
        }
    }
    Ok(FloorResponse { displacements, velocities, accelerations })
}
