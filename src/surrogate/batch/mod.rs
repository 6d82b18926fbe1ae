//! The metamodel's free run (Eq. 10, every mode jointly) for several samples at once.
//!
//! [`LANES`] samples advance through the recursion together: every arithmetic operation is applied
//! to all lanes, on AVX-512 or AVX2 vectors where the processor has them (chosen at run time) and
//! on arrays elsewhere. The models' terms are the same for every sample, only the coefficients
//! differ, so the lanes never diverge in control flow. Each step interpolates the modes' forces for
//! all lanes at once from lane-major copies of the wind's generation grid, then sums each mode's
//! terms.
//!
//! - `samples`: what a batch is given (each mode's terms, each sample's coefficients and forces);
//! - `inputs`: the lane-major inputs, in a [`BatchWorkspace`] the caller keeps between batches;
//! - `dense`: the paper's structures (constant, lagged inputs and outputs to the first power) as
//!   dense arrays with modes and lags fixed at compile time, one fused loop per step;
//! - `general`: any other structure, from term lists, a block of steps at a time;
//! - `dispatch`: the free run as a kernel of the vector type, run by [`crate::simd::run_widest`]
//!   on the widest vectors the processor has;
//! - `sink`: what the run produces (blocks of outputs or per-lane peaks), the reductions a peak
//!   request asks for, and where a run diverged.
//!
//! Every product that is summed is a fused multiply-add (`f64::mul_add`: one rounding, the same on
//! every processor; the SIMD versions are only chosen where the processor has FMA) and no operation
//! mixes lanes, so a lane's result does not depend on the instruction set or on which samples share
//! its batch.

mod dense;
mod dispatch;
mod general;
mod inputs;
mod samples;
mod sink;

pub use inputs::BatchWorkspace;
pub use samples::{BatchSample, ModeProgram};
pub use sink::{BatchInput, Divergence, ModalScales, MotionSink, Reduction, Sink, SinkFactory};

use super::narx::{NarxTerm, rest_output};
use crate::error::{Error, Result};
use crate::simd::{LANES, Lanes};
use dense::DenseLinear;
use dense::PairedPeaks;
use dispatch::{Compiled, Recursion, free_run, free_run_pair};
use general::TermLists;

/// Runs up to [`LANES`] samples over `steps` steps of `time_step` into `sink`, with the buffers of
/// `workspace`. Lanes beyond `samples.len()` run a zero model. Fails on a lane's divergence,
/// naming it.
pub fn run(
    programs: &[ModeProgram],
    samples: &[BatchSample],
    steps: usize,
    time_step: f64,
    workspace: &mut BatchWorkspace,
    sink: &mut Sink,
) -> std::result::Result<(), BatchError> {
    let compiled = compile(programs, samples, steps, time_step)?;
    free_run(&compiled, samples, workspace, sink).map_err(BatchError::Diverged)
}

/// Up to 2·[`LANES`] samples as two batches (the first [`LANES`], then the rest) run side by side,
/// each lane's peak of one combination into `peaks` (as [`Sink::Peaks`]: `offsets` per sample):
/// the free run waits on each step's power of the dampers' law, and the two batches' chains
/// overlap. Each lane's values are those of [`run`], to the bit. A failing lane is named by its
/// place among `samples`.
#[allow(clippy::too_many_arguments)]
pub fn run_paired_peaks(
    programs: &[ModeProgram],
    samples: &[BatchSample],
    steps: usize,
    time_step: f64,
    workspace: &mut BatchWorkspace,
    gains: &[f64],
    offsets: &[f64],
    peaks: &mut [f64],
) -> std::result::Result<(), BatchError> {
    assert!(samples.len() <= 2 * LANES, "at most {} samples per pair of batches", 2 * LANES);
    assert!(offsets.len() == samples.len() && peaks.len() == samples.len(), "one offset and peak per sample");
    let lanes = |values: &[f64]| -> Lanes {
        let mut lanes = [0.0; LANES];
        lanes[..values.len()].copy_from_slice(values);
        lanes
    };
    if samples.len() <= LANES {
        let mut peak = lanes(peaks);
        let mut sink = Sink::Peaks { gains, offsets: lanes(offsets), peaks: &mut peak };
        run(programs, samples, steps, time_step, workspace, &mut sink)?;
        peaks.copy_from_slice(&peak[..samples.len()]);
        return Ok(());
    }
    let (first, second) = samples.split_at(LANES);
    let compiled = [
        compile(programs, first, steps, time_step)?,
        compile(programs, second, steps, time_step).map_err(|error| error.shifted(LANES))?,
    ];
    let (mut peak_a, mut peak_b) = (lanes(&peaks[..LANES]), lanes(&peaks[LANES..]));
    let paired = PairedPeaks {
        gains,
        offsets: [lanes(&offsets[..LANES]), lanes(&offsets[LANES..])],
        peaks: [&mut peak_a, &mut peak_b],
    };
    free_run_pair([&compiled[0], &compiled[1]], [first, second], workspace, paired).map_err(BatchError::Diverged)?;
    peaks[..LANES].copy_from_slice(&peak_a);
    peaks[LANES..].copy_from_slice(&peak_b[..samples.len() - LANES]);
    Ok(())
}

/// A batch's models compiled for the free run: rests, coefficients by lane, the recursion.
fn compile(
    programs: &[ModeProgram],
    samples: &[BatchSample],
    steps: usize,
    time_step: f64,
) -> std::result::Result<Compiled, BatchError> {
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
    let recursion = match DenseLinear::new(programs, coefficient) {
        Some(dense) => Recursion::Dense(dense),
        None => Recursion::TermLists(TermLists::new(programs, coefficient)),
    };
    let inverse_scales = programs.iter().map(|p| 1.0 / p.input_scale).collect();
    Ok(Compiled { rests, inverse_scales, recursion, steps, time_step })
}

/// Why a batch failed.
#[derive(Debug)]
pub enum BatchError {
    /// A sample's model has no rest state.
    Model {
        /// The sample's lane in the batch.
        lane: usize,
        /// Why its model has no rest state.
        error: Error,
    },
    /// A lane's free run left the range a sane model can produce.
    Diverged(Divergence),
}

impl BatchError {
    /// The same failure with its lane counted `by` lanes further (a batch's among several).
    pub fn shifted(self, by: usize) -> Self {
        match self {
            BatchError::Model { lane, error } => BatchError::Model { lane: lane + by, error },
            BatchError::Diverged(d) => BatchError::Diverged(Divergence { lane: d.lane + by, ..d }),
        }
    }
}

/// The joint rest state of the modes under zero input deviation, by Gauss-Seidel on the modes'
/// fixed points (the coupling is weak).
fn joint_rest(models: &[(&[NarxTerm], &[f64])]) -> Result<Vec<f64>> {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::surrogate::DamperLaw;
    use crate::wind::ModalForces;

    /// Two coupled modes run jointly equal a hand-written recursion, in every lane, each lane with
    /// its own coefficients; blocks boundaries do not show; the blocks carry the inputs read.
    #[test]
    fn batch_equals_a_hand_written_recursion() {
        let a = [NarxTerm::input(0, 1), NarxTerm::output(1, 1, None), NarxTerm::output(1, 1, Some(1))];
        let b = [NarxTerm::input(0, 1), NarxTerm::output(1, 1, None), NarxTerm::output(2, 1, Some(0))];
        let steps = 1300;
        let inputs = vec![(0..steps).map(|t| (t as f64 * 0.01).sin()).collect::<Vec<f64>>(), vec![1.0; steps]];
        let forces = ModalForces { mean: vec![0.0, 0.0], series: inputs.clone() };
        let programs = [
            ModeProgram { terms: &a, input_scale: 1.0, law: None },
            ModeProgram { terms: &b, input_scale: 1.0, law: None },
        ];
        let samples: Vec<BatchSample> = (0..3)
            .map(|k| {
                let k = k as f64;
                BatchSample { theta: vec![vec![0.5, 0.9 - 0.1 * k, 0.05], vec![0.2, 0.8, -0.1 * k]], forces: &forces }
            })
            .collect();
        let mut got = vec![vec![vec![0.0; steps]; 2]; 3];
        let mut read = vec![vec![vec![f64::NAN; steps]; 2]; 3];
        let mut consume = |first: usize, outputs: &[Lanes], inputs: &[Lanes]| {
            for (k, (lanes, input)) in outputs.iter().zip(inputs).enumerate() {
                for lane in 0..3 {
                    got[lane][k % 2][first + k / 2] = lanes[lane];
                    read[lane][k % 2][first + k / 2] = input[lane];
                }
            }
        };
        run(&programs, &samples, steps, 0.01, &mut BatchWorkspace::default(), &mut Sink::Blocks(&mut consume)).unwrap();
        assert!(read.iter().all(|lane| lane == &inputs), "the blocks' inputs are the forces on the storm's grid");
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
            let programs = [
                ModeProgram { terms: a, input_scale: 2.0, law: None },
                ModeProgram { terms: b, input_scale: 1.0, law: None },
            ];
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
            let mut consume = |first: usize, outputs: &[Lanes], _: &[Lanes]| {
                for (k, lanes) in outputs.iter().enumerate() {
                    for (lane, history) in got.iter_mut().enumerate() {
                        history[first * 2 + k] = lanes[lane];
                    }
                }
            };
            run(&programs, &samples, steps, 0.01, &mut BatchWorkspace::default(), &mut Sink::Blocks(&mut consume))
                .unwrap();
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

    /// Two modes with the dampers' law: the first's own, the second reading the first's law and its
    /// own velocity at the first's secant.
    fn law_models() -> (DamperLaw, [NarxTerm; 4], [NarxTerm; 5]) {
        use crate::surrogate::narx::DamperTerm;
        let law = DamperLaw { exponent: 0.38, knees: vec![2e-3, 5e-3] };
        let a = [
            NarxTerm::input(0, 1),
            NarxTerm::output(1, 1, None),
            NarxTerm::output(2, 1, None),
            NarxTerm::damper(DamperTerm::Law, 1, None),
        ];
        let b = [
            NarxTerm::input(0, 1),
            NarxTerm::output(1, 1, None),
            NarxTerm::output(2, 1, None),
            NarxTerm::damper(DamperTerm::Law, 1, Some(0)),
            NarxTerm::damper(DamperTerm::Modulated, 1, Some(0)),
        ];
        (law, a, b)
    }

    /// Damper terms (a mode's own law, another's, and the own velocity at another's secant) run
    /// in the batch as in the scalar free run the calibration fits them with: by the dense
    /// recursion, and by the term lists when another term (a cubic stiffness) keeps the models out
    /// of it.
    #[test]
    fn damper_terms_run_as_in_the_scalar_free_run() {
        let (law, a, b) = law_models();
        let theta = vec![vec![0.004, 1.985, -0.9905, -0.003], vec![0.02, 1.95, -0.96, 0.002, -0.01]];
        let dense = |programs: &[ModeProgram]| DenseLinear::new(programs, |_, _| [0.0; LANES]).is_some();
        let programs = [
            ModeProgram { terms: &a, input_scale: 1.0, law: Some(&law) },
            ModeProgram { terms: &b, input_scale: 1.0, law: Some(&law) },
        ];
        assert!(dense(&programs));
        agrees_with_the_scalar_free_run(&programs, theta.clone(), &law);
        let cubic: Vec<NarxTerm> = a.iter().copied().chain([NarxTerm::output(1, 3, None)]).collect();
        let programs = [
            ModeProgram { terms: &cubic, input_scale: 1.0, law: Some(&law) },
            ModeProgram { terms: &b, input_scale: 1.0, law: Some(&law) },
        ];
        assert!(!dense(&programs));
        let mut theta = theta;
        theta[0].push(-0.5);
        agrees_with_the_scalar_free_run(&programs, theta, &law);
    }

    /// The batch's outputs of one sample agree with the scalar free run's, mode by mode.
    fn agrees_with_the_scalar_free_run(programs: &[ModeProgram], theta: Vec<Vec<f64>>, law: &DamperLaw) {
        use crate::surrogate::identify::{Record, simulate};
        use std::sync::Arc;
        let steps = 3000;
        let series =
            |f: f64| -> Vec<f64> { (0..steps).map(|t| (t as f64 * f).sin() + 0.3 * (t as f64 * 0.17).cos()).collect() };
        let forces = ModalForces { mean: vec![0.0, 0.0], series: vec![series(0.011), series(0.029)] };
        let samples = [BatchSample { theta: theta.clone(), forces: &forces }];
        let mut got = vec![vec![0.0; steps]; 2];
        let mut consume = |first: usize, outputs: &[Lanes], _: &[Lanes]| {
            for (k, lanes) in outputs.iter().enumerate() {
                got[k % 2][first + k / 2] = lanes[0];
            }
        };
        run(programs, &samples, steps, 0.01, &mut BatchWorkspace::default(), &mut Sink::Blocks(&mut consume)).unwrap();
        assert!(got[0].iter().any(|v| v.abs() > 0.05) && got[1].iter().any(|v| v.abs() > 0.05));
        let law = Arc::new(law.clone());
        let outputs: Vec<Arc<[f64]>> = got.iter().map(|o| o[..].into()).collect();
        for (m, terms) in programs.iter().map(|p| p.terms).enumerate() {
            let record = Record {
                mode: m,
                law: Some(law.clone()),
                secants: Record::secants_of(&outputs, &law),
                outputs: outputs.clone(),
                ..Record::single(vec![0.0; steps], forces.series[m].clone(), 0.0)
            };
            // The two sum the terms in different orders (the batch by fused multiply-adds), and the
            // lightly damped recursion carries the rounding on: equal to 1e-10 of the largest output.
            let scalar = simulate(terms, &theta[m], &record).unwrap();
            let largest = got[m].iter().fold(0.0f64, |a, v| a.max(v.abs()));
            let worst = scalar.iter().zip(&got[m]).fold(0.0f64, |a, (s, b)| a.max((s - b).abs()));
            assert!(worst <= 1e-10 * largest, "mode {m}: {worst:e} of {largest}");
        }
    }

    /// Two batches side by side give every lane the peak it gets in its batch alone, to the bit,
    /// with the dampers' law (the dense recursion) and without it; a diverging lane of the second
    /// batch is named by its place in the pair.
    #[test]
    fn paired_batches_equal_batches_alone() {
        let (law, a, b) = law_models();
        let steps = 2600;
        let series = |f: f64| -> Vec<f64> { (0..steps).map(|t| (t as f64 * f).sin() + 0.2).collect() };
        let forces = ModalForces { mean: vec![0.0, 0.0], series: vec![series(0.011), series(0.029)] };
        let with_law = [
            ModeProgram { terms: &a, input_scale: 1.0, law: Some(&law) },
            ModeProgram { terms: &b, input_scale: 1.0, law: Some(&law) },
        ];
        let linear = [
            ModeProgram { terms: &a[..3], input_scale: 1.0, law: None },
            ModeProgram { terms: &b[..3], input_scale: 1.0, law: None },
        ];
        let theta = |k: usize, law: bool| {
            let k = k as f64;
            let (mut ta, mut tb) = (vec![0.004, 1.985 - 1e-3 * k, -0.9905], vec![0.02, 1.95, -0.96 + 1e-4 * k]);
            if law {
                ta.push(-0.003 * (1.0 + 0.1 * k));
                tb.extend([0.002, -0.01]);
            }
            vec![ta, tb]
        };
        let (gains, offsets) = ([0.7, -0.4], (0..13).map(|k| 0.01 * k as f64).collect::<Vec<f64>>());
        for (programs, law) in [(&with_law, true), (&linear, false)] {
            let samples: Vec<BatchSample> =
                (0..13).map(|k| BatchSample { theta: theta(k, law), forces: &forces }).collect();
            let mut paired = vec![0.0; 13];
            let mut workspace = BatchWorkspace::default();
            run_paired_peaks(programs, &samples, steps, 0.01, &mut workspace, &gains, &offsets, &mut paired).unwrap();
            for (g, group) in samples.chunks(LANES).enumerate() {
                let mut lane_offsets = [0.0; LANES];
                lane_offsets[..group.len()].copy_from_slice(&offsets[g * LANES..g * LANES + group.len()]);
                let mut alone = [0.0; LANES];
                let mut sink = Sink::Peaks { gains: &gains, offsets: lane_offsets, peaks: &mut alone };
                run(programs, group, steps, 0.01, &mut workspace, &mut sink).unwrap();
                for (lane, peak) in alone[..group.len()].iter().enumerate() {
                    assert_eq!(peak.to_bits(), paired[g * LANES + lane].to_bits(), "law {law}, batch {g} lane {lane}");
                }
            }
            assert!(paired.iter().all(|p| *p > 0.1), "{paired:?}");
        }
        let mut samples: Vec<BatchSample> =
            (0..13).map(|k| BatchSample { theta: theta(k, true), forces: &forces }).collect();
        samples[11].theta[1][1] = 2.1;
        let mut peaks = vec![0.0; 13];
        let err = run_paired_peaks(
            &with_law,
            &samples,
            steps,
            0.01,
            &mut BatchWorkspace::default(),
            &gains,
            &offsets,
            &mut peaks,
        )
        .unwrap_err();
        match err {
            BatchError::Diverged(d) => assert_eq!((d.lane, d.mode), (11, 1)),
            other => panic!("{other:?}"),
        }
    }

    /// A lane whose model is unstable is reported with its mode and step; the others do not matter.
    #[test]
    fn divergence_names_the_lane() {
        let terms = [NarxTerm::input(0, 1), NarxTerm::output(1, 1, None), NarxTerm::output(2, 1, None)];
        let forces = ModalForces { mean: vec![0.0], series: vec![vec![1.0; 5000]] };
        let programs = [ModeProgram { terms: &terms, input_scale: 1.0, law: None }];
        let samples = [
            BatchSample { theta: vec![vec![0.02, 1.9, -0.95]], forces: &forces },
            BatchSample { theta: vec![vec![0.02, 2.1, -0.9]], forces: &forces },
        ];
        let err =
            run(&programs, &samples, 5000, 0.01, &mut BatchWorkspace::default(), &mut Sink::Blocks(&mut |_, _, _| {}))
                .unwrap_err();
        match err {
            BatchError::Diverged(d) => assert_eq!((d.lane, d.mode), (1, 0)),
            other => panic!("{other:?}"),
        }
    }
}
