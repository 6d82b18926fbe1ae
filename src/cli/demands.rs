//! `windmeta demands`: per storm at one wind speed, the peak floor accelerations and inter-storey
//! drift ratios, as a pelicun demand sample for loss assessment.

use super::read_metamodel;
use super::validate::Counter;
use crate::analysis::{OnThisMachine, metamodel_demands};
use crate::error::{Error, Result};
use clap::Args;
use std::path::PathBuf;
use std::time::Instant;

/// What `windmeta demands` samples and where it writes the demand sample.
#[derive(Debug, Clone, Args)]
pub struct DemandsArgs {
    /// The metamodel (JSON from `windmeta calibrate`).
    #[arg(long)]
    pub model: PathBuf,
    /// The storm speed at 10 m (m/s), inside the metamodel's wind-speed law's support.
    #[arg(long, allow_negative_numbers = true)]
    pub wind_speed: f64,
    /// Storms (rows of the demand sample).
    #[arg(long, default_value_t = 1000)]
    pub samples: usize,
    /// Seed of the input samples and of the storms' wind.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// The demand sample (CSV); written to standard output when absent.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// Runs `windmeta demands`: the CSV itself, or a summary when it was written to `--out`.
pub fn demands(args: &DemandsArgs) -> Result<String> {
    let (metamodel, study) = read_metamodel(&args.model)?;
    let started = Instant::now();
    let demands = metamodel_demands(
        &metamodel,
        &study,
        args.wind_speed,
        args.samples,
        args.seed,
        &OnThisMachine,
        &Counter(started),
    )?;
    let csv = demands.pelicun_csv();
    let Some(path) = &args.out else { return Ok(csv) };
    std::fs::write(path, &csv).map_err(|e| Error::invalid("out", format!("{}: {e}", path.display())))?;
    Ok(format!(
        "{} storms at {} m/s in {:.2} s: peak accelerations of {} floors (g) and drift ratios of {} storeys (rad) in {}",
        args.samples,
        args.wind_speed,
        started.elapsed().as_secs_f64(),
        study.structure.floors() + 1,
        study.structure.floors(),
        path.display()
    ))
}
