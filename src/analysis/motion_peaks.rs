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
use crate::problem::Problem;
use crate::surrogate::{LANES, Lanes, MotionSink};

/// Steps whose bound is tested together before any of them is looked at one by one.
const CHUNK: usize = 32;
/// Relative inflation of the bound against rounding.
const BOUND_MARGIN: f64 = 1e-9;

/// A sink for `response` (an acceleration or a damper force) over a batch whose lane i holds the
/// physical inputs `inputs[i]`, the floors' modal weights read from `shapes[m][floor]`.
pub fn motion_sink(
    problem: &Problem,
    shapes: &[Vec<f64>],
    response: Response,
    inputs: &[&[f64]],
) -> Result<Box<dyn MotionSink>> {
    response.check(&problem.structure)?;
    let lanes = LaneModels::new(problem, inputs)?;
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
    let modes = lanes.inverse_masses.len();
    Ok(Box::new(MotionPeaks {
        time_step: problem.storm.time_step,
        lanes,
        target,
        rest: vec![[0.0; LANES]; modes],
        previous: vec![[0.0; LANES]; modes],
        current: vec![[0.0; LANES]; modes],
        current_load: vec![[0.0; LANES]; modes],
        seen: 0,
        chunk: Chunk::default(),
        best: [0.0; LANES],
    }))
}

/// The reduced models of a batch's samples, lane-major.
struct LaneModels {
    /// 1/M_m, 2ζω_m and ω_m² per mode, every lane.
    inverse_masses: Vec<Lanes>,
    damping: Vec<Lanes>,
    stiffness: Vec<Lanes>,
    /// Per damper its coefficient c_d in every lane, and G_dm per mode (the same in every lane:
    /// the shapes are fixed across samples).
    coefficients: Vec<Lanes>,
    map: Vec<Vec<f64>>,
    exponent: f64,
}

impl LaneModels {
    fn new(problem: &Problem, inputs: &[&[f64]]) -> Result<Self> {
        let modes = problem.modes.count();
        let mut lanes = LaneModels {
            inverse_masses: vec![[0.0; LANES]; modes],
            damping: vec![[0.0; LANES]; modes],
            stiffness: vec![[0.0; LANES]; modes],
            coefficients: Vec::new(),
            map: Vec::new(),
            exponent: problem.damper_exponent,
        };
        for (lane, x) in inputs.iter().enumerate() {
            let p = problem.parameters(x)?;
            let (modes, dampers) = (problem.sample_modes(&p), problem.dampers(&p)?);
            for m in 0..modes.count() {
                let omega = modes.frequencies[m];
                lanes.inverse_masses[m][lane] = 1.0 / modes.modal_masses[m];
                lanes.damping[m][lane] = 2.0 * p.damping_ratio * omega;
                lanes.stiffness[m][lane] = omega * omega;
            }
            if lane == 0 {
                lanes.map = dampers
                    .modal_map(modes.shapes.as_ref())
                    .iter()
                    .map(|row| row.iter().map(|g| g.1).collect())
                    .collect();
                lanes.coefficients = vec![[0.0; LANES]; dampers.coefficients.len()];
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
                let used = || lanes.map.iter().zip(&h).filter(|(_, h)| h[l] != 0.0);
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

/// The steps of a chunk awaiting the bound's test: L and Σ_m K_m|ẏ_m| per step, and the modal
/// velocities `velocities[i·M + m]`, every lane.
#[derive(Default)]
struct Chunk {
    linear: Vec<Lanes>,
    speed: Vec<Lanes>,
    velocities: Vec<Lanes>,
}

struct MotionPeaks {
    time_step: f64,
    lanes: LaneModels,
    target: Target,
    /// y(0), y(s − 1), y(s) and Q'(s) per mode: step s is processed when s + 1 arrives, for its
    /// central difference.
    rest: Vec<Lanes>,
    previous: Vec<Lanes>,
    current: Vec<Lanes>,
    current_load: Vec<Lanes>,
    seen: usize,
    chunk: Chunk,
    /// The running peak: |a| for an acceleration, max |v| for a damper force.
    best: Lanes,
}

impl MotionSink for MotionPeaks {
    fn take(&mut self, _first: usize, displacements: &[Lanes], loads: &[Lanes]) {
        let modes = self.current.len();
        for (y, q) in displacements.chunks_exact(modes).zip(loads.chunks_exact(modes)) {
            self.arrive(y, q);
        }
    }

    fn finish(&mut self) -> Lanes {
        if self.seen > 0 {
            let scale = if self.seen > 1 { 1.0 / self.time_step } else { 0.0 };
            let velocities: Vec<Lanes> = (0..self.current.len())
                .map(|m| std::array::from_fn(|l| (self.current[m][l] - self.previous[m][l]) * scale))
                .collect();
            self.process(&velocities);
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
    /// Step `seen` arrives: the one before it now has its central difference.
    fn arrive(&mut self, y: &[Lanes], q: &[Lanes]) {
        if self.seen == 0 {
            self.rest.copy_from_slice(y);
        } else {
            let (from, scale) = if self.seen == 1 {
                (&self.current, 1.0 / self.time_step)
            } else {
                (&self.previous, 0.5 / self.time_step)
            };
            let velocities: Vec<Lanes> =
                y.iter().zip(from).map(|(y, f)| std::array::from_fn(|l| (y[l] - f[l]) * scale)).collect();
            self.process(&velocities);
        }
        self.previous.copy_from_slice(&self.current);
        self.current.copy_from_slice(y);
        self.current_load.copy_from_slice(q);
        self.seen += 1;
    }

    /// The step held in `current` with its velocities.
    fn process(&mut self, velocities: &[Lanes]) {
        let lanes = &self.lanes;
        match &self.target {
            Target::DamperForce { damper } => {
                let g = &lanes.map[*damper];
                for l in 0..LANES {
                    let v: f64 = velocities.iter().zip(g).map(|(v, g)| g * v[l]).sum();
                    self.best[l] = self.best[l].max(v.abs());
                }
            }
            Target::Acceleration { weights, k, .. } => {
                let mut linear = [0.0; LANES];
                let mut speed = [0.0; LANES];
                for (m, v) in velocities.iter().enumerate() {
                    let (y, q, rest) = (&self.current[m], &self.current_load[m], &self.rest[m]);
                    for l in 0..LANES {
                        let modal = q[l] * lanes.inverse_masses[m][l]
                            - lanes.damping[m][l] * v[l]
                            - lanes.stiffness[m][l] * (y[l] - rest[l]);
                        linear[l] = weights[m].mul_add(modal, linear[l]);
                        speed[l] = k[m][l].mul_add(v[l].abs(), speed[l]);
                    }
                }
                self.chunk.linear.push(linear);
                self.chunk.speed.push(speed);
                self.chunk.velocities.extend_from_slice(velocities);
                if self.chunk.linear.len() == CHUNK {
                    self.flush();
                }
            }
        }
    }

    /// Tests the chunk's steps against the running peak, lane by lane, and computes the damper
    /// term exactly where the bound does not rule a step out.
    fn flush(&mut self) {
        let Target::Acceleration { h, bound, .. } = &self.target else { return };
        let (lanes, chunk, modes) = (&self.lanes, &self.chunk, self.current.len());
        let alpha = lanes.exponent;
        let most = |l: usize| -> f64 { (1.0 + BOUND_MARGIN) * bound[l] };
        for (l, best) in self.best.iter_mut().enumerate() {
            let largest_linear = chunk.linear.iter().fold(0.0, |a: f64, x| a.max(x[l].abs()));
            let largest_speed = chunk.speed.iter().fold(0.0, |a: f64, x| a.max(x[l]));
            if (1.0 + BOUND_MARGIN) * largest_linear + most(l) * power(largest_speed, alpha) <= *best {
                continue;
            }
            for (i, (linear, speed)) in chunk.linear.iter().zip(&chunk.speed).enumerate() {
                if (1.0 + BOUND_MARGIN) * linear[l].abs() + most(l) * power(speed[l], alpha) <= *best {
                    continue;
                }
                let v = &chunk.velocities[i * modes..(i + 1) * modes];
                let dampers: f64 = lanes
                    .map
                    .iter()
                    .zip(h)
                    .map(|(g, h)| {
                        let velocity: f64 = g.iter().zip(v).map(|(g, v)| g * v[l]).sum();
                        h[l] * power(velocity.abs(), alpha).copysign(velocity)
                    })
                    .sum();
                *best = best.max((linear[l] - dampers).abs());
            }
        }
        self.chunk.linear.clear();
        self.chunk.speed.clear();
        self.chunk.velocities.clear();
    }
}
