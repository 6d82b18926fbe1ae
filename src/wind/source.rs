//! Where a sample's modal forces come from: a history on the storm's own grid, or the wind's
//! coarse generation grid interpolated on demand. The metamodel's free run reads either through
//! [`ForceSource`].

use super::{CoarseModalForces, CoarseSeries, ModalForces};

/// The modal forces of one storm, however they are held.
pub trait ForceSource: Sync {
    /// Mean generalized force of mode m (N).
    fn mean(&self, m: usize) -> f64;
    /// Mode m's force (N) at steps first, first + 1, … of the storm, into `out`.
    fn fill(&self, m: usize, time_step: f64, first: usize, out: &mut [f64]);
    /// The fluctuations on the wind's generation grid, where the forces come from one.
    fn coarse(&self) -> Option<&CoarseSeries> {
        None
    }
}

impl ForceSource for ModalForces {
    fn mean(&self, m: usize) -> f64 {
        self.mean[m]
    }
    fn fill(&self, m: usize, _: f64, first: usize, out: &mut [f64]) {
        out.copy_from_slice(&self.series[m][first..first + out.len()]);
    }
}

impl ForceSource for CoarseModalForces {
    fn mean(&self, m: usize) -> f64 {
        self.mean[m]
    }
    fn fill(&self, m: usize, time_step: f64, first: usize, out: &mut [f64]) {
        CoarseModalForces::fill(self, m, time_step, first, out);
    }
    fn coarse(&self) -> Option<&CoarseSeries> {
        Some(&self.fluctuations)
    }
}
