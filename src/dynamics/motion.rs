//! Responses that need the equations of motion of the reduced model: floor accelerations and damper
//! forces, from a sample's modal displacements and velocities.
//!
//! A metamodel predicts modal displacements only. Differentiating them twice would amplify the
//! NARX's small high-frequency errors by ω²; instead the accelerations come from the modal
//! equations themselves,
//! ÿ_m = (Q_m(t) − Q̄_m − g_m(t))/M_m − 2ζω_m ẏ_m − ω_m² (y_m − y_m(0)),
//! with g_m = Σ_d G_dm F_d(G_d ẏ) the modal damper force (written about the static state at rest
//! under the mean load, where the reduced model starts, so a small error in the predicted static
//! level does not become a constant acceleration). Only the velocities are differentiated, once,
//! by central differences: at Δt = 0.01 s their error on the third mode is (ωΔt)²/6 ≈ 10⁻³. The
//! reference integrator's own velocities go through the same equations, so both models' responses
//! are computed alike.

use super::damper::Dampers;
use super::power::sign_power;
use crate::structure::Modes;
use crate::wind::ModalForces;

/// Modal displacements and velocities, `[mode][step]`.
#[derive(Debug, Clone)]
pub struct ModalMotion {
    /// Modal displacements y_m (m).
    pub displacements: Vec<Vec<f64>>,
    /// Modal velocities ẏ_m (m/s).
    pub velocities: Vec<Vec<f64>>,
}

impl ModalMotion {
    /// The velocities of displacement histories by central differences (one-sided at the ends).
    pub fn from_displacements(displacements: Vec<Vec<f64>>, time_step: f64) -> ModalMotion {
        let velocities = displacements
            .iter()
            .map(|y| {
                let n = y.len();
                (0..n)
                    .map(|t| match (t, n) {
                        (_, 0 | 1) => 0.0,
                        (0, _) => (y[1] - y[0]) / time_step,
                        (t, n) if t == n - 1 => (y[t] - y[t - 1]) / time_step,
                        (t, _) => (y[t + 1] - y[t - 1]) / (2.0 * time_step),
                    })
                    .collect()
            })
            .collect();
        ModalMotion { displacements, velocities }
    }

    fn steps(&self) -> usize {
        self.displacements.first().map_or(0, Vec::len)
    }
}

/// One sample's reduced model: its modes (frequencies and masses scaled), damping and dampers.
pub struct SampleModel<'a> {
    modes: &'a Modes,
    damping_ratio: f64,
    dampers: &'a Dampers,
    /// Per damper, (mode, G_dm): damper velocity Σ_m G_dm ẏ_m, modal force Σ_d G_dm F_d.
    map: Vec<Vec<(usize, f64)>>,
}

impl<'a> SampleModel<'a> {
    /// The reduced model of a sample: its scaled modes, its damping ratio and its dampers.
    pub fn new(modes: &'a Modes, damping_ratio: f64, dampers: &'a Dampers) -> Self {
        let map = dampers.modal_map(modes.shapes.as_ref());
        SampleModel { modes, damping_ratio, dampers, map }
    }

    /// Number of dampers.
    pub fn dampers(&self) -> usize {
        self.map.len()
    }

    /// Axial velocity history of damper `d`.
    fn damper_velocity(&self, d: usize, motion: &ModalMotion) -> impl Iterator<Item = f64> {
        (0..motion.steps()).map(move |t| self.map[d].iter().map(|&(m, g)| g * motion.velocities[m][t]).sum())
    }

    /// Axial force history of damper `d` (N).
    pub fn damper_force(&self, d: usize, motion: &ModalMotion) -> Vec<f64> {
        self.damper_velocity(d, motion).map(|v| self.dampers.force(d, v)).collect()
    }

    /// Peak |axial force| of damper `d` (N): the law is monotonic in |v|, so c·max|v|^α.
    pub fn damper_force_peak(&self, d: usize, motion: &ModalMotion) -> f64 {
        let fastest = self.damper_velocity(d, motion).fold(0.0, |m: f64, v| m.max(v.abs()));
        self.dampers.force(d, fastest).abs()
    }

    /// Modal accelerations ÿ_m(t) from the equations of motion (see the module's notes).
    pub fn modal_accelerations(&self, motion: &ModalMotion, forces: &ModalForces) -> Vec<Vec<f64>> {
        let modes = self.modes.count();
        let steps = motion.steps();
        let mut damper_modal = vec![vec![0.0; steps]; modes];
        // Damper by damper over the whole history, in loops over arrays: velocity, force by the
        // law (with [`power`], twice as fast as `powf` here), its share of every modal force.
        let mut velocity = vec![0.0; steps];
        let alpha = self.dampers.exponent;
        for (d, &c) in self.dampers.coefficients.iter().enumerate() {
            if c == 0.0 {
                continue;
            }
            velocity.iter_mut().for_each(|v| *v = 0.0);
            for &(m, g) in &self.map[d] {
                velocity.iter_mut().zip(&motion.velocities[m]).for_each(|(v, y)| *v += g * y);
            }
            velocity.iter_mut().for_each(|v| *v = c * sign_power(*v, alpha));
            for &(m, g) in &self.map[d] {
                damper_modal[m].iter_mut().zip(&velocity).for_each(|(total, f)| *total += g * f);
            }
        }
        (0..modes)
            .map(|m| {
                let (omega, mass) = (self.modes.frequencies[m], self.modes.modal_masses[m]);
                let (y, v, q) = (&motion.displacements[m], &motion.velocities[m], &forces.series[m]);
                let rest = y.first().copied().unwrap_or(0.0);
                (0..steps)
                    .map(|t| {
                        (q[t] - forces.mean[m] - damper_modal[m][t]) / mass
                            - 2.0 * self.damping_ratio * omega * v[t]
                            - omega * omega * (y[t] - rest)
                    })
                    .collect()
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Central differences of sin(ωt) are ω·cos(ωt)·sin(ωΔt)/(ωΔt) inside the record.
    #[test]
    fn velocities_by_central_differences() {
        let (omega, dt) = (7.0, 0.01);
        let y = vec![(0..1000).map(|t| (omega * t as f64 * dt).sin()).collect::<Vec<f64>>()];
        let motion = ModalMotion::from_displacements(y, dt);
        let factor = (omega * dt).sin() / (omega * dt);
        for t in 1..999 {
            let exact = omega * (omega * t as f64 * dt).cos() * factor;
            assert!((motion.velocities[0][t] - exact).abs() < 1e-9, "t = {t}");
        }
    }
}
