//! The batch's inputs: every lane's scaled force deviations on one grid, lane-major, so that one
//! cubic interpolation serves all lanes, held in a [`BatchWorkspace`] the caller keeps from batch to
//! batch.

use super::BatchSample;
use crate::simd::Vector;
use crate::simd::{LANES, Lanes};
use crate::wind::{CoarseSeries, CubicSchedule};

/// The buffers a batch fills, kept by the caller and reused from batch to batch (one per worker
/// thread, e.g. through rayon's `map_init`): a batch's inputs are megabytes, and allocating them
/// afresh cost page faults.
#[derive(Default)]
pub struct BatchWorkspace {
    /// inputs[m][q][lane]: mode m's scaled input deviation at coarse point q, every lane.
    pub(super) inputs: Vec<Vec<Lanes>>,
    /// The same for the second of two batches run side by side.
    pub(super) paired: Vec<Vec<Lanes>>,
}

/// What a recursion runs on: each mode's rest state, the lane-major inputs and the schedule onto
/// them, and the storm's length.
pub(super) struct Prepared<'a> {
    /// rests[m][lane]: mode m's output before t = 0.
    pub rests: &'a [Lanes],
    /// The schedule from the storm's steps onto the points of `coarse`.
    pub schedule: CubicSchedule,
    /// coarse[m][q][lane], as in [`BatchWorkspace`].
    pub coarse: &'a [Vec<Lanes>],
    pub steps: usize,
}

/// The scaled input deviations of every lane into `inputs` (a [`BatchWorkspace`]'s): inputs[m][q][lane] the value at
/// coarse point q (at t = (q − 1)·dt_g); returns the schedule from the storm's grid onto the coarse
/// points. Samples from one generation grid are taken as they are; any others are filled on the
/// storm's grid and padded, which the same interpolation then reads exactly (one step per
/// generation step, weights 0, 1, 0, 0).
pub(super) fn lane_inputs(
    samples: &[BatchSample],
    inverse_scales: &[f64],
    steps: usize,
    time_step: f64,
    inputs: &mut Vec<Vec<Lanes>>,
) -> CubicSchedule {
    let transpose = |series: &[&[f64]], scale: f64, to: &mut Vec<Lanes>| {
        to.clear();
        to.extend((0..series[0].len()).map(|q| {
            let mut lanes = [0.0; LANES];
            for (t, x) in lanes.iter_mut().zip(series) {
                *t = x[q] * scale;
            }
            lanes
        }));
    };
    inputs.resize_with(inverse_scales.len(), Vec::new);
    let coarse: Option<Vec<&CoarseSeries>> = samples.iter().map(|s| s.forces.coarse()).collect();
    if let Some(all) =
        coarse.filter(|all| all.iter().all(|c| c.step == all[0].step && c.series[0].len() == all[0].series[0].len()))
        && let Some(step) = all.first().map(|c| c.step)
    {
        for (m, to) in inputs.iter_mut().enumerate() {
            transpose(&all.iter().map(|c| c.series[m].as_slice()).collect::<Vec<_>>(), inverse_scales[m], to);
        }
        return CubicSchedule::new(step, time_step);
    }
    for (m, to) in inputs.iter_mut().enumerate() {
        let padded: Vec<Vec<f64>> = samples
            .iter()
            .map(|sample| {
                let mut series = vec![0.0; steps + 3];
                sample.forces.fill(m, time_step, 0, &mut series[1..=steps]);
                let mean = sample.forces.mean(m);
                series[1..=steps].iter_mut().for_each(|f| *f -= mean);
                series
            })
            .collect();
        let padded: Vec<&[f64]> = padded.iter().map(Vec::as_slice).collect();
        if padded.is_empty() {
            to.clear();
            to.resize(steps + 3, [0.0; LANES]);
        } else {
            transpose(&padded, inverse_scales[m], to);
        }
    }
    CubicSchedule::new(time_step, time_step)
}

/// The scaled input of one mode at an instant: cubic convolution of the four coarse points from
/// `p` with weights `w`, every lane.
#[inline(always)]
pub(super) fn interpolate<V: Vector>(isa: V::Isa, coarse: &[Lanes], p: usize, w: &[V; 4]) -> V {
    let y = &coarse[p..p + 4];
    let first = w[0].mul(V::load(isa, &y[0]));
    w[3].mul_add(V::load(isa, &y[3]), w[2].mul_add(V::load(isa, &y[2]), w[1].mul_add(V::load(isa, &y[1]), first)))
}

/// The four interpolation weights, each in every lane.
#[inline(always)]
pub(super) fn splat_weights<V: Vector>(isa: V::Isa, w: &[f64; 4]) -> [V; 4] {
    [V::splat(isa, w[0]), V::splat(isa, w[1]), V::splat(isa, w[2]), V::splat(isa, w[3])]
}
