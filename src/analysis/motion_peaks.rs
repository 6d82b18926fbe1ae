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
//! ones that cannot raise the peak.

use super::Response;
use crate::dynamics::power;
use crate::error::{Error, Result};
use crate::problem::{MAX_MODES, Problem};
use crate::surrogate::{LANES, Lanes, ModalScales, MotionSink};

/// Steps whose bound is tested together before any of them is looked at one by one.
const CHUNK: usize = 32;
/// Relative inflation of the bound against rounding.
const BOUND_MARGIN: f64 = 1e-9;

/// A sink for `response` (an acceleration or a damper force) over a batch whose lane i holds the
/// physical inputs `inputs[i]` and whose blocks have `scales`, the floors' modal weights read from
/// `shapes[m][floor]`.
pub fn motion_sink(
    problem: &Problem,
    shapes: &[Vec<f64>],
    response: Response,
    inputs: &[&[f64]],
    scales: &ModalScales,
) -> Result<Box<dyn MotionSink>> {
    response.check(&problem.structure)?;
    let lanes = LaneModels::new(problem, inputs, scales)?;
    let target = match response {
        Response::Acceleration { floor } => {
            Target::acceleration(&lanes, &shapes.iter().map(|s| s[floor - 1]).collect::<Vec<_>>())
        }
        Response::DamperForce { floor } => {
            let damper = problem.structure.dampers.iter().position(|d| d.upper_floor + 1 == floor);
            Target::DamperForce {
                damper: damper
                    .ok_or_else(|| Error::invalid("floor", format!("the storey below floor {floor} has no damper")))?,
            }
        }
        other => unreachable!("{} is a combination of the modal displacements", other.kind()),
    };
    let zero = [[0.0; LANES]; MAX_MODES];
    Ok(Box::new(MotionPeaks {
        time_step: problem.storm.time_step,
        modes: lanes.inverse_masses.len(),
        lanes,
        target,
        rest: zero,
        previous: zero,
        current: zero,
        current_load: zero,
        seen: 0,
        chunk: Chunk::empty(),
        forces: vec![0.0; problem.structure.dampers.len()],
        best: [0.0; LANES],
    }))
}

/// The reduced models of a batch's samples, lane-major, with the blocks' scales folded in: the
/// sink works on the scaled outputs ŷ_m and inputs q̂_m as the free run gives them, and on the
/// scaled velocities ŷ'_m (y'_m = s_m ŷ'_m), so that nothing is converted step by step.
struct LaneModels {
    /// 1/M_m (for h_d), r_m/M_m, 2ζω_m s_m and ω_m² s_m per mode, every lane (s_m, r_m: the
    /// output and input scales).
    inverse_masses: Vec<Lanes>,
    load_gains: Vec<Lanes>,
    damping: Vec<Lanes>,
    stiffness: Vec<Lanes>,
    /// Per damper its coefficient c_d in every lane, G_dm per mode and G_dm s_m, the damper's
    /// velocity per scaled modal velocity (the same in every lane: the shapes are fixed across
    /// samples).
    coefficients: Vec<Lanes>,
    map: Vec<Vec<f64>>,
    velocity_map: Vec<Vec<f64>>,
    exponent: f64,
}

impl LaneModels {
    fn new(problem: &Problem, inputs: &[&[f64]], scales: &ModalScales) -> Result<Self> {
        let modes = problem.modes.count();
        let mut lanes = LaneModels {
            inverse_masses: vec![[0.0; LANES]; modes],
            load_gains: vec![[0.0; LANES]; modes],
            damping: vec![[0.0; LANES]; modes],
            stiffness: vec![[0.0; LANES]; modes],
            coefficients: Vec::new(),
            map: Vec::new(),
            velocity_map: Vec::new(),
            exponent: problem.damper_exponent,
        };
        for (lane, x) in inputs.iter().enumerate() {
            let p = problem.parameters(x)?;
            let (modes, dampers) = (problem.sample_modes(&p), problem.dampers(&p)?);
            for m in 0..modes.count() {
                let omega = modes.frequencies[m];
                lanes.inverse_masses[m][lane] = 1.0 / modes.modal_masses[m];
                lanes.load_gains[m][lane] = scales.inputs[m] / modes.modal_masses[m];
                lanes.damping[m][lane] = 2.0 * p.damping_ratio * omega * scales.outputs[m];
                lanes.stiffness[m][lane] = omega * omega * scales.outputs[m];
            }
            if lane == 0 {
                lanes.map = dampers
                    .modal_map(modes.shapes.as_ref())
                    .iter()
                    .map(|row| row.iter().map(|g| g.1).collect())
                    .collect();
                lanes.coefficients = vec![[0.0; LANES]; dampers.coefficients.len()];
                lanes.velocity_map =
                    lanes.map.iter().map(|g| g.iter().zip(&scales.outputs).map(|(g, s)| g * s).collect()).collect();
            }
            for (to, &c) in lanes.coefficients.iter_mut().zip(&dampers.coefficients) {
                to[lane] = c;
            }
        }
        Ok(lanes)
    }
}

/// What is tracked.
enum Target {
    /// A floor's acceleration: its modal weights φ_m, h_d per damper and the bound's P and K_m
    /// (|N| ≤ P (Σ_m K_m |ẏ_m|)^α), every lane.
    Acceleration { weights: Vec<f64>, h: Vec<Lanes>, bound: Lanes, k: Vec<Lanes> },
    /// A damper's force: the peak is c·max|v|^α, so only its fastest velocity is tracked.
    DamperForce { damper: usize },
}

impl Target {
    fn acceleration(lanes: &LaneModels, weights: &[f64]) -> Target {
        let modes = weights.len();
        let alpha = lanes.exponent;
        let h: Vec<Lanes> = lanes
            .map
            .iter()
            .zip(&lanes.coefficients)
            .map(|(g, c)| {
                std::array::from_fn(|l| {
                    c[l] * (0..modes).map(|m| weights[m] * g[m] * lanes.inverse_masses[m][l]).sum::<f64>()
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
        Target::Acceleration { weights: weights.to_vec(), h, bound, k }
    }
}

/// The steps of a chunk awaiting the bound's test, every lane: L and Σ_m K_m|ẏ_m| per step, the
/// modal velocities, and the chunk's largest |L| and Σ_m K_m|ẏ_m|.
struct Chunk {
    len: usize,
    linear: [Lanes; CHUNK],
    speed: [Lanes; CHUNK],
    velocities: [[Lanes; MAX_MODES]; CHUNK],
    largest_linear: Lanes,
    largest_speed: Lanes,
}

impl Chunk {
    fn empty() -> Box<Chunk> {
        Box::new(Chunk {
            len: 0,
            linear: [[0.0; LANES]; CHUNK],
            speed: [[0.0; LANES]; CHUNK],
            velocities: [[[0.0; LANES]; MAX_MODES]; CHUNK],
            largest_linear: [0.0; LANES],
            largest_speed: [0.0; LANES],
        })
    }
}

/// Modal values of every lane, for up to [`MAX_MODES`] modes.
type Modal = [Lanes; MAX_MODES];

struct MotionPeaks {
    time_step: f64,
    modes: usize,
    lanes: LaneModels,
    target: Target,
    /// y(0), and the last block's last two displacements and last loads: a step is processed
    /// when its successor arrives, for its central difference.
    rest: Modal,
    previous: Modal,
    current: Modal,
    current_load: Modal,
    seen: usize,
    chunk: Box<Chunk>,
    /// Scratch: one lane's damper velocities, then f(v), at a step computed exactly.
    forces: Vec<f64>,
    /// The running peak: |a| for an acceleration, max |v| for a damper force.
    best: Lanes,
}

impl MotionSink for MotionPeaks {
    fn take(&mut self, _first: usize, outputs: &[Lanes], inputs: &[Lanes]) {
        let modes = self.modes;
        let steps = outputs.len() / modes;
        let at = |k: usize| &outputs[k * modes..(k + 1) * modes];
        let load_at = |k: usize| &inputs[k * modes..(k + 1) * modes];
        let (previous, current, current_load) = (self.previous, self.current, self.current_load);
        let mut velocities = [[0.0; LANES]; MAX_MODES];
        // Block step i is the successor of the step processed with it: s = (first + i) − 1.
        for i in 0..steps {
            let seen = self.seen + i;
            if seen == 0 {
                self.rest[..modes].copy_from_slice(at(0));
                continue;
            }
            let (here, load) =
                if i == 0 { (&current[..modes], &current_load[..modes]) } else { (at(i - 1), load_at(i - 1)) };
            let (before, scale) = match (seen, i) {
                (1, _) => (here, 1.0 / self.time_step),
                (_, 0) => (&previous[..modes], 0.5 / self.time_step),
                (_, 1) => (&current[..modes], 0.5 / self.time_step),
                _ => (at(i - 2), 0.5 / self.time_step),
            };
            for (m, (after, before)) in at(i).iter().zip(before).enumerate() {
                velocities[m] = std::array::from_fn(|l| (after[l] - before[l]) * scale);
            }
            self.process(here, &velocities[..modes], load);
        }
        if steps > 0 {
            self.previous[..modes].copy_from_slice(if steps > 1 { at(steps - 2) } else { &current[..modes] });
            self.current[..modes].copy_from_slice(at(steps - 1));
            self.current_load[..modes].copy_from_slice(load_at(steps - 1));
            self.seen += steps;
        }
    }

    fn finish(&mut self) -> Lanes {
        let modes = self.modes;
        if self.seen > 0 {
            let scale = if self.seen > 1 { 1.0 / self.time_step } else { 0.0 };
            let (current, previous, load) = (self.current, self.previous, self.current_load);
            let velocities: Vec<Lanes> =
                (0..modes).map(|m| std::array::from_fn(|l| (current[m][l] - previous[m][l]) * scale)).collect();
            self.process(&current[..modes], &velocities, &load[..modes]);
        }
        self.flush();
        match self.target {
            Target::Acceleration { .. } => self.best,
            Target::DamperForce { damper } => std::array::from_fn(|l| {
                (self.lanes.coefficients[damper][l] * power(self.best[l], self.lanes.exponent)).abs()
            }),
        }
    }
}

impl MotionPeaks {
    /// Step s: its displacements, velocities and load deviations, every mode and lane.
    #[inline]
    fn process(&mut self, y: &[Lanes], velocities: &[Lanes], q: &[Lanes]) {
        let lanes = &self.lanes;
        match &self.target {
            Target::DamperForce { damper } => {
                let g = &lanes.velocity_map[*damper];
                let mut v = [0.0; LANES];
                for (g, velocity) in g.iter().zip(velocities) {
                    (0..LANES).for_each(|l| v[l] = g.mul_add(velocity[l], v[l]));
                }
                (0..LANES).for_each(|l| self.best[l] = self.best[l].max(v[l].abs()));
            }
            Target::Acceleration { weights, k, .. } => {
                let mut linear = [0.0; LANES];
                let mut speed = [0.0; LANES];
                for (m, v) in velocities.iter().enumerate() {
                    let (y, q, rest) = (&y[m], &q[m], &self.rest[m]);
                    let (load_gain, damping, stiffness) =
                        (&lanes.load_gains[m], &lanes.damping[m], &lanes.stiffness[m]);
                    for l in 0..LANES {
                        let modal = q[l] * load_gain[l] - damping[l] * v[l] - stiffness[l] * (y[l] - rest[l]);
                        linear[l] = weights[m].mul_add(modal, linear[l]);
                        speed[l] = k[m][l].mul_add(v[l].abs(), speed[l]);
                    }
                }
                let chunk = &mut self.chunk;
                let i = chunk.len;
                for l in 0..LANES {
                    chunk.largest_linear[l] = chunk.largest_linear[l].max(linear[l].abs());
                    chunk.largest_speed[l] = chunk.largest_speed[l].max(speed[l]);
                }
                chunk.linear[i] = linear;
                chunk.speed[i] = speed;
                chunk.velocities[i][..velocities.len()].copy_from_slice(velocities);
                chunk.len += 1;
                if chunk.len == CHUNK {
                    self.flush();
                }
            }
        }
    }

    /// Tests the chunk's steps against the running peak, lane by lane, and computes the damper
    /// term exactly where the bound does not rule a step out. The powers are taken over arrays
    /// (independent, so they overlap in the processor rather than wait on each other).
    fn flush(&mut self) {
        let Target::Acceleration { h, bound, .. } = &self.target else { return };
        let (lanes, chunk, modes) = (&self.lanes, &mut self.chunk, self.modes);
        let alpha = lanes.exponent;
        let inflate = 1.0 + BOUND_MARGIN;
        let chunk_bounds: Lanes = std::array::from_fn(|l| {
            inflate * (chunk.largest_linear[l] + bound[l] * power(chunk.largest_speed[l], alpha))
        });
        let (mut step_bounds, forces) = ([0.0; CHUNK], &mut self.forces);
        for (l, best) in self.best.iter_mut().enumerate() {
            if chunk.len == 0 || chunk_bounds[l] <= *best {
                continue;
            }
            for (i, to) in step_bounds[..chunk.len].iter_mut().enumerate() {
                *to = inflate * (chunk.linear[i][l].abs() + bound[l] * power(chunk.speed[i][l], alpha));
            }
            // The step with the largest bound first: it most likely raises the peak, which then
            // rules out more of the others.
            let first = (0..chunk.len).max_by(|&a, &b| step_bounds[a].total_cmp(&step_bounds[b])).unwrap_or(0);
            for i in std::iter::once(first).chain((0..chunk.len).filter(|&i| i != first)) {
                if step_bounds[i] <= *best {
                    continue;
                }
                let v = &chunk.velocities[i];
                for (force, g) in forces.iter_mut().zip(&lanes.velocity_map) {
                    *force = (0..modes).map(|m| g[m] * v[m][l]).sum();
                }
                for force in forces.iter_mut() {
                    *force = power(force.abs(), alpha).copysign(*force);
                }
                let dampers: f64 = forces.iter().zip(h).map(|(f, h)| h[l] * f).sum();
                *best = best.max((chunk.linear[i][l] - dampers).abs());
            }
        }
        chunk.len = 0;
        chunk.largest_linear = [0.0; LANES];
        chunk.largest_speed = [0.0; LANES];
    }
}
