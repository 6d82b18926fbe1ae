//! `windmeta validate`: a metamodel against the reference on fresh samples.

use super::read_metamodel;
use crate::analysis::{validate as run_validation, validation_svg};
use crate::error::{Error, Result};
use crate::progress::{Observer, Progress};
use crate::uncertainty::parse_assignment;
use clap::Args;
use std::path::PathBuf;
use std::time::Instant;

/// What `windmeta validate` compares.
#[derive(Debug, Clone, Args)]
pub struct ValidateArgs {
    /// The metamodel (JSON from `windmeta calibrate`).
    #[arg(long)]
    pub model: PathBuf,
    /// Fresh Monte Carlo samples, each one storm through both models.
    #[arg(long, default_value_t = 200)]
    pub samples: usize,
    /// Seed of the fresh samples and of their storms' wind.
    #[arg(long, default_value_t = 1000)]
    pub seed: u64,
    /// Hold an input at a value, e.g. --fix wind_speed=60 to validate at the end of a calibrated
    /// range (repeatable).
    #[arg(long = "fix", value_name = "NAME=VALUE")]
    pub fix: Vec<String>,
    /// Print the whole report as JSON.
    #[arg(long)]
    pub json: bool,
    /// Also write the JSON report here.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Write the figure (peak scatter and exceedance curves) as SVG.
    #[arg(long)]
    pub plot: Option<PathBuf>,
}

pub(super) struct Counter(pub Instant);

impl Observer for Counter {
    fn progress(&self, progress: Progress) {
        let (done, total, what) = match progress {
            Progress::Samples { done, total } => (done, total, "samples"),
            Progress::ReferenceStorms { done, total } => (done, total, "reference storms"),
            _ => return,
        };
        if done == total || done % (total / 10).max(1) == 0 {
            eprintln!("[{:>7.1} s] {done}/{total} {what}", self.0.elapsed().as_secs_f64());
        }
    }
}

/// Runs `windmeta validate`: the metamodel's peaks and curves against the reference's.
pub fn validate(args: &ValidateArgs) -> Result<String> {
    let (metamodel, study) = read_metamodel(&args.model)?;
    let mut inputs = study.inputs.clone();
    for assignment in &args.fix {
        let (name, value) = parse_assignment(assignment)?;
        inputs = inputs.with_fixed(&name, value)?;
    }
    let report = run_validation(&metamodel, &study, &inputs, args.samples, args.seed, &Counter(Instant::now()))?;
    let json = serde_json::to_string_pretty(&report).expect("a report serialises");
    if let Some(path) = &args.out {
        std::fs::write(path, &json).map_err(|e| Error::invalid("out", format!("{}: {e}", path.display())))?;
    }
    if let Some(path) = &args.plot {
        let svg = validation_svg(
            &report.reference_peak,
            &report.metamodel_peak,
            &[("reference", &report.reference_exceedance), ("PC-NARX", &report.metamodel_exceedance)],
        );
        std::fs::write(path, svg).map_err(|e| Error::invalid("plot", format!("{}: {e}", path.display())))?;
    }
    if args.json {
        return Ok(json);
    }
    let modes: Vec<String> = report.mode_mean_relative_errors.iter().map(|e| format!("{e:.2e}")).collect();
    let mut responses = format!(
        "{:<16} {:>5} {:>12} {:>15} {:>11} {:>9} {:>9} {:>6}\n",
        "response", "floor", "mean peak", "metamodel/ref.", "correlation", "median %", "p95 %", "gap"
    );
    for r in &report.responses {
        responses += &format!(
            "{:<16} {:>5} {:>9.4} {:<4} {:>15.4} {:>11.4} {:>9.2} {:>9.2} {:>6.3}\n",
            r.response.name(),
            r.floor,
            r.mean_reference_peak,
            r.unit,
            r.mean_metamodel_peak / r.mean_reference_peak,
            r.peak_correlation,
            100.0 * r.median_peak_relative_error,
            100.0 * r.p95_peak_relative_error,
            r.max_exceedance_gap
        );
    }
    Ok(format!(
        "{} on {} fresh samples (seed {}){}\n\
         peak roof displacement: correlation {:.4}, median relative error {:.2} %, 95th percentile {:.2} %\n\
         mean relative error, full PC-NARX: roof {:.2e}, modes [{}]\n\
         calibration mean relative error (NARX, mean over modes): {:.2e}\n\
         largest gap between the exceedance curves: {:.3}\n\
         per sample: reference {:.1} ms, metamodel {:.2} ms (×{:.0})\n{}",
        study.name,
        report.samples,
        report.seed,
        report.fixed.iter().map(|(name, value)| format!(", {name} held at {value}")).collect::<String>(),
        report.peak_correlation,
        100.0 * report.median_peak_relative_error,
        100.0 * report.p95_peak_relative_error,
        report.mean_relative_error,
        modes.join(", "),
        report.calibration_mean_relative_error,
        report.max_exceedance_gap,
        1e3 * report.reference_seconds_per_sample,
        1e3 * report.metamodel_seconds_per_sample,
        report.reference_seconds_per_sample / report.metamodel_seconds_per_sample,
        responses,
    ))
}
