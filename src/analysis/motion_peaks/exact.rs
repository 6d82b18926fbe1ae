//! The exact steps of an acceleration's reduction: a step's modal damper forces, computed once per
//! block and lane and shared by every floor that looks at that step.

use super::LaneModels;
use crate::dynamics::sign_power;
use crate::problem::MAX_MODES;
use crate::surrogate::{LANES, Lanes};

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
            let v = &velocities[i * modes..(i + 1) * modes];
            for (force, g) in forces.iter_mut().zip(&lanes.velocity_map) {
                *force = g.iter().zip(v).map(|(g, v)| g * v[l]).sum();
            }
            for force in forces.iter_mut() {
                *force = sign_power(*force, lanes.exponent);
            }
            for (m, g) in self.modal[key][..modes].iter_mut().enumerate() {
                *g = forces.iter().zip(&lanes.map).zip(&lanes.coefficients).map(|((f, g), c)| g[m] * c[l] * f).sum();
            }
            self.stamps[key] = self.block;
        }
        &self.modal[key][..modes]
    }
}
