//! `windmeta profile`: the profile of a quantile of a response's peaks up the height, sampled from
//! a metamodel.

use super::args::{AnalysisArgs, SamplingArgs, answer, out_format};
use super::read_metamodel;
use super::validate::Counter;
use crate::analysis::{
    OnThisMachine, PeakProfile, ResponseKind, check_confidence, check_quantile, metamodel_profiles, profile_svg,
};
use crate::error::Result;
use clap::Args;
use std::path::PathBuf;
use std::time::Instant;

/// What `windmeta profile` samples and which quantile it profiles.
#[derive(Debug, Clone, Args)]
pub struct ProfileArgs {
    /// The metamodel, the storms sampled and the inputs held.
    #[command(flatten)]
    pub sampling: SamplingArgs,
    /// The response at every floor: displacement, drift, acceleration, damper_force or
    /// damper_stroke (the floors above a damper).
    #[arg(long, default_value = "drift")]
    pub response: String,
    /// Probability of the quantile profiled, e.g. 0.9 for the peak one storm in ten exceeds.
    #[arg(long, default_value_t = 0.9, allow_negative_numbers = true)]
    pub quantile: f64,
    /// Seed, confidence level and JSON output.
    #[command(flatten)]
    pub analysis: AnalysisArgs,
    /// Write the profile: .csv, .json or .svg by extension.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

fn csv_text(profile: &PeakProfile, unit: &str) -> String {
    let mut out = format!("floor,quantile_{unit},lower_{unit},upper_{unit},mean_{unit}\n");
    for i in 0..profile.floors.len() {
        out += &format!(
            "{},{},{},{},{}\n",
            profile.floors[i], profile.values[i], profile.lower[i], profile.upper[i], profile.means[i]
        );
    }
    out
}

/// Runs `windmeta profile`: the quantile at every floor with its band.
pub fn profile(args: &ProfileArgs) -> Result<String> {
    check_quantile(args.quantile)?;
    check_confidence(args.analysis.confidence)?;
    let format = out_format(args.out.as_deref(), &["csv", "json", "svg"])?;
    let (metamodel, study) = read_metamodel(&args.sampling.model)?;
    let inputs = args.sampling.held_inputs(&study)?;
    let kind = ResponseKind::parse(&args.response)?;
    let started = Instant::now();
    let seed = args.analysis.seed;
    let samples = metamodel_profiles(
        &metamodel,
        &study,
        &inputs,
        args.sampling.samples,
        seed,
        kind,
        &OnThisMachine,
        &Counter(started),
    )?;
    let seconds = started.elapsed().as_secs_f64();
    let profile = samples.quantile_profile(args.quantile, args.analysis.confidence)?;
    let label = format!("{} ({})", kind.at_floor(1).per_storm().replace(" of floor 1", ""), profile.unit);
    let out = args.out.as_deref().zip(format);
    answer(
        &profile,
        args.analysis.json,
        out,
        |format| {
            if format == "csv" {
                csv_text(&profile, samples.responses[0].unit_tag())
            } else {
                profile_svg(&profile, &label)
            }
        },
        || {
            let percent = 100.0 * profile.quantile;
            let mut table = format!("{label} up the height: {} samples in {seconds:.2} s\n", profile.samples);
            table += &format!(
                "{:>6}  {:>12}  {:>12}  {:>12}  {:>12}\n",
                "floor",
                format!("{percent} %"),
                format!("lower {}", 100.0 * profile.confidence),
                "upper",
                "mean"
            );
            for i in (0..profile.floors.len()).rev() {
                table += &format!(
                    "{:>6}  {:>12.5}  {:>12.5}  {:>12.5}  {:>12.5}\n",
                    profile.floors[i], profile.values[i], profile.lower[i], profile.upper[i], profile.means[i]
                );
            }
            table
        },
    )
}
