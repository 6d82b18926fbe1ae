//! `windmeta sample-peaks`: peaks of a response over many storms through the reference model.

use super::StudyArgs;
use super::args::ResponseArgs;
use super::simulate::WindChoice;
use crate::analysis::{PeakSummary, reference_peak};
use crate::error::{Error, Result};
use crate::study::{Order, WindPath};
use crate::uncertainty::{InputModel, Rng, monte_carlo, rng_from_seed, stream_seed};
use clap::Args;
use rayon::prelude::*;
use serde_json::json;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

/// More reference storms than this is a job for the metamodel.
pub const MAX_REFERENCE_SAMPLES: usize = 100_000;

/// What `windmeta sample-peaks` runs through the reference model.
#[derive(Debug, Clone, Args)]
pub struct SamplePeaksArgs {
    /// The study whose reference model is run.
    #[command(flatten)]
    pub study: StudyArgs,
    /// Number of storms (one input sample each).
    #[arg(long, default_value_t = 200)]
    pub samples: usize,
    /// Seed of the input samples and of the storms' wind.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Hold every input at its mean; only the wind varies from storm to storm.
    #[arg(long)]
    pub nominal: bool,
    /// Integrate every floor instead of the retained modes.
    #[arg(long)]
    pub full_order: bool,
    /// Wind path of a reduced-order run (a full-order run, and every run of a three-dimensional
    /// study, uses the floor field).
    #[arg(long, value_enum, default_value = "modal")]
    pub wind: WindChoice,
    /// The peak response recorded per storm.
    #[command(flatten)]
    pub response: ResponseArgs,
    /// Print every peak with the summary as JSON.
    #[arg(long)]
    pub json: bool,
}

/// Runs `windmeta sample-peaks`: the peaks' mean, standard deviation and quantiles.
pub fn sample_peaks(args: &SamplePeaksArgs) -> Result<String> {
    if args.samples == 0 || args.samples > MAX_REFERENCE_SAMPLES {
        return Err(Error::invalid(
            "samples",
            format!("must be between 1 and {MAX_REFERENCE_SAMPLES}, got {}", args.samples),
        ));
    }
    let order = if args.full_order { Order::Full } else { Order::Reduced };
    if args.study.is_spatial() {
        let mut study = args.study.spatial_study()?;
        if args.nominal {
            study.inputs = study.inputs.nominal();
        }
        let response = args.response.spatial_response(&study)?;
        let sampled = Sampled {
            name: &study.name,
            duration: study.storm.duration,
            response: serde_json::to_value(response).expect("plain JSON"),
            per_storm: response.per_storm(),
            unit: response.unit(),
        };
        let dt = study.storm.time_step;
        return sampled.report(args, &study.inputs, &|x, rng| {
            response.of_run(&study.reference_run(x, order, rng)?, &study.structure, dt)
        });
    }
    let mut study = args.study.study()?;
    if args.nominal {
        study.inputs = study.inputs.nominal();
    }
    let response = args.response.response(&study)?;
    let path =
        if args.full_order || matches!(args.wind, WindChoice::Field) { WindPath::Field } else { WindPath::Modal };
    let sampled = Sampled {
        name: &study.name,
        duration: study.storm.duration,
        response: serde_json::to_value(response).expect("plain JSON"),
        per_storm: response.per_storm(),
        unit: response.unit(),
    };
    sampled.report(args, &study.inputs, &|x, rng| {
        reference_peak(&study, x, &study.reference_run(x, order, path, rng)?, response)
    })
}

/// A storm's one value of the response at inputs `x`, its wind from `rng`.
type StormValue<'a> = dyn Fn(&[f64], &mut Rng) -> Result<f64> + Sync + 'a;

/// What the storms of `sample-peaks` are run for: the study and the response, as reported.
struct Sampled<'a> {
    name: &'a str,
    duration: f64,
    response: serde_json::Value,
    per_storm: String,
    unit: &'static str,
}

impl Sampled<'_> {
    /// Runs the storms on every core (sample k's wind from stream k of the seed) and reports.
    fn report(&self, args: &SamplePeaksArgs, inputs: &InputModel, value: &StormValue) -> Result<String> {
        let started = Instant::now();
        let samples = monte_carlo(inputs, args.samples, &mut rng_from_seed(args.seed));
        let done = AtomicUsize::new(0);
        let step = (args.samples / 10).max(1);
        let peaks = samples
            .par_iter()
            .enumerate()
            .map(|(k, x)| {
                let peak = value(x, &mut rng_from_seed(stream_seed(args.seed, k as u64)))?;
                let finished = done.fetch_add(1, Ordering::Relaxed) + 1;
                if finished.is_multiple_of(step) || finished == args.samples {
                    eprintln!("{finished}/{} storms, {:.1} s", args.samples, started.elapsed().as_secs_f64());
                }
                Ok(peak)
            })
            .collect::<Result<Vec<f64>>>()?;
        let summary = PeakSummary::of(&peaks);
        let seconds = started.elapsed().as_secs_f64();
        let unit = self.unit;
        if args.json {
            let quantiles: serde_json::Map<String, serde_json::Value> =
                summary.quantiles.iter().map(|(p, v)| (format!("{p}"), json!(v))).collect();
            let value = json!({
                "preset": self.name,
                "samples": args.samples,
                "seed": args.seed,
                "nominal": args.nominal,
                "order": if args.full_order { "full" } else { "reduced" },
                "duration_s": self.duration,
                "response": self.response,
                "unit": unit,
                "peaks": peaks,
                "mean": summary.mean,
                "sd": summary.sd,
                "quantiles": quantiles,
                "seconds": seconds,
            });
            return Ok(serde_json::to_string_pretty(&value).expect("plain JSON"));
        }
        let mut out = format!(
            "{}: {} of {} storms of {} s ({} inputs, seed {})\n",
            self.name,
            self.per_storm,
            args.samples,
            self.duration,
            if args.nominal { "nominal" } else { "random" },
            args.seed
        );
        out += &format!("mean {:.5} {unit}, sd {:.5} {unit}\n", summary.mean, summary.sd);
        for (p, v) in &summary.quantiles {
            out += &format!("  q{:<5} {v:.5} {unit}\n", p);
        }
        out += &format!("{seconds:.1} s in all\n");
        Ok(out)
    }
}
