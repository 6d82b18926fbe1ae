//! A floor's peak acceleration over a metamodel block, every lane: the chunks and steps whose
//! bound could beat the running peak, largest first, computed exactly until the bound falls below
//! it (the bound and its use are described in [`super`]).

use super::exact::ExactSteps;
use super::gates::{Gate, Gates};
use super::lane_models::LaneModels;
use super::{BOUND_MARGIN, CHUNK, PART, WINDOW};
use crate::dynamics::power;
use crate::simd::{LANES, Lanes};

/// Per lane, the block's chunks of [`CHUNK`] steps in decreasing order of their bound, and in a
/// chunk its steps likewise, computed exactly until the bound falls below the running peak: the
/// largest accelerations come first and rule out the rest. A chunk's bound comes from the modes'
/// chunk maxima (|L| ≤ Σ_m |φ_m| max|ℓ_m|), so a floor looks at the steps of few chunks only, and
/// in those at the steps of the parts whose own maxima do not rule them out.
#[inline(always)]
pub(super) fn reduce_acceleration(
    lanes: &LaneModels,
    steps: &Steps,
    floor: Floor,
    peaks: &mut Lanes,
    (forces, exact, scratch): (&mut [f64], &mut ExactSteps, &mut Scratch),
) {
    let alpha = lanes.exponent;
    let Floor { shape, modal, bound, k, gates } = floor;
    let Steps { velocities, chunk_linear, chunk_speed, modes, .. } = *steps;
    // (1 + ε)(|L| + P S^α), the power spared by the lowest tangent where there are tangents.
    let most = |gates: &Gates, l: usize, linear: f64, speed: f64| {
        let damper = gates.damper_bound(l, speed);
        let damper = if damper.is_finite() { damper } else { bound[l] * power(speed, alpha) };
        (1.0 + BOUND_MARGIN) * (linear + damper)
    };
    // Each chunk's bounds on |L| and Σ_m K_m|ŷ'_m|, every lane at once.
    (0..LANES).for_each(|l| gates.open_to(l, peaks[l], bound[l], alpha));
    scratch.coarse.clear();
    scratch.coarse.extend(chunk_linear.chunks_exact(modes).zip(chunk_speed.chunks_exact(modes)).map(
        |(most_linear, most_speed)| {
            let (mut x, mut s) = ([0.0f64; LANES], [0.0f64; LANES]);
            for m in 0..modes {
                let (phi, k) = (shape[m].abs(), &k[m]);
                (0..LANES).for_each(|l| {
                    x[l] = phi.mul_add(most_linear[m][l], x[l]);
                    s[l] = k[l].mul_add(most_speed[m][l], s[l]);
                });
            }
            (gates.lanes_that_may_beat(&x, &s), x, s)
        },
    ));
    let Scratch { coarse, chunks, candidates } = scratch;
    // Per window of 64 chunks, each lane's chunks that may beat its peak as the bits of a word,
    // rather than a scan of every chunk's lanes per lane (the function holding that scan took
    // 5.6 % of a profile's time, a quarter of it the test of the lane's bit; measured).
    for (w, window) in coarse.chunks(WINDOW).enumerate() {
        let mut lane_chunks = [0u64; LANES];
        for (c, (lanes, _, _)) in window.iter().enumerate() {
            (0..LANES).for_each(|l| lane_chunks[l] |= u64::from(lanes >> l & 1) << c);
        }
        for (l, best) in peaks.iter_mut().enumerate() {
            chunks.clear();
            let mut bits = lane_chunks[l];
            while bits != 0 {
                let c = bits.trailing_zeros() as usize;
                bits &= bits - 1;
                let (_, linear, speed) = &window[c];
                if gates.lanes[l].may_beat(linear[l], speed[l]) {
                    chunks.push((most(gates, l, linear[l], speed[l]), (w * WINDOW + c) * CHUNK));
                }
            }
            chunks.sort_unstable_by(|a, b| b.0.total_cmp(&a.0));
            for &(chunk_bound, first) in chunks.iter() {
                if chunk_bound <= *best {
                    break;
                }
                gates.open_to(l, *best, bound[l], alpha);
                let bound_of = |linear: f64, speed: f64| most(gates, l, linear, speed);
                chunk_candidates(steps, (shape, k), (&gates.lanes[l], bound_of), (l, first), candidates);
                candidates.sort_unstable_by(|a, b| b.0.total_cmp(&a.0));
                for &(step_bound, i, x) in candidates.iter() {
                    if step_bound <= *best {
                        break;
                    }
                    let g = exact.modal_forces(i, l, velocities, lanes, forces);
                    let dampers: f64 = modal.iter().zip(g).map(|(modal, g)| modal[l] * g).sum();
                    *best = best.max((x - dampers).abs());
                }
            }
        }
    }
}

/// In `candidates` (cleared first), (bound, step, L) of the steps of lane l's chunk from step `first` that the
/// gate lets through, with `bound` their bound on |a|: the parts of [`PART`] steps are ruled out
/// by their maxima first.
#[inline(always)]
fn chunk_candidates(
    steps: &Steps,
    (shape, k): (&[f64], &[Lanes]),
    (gate, bound): (&Gate, impl Fn(f64, f64) -> f64),
    (l, first): (usize, usize),
    candidates: &mut Vec<(f64, usize, f64)>,
) {
    let Steps { velocities, linear, part_linear, part_speed, modes, .. } = *steps;
    let count = velocities.len() / modes;
    candidates.clear();
    for part in (first..(first + CHUNK).min(count)).step_by(PART) {
        let p = part / PART * modes;
        let (mut x, mut s) = (0.0, 0.0);
        for m in 0..modes {
            x = shape[m].abs().mul_add(part_linear[p + m][l], x);
            s = k[m][l].mul_add(part_speed[p + m][l], s);
        }
        if !gate.may_beat(x, s) {
            continue;
        }
        for i in part..(part + PART).min(count) {
            let (mut x, mut s) = (0.0, 0.0);
            for m in 0..modes {
                x = shape[m].mul_add(linear[i * modes + m][l], x);
                s = k[m][l].mul_add(velocities[i * modes + m][l].abs(), s);
            }
            if gate.may_beat(x.abs(), s) {
                candidates.push((bound(x.abs(), s), i, x));
            }
        }
    }
}

/// A block's processed steps as an acceleration's reduction reads them, every lane: the modal
/// velocities ŷ'_m and linear parts ℓ_m, `[i·M + m]`, and their maxima of magnitude per chunk,
/// `[c·M + m]`, and per part, `[p·M + m]`.
pub(super) struct Steps<'a> {
    pub(super) velocities: &'a [Lanes],
    pub(super) linear: &'a [Lanes],
    pub(super) chunk_linear: &'a [Lanes],
    pub(super) chunk_speed: &'a [Lanes],
    pub(super) part_linear: &'a [Lanes],
    pub(super) part_speed: &'a [Lanes],
    pub(super) modes: usize,
}

/// A floor's acceleration as [`super::Target::Acceleration`] holds it.
pub(super) struct Floor<'a> {
    pub(super) shape: &'a [f64],
    pub(super) modal: &'a [Lanes],
    pub(super) bound: &'a Lanes,
    pub(super) k: &'a [Lanes],
    pub(super) gates: &'a mut Gates,
}

/// Buffers reused from block to block: the floor's chunk bounds (the lanes they may beat, |L| and
/// Σ_m K_m|ŷ'_m| every lane),
/// one lane's chunks (bound, first step) and one chunk's steps (bound, step, L).
#[derive(Default)]
pub(super) struct Scratch {
    pub(super) coarse: Vec<(u8, Lanes, Lanes)>,
    pub(super) chunks: Vec<(f64, usize)>,
    pub(super) candidates: Vec<(f64, usize, f64)>,
}
