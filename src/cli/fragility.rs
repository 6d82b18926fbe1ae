//! `windmeta fragility`: P(peak > x | v) over a grid of storm speeds, with lognormal fits.

use super::args::{AnalysisArgs, CertifyArgs, ResponseArgs, answer, out_format};
use super::read_metamodel;
use super::validate::Counter;
use crate::analysis::{
    Fragility, FragilityOptions, MAX_WIND_SPEEDS, OnThisMachine, fragility_svg, metamodel_fragility,
};
use crate::error::{Error, Result};
use clap::Args;
use std::path::PathBuf;
use std::time::Instant;

/// What `windmeta fragility` samples: speeds, thresholds, storms per speed.
#[derive(Debug, Clone, Args)]
pub struct FragilityArgs {
    /// The metamodel (JSON from `windmeta calibrate`).
    #[arg(long)]
    pub model: PathBuf,
    /// Storm speeds (m/s): from:to:step, or a comma-separated list.
    #[arg(long, default_value = "20:60:2")]
    pub wind_speeds: String,
    /// Thresholds (m), comma separated.
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true, required = true)]
    pub thresholds: Vec<f64>,
    /// The peak response the thresholds are in.
    #[command(flatten)]
    pub response: ResponseArgs,
    /// Storms at each speed.
    #[arg(long, default_value_t = 500)]
    pub samples: usize,
    /// Seed, confidence level and JSON output.
    #[command(flatten)]
    pub analysis: AnalysisArgs,
    /// With --certify N: N storms at each speed through both models.
    #[command(flatten)]
    pub certify: CertifyArgs,
    /// Write the answer: .json or .svg by extension.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// `from:to:step` (both ends included) or a comma-separated list.
pub fn parse_speeds(text: &str) -> Result<Vec<f64>> {
    let bad = || Error::invalid("wind_speeds", format!("expected from:to:step or a list of numbers, got `{text}`"));
    let numbers = |sep: char| -> Result<Vec<f64>> {
        text.split(sep).map(|t| t.trim().parse::<f64>().map_err(|_| bad())).collect()
    };
    if text.contains(':') {
        let parts = numbers(':')?;
        let [from, to, step] = parts[..] else { return Err(bad()) };
        if !(from.is_finite() && to.is_finite() && step > 0.0 && to >= from) {
            return Err(bad());
        }
        let count = ((to - from) / step + 1e-9).floor() as usize + 1;
        if count > MAX_WIND_SPEEDS {
            return Err(Error::invalid("wind_speeds", format!("at most {MAX_WIND_SPEEDS} speeds")));
        }
        return Ok((0..count).map(|k| from + step * k as f64).collect());
    }
    numbers(',')
}

/// Runs `windmeta fragility`: the curves and their lognormal fits.
pub fn fragility(args: &FragilityArgs) -> Result<String> {
    let format = out_format(args.out.as_deref(), &["json", "svg"])?;
    let (metamodel, study) = read_metamodel(&args.model)?;
    let options = FragilityOptions {
        wind_speeds: parse_speeds(&args.wind_speeds)?,
        thresholds: args.thresholds.clone(),
        samples_per_speed: args.samples,
        seed: args.analysis.seed,
        confidence: args.analysis.confidence,
        certify: args.certify.options(),
    };
    let response = args.response.response(&study)?;
    let started = Instant::now();
    let result = metamodel_fragility(&metamodel, &study, response, &options, &OnThisMachine, &Counter(started))?;
    let seconds = started.elapsed().as_secs_f64();
    let what = response.per_storm();
    let out = args.out.as_deref().zip(format);
    let render = |_: &str| fragility_svg(&result, &what);
    answer(&result, args.analysis.json, out, render, || table(&result, &what, response.unit(), seconds))
}

fn table(result: &Fragility, what: &str, unit: &str, seconds: f64) -> String {
    let mut out = format!(
        "{what}: {} storms at each of {} speeds in {seconds:.2} s\n",
        result.samples_per_speed,
        result.wind_speeds.len()
    );
    out += &format!(
        "{:>10}  {:>14}  {:>22}  {:>8}  {:>16}\n",
        &format!("x ({})", unit),
        "median θ (m/s)",
        "interval",
        "β",
        "interval"
    );
    if let Some(c) = result.curves.first().and_then(|c| c.certification.as_ref()) {
        out += &format!(
            "certified with {} storms at each speed through the reference model as well\n",
            c.reference_storms
        );
    }
    for c in &result.curves {
        match &c.lognormal {
            Some(f) => {
                let interval = |i: Option<[f64; 2]>| i.map_or("-".into(), |[a, b]| format!("[{a:.3}, {b:.3}]"));
                out += &format!(
                    "{:>10.5}  {:>14.3}  {:>22}  {:>8.4}  {:>16}\n",
                    c.threshold,
                    f.median_speed,
                    interval(f.median_speed_ci),
                    f.dispersion,
                    interval(f.dispersion_ci)
                );
            }
            None => out += &format!("{:>10.5}  never or always exceeded on this grid\n", c.threshold),
        }
    }
    for (v, &count) in result.wind_speeds.iter().zip(&result.diverged_storms).filter(|(_, c)| **c > 0) {
        out += &format!(
            "at {v} m/s {count} of {} storms diverged (counted as exceeding; the speed is left out of the fits)\n",
            result.samples_per_speed
        );
    }
    if !result.first_diverged.is_empty() {
        out += &format!("the first diverged: {}\n", crate::analysis::describe_diverged(&result.first_diverged));
    }
    out += &format!(
        "calibrated wind speeds {:.1}-{:.1} m/s\n",
        result.calibrated_wind_range[0], result.calibrated_wind_range[1]
    );
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn speeds_parse_as_a_range_or_a_list() {
        assert_eq!(parse_speeds("20:26:2").unwrap(), vec![20.0, 22.0, 24.0, 26.0]);
        assert_eq!(parse_speeds("30, 40").unwrap(), vec![30.0, 40.0]);
        for bad in ["20:10:2", "20:30:0", "20:30", "a,b", "0:1e9:1"] {
            assert!(parse_speeds(bad).unwrap_err().to_string().starts_with("wind_speeds"), "{bad}");
        }
    }
}
