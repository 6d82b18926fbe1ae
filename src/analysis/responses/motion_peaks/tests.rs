use super::*;
use crate::analysis::ResponseView;
use crate::dynamics::{ModalMotion, SampleModel};
use crate::wind::ModalForces;

/// Fed synthetic scaled histories in uneven blocks (one longer than a window of chunks), the sink's peaks equal those of the same
/// physical histories through [`SampleModel`] (every damper at every step), RMS accelerations
/// those of the histories' squares, for damper laws
/// below, at and above α = 1 (the bound's two forms), in every lane; damper forces and
/// combinations (drift, displacement), bounded a chunk at a time, too.
#[test]
fn peaks_equal_those_of_every_step_for_any_exponent() {
    let mut study = Study::preset("frame40-kn").unwrap().with_storm(30.0, 0.01).unwrap();
    let steps = study.storm.steps();
    let modes = study.modes.count();
    // Storm-like amplitudes, and small ones where the dampers' term rules the accelerations
    // (their force falls only as |v|^α), so that its bound decides which steps are looked at.
    let amplitudes = [(vec![0.02, 0.005, 0.001], vec![3e5, 1e5, 5e4]), (vec![2e-5; 3], vec![1e2; 3])];
    let x = study.inputs.means();
    let inputs: Vec<&[f64]> = vec![&x[..]; LANES];
    // Lane l, mode m: a few incommensurate sines, different per lane.
    let output = |l: usize, m: usize, t: usize| -> f64 {
        let t = t as f64 * study.storm.time_step;
        let (a, b) = (1.0 + 0.1 * l as f64, (m + 1) as f64);
        (a * b * 1.3 * t).sin() + 0.4 * (a * 5.1 * t + b).sin() + 0.1 * (17.0 * t).cos() + 0.3
    };
    let input = |l: usize, m: usize, t: usize| -> f64 { (0.7 * (l + m + 1) as f64 * t as f64 * 0.01).cos() };
    for (alpha, (outputs, inputs_scale)) in
        [0.38, 1.0, 1.7].into_iter().flat_map(|a| amplitudes.iter().map(move |s| (a, s)))
    {
        study.damper_exponent = alpha;
        let scales =
            ModalScales { outputs: outputs.clone(), inputs: inputs_scale.clone(), levels: vec![[1.0; LANES]; 3] };
        let floors = study.structure.floors();
        let shapes: Vec<Vec<f64>> =
            (0..modes).map(|m| (0..floors).map(|f| study.modes.shapes[(f, m)]).collect()).collect();
        let run = |responses: &[Response]| -> Vec<Lanes> {
            let mut sink = motion_sink(&study, &shapes, responses, &inputs, &scales).unwrap();
            let mut first = 0;
            for len in [1usize, 2, 2900, 511, 512, 37].into_iter().cycle() {
                let len = len.min(steps - first);
                let block = |f: &dyn Fn(usize, usize, usize) -> f64| -> Vec<Lanes> {
                    (first..first + len)
                        .flat_map(|t| (0..modes).map(move |m| (t, m)))
                        .map(|(t, m)| std::array::from_fn(|l| f(l, m, t)))
                        .collect()
                };
                sink.take(first, &block(&output), &block(&input));
                first += len;
                if first == steps {
                    break;
                }
            }
            sink.finish()
        };
        let responses = [
            Response::Acceleration { floor: floors },
            Response::Acceleration { floor: 9 },
            Response::RmsAcceleration { floor: floors },
            Response::RmsAcceleration { floor: 9 },
            Response::DamperForce { floor: 5 },
            Response::Drift { floor: 7 },
            Response::Displacement { floor: floors },
        ];
        // Together (the accelerations sharing their exact steps' damper forces) as alone.
        assert_eq!(run(&responses), responses.iter().map(|r| run(&[*r])[0]).collect::<Vec<_>>());
        for response in responses {
            let peaks = run(&[response])[0];
            for (l, peak) in peaks.iter().enumerate() {
                let p = study.parameters(&x).unwrap();
                let (sample_modes, dampers) = (study.sample_modes(&p), study.dampers(&p).unwrap());
                let model = SampleModel::new(&sample_modes, p.damping_ratio, &dampers);
                let displacements = (0..modes)
                    .map(|m| (0..steps).map(|t| scales.outputs[m] * output(l, m, t) + 1.0).collect())
                    .collect();
                let motion = ModalMotion::from_displacements(displacements, study.storm.time_step);
                let forces = ModalForces {
                    mean: vec![0.0; modes],
                    series: (0..modes)
                        .map(|m| (0..steps).map(|t| scales.inputs[m] * input(l, m, t)).collect())
                        .collect(),
                };
                let view =
                    ResponseView::new(&shapes, &study.structure, &motion, &model, &forces, study.storm.time_step);
                let expected = response.peak(&view).unwrap();
                assert!(
                    (peak - expected).abs() <= 1e-9 * expected,
                    "α = {alpha}, {}, lane {l}: {peak} vs {expected}",
                    response.describe()
                );
            }
        }
    }
}
