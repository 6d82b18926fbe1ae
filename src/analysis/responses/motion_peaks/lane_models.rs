//! The reduced models of a batch's samples as the acceleration sink reads them, every lane at once.

use crate::error::Result;
use crate::simd::{LANES, Lanes};
use crate::study::Study;
use crate::surrogate::ModalScales;

/// The reduced models of a batch's samples, lane-major, with the blocks' scales folded in: the
/// sink works on the scaled outputs ŷ_m and inputs q̂_m as the free run gives them, and on the
/// scaled velocities ŷ'_m (y'_m = s_m ŷ'_m), so that nothing is converted step by step.
pub(super) struct LaneModels {
    /// 1/M_m (for h_d), r_m/M_m, 2ζω_m s_m and ω_m² s_m per mode, every lane (s_m, r_m: the
    /// output and input scales).
    pub(super) inverse_masses: Vec<Lanes>,
    pub(super) load_gains: Vec<Lanes>,
    pub(super) damping: Vec<Lanes>,
    pub(super) stiffness: Vec<Lanes>,
    /// Per damper its coefficient c_d in every lane, G_dm per mode and G_dm s_m, the damper's
    /// velocity per scaled modal velocity (the same in every lane: the shapes are fixed across
    /// samples).
    pub(super) coefficients: Vec<Lanes>,
    pub(super) map: Vec<Vec<f64>>,
    pub(super) velocity_map: Vec<Vec<f64>>,
    /// The same laid out for the exact steps' loops over the dampers, which then run in vector
    /// registers: G_dm s_m and G_dm mode-major (`[m][d]`), c_d lane-major (`[l][d]`).
    pub(super) velocity_columns: Vec<Vec<f64>>,
    pub(super) map_columns: Vec<Vec<f64>>,
    pub(super) lane_coefficients: Vec<Vec<f64>>,
    pub(super) exponent: f64,
}

impl LaneModels {
    pub(super) fn new(study: &Study, inputs: &[&[f64]], scales: &ModalScales) -> Result<Self> {
        let modes = study.modes.count();
        let mut lanes = LaneModels {
            inverse_masses: vec![[0.0; LANES]; modes],
            load_gains: vec![[0.0; LANES]; modes],
            damping: vec![[0.0; LANES]; modes],
            stiffness: vec![[0.0; LANES]; modes],
            coefficients: Vec::new(),
            map: Vec::new(),
            velocity_map: Vec::new(),
            velocity_columns: Vec::new(),
            map_columns: Vec::new(),
            lane_coefficients: Vec::new(),
            exponent: study.damper_exponent,
        };
        for (lane, x) in inputs.iter().enumerate() {
            let p = study.parameters(x)?;
            let (modes, dampers) = (study.sample_modes(&p), study.dampers(&p)?);
            for m in 0..modes.count() {
                let omega = modes.frequencies[m];
                lanes.inverse_masses[m][lane] = 1.0 / modes.modal_masses[m];
                lanes.load_gains[m][lane] = scales.inputs[m] / modes.modal_masses[m];
                lanes.damping[m][lane] = 2.0 * p.damping_ratio * omega * scales.outputs[m];
                lanes.stiffness[m][lane] = omega * omega * scales.outputs[m];
            }
            if lane == 0 {
                lanes.map = dampers
                    .modal_map(modes.shapes.as_ref())
                    .iter()
                    .map(|row| row.iter().map(|g| g.1).collect())
                    .collect();
                lanes.coefficients = vec![[0.0; LANES]; dampers.coefficients.len()];
                lanes.velocity_map =
                    lanes.map.iter().map(|g| g.iter().zip(&scales.outputs).map(|(g, s)| g * s).collect()).collect();
            }
            for (to, &c) in lanes.coefficients.iter_mut().zip(&dampers.coefficients) {
                to[lane] = c;
            }
        }
        let columns = |rows: &[Vec<f64>]| -> Vec<Vec<f64>> {
            (0..modes).map(|m| rows.iter().map(|row| row[m]).collect()).collect()
        };
        lanes.velocity_columns = columns(&lanes.velocity_map);
        lanes.map_columns = columns(&lanes.map);
        lanes.lane_coefficients = (0..LANES).map(|l| lanes.coefficients.iter().map(|c| c[l]).collect()).collect();
        Ok(lanes)
    }
}
