//! The exact steps of an acceleration's reduction: a step's modal damper forces, computed once per
//! block and lane and shared by every floor that looks at that step.

use super::LaneModels;
use crate::dynamics::sign_power;
use crate::linalg::dot;
use crate::simd::{LANES, Lanes};
use crate::study::MAX_MODES;

/// The modal damper forces g_m of the block's (step, lane) pairs computed exactly, shared by every
/// floor's acceleration: `modal[i·LANES + l]`, valid where `stamps` holds the block's number.
#[derive(Default)]
pub(super) struct ExactSteps {
    block: u64,
    stamps: Vec<u64>,
    modal: Vec<Modal1>,
}

/// One lane's modal values.
type Modal1 = [f64; MAX_MODES];

impl ExactSteps {
    /// A new block of `steps` steps: every entry invalid.
    pub(super) fn next_block(&mut self, steps: usize) {
        self.block += 1;
        if self.stamps.len() < steps * LANES {
            self.stamps.resize(steps * LANES, 0);
            self.modal.resize(steps * LANES, [0.0; MAX_MODES]);
        }
    }

    /// Step i's modal damper forces in lane l, computed (with `forces` as scratch) unless a floor
    /// already did.
    #[inline(always)]
    pub(super) fn modal_forces(
        &mut self,
        i: usize,
        l: usize,
        velocities: &[Lanes],
        lanes: &LaneModels,
        forces: &mut [f64],
    ) -> &[f64] {
        let modes = lanes.inverse_masses.len();
        let key = i * LANES + l;
        if self.stamps[key] != self.block {
            // Mode-major over the dampers, so that every loop runs a vector register of dampers
            // at a time (damper-major, the sums over dampers were chains of dependent additions).
            let v = &velocities[i * modes..(i + 1) * modes];
            forces.fill(0.0);
            for (column, v) in lanes.velocity_columns.iter().zip(v) {
                for (force, g) in forces.iter_mut().zip(column) {
                    *force = g.mul_add(v[l], *force);
                }
            }
            for (force, c) in forces.iter_mut().zip(&lanes.lane_coefficients[l]) {
                *force = c * sign_power(*force, lanes.exponent);
            }
            for (g, column) in self.modal[key][..modes].iter_mut().zip(&lanes.map_columns) {
                *g = dot(column, forces);
            }
            self.stamps[key] = self.block;
        }
        &self.modal[key][..modes]
    }
}
