//! `windmeta sample-peaks`: peaks of a response over many storms through the reference model.

use super::StudyArgs;
use super::args::ResponseArgs;
use super::simulate::WindChoice;
use crate::analysis::{PeakSummary, reference_peak};
use crate::error::{Error, Result};
use crate::study::{Order, WindPath};
use crate::uncertainty::{monte_carlo, rng_from_seed, stream_seed};
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
    /// Wind path of a reduced-order run (a full-order run uses the floor field).
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
    let mut study = args.study.study()?;
    if args.nominal {
        study.inputs = study.inputs.nominal();
    }
    let response = args.response.response(&study)?;
    let started = Instant::now();
    let inputs = monte_carlo(&study.inputs, args.samples, &mut rng_from_seed(args.seed));
    let order = if args.full_order { Order::Full } else { Order::Reduced };
    let path =
        if args.full_order || matches!(args.wind, WindChoice::Field) { WindPath::Field } else { WindPath::Modal };
    let done = AtomicUsize::new(0);
    let step = (args.samples / 10).max(1);
    let peaks = inputs
        .par_iter()
        .enumerate()
        .map(|(k, x)| {
            let run = study.reference_run(x, order, path, &mut rng_from_seed(stream_seed(args.seed, k as u64)))?;
            let finished = done.fetch_add(1, Ordering::Relaxed) + 1;
            if finished.is_multiple_of(step) || finished == args.samples {
                eprintln!("{finished}/{} storms, {:.1} s", args.samples, started.elapsed().as_secs_f64());
            }
            reference_peak(&study, x, &run, response)
        })
        .collect::<Result<Vec<f64>>>()?;
    let summary = PeakSummary::of(&peaks);
    let seconds = started.elapsed().as_secs_f64();
    if args.json {
        let quantiles: serde_json::Map<String, serde_json::Value> =
            summary.quantiles.iter().map(|(p, v)| (format!("{p}"), json!(v))).collect();
        let value = json!({
            "preset": study.name,
            "samples": args.samples,
            "seed": args.seed,
            "nominal": args.nominal,
            "order": if args.full_order { "full" } else { "reduced" },
            "duration_s": study.storm.duration,
            "response": response,
            "unit": response.unit(),
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
        study.name,
        response.per_storm(),
        args.samples,
        study.storm.duration,
        if args.nominal { "nominal" } else { "random" },
        args.seed
    );
    let unit = response.unit();
    out += &format!("mean {:.5} {unit}, sd {:.5} {unit}\n", summary.mean, summary.sd);
    for (p, v) in &summary.quantiles {
        out += &format!("  q{:<5} {v:.5} {unit}\n", p);
    }
    out += &format!("{seconds:.1} s in all\n");
    Ok(out)
}
