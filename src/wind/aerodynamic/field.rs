//! The across-wind forces and torques on every floor as one stationary Gaussian process, spread
//! from the base loads' spectra the way the codes spread them and force-balance studies assume.
//!
//! Floor j's RMS across-wind force is a·h_j·z_j/H and its RMS torque b·h_j·z_j/H (h_j the storey it
//! carries, z_j its height: the codes' floor loads, q_H C' A_z z/H, grow linearly with height), with
//! a vertical coherence γ(Δz) = exp(−k |Δz|/B) that does not depend on frequency, the same for both
//! loads and between them. a and b are set so that the base moment Σ z_j f_j and the base torque
//! Σ t_j have the RMS of their coefficients: σ_M = C'_L q_H B H², σ_T = C'_T q_H B² H. Because the
//! coherence does not depend on frequency, their spectra are then exactly the normalised spectra
//! given, whatever k is; k only shares the load among the modes.
//!
//! One-sided in hertz, G_jk(f) = σ_j σ_k γ_jk F(n)/(A f) for two floors' forces (F/A the spectrum
//! over its area, n = f·B/U_H), the same with F_T for torques, and ρ(n) σ_j σ_k γ_jk √(F_L F_T)/
//! (√(A_L A_T) f) between a force and a torque. Its lower Cholesky factor is known in closed form,
//! D(f)·(chol [[1, ρ], [ρ, 1]] ⊗ chol Γ) with D the diagonal of the square roots, so that no
//! frequency of a simulation factors a 2n × 2n matrix.

use super::WakeLoads;
use crate::error::{Error, Result};
use crate::linalg::cholesky_through_column;
use crate::wind::CrossSpectralDensity;
use std::f64::consts::PI;

/// The 2n-variate process of the floors' across-wind forces (components 0..n, N) and torques
/// (components n..2n, N·m) at one wind direction and speed.
#[derive(Debug, Clone)]
pub struct WakeField {
    loads: WakeLoads,
    /// B/U_H: n = f·B/U_H.
    frequency_scale: f64,
    /// Areas of the two normalised spectra.
    areas: [f64; 2],
    /// RMS across-wind force of each floor (N).
    pub force_rms: Vec<f64>,
    /// RMS torque of each floor (N·m).
    pub torque_rms: Vec<f64>,
    /// γ_jk, row-major n×n, and its lower Cholesky factor.
    coherence: Vec<f64>,
    coherence_factor: Vec<f64>,
}

/// What the field needs of the building and the flow.
#[derive(Debug, Clone, Copy)]
pub struct WakeGeometry<'a> {
    /// Floor heights above the ground (m), increasing.
    pub heights: &'a [f64],
    /// The storey each floor carries (m).
    pub storey_heights: &'a [f64],
    /// The breadth facing the wind, B (m).
    pub breadth: f64,
    /// The mean speed at the roof, U_H (m/s).
    pub roof_speed: f64,
    /// Air density (kg/m³).
    pub air_density: f64,
}

impl WakeField {
    /// The field of `loads` on a building of `geometry`.
    pub fn new(loads: &WakeLoads, geometry: WakeGeometry<'_>) -> Result<Self> {
        let WakeGeometry { heights, storey_heights, breadth, roof_speed, air_density } = geometry;
        let n = heights.len();
        if n == 0 || storey_heights.len() != n {
            return Err(Error::invalid("floor_elevations_m", "needs one storey height per floor"));
        }
        if !(breadth.is_finite() && breadth > 0.0 && roof_speed.is_finite() && roof_speed > 0.0) {
            return Err(Error::invalid(
                "aerodynamics",
                format!("needs a positive breadth and roof speed, got {breadth} m and {roof_speed} m/s"),
            ));
        }
        let height = heights[n - 1];
        let decay = loads.vertical_coherence_decay / breadth;
        let mut coherence = vec![0.0; n * n];
        for j in 0..n {
            for k in 0..n {
                coherence[j * n + k] = (-decay * (heights[j] - heights[k]).abs()).exp();
            }
        }
        let mut coherence_factor = coherence.clone();
        cholesky_through_column(&mut coherence_factor, n, n - 1);
        let profile: Vec<f64> = heights.iter().zip(storey_heights).map(|(z, h)| h * z / height).collect();
        let quadratic = |weights: &[f64]| -> f64 {
            (0..n)
                .flat_map(|j| (0..n).map(move |k| (j, k)))
                .map(|(j, k)| weights[j] * weights[k] * coherence[j * n + k])
                .sum()
        };
        let moment_weights: Vec<f64> = profile.iter().zip(heights).map(|(p, z)| p * z).collect();
        let q_h = 0.5 * air_density * roof_speed * roof_speed;
        let moment_rms = loads.across_coefficient * q_h * breadth * height * height;
        let torque_rms = loads.torsion_coefficient * q_h * breadth * breadth * height;
        let a = moment_rms / quadratic(&moment_weights).sqrt();
        let b = torque_rms / quadratic(&profile).sqrt();
        Ok(WakeField {
            areas: [loads.across.area(), loads.torsion.area()],
            loads: loads.clone(),
            frequency_scale: breadth / roof_speed,
            force_rms: profile.iter().map(|p| a * p).collect(),
            torque_rms: profile.iter().map(|p| b * p).collect(),
            coherence,
            coherence_factor,
        })
    }

    /// Number of floors.
    pub fn floors(&self) -> usize {
        self.force_rms.len()
    }

    /// One-sided spectral density (per Hz) at `frequency` of components a and b (a, b < 2n).
    pub fn one_sided(&self, a: usize, b: usize, frequency: f64) -> f64 {
        let n = self.floors();
        let roots = self.unit_roots(frequency);
        let (ka, ja) = (a / n, a % n);
        let (kb, jb) = (b / n, b % n);
        let rms = |kind: usize, j: usize| if kind == 0 { self.force_rms[j] } else { self.torque_rms[j] };
        let pair = if ka == kb { 1.0 } else { self.loads.coherence.value(frequency * self.frequency_scale) };
        pair * rms(ka, ja) * rms(kb, jb) * roots[ka] * roots[kb] * self.coherence[ja * n + jb]
    }

    /// √(F(n)/(A f)) of the across-wind force and of the torque: one-sided, per unit RMS.
    fn unit_roots(&self, frequency: f64) -> [f64; 2] {
        if frequency <= 0.0 {
            return [0.0; 2];
        }
        let n = frequency * self.frequency_scale;
        let spectra = [&self.loads.across, &self.loads.torsion];
        std::array::from_fn(|k| (spectra[k].value(n) / (self.areas[k] * frequency)).sqrt())
    }

    /// The two-sided density per rad/s, S(ω) = G(ω/2π)/(4π): the diagonal scale D of each
    /// component and ρ at ω.
    fn scales(&self, omega: f64, out: &mut [f64]) -> f64 {
        let n = self.floors();
        let frequency = omega.abs() / (2.0 * PI);
        let roots = self.unit_roots(frequency).map(|r| r / (4.0 * PI).sqrt());
        for j in 0..n {
            out[j] = self.force_rms[j] * roots[0];
            out[n + j] = self.torque_rms[j] * roots[1];
        }
        self.loads.coherence.value(frequency * self.frequency_scale)
    }
}

impl CrossSpectralDensity for WakeField {
    fn dim(&self) -> usize {
        2 * self.floors()
    }

    fn sweep(&self, omega0: f64, domega: f64, count: usize, visit: &mut dyn FnMut(usize, &[f64])) {
        let n = self.floors();
        let size = 2 * n;
        let mut scale = vec![0.0; size];
        let mut s = vec![0.0; size * size];
        for l in 0..count {
            let rho = self.scales(omega0 + l as f64 * domega, &mut scale);
            for a in 0..size {
                for b in 0..size {
                    let pair = if (a < n) == (b < n) { 1.0 } else { rho };
                    s[a * size + b] = pair * scale[a] * scale[b] * self.coherence[(a % n) * n + b % n];
                }
            }
            visit(l, &s);
        }
    }

    /// Column m of D(ω)·(chol C ⊗ chol Γ): for a force column (m < n) the forces' rows hold
    /// D·L_Γ and the torques' ρ·D·L_Γ; for a torque column only the torques' rows, √(1 − ρ²)·D·L_Γ.
    fn factor_columns(&self, omega0: f64, domega: f64, m: usize, columns: &mut [f64]) {
        let n = self.floors();
        let size = 2 * n;
        let lines = columns.len() / size;
        let column = m % n;
        let mut scale = vec![0.0; size];
        for l in 0..lines {
            let rho = self.scales(omega0 + l as f64 * domega, &mut scale);
            // A force column reaches every torque row, zero above its own floor.
            let first = if m < n { 0 } else { column };
            for j in first..n {
                let lower = if j >= column { self.coherence_factor[j * n + column] } else { 0.0 };
                if m < n {
                    if j >= column {
                        columns[j * lines + l] = scale[j] * lower;
                    }
                    columns[(n + j) * lines + l] = rho * scale[n + j] * lower;
                } else {
                    columns[(n + j) * lines + l] = (1.0 - rho * rho).max(0.0).sqrt() * scale[n + j] * lower;
                }
            }
        }
    }
}
