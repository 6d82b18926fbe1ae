//! Peaks of the responses that need the equations of motion (floor accelerations, damper forces),
//! formed while a metamodel batch runs, from its blocks of modal displacements and loads, every
//! lane at once: the metamodel's histories are never stored, and the loads on the storm's grid are
//! the ones the free run interpolated anyway.
//!
//! The responses are those of [`crate::dynamics::SampleModel`]: velocities by central differences,
//! ÿ_m = (Q_m − Q̄_m − g_m)/M_m − 2ζω_m ẏ_m − ω_m²(y_m − y_m(0)) with g_m = Σ_d G_dm c_d f(v_d),
//! f(v) = sign(v)|v|^α and v_d = Σ_m G_dm ẏ_m. A floor's acceleration is then
//! a = L − N: L = Σ_m φ_m (Q'_m/M_m − 2ζω_m ẏ_m − ω_m²(y_m − y_m(0))), cheap and linear, and
//! N = Σ_d h_d f(v_d) with h_d = c_d Σ_m φ_m G_dm / M_m, which costs a power per damper (forty at
//! every step of 90 000 on the paper's frame: what made a curve slow). N is bounded cheaply:
//! for α ≤ 1, by concavity (Jensen) and |v_d| ≤ Σ_m |G_dm||ẏ_m|,
//! |N| ≤ Σ_d |h_d||v_d|^α ≤ W^{1−α} (Σ_m K_m |ẏ_m|)^α with W = Σ_d |h_d|, K_m = Σ_d |h_d||G_dm|;
//! for α > 1, |N| ≤ W (Σ_m max_d |G_dm| |ẏ_m|)^α. So the peak of |a| is exact while N is
//! computed only at the steps where |L| + bound could beat the running peak, found a chunk of
//! steps at a time. The bound is inflated by 10⁻⁹ against rounding, so the skipped steps are
//! ones that cannot raise the peak. For a profile (forty floors) what is per step is shared: L is
//! Σ_m φ_m ℓ_m from modal linear parts ℓ_m formed once, a floor rules a chunk out from the modes'
//! chunk maxima of |ℓ_m| and |ẏ_m| before looking at its steps, and a step's modal damper forces,
//! once computed, serve every floor.

mod acceleration;
mod exact;
mod gates;
mod lane_models;
mod rms;

use super::response::{Response, damper_below, rms_stride};
use crate::dynamics::power;
use crate::error::{Error, Result};
use crate::simd::{Kernel, LANES, Lanes, Vector, run_widest};
use crate::study::{MAX_MODES, Study};
use crate::surrogate::{ModalScales, MotionSink};
use acceleration::{Floor, Scratch, Steps, reduce_acceleration};
use exact::ExactSteps;
use gates::Gates;
use lane_models::LaneModels;
use rms::sum_squared_accelerations;

/// Steps whose bound is taken together before any of them is looked at one by one.
const CHUNK: usize = 32;
/// Steps of a part of a chunk: in a chunk that is looked at, each part's bound is taken before its
/// steps are, since most steps of such a chunk cannot beat the peak and whole parts are passed over.
const PART: usize = 8;
/// Chunks whose lanes are told apart in one word: a block's chunks are looked at in windows of
/// as many.
const WINDOW: usize = u64::BITS as usize;
/// Relative inflation of the bound against rounding.
const BOUND_MARGIN: f64 = 1e-9;

/// A sink for `responses` over a batch whose lane i holds the physical inputs `inputs[i]` and
/// whose blocks have `scales`, the floors' modal weights read from `shapes[m][floor]`: one peak per
/// response and lane.
pub fn motion_sink(
    study: &Study,
    shapes: &[Vec<f64>],
    responses: &[Response],
    inputs: &[&[f64]],
    scales: &ModalScales,
) -> Result<Box<dyn MotionSink>> {
    let lanes = LaneModels::new(study, inputs, scales)?;
    let targets: Vec<Tracked> = responses
        .iter()
        .map(|response| {
            let target = match *response {
                Response::Acceleration { floor } => {
                    response.check(&study.structure)?;
                    Target::acceleration(&lanes, &shapes.iter().map(|s| s[floor - 1]).collect::<Vec<_>>())
                }
                Response::RmsAcceleration { floor } => {
                    response.check(&study.structure)?;
                    let shape: Vec<f64> = shapes.iter().map(|s| s[floor - 1]).collect();
                    let modal = lanes.inverse_masses.iter().zip(&shape).map(|(c, w)| c.map(|c| w * c)).collect();
                    let stride = rms_stride(study.storm.time_step);
                    Target::RmsAcceleration { shape, modal, stride, squares: [0.0; LANES], steps: 0, sampled: 0 }
                }
                Response::DamperForce { floor } => {
                    response.check(&study.structure)?;
                    Target::DamperForce { damper: damper_below(&study.structure, floor)? }
                }
                _ => {
                    let weights = response.modal_weights(shapes, &study.structure)?.ok_or_else(|| {
                        Error::Internal(format!("the {} is not one floor's combination", response.describe()))
                    })?;
                    let mut offsets = [0.0; LANES];
                    for (w, level) in weights.iter().zip(&scales.levels) {
                        (0..LANES).for_each(|l| offsets[l] = w.mul_add(level[l], offsets[l]));
                    }
                    let gains = weights.iter().zip(&scales.outputs).map(|(w, s)| w * s).collect();
                    Target::Combination { gains, offsets }
                }
            };
            Ok(Tracked { target, best: [0.0; LANES] })
        })
        .collect::<Result<_>>()?;
    let zero = [[0.0; LANES]; MAX_MODES];
    let accelerations = responses.iter().any(Response::is_acceleration);
    let combinations = targets.iter().any(|t| matches!(t.target, Target::Combination { .. }));
    Ok(Box::new(MotionPeaks {
        time_step: study.storm.time_step,
        modes: lanes.inverse_masses.len(),
        lanes,
        stepped: (0..targets.len())
            .filter(|&t| matches!(targets[t].target, Target::Combination { .. } | Target::DamperForce { .. }))
            .collect(),
        targets,
        rest: zero,
        previous: zero,
        current: zero,
        current_input: zero,
        seen: 0,
        velocities: Vec::new(),
        outputs: combinations.then(Vec::new),
        linear: accelerations.then(Vec::new),
        chunk_linear: Vec::new(),
        chunk_speed: Vec::new(),
        part_linear: Vec::new(),
        part_speed: Vec::new(),
        forces: vec![0.0; study.structure.dampers.len()],
        exact: ExactSteps::default(),
        scratch: Scratch::default(),
    }))
}

/// What is tracked.
enum Target {
    /// A floor's acceleration, every lane: L = Σ_m φ_m ℓ_m with ℓ_m the modal linear parts the
    /// sink shares between floors, N = Σ_m modal_m g_m with modal_m = φ_m/M_m and g_m the modal
    /// damper force, and the bound's P and K_m (|N| ≤ P (Σ_m K_m |ŷ'_m|)^α).
    /// `gates`: which chunks and steps could beat each lane's running peak.
    Acceleration { shape: Vec<f64>, modal: Vec<Lanes>, bound: Lanes, k: Vec<Lanes>, gates: Box<Gates> },
    /// A floor's RMS acceleration: Σ a² over every `stride`-th step of the storm so far, every
    /// lane, a formed at each (its dampers' forces, which no bound can spare); the steps seen and
    /// the steps sampled.
    RmsAcceleration { shape: Vec<f64>, modal: Vec<Lanes>, stride: usize, squares: Lanes, steps: usize, sampled: usize },
    /// A damper's force: the peak is c·max|v|^α, so only its fastest velocity is tracked.
    DamperForce { damper: usize },
    /// A combination Σ_m w_m y_m (displacement, drift, stroke): offsets Σ_m w_m level_m per lane
    /// plus Σ_m gains_m ŷ_m with gains_m = w_m s_m.
    Combination { gains: Vec<f64>, offsets: Lanes },
}

impl Target {
    fn acceleration(lanes: &LaneModels, shape: &[f64]) -> Target {
        let modes = shape.len();
        let alpha = lanes.exponent;
        let h: Vec<Lanes> = lanes
            .map
            .iter()
            .zip(&lanes.coefficients)
            .map(|(g, c)| {
                std::array::from_fn(|l| {
                    c[l] * (0..modes).map(|m| shape[m] * g[m] * lanes.inverse_masses[m][l]).sum::<f64>()
                })
            })
            .collect();
        let mut bound = [0.0; LANES];
        let mut k = vec![[0.0; LANES]; modes];
        for l in 0..LANES {
            let total: f64 = h.iter().map(|h| h[l].abs()).sum();
            for (m, k) in k.iter_mut().enumerate() {
                let used = || lanes.velocity_map.iter().zip(&h).filter(|(_, h)| h[l] != 0.0);
                k[l] = if alpha <= 1.0 {
                    used().map(|(g, h)| h[l].abs() * g[m].abs()).sum()
                } else {
                    used().map(|(g, _)| g[m].abs()).fold(0.0, f64::max)
                };
            }
            bound[l] = if alpha <= 1.0 { total.powf(1.0 - alpha) } else { total };
        }
        let modal = lanes.inverse_masses.iter().zip(shape).map(|(c, w)| c.map(|c| w * c)).collect();
        Target::Acceleration { shape: shape.to_vec(), modal, bound, k, gates: Box::default() }
    }
}

/// A response tracked through the storm and its running peak in every lane (|a|, max |v| for a
/// damper force, |u| for a combination).
struct Tracked {
    target: Target,
    best: Lanes,
}

/// Modal values of every lane, for up to [`MAX_MODES`] modes.
type Modal = [Lanes; MAX_MODES];

struct MotionPeaks {
    time_step: f64,
    modes: usize,
    lanes: LaneModels,
    targets: Vec<Tracked>,
    /// The combinations and damper forces ([`MotionPeaks::reduce_stepped`]).
    stepped: Vec<usize>,
    /// ŷ(0), and the last block's last two outputs and last inputs: a step is processed once its
    /// successor has arrived, for its central difference.
    rest: Modal,
    previous: Modal,
    current: Modal,
    current_input: Modal,
    seen: usize,
    /// The block's processed steps, every lane, `[i·M + m]`: the scaled modal velocities ŷ'_m and,
    /// when an acceleration is tracked, the modal linear parts
    /// ℓ_m = (r_m/M_m) q̂_m − 2ζω_m s_m ŷ'_m − ω_m² s_m (ŷ_m − ŷ_m(0)), shared by every floor.
    velocities: Vec<Lanes>,
    linear: Option<Vec<Lanes>>,
    /// Per chunk of [`CHUNK`] steps and mode, max |ℓ_m| and max |ŷ'_m|, `[c·M + m]`: a floor's
    /// chunk is ruled out by Σ_m |φ_m| max|ℓ_m| and Σ_m K_m max|ŷ'_m| without looking at its steps.
    chunk_linear: Vec<Lanes>,
    chunk_speed: Vec<Lanes>,
    /// The same per part of [`PART`] steps, `[p·M + m]`.
    part_linear: Vec<Lanes>,
    part_speed: Vec<Lanes>,
    /// The block's processed steps' scaled outputs ŷ_m, `[i·M + m]`, kept when a combination is
    /// tracked.
    outputs: Option<Vec<Lanes>>,
    /// Scratch: one lane's damper velocities, then f(v), at a step computed exactly.
    forces: Vec<f64>,
    exact: ExactSteps,
    scratch: Scratch,
}

impl MotionSink for MotionPeaks {
    fn take(&mut self, _first: usize, outputs: &[Lanes], inputs: &[Lanes]) {
        // The accelerations' reduction on the widest vectors: on AVX-512 every step works on
        // eight lanes, one register instead of two (a fifth less time for a profile, measured);
        // the combinations alone gained nothing from it and keep the baseline code.
        if self.linear.is_some() {
            run_widest(TakeBlock { peaks: self, outputs, inputs });
        } else {
            self.take_block(outputs, inputs);
        }
    }

    fn finish(&mut self) -> Vec<Lanes> {
        self.finish_storm()
    }
}

/// [`MotionPeaks::take_block`] as a kernel, compiled for each instruction set: everything it calls
/// for the accelerations is `#[inline(always)]`, so that it is compiled for those features too.
struct TakeBlock<'a> {
    peaks: &'a mut MotionPeaks,
    outputs: &'a [Lanes],
    inputs: &'a [Lanes],
}

impl Kernel for TakeBlock<'_> {
    type Output = ();
    #[inline(always)]
    fn run<V: Vector>(self, _: V::Isa) {
        self.peaks.take_block(self.outputs, self.inputs);
    }
}

impl MotionPeaks {
    /// A block of outputs and inputs: the velocities and linear parts of its steps, then its
    /// responses into their running peaks.
    #[inline(always)]
    fn take_block(&mut self, outputs: &[Lanes], inputs: &[Lanes]) {
        let modes = self.modes;
        let count = outputs.len() / modes;
        let at = |k: usize| &outputs[k * modes..(k + 1) * modes];
        let input_at = |k: usize| &inputs[k * modes..(k + 1) * modes];
        let (previous, current, current_input) = (self.previous, self.current, self.current_input);
        self.velocities.clear();
        // Block step i is the successor of the step processed with it, s = (first + i) − 1.
        for i in 0..count {
            let seen = self.seen + i;
            if seen == 0 {
                self.rest[..modes].copy_from_slice(at(0));
                continue;
            }
            let (here, input) =
                if i == 0 { (&current[..modes], &current_input[..modes]) } else { (at(i - 1), input_at(i - 1)) };
            let (before, scale) = match (seen, i) {
                (1, _) => (here, 1.0 / self.time_step),
                (_, 0) => (&previous[..modes], 0.5 / self.time_step),
                (_, 1) => (&current[..modes], 0.5 / self.time_step),
                _ => (at(i - 2), 0.5 / self.time_step),
            };
            for (after, before) in at(i).iter().zip(before) {
                self.velocities.push(std::array::from_fn(|l| (after[l] - before[l]) * scale));
            }
            self.step(here, input);
        }
        if count > 0 {
            self.previous[..modes].copy_from_slice(if count > 1 { at(count - 2) } else { &current[..modes] });
            self.current[..modes].copy_from_slice(at(count - 1));
            self.current_input[..modes].copy_from_slice(input_at(count - 1));
            self.seen += count;
        }
        self.reduce();
    }

    fn finish_storm(&mut self) -> Vec<Lanes> {
        let modes = self.modes;
        self.velocities.clear();
        if self.seen > 0 {
            let scale = if self.seen > 1 { 1.0 / self.time_step } else { 0.0 };
            let (current, previous, input) = (self.current, self.previous, self.current_input);
            for m in 0..modes {
                self.velocities.push(std::array::from_fn(|l| (current[m][l] - previous[m][l]) * scale));
            }
            self.step(&current[..modes], &input[..modes]);
        }
        self.reduce();
        let (coefficients, alpha) = (&self.lanes.coefficients, self.lanes.exponent);
        self.targets
            .iter()
            .map(|tracked| match tracked.target {
                Target::DamperForce { damper } => {
                    std::array::from_fn(|l| (coefficients[damper][l] * power(tracked.best[l], alpha)).abs())
                }
                Target::RmsAcceleration { squares, sampled, .. } => squares.map(|s| (s / sampled.max(1) as f64).sqrt()),
                _ => tracked.best,
            })
            .collect()
    }

    /// The step whose velocities were pushed last, from its outputs `y` and inputs `q`: kept for
    /// the combinations, and its modal linear parts ℓ_m.
    #[inline(always)]
    fn step(&mut self, y: &[Lanes], q: &[Lanes]) {
        if let Some(outputs) = &mut self.outputs {
            outputs.extend_from_slice(y);
        }
        let v = &self.velocities[self.velocities.len() - self.modes..];
        if let Some(linear) = &mut self.linear {
            let lanes = &self.lanes;
            for m in 0..self.modes {
                let (y, q, v, rest) = (&y[m], &q[m], &v[m], &self.rest[m]);
                let (load, damping, stiffness) = (&lanes.load_gains[m], &lanes.damping[m], &lanes.stiffness[m]);
                linear.push(std::array::from_fn(|l| {
                    load[l].mul_add(q[l], (-damping[l]).mul_add(v[l], -stiffness[l] * (y[l] - rest[l])))
                }));
            }
        }
    }

    /// The block's combinations and damper velocities into their running peaks, a chunk of
    /// [`CHUNK`] steps at a time: each is Σ_m g_m x_m (plus an offset) over the outputs or the
    /// velocities, and evaluated with the chunk's extremes of x_m in place of x_m, the same
    /// multiply-adds bound it over the chunk exactly (a rounded multiply-add is monotone in each
    /// argument); only chunks whose bound beats some lane's peak are looked at step by step.
    fn reduce_stepped(&mut self) {
        let modes = self.modes;
        let count = self.velocities.len() / modes;
        let dampers = self.targets.iter().any(|t| matches!(t.target, Target::DamperForce { .. }));
        let none = [[[0.0; LANES]; 2]; MAX_MODES];
        for first in (0..count).step_by(CHUNK) {
            let range = first * modes..(first + CHUNK).min(count) * modes;
            let outputs: &[Lanes] = self.outputs.as_ref().map_or(&[], |o| &o[range.clone()]);
            let velocities = &self.velocities[range];
            let output_range = if self.outputs.is_some() { ranges(outputs, modes) } else { none };
            let velocity_range = if dampers { ranges(velocities, modes) } else { none };
            for &t in &self.stepped {
                let Tracked { target, best } = &mut self.targets[t];
                let (gains, start, values, extremes) = match target {
                    Target::Combination { gains, offsets } => (&gains[..], *offsets, outputs, &output_range),
                    Target::DamperForce { damper } => {
                        (&self.lanes.velocity_map[*damper][..], [0.0; LANES], velocities, &velocity_range)
                    }
                    Target::Acceleration { .. } | Target::RmsAcceleration { .. } => continue,
                };
                let (mut high, mut low) = (start, start);
                for (m, g) in gains.iter().enumerate() {
                    let (up, down) = if *g >= 0.0 { (1, 0) } else { (0, 1) };
                    (0..LANES).for_each(|l| {
                        high[l] = g.mul_add(extremes[m][up][l], high[l]);
                        low[l] = g.mul_add(extremes[m][down][l], low[l]);
                    });
                }
                if (0..LANES).all(|l| high[l].max(-low[l]) <= best[l]) {
                    continue;
                }
                for step in values.chunks_exact(modes) {
                    let mut u = start;
                    for (g, x) in gains.iter().zip(step) {
                        (0..LANES).for_each(|l| u[l] = g.mul_add(x[l], u[l]));
                    }
                    (0..LANES).for_each(|l| best[l] = best[l].max(u[l].abs()));
                }
            }
        }
        if let Some(outputs) = &mut self.outputs {
            outputs.clear();
        }
    }

    /// The block's responses into their running peaks.
    #[inline(always)]
    fn reduce(&mut self) {
        if !self.stepped.is_empty() {
            self.reduce_stepped();
        }
        if let Some(linear) = &mut self.linear {
            let modes = self.modes;
            let count = self.velocities.len() / modes;
            magnitudes_by_group(&mut self.part_linear, linear, PART, modes);
            magnitudes_by_group(&mut self.part_speed, &self.velocities, PART, modes);
            magnitudes_by_group(&mut self.chunk_linear, &self.part_linear, CHUNK / PART, modes);
            magnitudes_by_group(&mut self.chunk_speed, &self.part_speed, CHUNK / PART, modes);
            self.exact.next_block(count);
            let steps = Steps {
                velocities: &self.velocities,
                linear,
                chunk_linear: &self.chunk_linear,
                chunk_speed: &self.chunk_speed,
                part_linear: &self.part_linear,
                part_speed: &self.part_speed,
                modes,
            };
            for Tracked { target, best } in &mut self.targets {
                match target {
                    Target::Acceleration { shape, modal, bound, k, gates } => {
                        let floor = Floor { shape, modal, bound, k, gates };
                        let work = (&mut self.forces[..], &mut self.exact, &mut self.scratch);
                        reduce_acceleration(&self.lanes, &steps, floor, best, work);
                    }
                    Target::RmsAcceleration { shape, modal, stride, squares, steps: seen, sampled } => {
                        // The block's steps that are the storm's multiples of the stride.
                        let first = (*stride - *seen % *stride) % *stride;
                        let work = (&mut self.forces[..], &mut self.exact);
                        let sampling = (first, *stride);
                        *sampled +=
                            sum_squared_accelerations(&self.lanes, &steps, (shape, modal), sampling, squares, work);
                        *seen += count;
                    }
                    _ => {}
                }
            }
            linear.clear();
        }
        self.velocities.clear();
    }
}

/// Per group of `steps` steps of `values` (`[i·M + m]`) and mode, the largest magnitude, every
/// lane: `maxima[g·M + m]`.
#[inline(always)]
fn magnitudes_by_group(maxima: &mut Vec<Lanes>, values: &[Lanes], steps: usize, modes: usize) {
    maxima.clear();
    for group in values.chunks(steps * modes) {
        for m in 0..modes {
            let mut most = [0.0f64; LANES];
            // Whole steps and an index rather than `step_by`, whose per-item state kept the
            // maxima out of registers (an eighth of the sink's time, measured).
            for x in group.chunks_exact(modes) {
                (0..LANES).for_each(|l| most[l] = most[l].max(x[m][l].abs()));
            }
            maxima.push(most);
        }
    }
}

/// Per mode the lowest and highest of `values` (`[i·M + m]`), every lane: `[m][0]` and `[m][1]`.
fn ranges(values: &[Lanes], modes: usize) -> [[Lanes; 2]; MAX_MODES] {
    let mut extremes = [[[f64::INFINITY; LANES], [f64::NEG_INFINITY; LANES]]; MAX_MODES];
    for step in values.chunks_exact(modes) {
        for (x, [low, high]) in step.iter().zip(&mut extremes) {
            (0..LANES).for_each(|l| {
                low[l] = low[l].min(x[l]);
                high[l] = high[l].max(x[l]);
            });
        }
    }
    extremes
}

#[cfg(test)]
mod tests;
