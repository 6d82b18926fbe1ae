//! Where a batch's outputs go. The free run hands its blocks of scaled outputs to a [`Sink`]:
//! every block to a consumer, or the peaks of a fixed combination formed inside its vector code. A
//! peak request says which by its [`Reduction`]: a [`Combination`](Reduction::Combination) of the
//! modal displacements, or the [`Motion`](Reduction::Motion), whose blocks go to a [`MotionSink`]
//! that a [`SinkFactory`] builds for each batch (the accelerations and damper forces of
//! `analysis::responses::motion_peaks`). Also here: how a diverging lane is named.

use crate::error::Result;
use crate::simd::Lanes;
use crate::surrogate::narx::{DIVERGENCE_BOUND, diverged};
use crate::wind::ForceSource;

/// Steps per block: the granularity of the divergence test and of [`Sink::Blocks`].
pub(super) const BLOCK: usize = 512;

/// `consume(first, outputs, inputs)` of [`Sink::Blocks`].
pub type BlockConsumer<'a> = dyn FnMut(usize, &[Lanes], &[Lanes]) + 'a;

/// What a batch produces from its scaled outputs ŷ.
pub enum Sink<'a> {
    /// Every block to `consume(first, outputs, inputs)`, `outputs[i·modes + m]` being mode m's
    /// scaled output at step first + i and `inputs[i·modes + m]` the scaled input deviation it
    /// read there, one value per lane.
    Blocks(&'a mut BlockConsumer<'a>),
    /// Per lane the peak over the storm of |offset + Σ_m gain_m ŷ_m| (a response u = Σ_m w_m y_m
    /// with y_m = level_m + scale_m ŷ_m: gain_m = w_m scale_m, offset = Σ_m w_m level_m), formed
    /// inside the batch's own vectorised code.
    Peaks {
        /// gain_m = w_m scale_m of each mode.
        gains: &'a [f64],
        /// Per lane, offset = Σ_m w_m level_m.
        offsets: Lanes,
        /// Per lane, the running peak, raised in place.
        peaks: &'a mut Lanes,
    },
}

/// One sample of a batch: its number in the request, its physical inputs, its forces.
pub type BatchInput<'a> = (usize, &'a [f64], &'a dyn ForceSource);

/// How a batch's runs become one peak per lane.
pub enum Reduction<'a> {
    /// Peak |Σ_m w_m y_m(t)| of a fixed combination of the modal displacements (displacement,
    /// drift, stroke), formed inside the free run's vectorised code.
    Combination(&'a [f64]),
    /// Responses of the motion and the loads (any, accelerations and damper forces included), by
    /// a sink built for the batch: lane i's physical inputs at i, and the scales of its blocks.
    Motion(&'a SinkFactory<'a>),
}

/// Builds a batch's [`MotionSink`] from its lanes' physical inputs and its blocks' scales.
pub type SinkFactory<'a> = dyn Fn(&[&[f64]], &ModalScales) -> Result<Box<dyn MotionSink>> + Sync + 'a;

/// The scales of the free run's blocks, per mode: the output ŷ_m is
/// (y_m − `levels[m]`)/`outputs[m]` and the input q̂_m is (Q_m − Q̄_m)/`inputs[m]`, `levels[m]`
/// the static level of every lane.
#[derive(Debug, Clone)]
pub struct ModalScales {
    /// Output scale of each mode (m).
    pub outputs: Vec<f64>,
    /// Input scale of each mode (N).
    pub inputs: Vec<f64>,
    /// Static level of each mode (m), per lane.
    pub levels: Vec<Lanes>,
}

/// What a batch's modal motion is reduced to, block by block: one peak per lane.
pub trait MotionSink {
    /// Steps `first..` of a block, every lane: `outputs[i·M + m]` the scaled output ŷ_m at step
    /// first + i and `inputs[i·M + m]` the scaled input q̂_m it read (see [`ModalScales`]).
    fn take(&mut self, first: usize, outputs: &[Lanes], inputs: &[Lanes]);
    /// Per response, every lane's peak, once the storm is over.
    fn finish(&mut self) -> Vec<Lanes>;
}

/// Where a lane's run left the range a sane model can produce.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Divergence {
    /// The lane within the batch.
    pub lane: usize,
    /// The mode, 0-based.
    pub mode: usize,
    /// The time step at which the output left the bound.
    pub step: usize,
}

/// The earliest (step, mode, lane) of a block of outputs from step `first` whose output left the
/// bound (a NaN counts as out).
pub(super) fn first_divergence(block: &[Lanes], modes: usize, first: usize) -> Option<Divergence> {
    // A branch-free pass over the block first; the search only where it failed.
    let mut sane = true;
    for lanes in block {
        for v in lanes {
            sane &= v.abs() <= DIVERGENCE_BOUND;
        }
    }
    if sane {
        return None;
    }
    block.iter().enumerate().find_map(|(k, lanes)| {
        lanes.iter().position(|&v| diverged(v)).map(|lane| Divergence {
            lane,
            mode: k % modes,
            step: first + k / modes,
        })
    })
}
