//! `windmeta sensitivity`: Sobol indices of a peak response for every input and the storm.

use super::args::{AnalysisArgs, ResponseArgs};
use super::read_metamodel;
use super::validate::Counter;
use crate::analysis::{OnThisMachine, metamodel_sensitivity};
use crate::error::Result;
use clap::Args;
use std::path::PathBuf;
use std::time::Instant;

/// What `windmeta sensitivity` samples for the Sobol indices.
#[derive(Debug, Clone, Args)]
pub struct SensitivityArgs {
    /// The metamodel (JSON from `windmeta calibrate`).
    #[arg(long)]
    pub model: PathBuf,
    /// The peak response whose variance is apportioned.
    #[command(flatten)]
    pub response: ResponseArgs,
    /// Rows N of each of the two base samples; the analysis runs N·(groups + 2) storms.
    #[arg(long, default_value_t = 4096)]
    pub samples: usize,
    /// Seed, confidence level and JSON output.
    #[command(flatten)]
    pub analysis: AnalysisArgs,
}

/// Runs `windmeta sensitivity`: first-order and total indices with their intervals.
pub fn sensitivity(args: &SensitivityArgs) -> Result<String> {
    let (metamodel, study) = read_metamodel(&args.model)?;
    let response = args.response.response(&study)?;
    let started = Instant::now();
    let result = metamodel_sensitivity(
        &metamodel,
        &study,
        response,
        args.samples,
        args.analysis.seed,
        args.analysis.confidence,
        &OnThisMachine,
        &Counter(started),
    )?;
    let seconds = started.elapsed().as_secs_f64();
    if args.analysis.json {
        return Ok(serde_json::to_string_pretty(&result).expect("plain JSON"));
    }
    let unit = response.unit();
    let mut out = format!(
        "{}: {} storms (N = {}) in {seconds:.2} s; mean {:.5} {unit}, sd {:.5} {unit}\n",
        response.per_storm(),
        result.evaluations,
        result.samples,
        result.mean,
        result.variance.sqrt()
    );
    out += &format!("{:<16}  {:>8}  {:>18}  {:>8}  {:>18}\n", "input", "S", "interval", "S_T", "interval");
    for i in &result.indices {
        out += &format!(
            "{:<16}  {:>8.4}  [{:>7.4}, {:>7.4}]  {:>8.4}  [{:>7.4}, {:>7.4}]\n",
            i.name, i.first_order, i.first_order_ci[0], i.first_order_ci[1], i.total, i.total_ci[0], i.total_ci[1]
        );
    }
    Ok(out)
}
