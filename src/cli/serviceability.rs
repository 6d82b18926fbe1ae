//! `windmeta serviceability`: criteria of comfort, drift and strength judged together under a
//! site's climate, each with its governing floor, band and verdict.

use super::args::{AnalysisArgs, CertifyArgs, answer, climate_arg, out_format};
use super::read_metamodel;
use super::validate::Counter;
use crate::analysis::{
    BUILT_IN, CriterionChoice, OnThisMachine, Serviceability, ServiceabilityOptions, metamodel_serviceability,
    serviceability_svg,
};
use crate::error::{Error, Result};
use clap::Args;
use std::path::PathBuf;
use std::time::Instant;

/// What `windmeta serviceability` checks, under which climate.
#[derive(Debug, Clone, Args)]
pub struct ServiceabilityArgs {
    /// The metamodel (JSON from `windmeta calibrate`).
    #[arg(long)]
    pub model: PathBuf,
    /// The law of the annual maximum storm speed, as JSON (as for `hazard`). Default: the
    /// metamodel's wind_speed.
    #[arg(long)]
    pub climate: Option<String>,
    /// Built-in criteria, comma separated: nbcc-residential, nbcc-office, drift-h400 (all three
    /// when neither this nor --criteria-file is given).
    #[arg(long, value_delimiter = ',')]
    pub criteria: Vec<String>,
    /// A JSON array of criteria: built-in names or objects {"name", "response", "statistic",
    /// "return_period_years", "limit" | "limit_per_storey_height", "floors", "strength"}.
    #[arg(long)]
    pub criteria_file: Option<PathBuf>,
    /// Storms of the annual analysis.
    #[arg(long, default_value_t = 20_000)]
    pub samples: usize,
    /// With --certify N: each criterion's governing floor certified by N storms through both models.
    #[command(flatten)]
    pub certify: CertifyArgs,
    /// Seed, confidence level and JSON output.
    #[command(flatten)]
    pub analysis: AnalysisArgs,
    /// Write the answer: .csv, .json or .svg by extension.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// Runs `windmeta serviceability`: each criterion's level, band and verdict.
pub fn serviceability(args: &ServiceabilityArgs) -> Result<String> {
    let format = out_format(args.out.as_deref(), &["csv", "json", "svg"])?;
    let (metamodel, study) = read_metamodel(&args.model)?;
    let named: Vec<String> = match (&args.criteria[..], &args.criteria_file) {
        ([], None) => BUILT_IN.iter().map(|name| name.to_string()).collect(),
        (names, _) => names.to_vec(),
    };
    let mut choices: Vec<CriterionChoice> = named.into_iter().map(CriterionChoice::BuiltIn).collect();
    if let Some(path) = &args.criteria_file {
        let text = std::fs::read_to_string(path)
            .map_err(|e| Error::invalid("criteria_file", format!("cannot read {}: {e}", path.display())))?;
        let listed: Vec<CriterionChoice> = serde_json::from_str(&text)
            .map_err(|e| Error::invalid("criteria_file", format!("{}: {e}", path.display())))?;
        choices.extend(listed);
    }
    let floors = study.structure.floors();
    let options = ServiceabilityOptions {
        climate: climate_arg(args.climate.as_deref(), &study)?,
        criteria: choices.iter().map(|c| c.criterion(floors)).collect::<Result<_>>()?,
        samples: args.samples,
        seed: args.analysis.seed,
        confidence: args.analysis.confidence,
        certify: args.certify.options(),
    };
    let started = Instant::now();
    let check = metamodel_serviceability(&metamodel, &study, &options, &OnThisMachine, &Counter(started))?;
    let seconds = started.elapsed().as_secs_f64();
    let out = args.out.as_deref().zip(format);
    let render = |format: &str| if format == "csv" { check.csv() } else { serviceability_svg(&check) };
    answer(&check, args.analysis.json, out, render, || table(&check, seconds))
}

fn table(check: &Serviceability, seconds: f64) -> String {
    let number = |x: Option<f64>| x.map_or("-".to_string(), |x| format!("{x:.4}"));
    let mut out = format!(
        "serviceability: {} storms in {} strata in {seconds:.2} s; bands at {}\n",
        check.samples, check.strata, check.confidence
    );
    out += &format!(
        "{:<18} {:>14} {:>7} {:>5} {:>9} {:>20} {:>9} {:>6}  verdict\n",
        "criterion", "response", "T (y)", "floor", "level", "band", "limit", "util."
    );
    for c in &check.criteria {
        let response = match c.statistic {
            crate::analysis::Statistic::Rms => "rms acceleration".to_string(),
            crate::analysis::Statistic::Peak => c.response.name().to_string(),
        };
        out += &format!(
            "{:<18} {:>14} {:>7} {:>5} {:>9} {:>20} {:>9.4} {:>6}  {:?}\n",
            c.name,
            response,
            c.return_period_years,
            c.governing_floor,
            number(c.value),
            format!("[{}, {}]", number(c.lower), number(c.upper)),
            c.limit,
            c.utilisation.map_or("-".into(), |u| format!("{u:.2}")),
            c.verdict
        );
        if let Some(certified) = &c.certification {
            out += &format!(
                "{:<18} certified at floor {} with {} reference storms ({:?} order); the metamodel alone: {} [{}, {}]\n",
                "",
                certified.floor,
                certified.reference_storms,
                certified.order,
                number(certified.metamodel_value),
                number(certified.metamodel_lower),
                number(certified.metamodel_upper),
            );
        }
        if let Some(s) = &c.strength {
            out += &format!(
                "{:<18} floor {}: P = {:.2e} per year [{:.2e}, {:.2e}], beta {} against the target {:.2e} (beta {:.2}) of risk category {:?}\n",
                "",
                s.floor,
                s.annual_probability,
                s.lower,
                s.upper,
                s.beta.map_or("-".into(), |b| format!("{b:.2}")),
                s.target_annual_probability,
                s.target_beta,
                s.risk_category
            );
        }
    }
    out += &format!("units: SI ({}); levels at the governing floor\n", units(check));
    if check.diverged_storms > 0 {
        out += &format!(
            "{} of {} storms diverged (counted as exceeding every level); the first: {}\n",
            check.diverged_storms,
            check.samples,
            crate::analysis::describe_diverged(&check.first_diverged)
        );
    }
    out
}

/// Each criterion's unit, once.
fn units(check: &Serviceability) -> String {
    let mut units: Vec<&str> = check.criteria.iter().map(|c| c.unit.as_str()).collect();
    units.dedup();
    units.join(", ")
}
