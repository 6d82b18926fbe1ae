//! The metamodel's free run (Eq. 10, every mode jointly) for several samples at once.
//!
//! [`LANES`] samples advance through the recursion together: every arithmetic operation is applied
//! to all lanes of a `[f64; LANES]`, which the compiler turns into SIMD instructions (AVX2 or
//! AVX-512 where the processor has them, chosen at run time). The models' terms are the same for
//! every sample, only the coefficients differ, so the lanes never diverge in control flow. Each
//! step interpolates the modes' forces for all lanes at once from lane-major copies of the wind's
//! generation grid, then sums each mode's terms. Structures made only of the constant and lagged
//! inputs and outputs to the first power (what the paper's selection finds) run as dense
//! coefficient arrays with the modes and lags fixed at compile time, in one loop that interpolates,
//! recurses, reduces the outputs (a [`Sink`]) and accumulates the divergence test, with the state in
//! registers; any other structure runs from term lists, a block of [`BLOCK`] steps at a time.
//!
//! Every product that is summed is a fused multiply-add (`f64::mul_add`: one rounding, the same on
//! every processor; the SIMD versions are only chosen where the processor has FMA) and no operation
//! mixes lanes, so a lane's result does not depend on the instruction set or on which samples share
//! its batch.

pub use super::lanes::{LANES, Lanes};
use super::narx::{DIVERGENCE_BOUND, NarxTerm, diverged, rest_output};
use super::simd::{self, Vector};
use crate::error::{Error, Result};
use crate::wind::{CoarseModalForces, CoarseSeries, CubicSchedule, ModalForces};
use std::cell::RefCell;

/// Steps per block: the granularity of the divergence test and of [`Sink::Blocks`].
const BLOCK: usize = 512;

/// Where a sample's modal forces come from.
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

/// One mode's model as the batch runs it: the terms, and how its series are scaled.
#[derive(Debug, Clone, Copy)]
pub struct ModeProgram<'a> {
    pub terms: &'a [NarxTerm],
    /// The NARX reads (Q − Q̄)/input_scale.
    pub input_scale: f64,
}

/// One sample of a batch: its coefficients and forces.
pub struct BatchSample<'a> {
    /// theta[m]: the NARX coefficients of mode m, in the order of its terms.
    pub theta: Vec<Vec<f64>>,
    pub forces: &'a dyn ForceSource,
}

/// Where a lane's run left the range a sane model can produce.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Divergence {
    pub lane: usize,
    pub mode: usize,
    pub step: usize,
}

/// The joint rest state of the modes under zero input deviation, by Gauss-Seidel on the modes'
/// fixed points (the coupling is weak).
pub fn joint_rest(models: &[(&[NarxTerm], &[f64])]) -> Result<Vec<f64>> {
    let mut rests = vec![0.0; models.len()];
    for _ in 0..50 {
        let before = rests.clone();
        for (m, (terms, theta)) in models.iter().enumerate() {
            rests[m] = rest_output(terms, theta, 0.0, &rests, rests[m])?;
        }
        if rests.iter().zip(&before).all(|(a, b)| (a - b).abs() <= 1e-15 * a.abs().max(1e-300)) {
            break;
        }
    }
    Ok(rests)
}

/// What a batch produces from its scaled outputs ŷ.
pub enum Sink<'a> {
    /// Every block to `consume(first, outputs)`, `outputs[i·modes + m]` being mode m at step
    /// first + i, one value per lane.
    Blocks(&'a mut dyn FnMut(usize, &[Lanes])),
    /// Per lane the peak over the storm of |offset + Σ_m gain_m ŷ_m| (a response u = Σ_m w_m y_m
    /// with y_m = level_m + scale_m ŷ_m: gain_m = w_m scale_m, offset = Σ_m w_m level_m), formed
    /// inside the batch's own vectorised code.
    Peaks { gains: &'a [f64], offsets: Lanes, peaks: &'a mut Lanes },
}

/// Runs up to [`LANES`] samples over `steps` steps of `time_step` into `sink`. Lanes beyond
/// `samples.len()` run a zero model. Fails on a lane's divergence, naming it.
pub fn run(
    programs: &[ModeProgram],
    samples: &[BatchSample],
    steps: usize,
    time_step: f64,
    sink: &mut Sink,
) -> std::result::Result<(), BatchError> {
    assert!(samples.len() <= LANES, "at most {LANES} samples per batch");
    let modes = programs.len();
    let mut rests = vec![[0.0; LANES]; modes];
    for (lane, sample) in samples.iter().enumerate() {
        let models: Vec<(&[NarxTerm], &[f64])> =
            programs.iter().zip(&sample.theta).map(|(p, t)| (p.terms, &t[..])).collect();
        let rest = joint_rest(&models).map_err(|e| BatchError::Model { lane, error: e })?;
        for m in 0..modes {
            rests[m][lane] = rest[m];
        }
    }
    let coefficient = |m: usize, k: usize| -> Lanes {
        let mut c = [0.0; LANES];
        for (lane, sample) in samples.iter().enumerate() {
            c[lane] = sample.theta[m][k];
        }
        c
    };
    let mut exogenous = vec![Vec::new(); modes];
    let mut linear = vec![Vec::new(); modes];
    let mut feedback = vec![Vec::new(); modes];
    for (m, program) in programs.iter().enumerate() {
        for (k, t) in program.terms.iter().enumerate() {
            let term = Compiled {
                source: t.output_mode.unwrap_or(m),
                output_lag: t.output_lag,
                output_power: t.output_power,
                input_lag: t.input_lag,
                input_power: t.input_power,
                coefficient: coefficient(m, k),
            };
            match (t.output_power, t.input_power) {
                (0, _) => exogenous[m].push(term),
                // Output t−lag of mode `source` sits lag·modes − source entries before this step's first.
                (1, 0) => linear[m].push((t.output_lag * modes - term.source, term.coefficient)),
                _ => feedback[m].push(term),
            }
        }
    }
    let history =
        programs.iter().flat_map(|p| p.terms.iter()).map(|t| t.output_lag.max(t.input_lag)).max().unwrap_or(0);
    let inverse_scales = programs.iter().map(|p| 1.0 / p.input_scale).collect();
    let dense = DenseLinear::new(programs, history, coefficient);
    let state = State { rests, exogenous, linear, feedback, history, inverse_scales, dense };
    dispatch(&state, samples, steps, time_step, sink).map_err(BatchError::Diverged)
}

/// Why a batch failed.
#[derive(Debug)]
pub enum BatchError {
    /// A sample's model has no rest state.
    Model {
        lane: usize,
        error: Error,
    },
    Diverged(Divergence),
}

/// A term with its sources resolved and its coefficient in every lane.
#[derive(Debug, Clone, Copy)]
struct Compiled {
    /// The mode whose output the term reads.
    source: usize,
    output_lag: usize,
    output_power: u32,
    input_lag: usize,
    input_power: u32,
    coefficient: Lanes,
}

struct State {
    rests: Vec<Lanes>,
    /// Per mode, the terms that read only the input (and the constant); they come first in a step,
    /// off the critical path of the recursion.
    exogenous: Vec<Vec<Compiled>>,
    /// Per mode, the terms c·y_source(t − lag), the common case, as (how far back in `outputs`, c).
    linear: Vec<Vec<(usize, Lanes)>>,
    /// Per mode, the other terms that read an output.
    feedback: Vec<Vec<Compiled>>,
    /// Longest lag: the steps each block carries over from the one before.
    history: usize,
    inverse_scales: Vec<f64>,
    /// The same models as dense arrays, when they fit the fast recursion.
    dense: Option<DenseLinear>,
}

/// Most modes, and longest lag, the fast recursion is compiled for.
const DENSE_MODES: usize = 3;
const DENSE_LAGS: usize = 2;

/// The models of a batch as dense coefficient arrays, zero where a term is absent, when every term
/// is the constant, Q_m(t − k) or y_s(t − k) with k ≤ [`DENSE_LAGS`] — which is what the paper's
/// structures select. With the modes and lags then fixed at compile time ([`dense_steps`]) the last
/// outputs are kept in local variables the compiler can hold in registers, instead of being read
/// back from the output buffer every step.
struct DenseLinear {
    /// Lag slots K = longest lag + 1 (slot 0 is the present, read only by input terms).
    slots: usize,
    /// Input lag slots: 1 when every input term reads Q(t) only (the usual case), else K.
    input_slots: usize,
    constant: Vec<Lanes>,
    /// input[k·M + m]: coefficient of Q_m(t − k).
    input: Vec<Lanes>,
    /// output[(k·M + m)·M + s]: coefficient of y_s(t − k) in mode m (slot 0 stays zero).
    output: Vec<Lanes>,
    /// Whether no mode reads a later mode's output (output[(k·M + m)·M + s] = 0 for s > m), as
    /// the paper's structures select: higher modes read lower ones, not the reverse. The
    /// recursion then skips the zeros, a sixth of its operations on three modes.
    lower: bool,
}

impl DenseLinear {
    fn new(programs: &[ModeProgram], history: usize, coefficient: impl Fn(usize, usize) -> Lanes) -> Option<Self> {
        let modes = programs.len();
        if !(1..=DENSE_MODES).contains(&modes) || !(1..=DENSE_LAGS).contains(&history) {
            return None;
        }
        let slots = history + 1;
        let input_lags = programs.iter().flat_map(|p| p.terms.iter()).filter(|t| t.input_power > 0);
        let input_slots = if input_lags.clone().all(|t| t.input_lag == 0) { 1 } else { slots };
        let mut dense = DenseLinear {
            slots,
            input_slots,
            constant: vec![[0.0; LANES]; modes],
            input: vec![[0.0; LANES]; slots * modes],
            output: vec![[0.0; LANES]; slots * modes * modes],
            lower: false,
        };
        for (m, program) in programs.iter().enumerate() {
            for (k, t) in program.terms.iter().enumerate() {
                let target = match (t.output_power, t.input_power) {
                    (0, 0) => &mut dense.constant[m],
                    (0, 1) => &mut dense.input[t.input_lag * modes + m],
                    (1, 0) if t.output_lag >= 1 => {
                        &mut dense.output[(t.output_lag * modes + m) * modes + t.output_mode.unwrap_or(m)]
                    }
                    _ => return None,
                };
                let c = coefficient(m, k);
                (0..LANES).for_each(|l| target[l] += c[l]);
            }
        }
        let upper = |e: usize| e % modes > (e / modes) % modes;
        dense.lower = dense.output.iter().enumerate().all(|(e, c)| !upper(e) || c.iter().all(|c| *c == 0.0));
        Some(dense)
    }
}

/// What the dense recursion does with each step's outputs, inside its own loop.
trait StepSink<V: Vector, const M: usize> {
    /// Step `i` of the block (counted from the block's first step) gave `y[m]`, every lane.
    fn take(&mut self, i: usize, y: &[V; M]);
}

/// Per lane the running peak of |offset + Σ_m gain_m ŷ_m| (see [`Sink::Peaks`]).
struct PeakTracker<V, const M: usize> {
    gains: [V; M],
    offsets: V,
    peaks: V,
}

impl<V: Vector, const M: usize> StepSink<V, M> for PeakTracker<V, M> {
    #[inline(always)]
    fn take(&mut self, _: usize, y: &[V; M]) {
        let mut u = self.offsets;
        for (gain, y) in self.gains.iter().zip(y) {
            u = gain.mul_add(*y, u);
        }
        // A NaN is caught by the divergence test of the block, whatever `max` makes of it.
        self.peaks = u.abs().max(self.peaks);
    }
}

/// The block's outputs as `outputs[i·M + m]`.
struct Recorder<'a> {
    outputs: &'a mut [Lanes],
}

impl<V: Vector, const M: usize> StepSink<V, M> for Recorder<'_> {
    #[inline(always)]
    fn take(&mut self, i: usize, y: &[V; M]) {
        for (y, to) in y.iter().zip(&mut self.outputs[i * M..(i + 1) * M]) {
            y.store(to);
        }
    }
}

/// The state the dense recursion carries from one block to the next: the last two outputs and
/// inputs of every mode (the dense models look back at most [`DENSE_LAGS`] steps).
#[derive(Clone, Copy)]
struct Carry<V, const M: usize> {
    /// ŷ(t − 1) and ŷ(t − 2) before step t.
    last: [V; M],
    before: [V; M],
    /// q(t − 1) and q(t − 2) before step t.
    last_input: [V; M],
    before_input: [V; M],
}

/// The scaled input of one mode at an instant: cubic convolution of the four coarse points from
/// `p` with weights `w`, every lane.
#[inline(always)]
fn interpolate<V: Vector>(coarse: &[Lanes], p: usize, w: &[V; 4]) -> V {
    let y = &coarse[p..p + 4];
    let first = w[0].mul(V::load(&y[0]));
    w[3].mul_add(V::load(&y[3]), w[2].mul_add(V::load(&y[2]), w[1].mul_add(V::load(&y[1]), first)))
}

/// The four interpolation weights, each in every lane.
#[inline(always)]
fn splat_weights<V: Vector>(w: &[f64; 4]) -> [V; 4] {
    [V::splat(w[0]), V::splat(w[1]), V::splat(w[2]), V::splat(w[3])]
}

/// Steps `first..first + len` (first ≥ 1) by the dense linear models, M modes, K output lag slots
/// and KI input lag slots (LOWER: no mode reads a later one, see [`DenseLinear::lower`]), each step's inputs interpolated from the lane-major coarse inputs and
/// its outputs handed to `sink` as step `i + sink_offset`. Returns the sum over the steps of each
/// lane's squared outputs, which the caller tests for divergence once per block. Interpolation,
/// recursion, reduction and check share one loop, so the outputs never go through memory; the sum
/// of each step takes the constant, the inputs, the older outputs and the newest outputs last, so
/// that only the last few operations wait on the previous step.
#[inline(always)]
#[allow(clippy::needless_range_loop, clippy::too_many_arguments)] // index loops over the fixed sizes
fn dense_steps<V: Vector, const M: usize, const K: usize, const KI: usize, const LOWER: bool>(
    dense: &DenseLinear,
    schedule: &CubicSchedule,
    coarse: &[Vec<Lanes>],
    carry: &mut Carry<V, M>,
    first: usize,
    len: usize,
    sink_offset: usize,
    sink: &mut impl StepSink<V, M>,
) -> Lanes {
    let zero = V::splat(0.0);
    let mut constant = [zero; M];
    let mut input = [[zero; M]; KI];
    let mut output = [[[zero; M]; M]; K];
    let mut modes: [&[Lanes]; M] = [&[]; M];
    for m in 0..M {
        constant[m] = V::load(&dense.constant[m]);
        modes[m] = &coarse[m];
        for k in 0..K {
            if k < KI {
                input[k][m] = V::load(&dense.input[k * M + m]);
            }
            for s in 0..M {
                output[k][m][s] = V::load(&dense.output[(k * M + m) * M + s]);
            }
        }
    }
    let Carry { mut last, mut before, mut last_input, mut before_input } = *carry;
    let mut squares = zero;
    schedule.for_each(
        first,
        len,
        #[inline(always)]
        |i, p, w| {
            let w = splat_weights::<V>(w);
            let mut q = [zero; M];
            for m in 0..M {
                q[m] = interpolate(modes[m], p, &w);
            }
            let mut next = constant;
            for m in 0..M {
                next[m] = input[0][m].mul_add(q[m], next[m]);
                if KI > 1 {
                    next[m] = input[1 % KI][m].mul_add(last_input[m], next[m]);
                }
                if KI > 2 {
                    next[m] = input[2 % KI][m].mul_add(before_input[m], next[m]);
                }
                let sources = if LOWER { m + 1 } else { M };
                if K > 2 {
                    for s in 0..sources {
                        next[m] = output[2 % K][m][s].mul_add(before[s], next[m]);
                    }
                }
                for s in 0..sources {
                    next[m] = output[1][m][s].mul_add(last[s], next[m]);
                }
            }
            before_input = last_input;
            last_input = q;
            before = last;
            last = next;
            for m in 0..M {
                squares = next[m].mul_add(next[m], squares);
            }
            sink.take(i + sink_offset, &next);
        },
    );
    *carry = Carry { last, before, last_input, before_input };
    let mut sums = [0.0; LANES];
    squares.store(&mut sums);
    sums
}

/// Whether a block whose outputs have these per-lane sums of squares may have left the bound (or
/// produced a NaN). A single output beyond the bound makes the sum exceed its square, so a block
/// that passes is sane; one that fails is searched output by output.
#[inline(always)]
fn suspicious(squares: &Lanes) -> bool {
    let mut sane = true;
    for s in squares {
        sane &= *s <= DIVERGENCE_BOUND * DIVERGENCE_BOUND;
    }
    !sane
}

/// The whole storm by the dense linear models: step 0 at rest, then blocks of [`BLOCK`] steps into
/// `sink`. A block that fails the cheap divergence test is run again from its start into memory
/// and searched, so the error names the first step out of bounds.
#[inline(always)]
fn dense_run<V: Vector, const M: usize, const K: usize, const KI: usize, const LOWER: bool>(
    dense: &DenseLinear,
    rests: &[Lanes],
    schedule: &CubicSchedule,
    coarse: &[Vec<Lanes>],
    steps: usize,
    sink: &mut Sink,
) -> std::result::Result<(), Divergence> {
    let zero = V::splat(0.0);
    let mut rest = [zero; M];
    for (rest, from) in rest.iter_mut().zip(rests) {
        *rest = V::load(from);
    }
    let mut carry = Carry { last: rest, before: rest, last_input: [zero; M], before_input: [zero; M] };
    schedule.for_each(0, 1, |_, p, w| {
        for (input, coarse) in carry.last_input.iter_mut().zip(coarse) {
            *input = interpolate(coarse, p, &splat_weights(w));
        }
    });
    let mut block = vec![[0.0; LANES]; BLOCK * M];
    let mut first = 0;
    while first < steps {
        let len = BLOCK.min(steps - first);
        // Step 0 is the rest state; every later step is computed.
        let from = first.max(1);
        let (count, offset) = (first + len - from, from - first);
        let start = carry;
        // The block's outputs into `block`, step 0's rest first when the block starts the storm.
        let record = |carry: &mut Carry<V, M>, block: &mut [Lanes]| {
            let mut recorder = Recorder { outputs: block };
            if first == 0 {
                recorder.take(0, &rest);
            }
            dense_steps::<V, M, K, KI, LOWER>(dense, schedule, coarse, carry, from, count, offset, &mut recorder)
        };
        let squares = match sink {
            Sink::Peaks { gains, offsets, peaks } => {
                let mut tracker = PeakTracker { gains: [zero; M], offsets: V::load(offsets), peaks: V::load(peaks) };
                for m in 0..M {
                    tracker.gains[m] = V::splat(gains[m]);
                }
                if first == 0 {
                    tracker.take(0, &rest);
                }
                let squares = dense_steps::<V, M, K, KI, LOWER>(
                    dense,
                    schedule,
                    coarse,
                    &mut carry,
                    from,
                    count,
                    offset,
                    &mut tracker,
                );
                tracker.peaks.store(peaks);
                squares
            }
            Sink::Blocks(_) => record(&mut carry, &mut block),
        };
        if suspicious(&squares) {
            let mut replay = start;
            record(&mut replay, &mut block);
            if let Some(divergence) = first_divergence(&block[..len * M], M, first) {
                return Err(divergence);
            }
        }
        if let Sink::Blocks(consume) = sink {
            consume(first, &block[..len * M]);
        }
        first += len;
    }
    Ok(())
}

/// [`dense_run`] for the batch's modes and lags: one instance per (M, K, KI, LOWER) listed, the
/// shapes the paper's structures take (inputs at lag 0 or up to the output lags; one mode is
/// always LOWER).
macro_rules! dense_shapes {
    ($dense:ident, $rests:ident, $schedule:ident, $coarse:ident, $steps:ident, $sink:ident;
     $(($m:literal, $k:literal, $ki:literal, $lower:literal)),*) => {
        match ($dense.constant.len(), $dense.slots, $dense.input_slots, $dense.lower) {
            $(($m, $k, $ki, $lower) => {
                dense_run::<V, $m, $k, $ki, $lower>($dense, $rests, $schedule, $coarse, $steps, $sink)
            })*
            other => unreachable!("no dense recursion for {other:?} (DenseLinear::new admits none)"),
        }
    };
}

#[inline(always)]
fn dense_storm<V: Vector>(
    dense: &DenseLinear,
    rests: &[Lanes],
    schedule: &CubicSchedule,
    coarse: &[Vec<Lanes>],
    steps: usize,
    sink: &mut Sink,
) -> std::result::Result<(), Divergence> {
    dense_shapes!(dense, rests, schedule, coarse, steps, sink;
        (1, 2, 1, true), (1, 3, 1, true), (1, 2, 2, true), (1, 3, 3, true),
        (2, 2, 1, true), (3, 2, 1, true), (2, 3, 1, true), (3, 3, 1, true),
        (2, 2, 2, true), (3, 2, 2, true), (2, 3, 3, true), (3, 3, 3, true),
        (2, 2, 1, false), (3, 2, 1, false), (2, 3, 1, false), (3, 3, 1, false),
        (2, 2, 2, false), (3, 2, 2, false), (2, 3, 3, false), (3, 3, 3, false))
}

fn dispatch(
    state: &State,
    samples: &[BatchSample],
    steps: usize,
    time_step: f64,
    sink: &mut Sink,
) -> std::result::Result<(), Divergence> {
    // The buffer is borrowed here, outside the functions compiled for an instruction set: code in a
    // closure called through the thread-local's accessor is not compiled for it, and there the
    // AVX-512 intrinsics become function calls (a tenfold slower free run, measured).
    LANE_INPUTS.with_borrow_mut(|coarse| {
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx512f") && std::arch::is_x86_feature_detected!("fma") {
                // SAFETY: the processor has the features the function is compiled for.
                return unsafe { recurse_avx512(state, samples, steps, time_step, coarse, sink) };
            }
            if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma") {
                // SAFETY: as above.
                return unsafe { recurse_avx2(state, samples, steps, time_step, coarse, sink) };
            }
        }
        recurse::<Lanes>(state, samples, steps, time_step, coarse, sink)
    })
}

/// `recurse` on the vectors of an instruction set, compiled for it; called only where the
/// processor was checked for it at run time.
macro_rules! recurse_with {
    ($name:ident, $vector:ident, $features:literal) => {
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = $features)]
        unsafe fn $name(
            state: &State,
            samples: &[BatchSample],
            steps: usize,
            time_step: f64,
            coarse: &mut Vec<Vec<Lanes>>,
            sink: &mut Sink,
        ) -> std::result::Result<(), Divergence> {
            recurse::<simd::$vector>(state, samples, steps, time_step, coarse, sink)
        }
    };
}

recurse_with!(recurse_avx512, Avx512, "avx512f,fma");
recurse_with!(recurse_avx2, Avx2, "avx2,fma");

#[inline(always)]
fn power(x: &Lanes, p: u32) -> Lanes {
    match p {
        0 => [1.0; LANES],
        1 => *x,
        2 => std::array::from_fn(|l| x[l] * x[l]),
        3 => std::array::from_fn(|l| x[l] * x[l] * x[l]),
        _ => std::array::from_fn(|l| x[l].powi(p as i32)),
    }
}

thread_local! {
    /// Each thread's lane-major inputs, reused from batch to batch (a batch's are megabytes, and
    /// allocating them afresh cost page faults).
    static LANE_INPUTS: RefCell<Vec<Vec<Lanes>>> = const { RefCell::new(Vec::new()) };
}

/// The scaled input deviations of every lane, lane-major so that one interpolation serves all
/// lanes: inputs[m][q][lane] the value at coarse point q (at t = (q − 1)·dt_g), into `inputs`;
/// returns the schedule from the storm's grid onto the coarse points. Samples from one generation
/// grid are taken as they are; any others are filled on the storm's grid and padded, which the same
/// interpolation then reads exactly (one step per generation step, weights 0, 1, 0, 0).
fn lane_inputs(
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

/// The recursion itself: the dense models' fused loop when they apply, otherwise a block of steps
/// at a time by the term lists, each block's inputs interpolated first from the lane-major coarse
/// inputs. `inputs` and `outputs` hold `history` carried-over steps, then the block, the modes
/// interleaved: outputs[(h + i)·modes + m]. Before t = 0 the outputs are at rest and the input
/// deviations zero.
#[inline(always)]
fn recurse<V: Vector>(
    state: &State,
    samples: &[BatchSample],
    steps: usize,
    time_step: f64,
    coarse: &mut Vec<Vec<Lanes>>,
    sink: &mut Sink,
) -> std::result::Result<(), Divergence> {
    let schedule = lane_inputs(samples, &state.inverse_scales, steps, time_step, coarse);
    recurse_on::<V>(state, &schedule, coarse, steps, sink)
}

/// [`recurse`] on the lane-major inputs.
#[inline(always)]
fn recurse_on<V: Vector>(
    state: &State,
    schedule: &CubicSchedule,
    coarse: &[Vec<Lanes>],
    steps: usize,
    sink: &mut Sink,
) -> std::result::Result<(), Divergence> {
    if let Some(dense) = &state.dense {
        return dense_storm::<V>(dense, &state.rests, schedule, coarse, steps, sink);
    }
    let modes = state.rests.len();
    let h = state.history;
    let mut inputs: Vec<Lanes> = vec![[0.0; LANES]; (h + BLOCK) * modes];
    let mut outputs: Vec<Lanes> = (0..(h + BLOCK) * modes).map(|k| state.rests[k % modes]).collect();
    let mut first = 0;
    while first < steps {
        let len = BLOCK.min(steps - first);
        outputs.copy_within(BLOCK * modes.., 0);
        inputs.copy_within(BLOCK * modes.., 0);
        schedule.for_each(
            first,
            len,
            #[inline(always)]
            |i, p, w| {
                for (m, lanes) in coarse.iter().enumerate() {
                    inputs[(h + i) * modes + m] = interpolate::<Lanes>(lanes, p, &splat_weights(w));
                }
            },
        );
        general_block(state, &inputs, &mut outputs, usize::from(first == 0), len);
        let block = &outputs[h * modes..(h + len) * modes];
        // Checked once a block, so that the lanes never branch apart inside the recursion.
        if let Some(divergence) = first_divergence(block, modes, first) {
            return Err(divergence);
        }
        match sink {
            Sink::Blocks(consume) => consume(first, block),
            Sink::Peaks { gains, offsets, peaks } => {
                for step in block.chunks_exact(modes) {
                    let mut u = *offsets;
                    for (y, g) in step.iter().zip(gains.iter()) {
                        (0..LANES).for_each(|l| u[l] = g.mul_add(y[l], u[l]));
                    }
                    for l in 0..LANES {
                        peaks[l] = peaks[l].max(u[l].abs());
                    }
                }
            }
        }
        first += len;
    }
    Ok(())
}

/// Steps `from..len` of a block by the models as term lists, for structures the dense recursion
/// does not cover: each mode's input terms first (off the recursion's critical path), then its
/// output terms.
#[inline(always)]
fn general_block(state: &State, inputs: &[Lanes], outputs: &mut [Lanes], from: usize, len: usize) {
    let modes = state.rests.len();
    let h = state.history;
    for i in from..len {
        let here = (h + i) * modes;
        for m in 0..modes {
            let mut value = [0.0; LANES];
            for term in &state.exogenous[m] {
                let c = &term.coefficient;
                match term.input_power {
                    0 => (0..LANES).for_each(|l| value[l] += c[l]),
                    p => {
                        let g = power(&inputs[here - term.input_lag * modes + m], p);
                        (0..LANES).for_each(|l| value[l] = c[l].mul_add(g[l], value[l]));
                    }
                }
            }
            for (back, c) in &state.linear[m] {
                let y = &outputs[here - back];
                for l in 0..LANES {
                    value[l] = c[l].mul_add(y[l], value[l]);
                }
            }
            for term in &state.feedback[m] {
                let y = power(&outputs[here - term.output_lag * modes + term.source], term.output_power);
                let q = power(&inputs[here - term.input_lag * modes + m], term.input_power);
                for l in 0..LANES {
                    value[l] = term.coefficient[l].mul_add(y[l] * q[l], value[l]);
                }
            }
            outputs[here + m] = value;
        }
    }
}

/// The earliest (step, mode, lane) of a block of outputs from step `first` whose output left the
/// bound (a NaN counts as out).
fn first_divergence(block: &[Lanes], modes: usize, first: usize) -> Option<Divergence> {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Two coupled modes run jointly equal a hand-written recursion, in every lane, each lane with
    /// its own coefficients; blocks boundaries do not show.
    #[test]
    fn batch_equals_a_hand_written_recursion() {
        let a = [NarxTerm::input(0, 1), NarxTerm::output(1, 1, None), NarxTerm::output(1, 1, Some(1))];
        let b = [NarxTerm::input(0, 1), NarxTerm::output(1, 1, None), NarxTerm::output(2, 1, Some(0))];
        let steps = 1300;
        let inputs = vec![(0..steps).map(|t| (t as f64 * 0.01).sin()).collect::<Vec<f64>>(), vec![1.0; steps]];
        let forces = ModalForces { mean: vec![0.0, 0.0], series: inputs.clone() };
        let programs = [ModeProgram { terms: &a, input_scale: 1.0 }, ModeProgram { terms: &b, input_scale: 1.0 }];
        let samples: Vec<BatchSample> = (0..3)
            .map(|k| {
                let k = k as f64;
                BatchSample { theta: vec![vec![0.5, 0.9 - 0.1 * k, 0.05], vec![0.2, 0.8, -0.1 * k]], forces: &forces }
            })
            .collect();
        let mut got = vec![vec![vec![0.0; steps]; 2]; 3];
        let mut consume = |first: usize, outputs: &[Lanes]| {
            for (k, lanes) in outputs.iter().enumerate() {
                for (lane, history) in got.iter_mut().enumerate() {
                    history[k % 2][first + k / 2] = lanes[lane];
                }
            }
        };
        run(&programs, &samples, steps, 0.01, &mut Sink::Blocks(&mut consume)).unwrap();
        for (k, history) in got.iter().enumerate() {
            let (ta, tb) = (&samples[k].theta[0], &samples[k].theta[1]);
            let (mut ya, mut yb) = (vec![0.0; steps], vec![0.0; steps]);
            for t in 1..steps {
                ya[t] = ta[0] * inputs[0][t] + ta[1] * ya[t - 1] + ta[2] * yb[t - 1];
                yb[t] = tb[0] * inputs[1][t] + tb[1] * yb[t - 1] + tb[2] * if t >= 2 { ya[t - 2] } else { 0.0 };
            }
            for t in 0..steps {
                assert!(
                    (history[0][t] - ya[t]).abs() < 1e-13 && (history[1][t] - yb[t]).abs() < 1e-13,
                    "lane {k} t {t}"
                );
            }
        }
    }

    /// The dense recursion and the term lists agree: the same linear models, once as they are and
    /// once with a zero-coefficient cubic term that sends them through the term lists.
    #[test]
    fn dense_and_term_list_recursions_agree() {
        let linear = [NarxTerm::CONSTANT, NarxTerm::input(0, 1), NarxTerm::input(1, 1), NarxTerm::output(1, 1, None)];
        let linear_b = [NarxTerm::input(0, 1), NarxTerm::output(1, 1, None), NarxTerm::output(2, 1, Some(0))];
        let cubic = NarxTerm::output(1, 3, None);
        let (with_a, with_b) = ([&linear[..], &[cubic]].concat(), [&linear_b[..], &[cubic]].concat());
        let steps = 1100;
        let forces = ModalForces {
            mean: vec![0.0, 0.0],
            series: vec![(0..steps).map(|t| (t as f64 * 0.013).sin()).collect(), vec![0.5; steps]],
        };
        let run_with = |a: &[NarxTerm], b: &[NarxTerm], extra: usize| -> Vec<Vec<f64>> {
            let programs = [ModeProgram { terms: a, input_scale: 2.0 }, ModeProgram { terms: b, input_scale: 1.0 }];
            let samples: Vec<BatchSample> = (0..5)
                .map(|k| {
                    let k = k as f64;
                    let mut ta = vec![0.01, 0.3, -0.1 * k, 0.9 - 0.05 * k];
                    let mut tb = vec![0.2, 0.7, 0.02 * k];
                    ta.extend(vec![0.0; extra]);
                    tb.extend(vec![0.0; extra]);
                    BatchSample { theta: vec![ta, tb], forces: &forces }
                })
                .collect();
            let mut got = vec![vec![0.0; steps * 2]; 5];
            let mut consume = |first: usize, outputs: &[Lanes]| {
                for (k, lanes) in outputs.iter().enumerate() {
                    for (lane, history) in got.iter_mut().enumerate() {
                        history[first * 2 + k] = lanes[lane];
                    }
                }
            };
            run(&programs, &samples, steps, 0.01, &mut Sink::Blocks(&mut consume)).unwrap();
            got
        };
        let dense = run_with(&linear, &linear_b, 0);
        let lists = run_with(&with_a, &with_b, 1);
        for (d, l) in dense.iter().zip(&lists) {
            for (a, b) in d.iter().zip(l) {
                assert!((a - b).abs() <= 1e-13 * a.abs().max(1.0), "{a} vs {b}");
            }
        }
        assert!(dense[0].iter().any(|v| v.abs() > 0.1));
    }

    /// A lane whose model is unstable is reported with its mode and step; the others do not matter.
    #[test]
    fn divergence_names_the_lane() {
        let terms = [NarxTerm::input(0, 1), NarxTerm::output(1, 1, None), NarxTerm::output(2, 1, None)];
        let forces = ModalForces { mean: vec![0.0], series: vec![vec![1.0; 5000]] };
        let programs = [ModeProgram { terms: &terms, input_scale: 1.0 }];
        let samples = [
            BatchSample { theta: vec![vec![0.02, 1.9, -0.95]], forces: &forces },
            BatchSample { theta: vec![vec![0.02, 2.1, -0.9]], forces: &forces },
        ];
        let err = run(&programs, &samples, 5000, 0.01, &mut Sink::Blocks(&mut |_, _| {})).unwrap_err();
        match err {
            BatchError::Diverged(d) => assert_eq!((d.lane, d.mode), (1, 0)),
            other => panic!("{other:?}"),
        }
    }
}
