//! `windmeta hazard`: the annual exceedance curve of a peak response under a wind climate, its
//! return levels and, at a limit, the reliability index.

use super::args::{AnalysisArgs, CertifyArgs, ResponseArgs, answer, climate_arg, out_format};
use super::read_metamodel;
use super::validate::Counter;
use crate::analysis::{
    DEFAULT_RETURN_PERIODS, HazardCurve, HazardOptions, OnThisMachine, Sampling, hazard_svg, metamodel_hazard,
};
use crate::error::Result;
use clap::{Args, ValueEnum};
use std::path::PathBuf;
use std::time::Instant;

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum SamplingArg {
    Stratified,
    MonteCarlo,
}

/// What `windmeta hazard` samples under which climate, and what it reports.
#[derive(Debug, Clone, Args)]
pub struct HazardArgs {
    /// The metamodel (JSON from `windmeta calibrate`).
    #[arg(long)]
    pub model: PathBuf,
    /// The law of the annual maximum storm speed, as JSON: a marginal such as
    /// '{"distribution": "gumbel", "location": 22, "scale": 2.2}', or
    /// '{"return_period_speeds": {"50": 32, "700": 40}}'. Default: the metamodel's wind_speed.
    #[arg(long)]
    pub climate: Option<String>,
    /// The peak response whose annual curve is computed.
    #[command(flatten)]
    pub response: ResponseArgs,
    /// Thresholds (m), comma separated; 50 spread over the sampled peaks when absent.
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true)]
    pub thresholds: Option<Vec<f64>>,
    /// Return periods (years, from 1 to 10⁶), comma separated; the T-year level is exceeded in a
    /// year with probability 1 − exp(−1/T).
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true)]
    pub return_periods: Option<Vec<f64>>,
    /// A limit (m) whose annual probability and reliability index are reported.
    #[arg(long, allow_negative_numbers = true)]
    pub limit: Option<f64>,
    /// Storms of the annual analysis.
    #[arg(long, default_value_t = 20_000)]
    pub samples: usize,
    /// How the storm speeds are drawn: equal numbers per stratum of the climate's tail, or plain
    /// Monte Carlo.
    #[arg(long, value_enum, default_value = "stratified")]
    pub sampling: SamplingArg,
    /// With --certify N: N storms through both models, shared out over the wind strata.
    #[command(flatten)]
    pub certify: CertifyArgs,
    /// Seed, confidence level and JSON output.
    #[command(flatten)]
    pub analysis: AnalysisArgs,
    /// Write the answer: .csv, .json or .svg by extension.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// Runs `windmeta hazard`: the annual curve, return levels and reliability index.
pub fn hazard(args: &HazardArgs) -> Result<String> {
    let format = out_format(args.out.as_deref(), &["csv", "json", "svg"])?;
    let (metamodel, study) = read_metamodel(&args.model)?;
    let climate = climate_arg(args.climate.as_deref(), &study)?;
    let options = HazardOptions {
        climate,
        samples: args.samples,
        seed: args.analysis.seed,
        thresholds: args.thresholds.clone(),
        return_periods: args.return_periods.clone().unwrap_or_else(|| DEFAULT_RETURN_PERIODS.to_vec()),
        limit: args.limit,
        confidence: args.analysis.confidence,
        sampling: match args.sampling {
            SamplingArg::Stratified => Sampling::Stratified,
            SamplingArg::MonteCarlo => Sampling::MonteCarlo,
        },
        certify: args.certify.options(),
    };
    let response = args.response.response(&study)?;
    let started = Instant::now();
    let curve = metamodel_hazard(&metamodel, &study, response, &options, &OnThisMachine, &Counter(started))?;
    let seconds = started.elapsed().as_secs_f64();
    let what = response.per_storm();
    let out = args.out.as_deref().zip(format);
    let render = |format: &str| {
        if format == "csv" {
            curve.csv(response.unit_tag())
        } else {
            hazard_svg(&curve, &format!("{what} x ({})", response.unit()))
        }
    };
    answer(&curve, args.analysis.json, out, render, || table(&curve, &what, response.unit(), seconds))
}

fn table(curve: &HazardCurve, what: &str, unit: &str, seconds: f64) -> String {
    let number = |x: Option<f64>| x.map_or("-".to_string(), |x| format!("{x:.5}"));
    let mut out = format!(
        "annual {what}: {} storms in {} strata ({:?}) in {seconds:.2} s\n",
        curve.samples, curve.strata, curve.sampling
    );
    if let Some(c) = &curve.certification {
        out += &format!(
            "certified with {} reference storms ({:?} order) over the strata: {:?}\n",
            c.points.reference_storms, c.points.order, c.reference_storms_per_stratum
        );
    }
    out += &format!(
        "{:>10}  {:>10}  {:>10}  {:>10}  {:>6}  {:>10}",
        &format!("x ({})", unit),
        "P/year",
        "lower",
        "upper",
        "cov",
        "MRI (y)"
    );
    if curve.certification.is_some() {
        out += &format!("  {:>10}  {:>9}", "PC-NARX", "mismatch");
    }
    out += "\n";
    let step = (curve.thresholds.len() / 12).max(1);
    for i in (0..curve.thresholds.len()).step_by(step) {
        out += &format!(
            "{:>10.5}  {:>10.3e}  {:>10.3e}  {:>10.3e}  {:>6}  {:>10}",
            curve.thresholds[i],
            curve.annual_probability[i],
            curve.lower[i],
            curve.upper[i],
            curve.cov[i].map_or("-".into(), |c| format!("{c:.3}")),
            curve.mri_years[i].map_or("-".into(), |t| format!("{t:.4}")),
        );
        if let Some(c) = &curve.certification {
            out += &format!("  {:>10.3e}  {:>9.2e}", c.points.metamodel_probabilities[i], c.points.mismatch_rate[i]);
        }
        out += "\n";
    }
    out += &format!("{:>10}  {:>10}  {:>10}  {:>10}\n", "T (years)", &format!("x_T ({})", unit), "lower", "upper");
    for r in &curve.return_levels {
        out += &format!(
            "{:>10}  {:>10}  {:>10}  {:>10}\n",
            r.return_period_years,
            number(r.value),
            number(r.lower),
            number(r.upper)
        );
    }
    if let Some(r) = &curve.reliability {
        out += &format!(
            "limit {} m: P = {:.3e} per year [{:.3e}, {:.3e}], β = {}\n",
            r.limit,
            r.annual_probability,
            r.lower,
            r.upper,
            r.beta.map_or("-".into(), |b| format!("{b:.3}"))
        );
    }
    if curve.diverged_storms > 0 {
        out += &format!(
            "{} of {} storms diverged (counted as exceeding every threshold); the first: {}\n",
            curve.diverged_storms,
            curve.samples,
            crate::analysis::describe_diverged(&curve.first_diverged)
        );
    }
    out += &format!(
        "calibrated wind speeds {:.1}-{:.1} m/s; the climate's probability outside them {:.2e}\n",
        curve.calibrated_wind_range[0], curve.calibrated_wind_range[1], curve.climate_beyond_calibrated_range
    );
    out
}
