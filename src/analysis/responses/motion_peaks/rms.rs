//! An RMS acceleration's reduction: the squared acceleration of every sampled step, summed per lane.

use super::exact::ExactSteps;
use super::{LaneModels, Steps};
use crate::simd::Lanes;

/// Adds to `squares` the squared acceleration a = L − N of the block's steps `first`,
/// `first + stride`, … in every lane, the modal damper forces of each (step, lane) computed once
/// and shared with the peaks' floors; returns how many steps it added.
#[inline(always)]
pub(super) fn sum_squared_accelerations(
    lanes: &LaneModels,
    steps: &Steps,
    (shape, modal): (&[f64], &[Lanes]),
    (first, stride): (usize, usize),
    squares: &mut Lanes,
    (forces, exact): (&mut [f64], &mut ExactSteps),
) -> usize {
    let Steps { velocities, linear, modes, .. } = *steps;
    let sampled = (first..velocities.len() / modes).step_by(stride);
    let count = sampled.len();
    for i in sampled {
        for (l, square) in squares.iter_mut().enumerate() {
            let x: f64 = (0..modes).map(|m| shape[m] * linear[i * modes + m][l]).sum();
            let g = exact.modal_forces(i, l, velocities, lanes, forces);
            let a = x - modal.iter().zip(g).map(|(modal, g)| modal[l] * g).sum::<f64>();
            *square = a.mul_add(a, *square);
        }
    }
    count
}
