//! `windmeta sweep`: the T-year level of a response with one input held at each of several
//! values, the same storms at every value: how a damper is sized against a limit.

use super::args::{AnalysisArgs, ResponseArgs, answer, climate_arg, out_format};
use super::read_metamodel;
use super::validate::Counter;
use crate::analysis::{OnThisMachine, Sweep, SweepOptions, metamodel_sweep, sweep_svg};
use crate::error::Result;
use clap::Args;
use std::path::PathBuf;
use std::time::Instant;

/// What `windmeta sweep` holds, at which values, and which level it reports.
#[derive(Debug, Clone, Args)]
pub struct SweepArgs {
    /// The metamodel (JSON from `windmeta calibrate`).
    #[arg(long)]
    pub model: PathBuf,
    /// The input held at each value, e.g. damper_c4 (a random input other than wind_speed).
    #[arg(long)]
    pub input: String,
    /// The values, comma separated, inside the input's support.
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true, required = true)]
    pub values: Vec<f64>,
    /// The law of the annual maximum storm speed, as JSON (as for `hazard`). Default: the
    /// metamodel's wind_speed.
    #[arg(long)]
    pub climate: Option<String>,
    /// The return period (years) whose level is reported.
    #[arg(long, default_value_t = 10.0)]
    pub return_period: f64,
    /// The peak response whose level is reported.
    #[command(flatten)]
    pub response: ResponseArgs,
    /// Storms at each value (the same storms at every value).
    #[arg(long, default_value_t = 10_000)]
    pub samples: usize,
    /// A limit (SI) drawn on the SVG.
    #[arg(long)]
    pub limit: Option<f64>,
    /// Seed, confidence level and JSON output.
    #[command(flatten)]
    pub analysis: AnalysisArgs,
    /// Write the answer: .csv, .json or .svg by extension.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// Runs `windmeta sweep`: the T-year level at each value, with its band.
pub fn sweep(args: &SweepArgs) -> Result<String> {
    let format = out_format(args.out.as_deref(), &["csv", "json", "svg"])?;
    let (metamodel, study) = read_metamodel(&args.model)?;
    let response = args.response.response(&study)?;
    let options = SweepOptions {
        input: args.input.clone(),
        values: args.values.clone(),
        climate: climate_arg(args.climate.as_deref(), &study)?,
        return_period_years: args.return_period,
        samples: args.samples,
        seed: args.analysis.seed,
        confidence: args.analysis.confidence,
    };
    let started = Instant::now();
    let sweep = metamodel_sweep(&metamodel, &study, response, &options, &OnThisMachine, &Counter(started))?;
    let seconds = started.elapsed().as_secs_f64();
    let label = format!("{}-year {} ({})", sweep.return_period_years, response.per_storm(), response.unit());
    let out = args.out.as_deref().zip(format);
    let render = |format: &str| {
        if format == "csv" { sweep.csv(response.unit_tag()) } else { sweep_svg(&sweep, &label, args.limit) }
    };
    answer(&sweep, args.analysis.json, out, render, || table(&sweep, &label, seconds))
}

fn table(sweep: &Sweep, label: &str, seconds: f64) -> String {
    let number = |x: Option<f64>| x.map_or("-".to_string(), |x| format!("{x:.5}"));
    let mut out = format!(
        "{label} over {}: {} storms at each of {} values ({} strata) in {seconds:.2} s\n",
        sweep.input,
        sweep.samples,
        sweep.results.len(),
        sweep.strata
    );
    out += &format!("{:>14}  {:>10}  {:>10}  {:>10}\n", sweep.input, "level", "lower", "upper");
    let value = |x: f64| if x != 0.0 && !(1e-3..1e6).contains(&x.abs()) { format!("{x:.4e}") } else { x.to_string() };
    for p in &sweep.results {
        out += &format!(
            "{:>14}  {:>10}  {:>10}  {:>10}\n",
            value(p.input_value),
            number(p.level),
            number(p.lower),
            number(p.upper)
        );
    }
    let [lo, hi] = sweep.calibrated_input_range;
    out += &format!("calibrated {}: {lo:.4e} to {hi:.4e}\n", sweep.input);
    if sweep.diverged_storms > 0 {
        out += &format!("{} storms diverged at some value (counted as exceeding there)\n", sweep.diverged_storms);
    }
    out
}
