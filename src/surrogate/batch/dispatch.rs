//! The free run as a kernel of the vector type, run on the widest vectors the processor has.

use super::BatchSample;
use super::dense::{self, DenseLinear, PairedPeaks};
use super::general::{self, TermLists};
use super::inputs::{BatchWorkspace, Prepared, lane_inputs};
use super::sink::{Divergence, Sink};
use crate::simd::Lanes;
use crate::simd::{Kernel, Vector, run_widest};

/// A batch's models compiled for the free run, and the storm they run over.
pub(super) struct Compiled {
    /// Each mode's rest state, every lane: its outputs before t = 0.
    pub rests: Vec<Lanes>,
    /// 1 / input scale per mode.
    pub inverse_scales: Vec<f64>,
    pub recursion: Recursion,
    /// The storm's steps, and their length in seconds.
    pub steps: usize,
    pub time_step: f64,
}

/// How the steps are computed.
pub(super) enum Recursion {
    /// Dense arrays with the modes and lags fixed at compile time: the paper's structures.
    Dense(DenseLinear),
    /// Term lists: any structure.
    TermLists(TermLists),
}

/// Runs the compiled batch on the widest vectors the processor has.
pub(super) fn free_run(
    compiled: &Compiled,
    samples: &[BatchSample],
    workspace: &mut BatchWorkspace,
    sink: &mut Sink,
) -> Result<(), Divergence> {
    run_widest(FreeRun { compiled, samples, workspace, sink })
}

/// The free run as a kernel of the vector type, so that it is compiled for each.
struct FreeRun<'a, 's, 'k> {
    compiled: &'a Compiled,
    samples: &'a [BatchSample<'s>],
    workspace: &'a mut BatchWorkspace,
    sink: &'a mut Sink<'k>,
}

impl Kernel for FreeRun<'_, '_, '_> {
    type Output = Result<(), Divergence>;
    #[inline(always)]
    fn run<V: Vector>(self, isa: V::Isa) -> Self::Output {
        free_run_on::<V>(isa, self.compiled, self.samples, self.workspace, self.sink)
    }
}

/// The inputs into the workspace, then the recursion, on the vectors V. Everything here inlines
/// into its caller, so that it is compiled for the caller's features; nothing may go through a
/// closure that is not (a thread-local's accessor once did, and the AVX-512 intrinsics became
/// calls: a tenfold slower free run).
#[inline(always)]
fn free_run_on<V: Vector>(
    isa: V::Isa,
    compiled: &Compiled,
    samples: &[BatchSample],
    workspace: &mut BatchWorkspace,
    sink: &mut Sink,
) -> Result<(), Divergence> {
    let (steps, time_step) = (compiled.steps, compiled.time_step);
    let schedule = lane_inputs(samples, &compiled.inverse_scales, steps, time_step, &mut workspace.inputs);
    let prepared = Prepared { rests: &compiled.rests, schedule, coarse: &workspace.inputs, steps };
    match &compiled.recursion {
        Recursion::Dense(models) => dense::run::<V>(isa, models, &prepared, sink),
        Recursion::TermLists(lists) => general::run(lists, &prepared, sink),
    }
}

/// Two batches' peaks of one combination: side by side through the dense recursion where their
/// models allow it (the free run waits on each step's power, and two batches' chains overlap),
/// else one after the other. A diverging lane is named by its place in the pair.
pub(super) fn free_run_pair(
    compiled: [&Compiled; 2],
    samples: [&[BatchSample]; 2],
    workspace: &mut BatchWorkspace,
    peaks: PairedPeaks,
) -> Result<(), Divergence> {
    run_widest(FreeRunPair { compiled, samples, workspace, peaks })
}

struct FreeRunPair<'a, 's> {
    compiled: [&'a Compiled; 2],
    samples: [&'a [BatchSample<'s>]; 2],
    workspace: &'a mut BatchWorkspace,
    peaks: PairedPeaks<'a>,
}

impl Kernel for FreeRunPair<'_, '_> {
    type Output = Result<(), Divergence>;
    #[inline(always)]
    fn run<V: Vector>(self, isa: V::Isa) -> Self::Output {
        let FreeRunPair { compiled, samples, workspace, peaks } = self;
        let (steps, time_step) = (compiled[0].steps, compiled[0].time_step);
        let BatchWorkspace { inputs, paired } = workspace;
        let schedules = [
            lane_inputs(samples[0], &compiled[0].inverse_scales, steps, time_step, inputs),
            lane_inputs(samples[1], &compiled[1].inverse_scales, steps, time_step, paired),
        ];
        let [schedule_a, schedule_b] = schedules;
        let prepared = [
            Prepared { rests: &compiled[0].rests, schedule: schedule_a, coarse: inputs, steps },
            Prepared { rests: &compiled[1].rests, schedule: schedule_b, coarse: paired, steps },
        ];
        if let (Recursion::Dense(a), Recursion::Dense(b)) = (&compiled[0].recursion, &compiled[1].recursion)
            && dense::pairable([a, b], [&prepared[0], &prepared[1]])
        {
            return dense::run_pair::<V>(isa, [a, b], [&prepared[0], &prepared[1]], peaks);
        }
        let PairedPeaks { gains, offsets, peaks: [first, second] } = peaks;
        for (g, peaks) in [first, second].into_iter().enumerate() {
            let mut sink = Sink::Peaks { gains, offsets: offsets[g], peaks };
            let outcome = match &compiled[g].recursion {
                Recursion::Dense(models) => dense::run::<V>(isa, models, &prepared[g], &mut sink),
                Recursion::TermLists(lists) => general::run(lists, &prepared[g], &mut sink),
            };
            outcome.map_err(|d| Divergence { lane: g * crate::simd::LANES + d.lane, ..d })?;
        }
        Ok(())
    }
}
