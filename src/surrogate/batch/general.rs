//! The free run of any structure, from term lists: a block of [`BLOCK`] steps at a time, each
//! block's inputs interpolated first, then each step's terms summed mode by mode. The dense
//! recursion (`dense`) covers the paper's structures faster; this path covers the rest (powers,
//! products of inputs and outputs, long lags).

use super::ModeProgram;
use super::inputs::{Prepared, interpolate, splat_weights};
use super::samples::longest_lag;
use super::sink::{BLOCK, Divergence, Sink, first_divergence};
use crate::simd::{LANES, Lanes};
use crate::surrogate::damper_law::secant_lanes;
use crate::surrogate::narx::DamperTerm;

/// A term with its sources resolved and its coefficient in every lane.
#[derive(Debug, Clone, Copy)]
struct Term {
    /// The mode whose output the term reads.
    source: usize,
    output_lag: usize,
    output_power: u32,
    input_lag: usize,
    input_power: u32,
    coefficient: Lanes,
}

/// A damper term: c·D(Δ_source) = c·Δ_source·S(Δ_source), or with `modulated` c·Δ_own·S(Δ_source),
/// Δ the first difference at `lag`; Δ_source and S are the step's number `secant` of
/// [`TermLists::secants`].
#[derive(Debug, Clone, Copy)]
struct LawTerm {
    modulated: bool,
    lag: usize,
    secant: usize,
    coefficient: Lanes,
}

/// A secant S(Δ) the damper terms of a step read: of mode `source`'s first difference at `lag`,
/// with that mode's knee.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Secant {
    source: usize,
    lag: usize,
    knee: f64,
}

/// The batch's models as lists of terms, sorted by what they read.
pub(super) struct TermLists {
    /// Per mode, the terms that read only the input (and the constant); they come first in a step,
    /// off the critical path of the recursion.
    exogenous: Vec<Vec<Term>>,
    /// Per mode, the terms c·y_source(t − lag), the common case, as (how far back in `outputs`, c).
    linear: Vec<Vec<(usize, Lanes)>>,
    /// Per mode, the other terms that read an output.
    feedback: Vec<Vec<Term>>,
    /// Per mode, the terms of the dampers' law.
    damper: Vec<Vec<LawTerm>>,
    /// The distinct secants the damper terms read, each computed once a step: the default
    /// structures read mode 1's at lag 1 in every mode (D(y1), Δy·S(y1)), and a power is the
    /// costliest operation of the recursion.
    secants: Vec<Secant>,
    /// The dampers' exponent α (unused without damper terms).
    exponent: f64,
    /// Longest lag: the steps each block carries over from the one before.
    history: usize,
}

impl TermLists {
    /// `coefficient(m, k)`: term k of mode m's coefficient in every lane.
    pub(super) fn new(programs: &[ModeProgram], coefficient: impl Fn(usize, usize) -> Lanes) -> Self {
        let modes = programs.len();
        let mut lists = TermLists {
            exogenous: vec![Vec::new(); modes],
            linear: vec![Vec::new(); modes],
            feedback: vec![Vec::new(); modes],
            damper: vec![Vec::new(); modes],
            secants: Vec::new(),
            exponent: programs.iter().find_map(|p| p.law).map_or(1.0, |law| law.exponent),
            history: longest_lag(programs),
        };
        for (m, program) in programs.iter().enumerate() {
            for (k, t) in program.terms.iter().enumerate() {
                let term = Term {
                    source: t.output_mode.unwrap_or(m),
                    output_lag: t.output_lag,
                    output_power: t.output_power,
                    input_lag: t.input_lag,
                    input_power: t.input_power,
                    coefficient: coefficient(m, k),
                };
                if let Some(kind) = t.damper {
                    let law = program.law.expect("a damper term runs with its damper law");
                    let secant = Secant { source: term.source, lag: t.output_lag, knee: law.knees[term.source] };
                    let index = lists.secants.iter().position(|s| *s == secant).unwrap_or_else(|| {
                        lists.secants.push(secant);
                        lists.secants.len() - 1
                    });
                    lists.damper[m].push(LawTerm {
                        modulated: kind == DamperTerm::Modulated && term.source != m,
                        lag: t.output_lag,
                        secant: index,
                        coefficient: term.coefficient,
                    });
                    continue;
                }
                match (t.output_power, t.input_power) {
                    (0, _) => lists.exogenous[m].push(term),
                    // Output t−lag of mode `source` sits lag·modes − source entries before this step's first.
                    (1, 0) => lists.linear[m].push((t.output_lag * modes - term.source, term.coefficient)),
                    _ => lists.feedback[m].push(term),
                }
            }
        }
        lists
    }
}

/// The whole storm by the term lists. `inputs` and `outputs` hold `history` carried-over steps,
/// then the block, the modes interleaved: outputs[(h + i)·modes + m]. Before t = 0 the outputs are
/// at rest and the input deviations zero.
#[inline(always)]
pub(super) fn run(lists: &TermLists, prepared: &Prepared, sink: &mut Sink) -> Result<(), Divergence> {
    let &Prepared { rests, ref schedule, coarse, steps } = prepared;
    let modes = rests.len();
    let h = lists.history;
    let mut inputs: Vec<Lanes> = vec![[0.0; LANES]; (h + BLOCK) * modes];
    let mut outputs: Vec<Lanes> = (0..(h + BLOCK) * modes).map(|k| rests[k % modes]).collect();
    let mut laws = vec![([0.0; LANES], [0.0; LANES]); lists.secants.len()];
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
                    inputs[(h + i) * modes + m] = interpolate::<Lanes>((), lanes, p, &splat_weights((), w));
                }
            },
        );
        step_block(lists, &inputs, &mut outputs, &mut laws, usize::from(first == 0), len);
        let block = &outputs[h * modes..(h + len) * modes];
        let block_inputs = &inputs[h * modes..(h + len) * modes];
        // Checked once a block, so that the lanes never branch apart inside the recursion.
        if let Some(divergence) = first_divergence(block, modes, first) {
            return Err(divergence);
        }
        match sink {
            Sink::Blocks(consume) => consume(first, block, block_inputs),
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

/// Steps `from..len` of a block: the step's source velocities and their secants first
/// (`laws`, one per [`TermLists::secants`], kept by the caller), then each mode's input terms
/// (off the recursion's critical path), then its output terms.
#[inline(always)]
fn step_block(
    lists: &TermLists,
    inputs: &[Lanes],
    outputs: &mut [Lanes],
    laws: &mut [(Lanes, Lanes)],
    from: usize,
    len: usize,
) {
    let modes = lists.linear.len();
    let h = lists.history;
    for i in from..len {
        let here = (h + i) * modes;
        // Damper terms read earlier steps only (lag ≥ 1), so the step's secants come first.
        for ((difference, value), secant) in laws.iter_mut().zip(&lists.secants) {
            let (near, far) = (
                &outputs[here - secant.lag * modes + secant.source],
                &outputs[here - (secant.lag + 1) * modes + secant.source],
            );
            *difference = std::array::from_fn(|l| near[l] - far[l]);
            *value = secant_lanes(*difference, secant.knee, lists.exponent);
        }
        for m in 0..modes {
            let mut value = [0.0; LANES];
            for term in &lists.exogenous[m] {
                let c = &term.coefficient;
                match term.input_power {
                    0 => (0..LANES).for_each(|l| value[l] += c[l]),
                    p => {
                        let g = power(&inputs[here - term.input_lag * modes + m], p);
                        (0..LANES).for_each(|l| value[l] = c[l].mul_add(g[l], value[l]));
                    }
                }
            }
            for (back, c) in &lists.linear[m] {
                let y = &outputs[here - back];
                for l in 0..LANES {
                    value[l] = c[l].mul_add(y[l], value[l]);
                }
            }
            for term in &lists.damper[m] {
                let (source_difference, secant) = &laws[term.secant];
                // Δ·S(Δ) is the law D(Δ), lane by lane `DamperLaw::value` to the bit.
                let g: Lanes = if term.modulated {
                    let (near, far) = (here - term.lag * modes + m, here - (term.lag + 1) * modes + m);
                    std::array::from_fn(|l| (outputs[near][l] - outputs[far][l]) * secant[l])
                } else {
                    std::array::from_fn(|l| source_difference[l] * secant[l])
                };
                for l in 0..LANES {
                    value[l] = term.coefficient[l].mul_add(g[l], value[l]);
                }
            }
            for term in &lists.feedback[m] {
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
