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

/// What the dense recursion does with each step's outputs, inside its own loop.
trait StepSink<V: Vector, const M: usize> {
    /// Step `i` of the block (counted from the block's first step) read `q[m]` and gave `y[m]`,
    /// every lane.
    fn take(&mut self, i: usize, y: &[V; M], q: &[V; M]);
}

/// Per lane the running peak of |offset + Σ_m gain_m ŷ_m| (see [`Sink::Peaks`]).
struct PeakTracker<V, const M: usize> {
    gains: [V; M],
    offsets: V,
    peaks: V,
}

impl<V: Vector, const M: usize> StepSink<V, M> for PeakTracker<V, M> {
    #[inline(always)]
    fn take(&mut self, _: usize, y: &[V; M], _: &[V; M]) {
        let mut u = self.offsets;
        for (gain, y) in self.gains.iter().zip(y) {
            u = gain.mul_add(*y, u);
        }
        // A NaN is caught by the divergence test of the block, whatever `max` makes of it.
        self.peaks = u.abs().max(self.peaks);
    }
}

/// The block's outputs and inputs as `outputs[i·M + m]`, `inputs[i·M + m]`.
struct Recorder<'a> {
    outputs: &'a mut [Lanes],
    inputs: &'a mut [Lanes],
}

impl<V: Vector, const M: usize> StepSink<V, M> for Recorder<'_> {
    #[inline(always)]
    fn take(&mut self, i: usize, y: &[V; M], q: &[V; M]) {
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

/// Steps `first..first + len` (first ≥ 1) by the dense linear models, M modes, K output lag slots
/// and KI input lag slots (LOWER: no mode reads a later one, see [`DenseLinear::lower`]), each
/// step's inputs interpolated from the lane-major coarse inputs and its outputs handed to `sink` as step `i + sink_offset`. Returns the sum over the steps of each
/// lane's squared outputs, which the caller tests for divergence once per block. Interpolation,
/// recursion, reduction and check share one loop, so the outputs never go through memory; the sum
/// of each step takes the constant, the inputs, the older outputs and the newest outputs last, so
/// that only the last few operations wait on the previous step.
#[inline(always)]
#[allow(clippy::needless_range_loop, clippy::too_many_arguments)] // index loops over the fixed sizes
fn advance<V: Vector, const M: usize, const K: usize, const KI: usize, const LOWER: bool>(
    isa: V::Isa,
    dense: &DenseLinear,
    schedule: &CubicSchedule,
    coarse: &[Vec<Lanes>],
    carry: &mut Carry<V, M>,
    first: usize,
    len: usize,
    sink_offset: usize,
    sink: &mut impl StepSink<V, M>,
) -> Lanes {
    let zero = V::splat(isa, 0.0);
    let mut constant = [zero; M];
    let mut input = [[zero; M]; KI];
    let mut output = [[[zero; M]; M]; K];
    let mut modes: [&[Lanes]; M] = [&[]; M];
    for m in 0..M {
        constant[m] = V::load(isa, &dense.constant[m]);
        modes[m] = &coarse[m];
        for k in 0..K {
            if k < KI {
                input[k][m] = V::load(isa, &dense.input[k * M + m]);
            }
            for s in 0..M {
                output[k][m][s] = V::load(isa, &dense.output[(k * M + m) * M + s]);
            }
        }
    }
    let minus_one = V::splat(isa, -1.0);
    let mut law_coefficient = [[zero; M]; M];
    let mut modulated_coefficient = [[zero; M]; M];
    let mut modulated = false;
    if let Some(law) = &dense.law {
        for m in 0..M {
            for s in 0..M {
                law_coefficient[m][s] = V::load(isa, &law.coefficient[m * M + s]);
                modulated_coefficient[m][s] = V::load(isa, &law.modulated[m * M + s]);
                modulated |= law.modulated[m * M + s].iter().any(|c| *c != 0.0);
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
            let w = splat_weights::<V>(isa, w);
            let mut q = [zero; M];
            for m in 0..M {
                q[m] = interpolate(isa, modes[m], p, &w);
            }
            let mut next = constant;
            if let Some(law) = &dense.law {
                // D(Δ_s) = Δ_s·S(Δ_s) of every lane, vectorised, as the scalar free run and the term
                // lists form it; with modulated terms Δ_m·S(Δ_s) from the same secants.
                let mut differences = [zero; M];
                let mut secants = [zero; M];
                for s in 0..M {
                    differences[s] = minus_one.mul_add(before[s], last[s]);
                    if law.read[s] {
                        let mut difference = [0.0; LANES];
                        differences[s].store(&mut difference);
                        secants[s] = V::load(isa, &secant_lanes(difference, law.knees[s], law.exponent));
                    }
                }
                for m in 0..M {
                    for s in 0..M {
                        next[m] = law_coefficient[m][s].mul_add(differences[s].mul(secants[s]), next[m]);
                    }
                }
                if modulated {
                    for m in 0..M {
                        for s in 0..M {
                            next[m] = modulated_coefficient[m][s].mul_add(differences[m].mul(secants[s]), next[m]);
                        }
                    }
                }
            }
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
            sink.take(i + sink_offset, &next, &q);
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
        recorder.take(0, rest, &carry.last_input);
    }
    advance::<V, M, K, KI, LOWER>(isa, dense, schedule, coarse, carry, from, count, offset, &mut recorder)
}

/// The whole storm by the dense linear models: step 0 at rest, then blocks of [`BLOCK`] steps into
/// `sink`. A block that fails the cheap divergence test is run again from its start into memory
/// and searched, so the error names the first step out of bounds.
#[inline(always)]
fn run_shape<V: Vector, const M: usize, const K: usize, const KI: usize, const LOWER: bool>(
    isa: V::Isa,
    dense: &DenseLinear,
    prepared: &Prepared,
    sink: &mut Sink,
) -> Result<(), Divergence> {
    let &Prepared { rests, ref schedule, coarse, steps } = prepared;
    let zero = V::splat(isa, 0.0);
    let mut rest = [zero; M];
    for (rest, from) in rest.iter_mut().zip(rests) {
        *rest = V::load(isa, from);
    }
    let mut carry = Carry { last: rest, before: rest, last_input: [zero; M], before_input: [zero; M] };
    schedule.for_each(0, 1, |_, p, w| {
        for (input, coarse) in carry.last_input.iter_mut().zip(coarse) {
            *input = interpolate(isa, coarse, p, &splat_weights(isa, w));
        }
    });
    let (mut block, mut inputs) = (vec![[0.0; LANES]; BLOCK * M], vec![[0.0; LANES]; BLOCK * M]);
    let mut first = 0;
    while first < steps {
        let len = BLOCK.min(steps - first);
        // Step 0 is the rest state; every later step is computed.
        let from = first.max(1);
        let (count, offset) = (first + len - from, from - first);
        let start = carry;
        let span = [first, from, count, offset];
        let squares = match sink {
            Sink::Peaks { gains, offsets, peaks } => {
                let mut tracker =
                    PeakTracker { gains: [zero; M], offsets: V::load(isa, offsets), peaks: V::load(isa, peaks) };
                for m in 0..M {
                    tracker.gains[m] = V::splat(isa, gains[m]);
                }
                if first == 0 {
                    tracker.take(0, &rest, &carry.last_input);
                }
                let squares = advance::<V, M, K, KI, LOWER>(
                    isa,
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
        if suspicious(&squares) {
            let mut replay = start;
            record_block::<V, M, K, KI, LOWER>(
                isa,
                dense,
                schedule,
                coarse,
                &rest,
                &mut replay,
                span,
                &mut block,
                &mut inputs,
            );
            if let Some(divergence) = first_divergence(&block[..len * M], M, first) {
                return Err(divergence);
            }
        }
        if let Sink::Blocks(consume) = sink {
            consume(first, &block[..len * M], &inputs[..len * M]);
        }
        first += len;
    }
    Ok(())
}

/// [`run_shape`] for the batch's modes and lags: one instance per (M, K, KI, LOWER) listed, the
/// shapes the paper's structures take (inputs at lag 0 or up to the output lags; one mode is
/// always LOWER).
macro_rules! dense_shapes {
    ($isa:ident, $dense:ident, $prepared:ident, $sink:ident;
     $(($m:literal, $k:literal, $ki:literal, $lower:literal)),*) => {
        match ($dense.constant.len(), $dense.slots, $dense.input_slots, $dense.lower) {
            $(($m, $k, $ki, $lower) => {
                run_shape::<V, $m, $k, $ki, $lower>($isa, $dense, $prepared, $sink)
            })*
            other => unreachable!("no dense recursion for {other:?} (DenseLinear::new admits none)"),
        }
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
    dense_shapes!(isa, dense, prepared, sink;
        (1, 2, 1, true), (1, 3, 1, true), (1, 2, 2, true), (1, 3, 3, true),
        (2, 2, 1, true), (3, 2, 1, true), (2, 3, 1, true), (3, 3, 1, true),
        (2, 2, 2, true), (3, 2, 2, true), (2, 3, 3, true), (3, 3, 3, true),
        (2, 2, 1, false), (3, 2, 1, false), (2, 3, 1, false), (3, 3, 1, false),
        (2, 2, 2, false), (3, 2, 2, false), (2, 3, 3, false), (3, 3, 3, false))
}
