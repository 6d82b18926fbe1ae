//! `windmeta exceedance`: the exceedance curve of a peak response, sampled from a metamodel.

use super::args::{CertifyArgs, ResponseArgs, SamplingArgs, out_format, write_out};
use super::read_metamodel;
use super::validate::Counter;
use crate::analysis::{
    Exceedance, ExceedanceOptions, OnThisMachine, STANDARD_GRAVITY, exceedance_csv, exceedance_figure,
    metamodel_exceedance,
};
use crate::error::Result;
use clap::Args;
use serde_json::json;
use std::path::PathBuf;
use std::time::Instant;

/// What `windmeta exceedance` samples, at which thresholds, and how it is certified.
#[derive(Debug, Clone, Args)]
pub struct ExceedanceArgs {
    /// The metamodel, the storms sampled and the inputs held.
    #[command(flatten)]
    pub sampling: SamplingArgs,
    /// Seed of the input samples and of the storms' wind.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// The peak response whose curve is computed.
    #[command(flatten)]
    pub response: ResponseArgs,
    /// Thresholds in the response's unit (m, m/s² or N), comma separated; automatic when absent.
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true)]
    pub thresholds: Option<Vec<f64>>,
    /// Confidence level of the band.
    #[arg(long, default_value_t = 0.95)]
    pub confidence: f64,
    /// Whether the curve is certified by reference storms.
    #[command(flatten)]
    pub certify: CertifyArgs,
    /// Write the curve: .csv, .json or .svg by extension.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// Runs `windmeta exceedance`: the curve with its band.
pub fn exceedance(args: &ExceedanceArgs) -> Result<String> {
    let options = ExceedanceOptions {
        samples: args.sampling.samples,
        seed: args.seed,
        fixed: args.sampling.fixed()?,
        thresholds: args.thresholds.clone(),
        confidence: args.confidence,
        profile_quantile: None,
        certify: args.certify.options(),
    };
    options.check()?;
    let format = out_format(args.out.as_deref(), &["csv", "json", "svg"])?;
    let (metamodel, study) = read_metamodel(&args.sampling.model)?;
    let response = args.response.response(&study)?;
    let started = Instant::now();
    let Exceedance { curve, certification, .. } =
        metamodel_exceedance(&metamodel, &study, response, &options, &OnThisMachine, &Counter(started))?;
    let seconds = started.elapsed().as_secs_f64();
    let what = response.per_storm();
    if let (Some(path), Some(format)) = (&args.out, format) {
        let text = match format.as_str() {
            "csv" => exceedance_csv(&curve, certification.as_ref(), &response),
            "json" => serde_json::to_string_pretty(
                &json!({"response": response, "curve": curve, "certification": certification, "seconds": seconds}),
            )
            .expect("plain JSON"),
            _ => exceedance_figure(&curve, certification.as_ref(), &format!("{what} x ({})", response.unit())),
        };
        write_out(path, &text)?;
    }
    let mut out = format!("{what}: {} samples in {seconds:.2} s\n", args.sampling.samples);
    if let Some(c) = &certification {
        out += &format!(
            "certified with {} storms through the {} reference model as well\n",
            c.reference_storms,
            if c.order == crate::study::Order::Full { "full-order" } else { "reduced-order" }
        );
    }
    out +=
        &format!("{:>12}  {:>10}  {:>10}  {:>10}", &format!("x ({})", response.unit()), "P(peak>x)", "lower", "upper");
    let milli_g = response.is_acceleration();
    if milli_g {
        out += &format!("  {:>11}", "x (milli-g)");
    }
    if certification.is_some() {
        out += &format!("  {:>10}  {:>10}", "metamodel", "mismatch");
    }
    out += "\n";
    let step = (curve.thresholds.len() / 12).max(1);
    for i in (0..curve.thresholds.len()).step_by(step) {
        out += &format!(
            "{:>12.5}  {:>10.4}  {:>10.4}  {:>10.4}",
            curve.thresholds[i], curve.probabilities[i], curve.lower[i], curve.upper[i]
        );
        if milli_g {
            out += &format!("  {:>11.2}", curve.thresholds[i] / STANDARD_GRAVITY * 1e3);
        }
        if let Some(c) = &certification {
            out += &format!("  {:>10.4}  {:>10.4}", c.metamodel_probabilities[i], c.mismatch_rate[i]);
        }
        out += "\n";
    }
    Ok(out)
}
