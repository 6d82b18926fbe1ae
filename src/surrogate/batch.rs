//! The metamodel's free run (Eq. 10, every mode jointly) for several samples at once.
//!
//! [`LANES`] samples advance through the recursion together: every arithmetic operation is applied
//! to all lanes of a `[f64; LANES]`, which the compiler turns into SIMD instructions (AVX2 or
//! AVX-512 where the processor has them, chosen at run time). The models' terms are the same for
//! every sample, only the coefficients differ, so the lanes never diverge in control flow. Forces
//! are filled in blocks of [`BLOCK`] steps (interpolated from the wind's generation grid where they
//! come from it), so that the working set stays in the first-level cache whatever the storm's length.
//!
//! The arithmetic of each lane is the scalar recursion's, operation for operation and in the same
//! order (no fused multiply-adds), so the result does not depend on the instruction set or on which
//! samples share a batch.

use super::narx::{DIVERGENCE_BOUND, NarxTerm, diverged, rest_output};
use crate::error::{Error, Result};
use crate::wind::{CoarseModalForces, ModalForces};

/// Samples per batch: one AVX-512 register of f64, two AVX2 ones.
pub const LANES: usize = 8;
/// Steps per block of forces.
const BLOCK: usize = 512;

pub type Lanes = [f64; LANES];

/// Where a sample's modal forces come from.
pub trait ForceSource: Sync {
    /// Mean generalized force of mode m (N).
    fn mean(&self, m: usize) -> f64;
    /// Mode m's force (N) at steps first, first + 1, … of the storm, into `out`.
    fn fill(&self, m: usize, time_step: f64, first: usize, out: &mut [f64]);
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

/// Runs up to [`LANES`] samples over `steps` steps of `time_step` and hands every block of scaled
/// outputs (`outputs[m][i]`, the block's step i, one value per lane) to `consume(first, outputs)`.
/// Lanes beyond `samples.len()` run a zero model. Fails on a lane's divergence, naming it.
pub fn run(
    programs: &[ModeProgram],
    samples: &[BatchSample],
    steps: usize,
    time_step: f64,
    consume: &mut dyn FnMut(usize, &[&[Lanes]]),
) -> std::result::Result<(), BatchError> {
    assert!(samples.len() <= LANES, "at most {LANES} samples per batch");
    let modes = programs.len();
    let mut theta: Vec<Vec<Lanes>> = programs.iter().map(|p| vec![[0.0; LANES]; p.terms.len()]).collect();
    let mut rests = vec![[0.0; LANES]; modes];
    for (lane, sample) in samples.iter().enumerate() {
        let models: Vec<(&[NarxTerm], &[f64])> =
            programs.iter().zip(&sample.theta).map(|(p, t)| (p.terms, &t[..])).collect();
        let rest = joint_rest(&models).map_err(|e| BatchError::Model { lane, error: e })?;
        for m in 0..modes {
            rests[m][lane] = rest[m];
            for (i, c) in sample.theta[m].iter().enumerate() {
                theta[m][i][lane] = *c;
            }
        }
    }
    let history =
        programs.iter().flat_map(|p| p.terms.iter()).map(|t| t.output_lag.max(t.input_lag)).max().unwrap_or(0);
    let compiled: Vec<Vec<Compiled>> =
        programs.iter().enumerate().map(|(m, p)| p.terms.iter().map(|t| Compiled::of(t, m)).collect()).collect();
    let state = State { theta, rests, compiled, history };
    dispatch(&state, programs, samples, steps, time_step, consume).map_err(BatchError::Diverged)
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

/// A term with its sources resolved: which mode's output it reads, at which lags.
#[derive(Debug, Clone, Copy)]
struct Compiled {
    output_mode: usize,
    output_lag: usize,
    output_power: u32,
    input_lag: usize,
    input_power: u32,
}

impl Compiled {
    fn of(term: &NarxTerm, mode: usize) -> Compiled {
        Compiled {
            output_mode: term.output_mode.unwrap_or(mode),
            output_lag: term.output_lag,
            output_power: term.output_power,
            input_lag: term.input_lag,
            input_power: term.input_power,
        }
    }
}

struct State {
    theta: Vec<Vec<Lanes>>,
    rests: Vec<Lanes>,
    compiled: Vec<Vec<Compiled>>,
    /// Longest lag: the steps each block carries over from the one before.
    history: usize,
}

fn dispatch(
    state: &State,
    programs: &[ModeProgram],
    samples: &[BatchSample],
    steps: usize,
    time_step: f64,
    consume: &mut dyn FnMut(usize, &[&[Lanes]]),
) -> std::result::Result<(), Divergence> {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx512f") {
            // SAFETY: the processor has the features the function is compiled for.
            return unsafe { recurse_avx512(state, programs, samples, steps, time_step, consume) };
        }
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: as above.
            return unsafe { recurse_avx2(state, programs, samples, steps, time_step, consume) };
        }
    }
    recurse(state, programs, samples, steps, time_step, consume)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
unsafe fn recurse_avx512(
    state: &State,
    programs: &[ModeProgram],
    samples: &[BatchSample],
    steps: usize,
    time_step: f64,
    consume: &mut dyn FnMut(usize, &[&[Lanes]]),
) -> std::result::Result<(), Divergence> {
    recurse(state, programs, samples, steps, time_step, consume)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn recurse_avx2(
    state: &State,
    programs: &[ModeProgram],
    samples: &[BatchSample],
    steps: usize,
    time_step: f64,
    consume: &mut dyn FnMut(usize, &[&[Lanes]]),
) -> std::result::Result<(), Divergence> {
    recurse(state, programs, samples, steps, time_step, consume)
}

#[inline(always)]
fn power(x: &Lanes, p: u32) -> Lanes {
    match p {
        1 => *x,
        2 => std::array::from_fn(|l| x[l] * x[l]),
        3 => std::array::from_fn(|l| x[l] * x[l] * x[l]),
        _ => std::array::from_fn(|l| x[l].powi(p as i32)),
    }
}

/// The recursion itself. `inputs[m]` and `outputs[m]` hold `history` carried-over steps, then the
/// block; before t = 0 the outputs are at rest and the input deviations zero.
#[inline(always)]
fn recurse(
    state: &State,
    programs: &[ModeProgram],
    samples: &[BatchSample],
    steps: usize,
    time_step: f64,
    consume: &mut dyn FnMut(usize, &[&[Lanes]]),
) -> std::result::Result<(), Divergence> {
    let modes = programs.len();
    let h = state.history;
    let mut inputs: Vec<Vec<Lanes>> = vec![vec![[0.0; LANES]; h + BLOCK]; modes];
    let mut outputs: Vec<Vec<Lanes>> = (0..modes).map(|m| vec![state.rests[m]; h + BLOCK]).collect();
    let mut forces = vec![0.0; BLOCK];
    let mut out_of_bounds = [false; LANES];
    let mut first = 0;
    while first < steps {
        let len = BLOCK.min(steps - first);
        for m in 0..modes {
            let carried = inputs[m].len() - h;
            inputs[m].copy_within(carried.., 0);
            let carried = outputs[m].len() - h;
            outputs[m].copy_within(carried.., 0);
            let inverse_scale = 1.0 / programs[m].input_scale;
            for (lane, sample) in samples.iter().enumerate() {
                let mean = sample.forces.mean(m);
                sample.forces.fill(m, time_step, first, &mut forces[..len]);
                for (input, f) in inputs[m][h..h + len].iter_mut().zip(&forces[..len]) {
                    input[lane] = (f - mean) * inverse_scale;
                }
            }
        }
        for i in 0..len {
            let t = first + i;
            if t == 0 {
                continue;
            }
            for m in 0..modes {
                let mut value = [0.0; LANES];
                for (term, c) in state.compiled[m].iter().zip(&state.theta[m]) {
                    let g: Lanes = match (term.output_power, term.input_power) {
                        (0, 0) => [1.0; LANES],
                        (0, q) => power(&inputs[m][h + i - term.input_lag], q),
                        (y, 0) => power(&outputs[term.output_mode][h + i - term.output_lag], y),
                        (y, q) => {
                            let a = power(&outputs[term.output_mode][h + i - term.output_lag], y);
                            let b = power(&inputs[m][h + i - term.input_lag], q);
                            std::array::from_fn(|l| a[l] * b[l])
                        }
                    };
                    for l in 0..LANES {
                        value[l] += c[l] * g[l];
                    }
                }
                for l in 0..LANES {
                    // Written so that a NaN counts as out of bounds.
                    out_of_bounds[l] |= !(value[l].abs() <= DIVERGENCE_BOUND);
                }
                outputs[m][h + i] = value;
            }
        }
        // Checked once a block, then located: the lanes never branch apart inside the recursion.
        if let Some(lane) = out_of_bounds.iter().position(|&b| b) {
            return Err(first_divergence(&outputs, h, first, len).unwrap_or(Divergence { lane, mode: 0, step: first }));
        }
        let view: Vec<&[Lanes]> = outputs.iter().map(|o| &o[h..h + len]).collect();
        consume(first, &view);
        first += len;
    }
    Ok(())
}

/// The earliest (step, mode, lane) of a block whose output left the bound.
fn first_divergence(outputs: &[Vec<Lanes>], h: usize, first: usize, len: usize) -> Option<Divergence> {
    (0..len).find_map(|i| {
        outputs.iter().enumerate().find_map(|(mode, series)| {
            series[h + i].iter().position(|&v| diverged(v)).map(|lane| Divergence { lane, mode, step: first + i })
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
        run(&programs, &samples, steps, 0.01, &mut |first, outputs| {
            for (m, series) in outputs.iter().enumerate() {
                for (i, lanes) in series.iter().enumerate() {
                    for (lane, history) in got.iter_mut().enumerate() {
                        history[m][first + i] = lanes[lane];
                    }
                }
            }
        })
        .unwrap();
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
        let err = run(&programs, &samples, 5000, 0.01, &mut |_, _| {}).unwrap_err();
        match err {
            BatchError::Diverged(d) => assert_eq!((d.lane, d.mode), (1, 0)),
            other => panic!("{other:?}"),
        }
    }
}
