//! The free run of the paper's structures: every term the constant, Q_m(t − k), y_s(t − k) with
//! k ≤ [`DENSE_LAGS`] or the dampers' law D(Δ_s) of a mode's last first difference, on at most
//! [`DENSE_MODES`] modes, run as dense coefficient arrays with the modes and lags fixed at compile
//! time, in one loop that interpolates, recurses, reduces the outputs (a [`StepSink`]) and
//! accumulates the divergence test, with the state in registers.
//! Written once over [`Vector`] and compiled per instruction set ([`crate::simd::run_widest`]).

use super::ModeProgram;
use super::inputs::{Prepared, interpolate, splat_weights};
use super::samples::longest_lag;
use super::sink::{BLOCK, Divergence, Sink, first_divergence};
use crate::simd::Vector;
use crate::simd::{LANES, Lanes};
use crate::surrogate::damper_law::secant_lanes;
use crate::surrogate::narx::DIVERGENCE_BOUND;
use crate::surrogate::narx::DamperTerm;
use crate::wind::CubicSchedule;

/// Most modes, and longest lag, the fast recursion is compiled for.
const DENSE_MODES: usize = 3;
const DENSE_LAGS: usize = 2;

/// The models of a batch as dense coefficient arrays, zero where a term is absent, when every term
/// is the constant, Q_m(t − k), y_s(t − k) with k ≤ [`DENSE_LAGS`] or D(y_s(t − 1) − y_s(t − 2)) —
/// which is what the paper's structures select, with or without the dampers' law. With the modes
/// and lags then fixed at compile time ([`advance`]) the last outputs are kept in local variables
/// the compiler can hold in registers, instead of being read back from the output buffer every
/// step.
pub(super) struct DenseLinear {
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
    /// The dampers' law terms, where any mode has one.
    law: Option<DenseLaw>,
}

/// The terms c·D(Δ_s) = c·Δ_s·S(Δ_s) of the dampers' law, Δ_s = y_s(t − 1) − y_s(t − 2), and
/// c·Δ_m·S(Δ_s), mode m's own velocity at the law's secant at mode s's: one power per source mode
/// and step, shared by every mode that reads it.
struct DenseLaw {
    /// coefficient[m·M + s]: coefficient of D(Δ_s) in mode m.
    coefficient: Vec<Lanes>,
    /// modulated[m·M + s]: coefficient of Δ_m·S(Δ_s) in mode m (s ≠ m).
    modulated: Vec<Lanes>,
    /// Whether any mode reads D(Δ_s).
    read: Vec<bool>,
    /// κ_s, the law's knee of each source mode.
    knees: Vec<f64>,
    exponent: f64,
}

impl DenseLinear {
    /// The dense arrays of `programs`, if their terms fit; `coefficient(m, k)`: term k of mode m's
    /// coefficient in every lane.
    pub(super) fn new(programs: &[ModeProgram], coefficient: impl Fn(usize, usize) -> Lanes) -> Option<Self> {
        let modes = programs.len();
        let history = longest_lag(programs);
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
            law: None,
        };
        for (m, program) in programs.iter().enumerate() {
            for (k, t) in program.terms.iter().enumerate() {
                let target = match (t.output_power, t.input_power) {
                    (0, 0) => &mut dense.constant[m],
                    (0, 1) => &mut dense.input[t.input_lag * modes + m],
                    (1, 0) if t.output_lag >= 1 && t.damper.is_none() => {
                        &mut dense.output[(t.output_lag * modes + m) * modes + t.output_mode.unwrap_or(m)]
                    }
                    (1, 0) if t.output_lag == 1 => {
                        let law = program.law.expect("a damper term runs with its damper law");
                        let source = t.output_mode.unwrap_or(m);
                        let dense_law = dense.law.get_or_insert_with(|| DenseLaw {
                            coefficient: vec![[0.0; LANES]; modes * modes],
                            modulated: vec![[0.0; LANES]; modes * modes],
                            read: vec![false; modes],
                            knees: law.knees.clone(),
                            exponent: law.exponent,
                        });
                        dense_law.read[source] = true;
                        match t.damper {
                            Some(DamperTerm::Modulated) if source != m => &mut dense_law.modulated[m * modes + source],
                            _ => &mut dense_law.coefficient[m * modes + source],
                        }
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

/// What the dense recursion does with each step's outputs, inside its own loop, for G batches
/// run side by side.
trait StepSink<V: Vector, const M: usize, const G: usize> {
    /// Step `i` of the block (counted from the block's first step) read `q[g][m]` and gave
    /// `y[g][m]`, every lane of every batch g.
    fn take(&mut self, i: usize, y: &[[V; M]; G], q: &[[V; M]; G]);
}

/// Per lane of each of G batches the running peak of |offset + Σ_m gain_m ŷ_m| (see
/// [`Sink::Peaks`]; the batches run the same models, so they share the gains).
struct PeakTracker<V, const M: usize, const G: usize> {
    gains: [V; M],
    offsets: [V; G],
    peaks: [V; G],
}

impl<V: Vector, const M: usize, const G: usize> StepSink<V, M, G> for PeakTracker<V, M, G> {
    #[inline(always)]
    fn take(&mut self, _: usize, y: &[[V; M]; G], _: &[[V; M]; G]) {
        for g in 0..G {
            let mut u = self.offsets[g];
            for (gain, y) in self.gains.iter().zip(&y[g]) {
                u = gain.mul_add(*y, u);
            }
            // A NaN is caught by the divergence test of the block, whatever `max` makes of it.
            self.peaks[g] = u.abs().max(self.peaks[g]);
        }
    }
}

/// The block's outputs and inputs as `outputs[i·M + m]`, `inputs[i·M + m]` (one batch).
struct Recorder<'a> {
    outputs: &'a mut [Lanes],
    inputs: &'a mut [Lanes],
}

impl<V: Vector, const M: usize> StepSink<V, M, 1> for Recorder<'_> {
    #[inline(always)]
    fn take(&mut self, i: usize, [y]: &[[V; M]; 1], [q]: &[[V; M]; 1]) {
        for (y, to) in y.iter().zip(&mut self.outputs[i * M..(i + 1) * M]) {
            y.store(to);
        }
        for (q, to) in q.iter().zip(&mut self.inputs[i * M..(i + 1) * M]) {
            q.store(to);
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

/// Steps `first..first + len` (first ≥ 1) of G batches side by side by their dense linear models
/// (of one shape: M modes, K output lag slots and KI input lag slots, LOWER: no mode reads a later
/// one, see [`DenseLinear::lower`]), each step's inputs interpolated from the batch's lane-major
/// coarse inputs and its outputs handed to `sink` as step `i + sink_offset`. Returns per batch the
/// sum over the steps of each lane's squared outputs, which the caller tests for divergence once
/// per block. Interpolation, recursion, reduction and check share one loop, so the outputs never
/// go through memory; the sum of each step takes the constant, the inputs, the older outputs and
/// the newest outputs last, so that only the last few operations wait on the previous step. A
/// step waits on the power of the dampers' law, whose latency is most of a step: two batches (G =
/// 2) give the processor two independent chains to overlap.
#[inline(always)]
#[allow(clippy::needless_range_loop, clippy::too_many_arguments)] // index loops over the fixed sizes
fn advance<V: Vector, const M: usize, const K: usize, const KI: usize, const LOWER: bool, const G: usize>(
    isa: V::Isa,
    dense: [&DenseLinear; G],
    schedule: &CubicSchedule,
    coarse: [&[Vec<Lanes>]; G],
    carry: &mut [Carry<V, M>; G],
    first: usize,
    len: usize,
    sink_offset: usize,
    sink: &mut impl StepSink<V, M, G>,
) -> [Lanes; G] {
    let zero = V::splat(isa, 0.0);
    let mut constant = [[zero; M]; G];
    let mut input = [[[zero; M]; KI]; G];
    let mut output = [[[[zero; M]; M]; K]; G];
    let mut modes: [[&[Lanes]; M]; G] = [[&[]; M]; G];
    for g in 0..G {
        for m in 0..M {
            constant[g][m] = V::load(isa, &dense[g].constant[m]);
            modes[g][m] = &coarse[g][m];
            for k in 0..K {
                if k < KI {
                    input[g][k][m] = V::load(isa, &dense[g].input[k * M + m]);
                }
                for s in 0..M {
                    output[g][k][m][s] = V::load(isa, &dense[g].output[(k * M + m) * M + s]);
                }
            }
        }
    }
    let minus_one = V::splat(isa, -1.0);
    // The batches run the same models: the law's form (which modes read it, the knees, the
    // exponent) is the first's, the coefficients each batch's own.
    let law = dense[0].law.as_ref();
    let mut law_coefficient = [[[zero; M]; M]; G];
    let mut modulated_coefficient = [[[zero; M]; M]; G];
    let mut modulated = false;
    for g in 0..G {
        if let Some(own) = &dense[g].law {
            for m in 0..M {
                for s in 0..M {
                    law_coefficient[g][m][s] = V::load(isa, &own.coefficient[m * M + s]);
                    modulated_coefficient[g][m][s] = V::load(isa, &own.modulated[m * M + s]);
                    modulated |= own.modulated[m * M + s].iter().any(|c| *c != 0.0);
                }
            }
        }
    }
    let mut last = [[zero; M]; G];
    let mut before = [[zero; M]; G];
    let mut last_input = [[zero; M]; G];
    let mut before_input = [[zero; M]; G];
    for g in 0..G {
        Carry { last: last[g], before: before[g], last_input: last_input[g], before_input: before_input[g] } = carry[g];
    }
    let mut squares = [zero; G];
    schedule.for_each(
        first,
        len,
        #[inline(always)]
        |i, p, w| {
            let w = splat_weights::<V>(isa, w);
            let mut q = [[zero; M]; G];
            for g in 0..G {
                for m in 0..M {
                    q[g][m] = interpolate(isa, modes[g][m], p, &w);
                }
            }
            let mut next = constant;
            if let Some(law) = law {
                // D(Δ_s) = Δ_s·S(Δ_s) of every lane, vectorised, as the scalar free run and the term
                // lists form it; with modulated terms Δ_m·S(Δ_s) from the same secants.
                let mut differences = [[zero; M]; G];
                let mut secants = [[zero; M]; G];
                for g in 0..G {
                    for s in 0..M {
                        differences[g][s] = minus_one.mul_add(before[g][s], last[g][s]);
                        if law.read[s] {
                            let mut difference = [0.0; LANES];
                            differences[g][s].store(&mut difference);
                            secants[g][s] = V::load(isa, &secant_lanes(difference, law.knees[s], law.exponent));
                        }
                    }
                }
                for g in 0..G {
                    for m in 0..M {
                        for s in 0..M {
                            let term = differences[g][s].mul(secants[g][s]);
                            next[g][m] = law_coefficient[g][m][s].mul_add(term, next[g][m]);
                        }
                    }
                    if modulated {
                        for m in 0..M {
                            for s in 0..M {
                                let term = differences[g][m].mul(secants[g][s]);
                                next[g][m] = modulated_coefficient[g][m][s].mul_add(term, next[g][m]);
                            }
                        }
                    }
                }
            }
            for g in 0..G {
                for m in 0..M {
                    next[g][m] = input[g][0][m].mul_add(q[g][m], next[g][m]);
                    if KI > 1 {
                        next[g][m] = input[g][1 % KI][m].mul_add(last_input[g][m], next[g][m]);
                    }
                    if KI > 2 {
                        next[g][m] = input[g][2 % KI][m].mul_add(before_input[g][m], next[g][m]);
                    }
                    let sources = if LOWER { m + 1 } else { M };
                    if K > 2 {
                        for s in 0..sources {
                            next[g][m] = output[g][2 % K][m][s].mul_add(before[g][s], next[g][m]);
                        }
                    }
                    for s in 0..sources {
                        next[g][m] = output[g][1][m][s].mul_add(last[g][s], next[g][m]);
                    }
                }
            }
            before_input = last_input;
            last_input = q;
            before = last;
            last = next;
            for g in 0..G {
                for m in 0..M {
                    squares[g] = next[g][m].mul_add(next[g][m], squares[g]);
                }
            }
            sink.take(i + sink_offset, &next, &q);
        },
    );
    let mut sums = [[0.0; LANES]; G];
    for g in 0..G {
        carry[g] = Carry { last: last[g], before: before[g], last_input: last_input[g], before_input: before_input[g] };
        squares[g].store(&mut sums[g]);
    }
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

/// Steps `from..from + count` into `block` and `inputs` as [`Recorder`] outputs from slot
/// `offset`, with the rest state in slot 0 when the block is the storm's first (`first` = 0).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn record_block<V: Vector, const M: usize, const K: usize, const KI: usize, const LOWER: bool>(
    isa: V::Isa,
    dense: &DenseLinear,
    schedule: &CubicSchedule,
    coarse: &[Vec<Lanes>],
    rest: &[V; M],
    carry: &mut Carry<V, M>,
    [first, from, count, offset]: [usize; 4],
    block: &mut [Lanes],
    inputs: &mut [Lanes],
) -> Lanes {
    let mut recorder = Recorder { outputs: block, inputs };
    if first == 0 {
        StepSink::<V, M, 1>::take(&mut recorder, 0, &[*rest], &[carry.last_input]);
    }
    advance_one::<V, M, K, KI, LOWER>(isa, dense, schedule, coarse, carry, [from, count, offset], &mut recorder)
}

/// [`advance`] of one batch: steps `from..from + count`, handed to `sink` from slot `offset`.
#[inline(always)]
fn advance_one<V: Vector, const M: usize, const K: usize, const KI: usize, const LOWER: bool>(
    isa: V::Isa,
    dense: &DenseLinear,
    schedule: &CubicSchedule,
    coarse: &[Vec<Lanes>],
    carry: &mut Carry<V, M>,
    [from, count, offset]: [usize; 3],
    sink: &mut impl StepSink<V, M, 1>,
) -> Lanes {
    let mut carries = [*carry];
    let [squares] =
        advance::<V, M, K, KI, LOWER, 1>(isa, [dense], schedule, [coarse], &mut carries, from, count, offset, sink);
    *carry = carries[0];
    squares
}

/// A batch's state before its first step: the rests, and the inputs at step 0.
#[inline(always)]
fn start<V: Vector, const M: usize>(isa: V::Isa, prepared: &Prepared) -> ([V; M], Carry<V, M>) {
    let zero = V::splat(isa, 0.0);
    let mut rest = [zero; M];
    for (rest, from) in rest.iter_mut().zip(prepared.rests) {
        *rest = V::load(isa, from);
    }
    let mut carry = Carry { last: rest, before: rest, last_input: [zero; M], before_input: [zero; M] };
    prepared.schedule.for_each(0, 1, |_, p, w| {
        for (input, coarse) in carry.last_input.iter_mut().zip(prepared.coarse) {
            *input = interpolate(isa, coarse, p, &splat_weights(isa, w));
        }
    });
    (rest, carry)
}

/// The storm's blocks: (first step, length, first computed step, steps computed, its offset).
fn blocks(steps: usize) -> impl Iterator<Item = [usize; 4]> {
    (0..steps).step_by(BLOCK).map(move |first| {
        let len = BLOCK.min(steps - first);
        // Step 0 is the rest state; every later step is computed.
        let from = first.max(1);
        [first, from, first + len - from, from - first]
    })
}

/// Where a block that failed the cheap divergence test left the bound: the block run again from
/// its start into memory and searched, so that the error names the first step out of bounds.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn search_block<V: Vector, const M: usize, const K: usize, const KI: usize, const LOWER: bool>(
    isa: V::Isa,
    dense: &DenseLinear,
    prepared: &Prepared,
    rest: &[V; M],
    start: Carry<V, M>,
    span: [usize; 4],
    block: &mut [Lanes],
    inputs: &mut [Lanes],
) -> Option<Divergence> {
    let mut replay = start;
    let coarse = prepared.coarse;
    record_block::<V, M, K, KI, LOWER>(isa, dense, &prepared.schedule, coarse, rest, &mut replay, span, block, inputs);
    let [first, from, count, _] = span;
    first_divergence(&block[..(from + count - first) * M], M, first)
}

/// The whole storm by the dense linear models: step 0 at rest, then blocks of [`BLOCK`] steps into
/// `sink`. A block that fails the cheap divergence test is searched ([`search_block`]).
#[inline(always)]
fn run_shape<V: Vector, const M: usize, const K: usize, const KI: usize, const LOWER: bool>(
    isa: V::Isa,
    dense: &DenseLinear,
    prepared: &Prepared,
    sink: &mut Sink,
) -> Result<(), Divergence> {
    let zero = V::splat(isa, 0.0);
    let (rest, mut carry) = start::<V, M>(isa, prepared);
    let (schedule, coarse) = (&prepared.schedule, prepared.coarse);
    let (mut block, mut inputs) = (vec![[0.0; LANES]; BLOCK * M], vec![[0.0; LANES]; BLOCK * M]);
    for span in blocks(prepared.steps) {
        let [first, from, count, offset] = span;
        let start = carry;
        let squares = match sink {
            Sink::Peaks { gains, offsets, peaks } => {
                let mut tracker =
                    PeakTracker { gains: [zero; M], offsets: [V::load(isa, offsets)], peaks: [V::load(isa, peaks)] };
                for m in 0..M {
                    tracker.gains[m] = V::splat(isa, gains[m]);
                }
                if first == 0 {
                    tracker.take(0, &[rest], &[carry.last_input]);
                }
                let span = [from, count, offset];
                let squares =
                    advance_one::<V, M, K, KI, LOWER>(isa, dense, schedule, coarse, &mut carry, span, &mut tracker);
                tracker.peaks[0].store(peaks);
                squares
            }
            // The block's outputs into `block`: a function, not a closure, since a closure does
            // not inherit the target features this is compiled for, and its vector intrinsics
            // became calls (a 40-fold slower recorded run).
            Sink::Blocks(_) => record_block::<V, M, K, KI, LOWER>(
                isa,
                dense,
                schedule,
                coarse,
                &rest,
                &mut carry,
                span,
                &mut block,
                &mut inputs,
            ),
        };
        if suspicious(&squares)
            && let Some(divergence) =
                search_block::<V, M, K, KI, LOWER>(isa, dense, prepared, &rest, start, span, &mut block, &mut inputs)
        {
            return Err(divergence);
        }
        if let Sink::Blocks(consume) = sink {
            let len = from + count - first;
            consume(first, &block[..len * M], &inputs[..len * M]);
        }
    }
    Ok(())
}

/// Two batches' peaks of one combination, side by side through the storm ([`advance`] with G = 2).
/// A lane that diverges is named by its place in the pair (the second batch's lanes after the
/// first's).
#[inline(always)]
fn run_pair_shape<V: Vector, const M: usize, const K: usize, const KI: usize, const LOWER: bool>(
    isa: V::Isa,
    dense: [&DenseLinear; 2],
    prepared: [&Prepared; 2],
    peaks: PairedPeaks,
) -> Result<(), Divergence> {
    let zero = V::splat(isa, 0.0);
    let (rest_a, carry_a) = start::<V, M>(isa, prepared[0]);
    let (rest_b, carry_b) = start::<V, M>(isa, prepared[1]);
    let (rests, mut carries) = ([rest_a, rest_b], [carry_a, carry_b]);
    let mut tracker = PeakTracker {
        gains: [zero; M],
        offsets: [V::load(isa, &peaks.offsets[0]), V::load(isa, &peaks.offsets[1])],
        peaks: [V::load(isa, peaks.peaks[0]), V::load(isa, peaks.peaks[1])],
    };
    for m in 0..M {
        tracker.gains[m] = V::splat(isa, peaks.gains[m]);
    }
    let coarse = [prepared[0].coarse, prepared[1].coarse];
    let (mut block, mut inputs) = (vec![[0.0; LANES]; BLOCK * M], vec![[0.0; LANES]; BLOCK * M]);
    for span in blocks(prepared[0].steps) {
        let [first, from, count, offset] = span;
        let starts = carries;
        if first == 0 {
            tracker.take(0, &rests, &[carries[0].last_input, carries[1].last_input]);
        }
        let schedule = &prepared[0].schedule;
        let squares = advance::<V, M, K, KI, LOWER, 2>(
            isa,
            dense,
            schedule,
            coarse,
            &mut carries,
            from,
            count,
            offset,
            &mut tracker,
        );
        for g in 0..2 {
            if suspicious(&squares[g])
                && let Some(divergence) = search_block::<V, M, K, KI, LOWER>(
                    isa,
                    dense[g],
                    prepared[g],
                    &rests[g],
                    starts[g],
                    span,
                    &mut block,
                    &mut inputs,
                )
            {
                return Err(Divergence { lane: g * LANES + divergence.lane, ..divergence });
            }
        }
    }
    tracker.peaks[0].store(peaks.peaks[0]);
    tracker.peaks[1].store(peaks.peaks[1]);
    Ok(())
}

/// What two batches run side by side produce: per lane of each, the peak of one combination (as
/// [`Sink::Peaks`]; the batches share its gains).
pub(super) struct PairedPeaks<'a> {
    pub gains: &'a [f64],
    pub offsets: [Lanes; 2],
    pub peaks: [&'a mut Lanes; 2],
}

/// One instance of `$run` per (M, K, KI, LOWER) listed, the shapes the paper's structures take
/// (inputs at lag 0 or up to the output lags; one mode is always LOWER), chosen by `$dense`'s.
macro_rules! dense_shapes {
    ($run:ident, $dense:expr, $args:tt;
     $(($m:literal, $k:literal, $ki:literal, $lower:literal)),*) => {
        match ($dense.constant.len(), $dense.slots, $dense.input_slots, $dense.lower) {
            $(($m, $k, $ki, $lower) => $run::<V, $m, $k, $ki, $lower> $args,)*
            other => unreachable!("no dense recursion for {other:?} (DenseLinear::new admits none)"),
        }
    };
}

/// Calls `$run` for the shape of `$dense` among the shapes the dense recursion is compiled for.
macro_rules! each_dense_shape {
    ($run:ident, $dense:expr, $args:tt) => {
        dense_shapes!($run, $dense, $args;
            (1, 2, 1, true), (1, 3, 1, true), (1, 2, 2, true), (1, 3, 3, true),
            (2, 2, 1, true), (3, 2, 1, true), (2, 3, 1, true), (3, 3, 1, true),
            (2, 2, 2, true), (3, 2, 2, true), (2, 3, 3, true), (3, 3, 3, true),
            (2, 2, 1, false), (3, 2, 1, false), (2, 3, 1, false), (3, 3, 1, false),
            (2, 2, 2, false), (3, 2, 2, false), (2, 3, 3, false), (3, 3, 3, false))
    };
}

/// The whole storm by the dense models, on the vectors of `isa`.
#[inline(always)]
pub(super) fn run<V: Vector>(
    isa: V::Isa,
    dense: &DenseLinear,
    prepared: &Prepared,
    sink: &mut Sink,
) -> Result<(), Divergence> {
    each_dense_shape!(run_shape, dense, (isa, dense, prepared, sink))
}

/// Whether two batches' dense models have one shape and their inputs one schedule, so that
/// [`run_pair`] can run them side by side.
pub(super) fn pairable(dense: [&DenseLinear; 2], prepared: [&Prepared; 2]) -> bool {
    let [a, b] = dense;
    let law = |l: &DenseLaw, k: &DenseLaw| l.read == k.read && l.knees == k.knees && l.exponent == k.exponent;
    let laws = match (&a.law, &b.law) {
        (Some(l), Some(k)) => law(l, k),
        (None, None) => true,
        _ => false,
    };
    laws && (a.constant.len(), a.slots, a.input_slots, a.lower) == (b.constant.len(), b.slots, b.input_slots, b.lower)
        && prepared[0].schedule == prepared[1].schedule
        && prepared[0].steps == prepared[1].steps
}

/// Two batches' peaks side by side through the storm, on the vectors of `isa`; the batches must be
/// [`pairable`].
#[inline(always)]
pub(super) fn run_pair<V: Vector>(
    isa: V::Isa,
    dense: [&DenseLinear; 2],
    prepared: [&Prepared; 2],
    peaks: PairedPeaks,
) -> Result<(), Divergence> {
    each_dense_shape!(run_pair_shape, dense[0], (isa, dense, prepared, peaks))
}
