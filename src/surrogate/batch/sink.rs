//! What a batch produces (its [`Sink`]) and how a diverging lane is named.

use super::Lanes;
use crate::surrogate::narx::{DIVERGENCE_BOUND, diverged};

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
    Peaks { gains: &'a [f64], offsets: Lanes, peaks: &'a mut Lanes },
}

/// Where a lane's run left the range a sane model can produce.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Divergence {
    pub lane: usize,
    pub mode: usize,
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
