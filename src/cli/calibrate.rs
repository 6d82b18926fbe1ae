//! `windmeta calibrate`: a PC-NARX metamodel from a Latin-hypercube design of reference storms.

use super::StudyArgs;
use crate::analysis::{ClimateCoverage, ClimateSpec};
use crate::error::{Error, Result};
use crate::progress::{Observer, Progress};
use crate::surrogate::{CalibrationOptions, Refinement, WindCoverage, calibrate as run_calibration};
use clap::{Args, ValueEnum};
use std::path::PathBuf;
use std::sync::Mutex;
use std::time::Instant;

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum RefinementChoice {
    /// Levenberg-Marquardt with sensitivities of the recursion (default).
    Lm,
    /// The paper's Nelder-Mead simplex.
    NelderMead,
    /// One-step least squares only.
    None,
}

/// What `windmeta calibrate` fits and where it writes the metamodel.
#[derive(Debug, Clone, Args)]
pub struct CalibrateArgs {
    /// The study calibrated on.
    #[command(flatten)]
    pub study: StudyArgs,
    /// Experiments K of the Latin-hypercube design.
    #[arg(long, default_value_t = 200)]
    pub experiments: usize,
    /// Seed of the Latin-hypercube design and of the experiments' storms.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Refinement of the coefficients on the simulation error.
    #[arg(long, value_enum, default_value = "lm")]
    pub refinement: RefinementChoice,
    /// Allow products of output and input powers in the NARX dictionary (22 candidates).
    #[arg(long)]
    pub cross_terms: bool,
    /// The dampers' law of the modal velocities as candidate terms besides the paper's
    /// polynomial dictionary (about half the acceleration's and damper force's error); false
    /// keeps the paper's dictionary alone, whose curves sample about three times faster
    /// (docs/method.md)
    #[arg(long, value_name = "BOOL", default_value_t = true, action = clap::ArgAction::Set)]
    pub damper_terms: bool,
    /// With the dampers' law, also each mode's own velocity at the law's secant at another
    /// mode's, refined and expanded as a damping (the peak acceleration's and damper force's
    /// bias under 1 % at full size, where without it they are about 3 % low; docs/method.md);
    /// false leaves it out
    #[arg(long, value_name = "BOOL", default_value_t = true, action = clap::ArgAction::Set)]
    pub secant_terms: bool,
    /// Cover these wind speeds (m/s) beyond the input model's spread, as LOWER:UPPER; the fits
    /// are weighted so the expansions stay the input model's.
    #[arg(long, value_name = "LOWER:UPPER", conflicts_with = "cover_climate")]
    pub cover_wind_speeds: Option<String>,
    /// Cover a climate (JSON, as `windmeta hazard --climate`): from its 1-year speed to
    /// the speed of --cover-annual-probability.
    #[arg(long, value_name = "JSON")]
    pub cover_climate: Option<String>,
    /// The rarest annual exceedance probability a covered climate's answers must reach.
    #[arg(long, default_value_t = 1e-5, requires = "cover_climate")]
    pub cover_annual_probability: f64,
    /// Where to write the metamodel (JSON).
    #[arg(long)]
    pub out: PathBuf,
}

/// Prints each stage once and experiment counts every 10 %, on standard error.
struct Terminal {
    started: Instant,
    last: Mutex<String>,
}

impl Observer for Terminal {
    fn progress(&self, progress: Progress) {
        let line = match progress {
            Progress::Experiments { done, total } if done == total || done % (total / 10).max(1) == 0 => {
                format!("experiments {done}/{total}")
            }
            Progress::Structure { mode } => format!("mode {mode}: structure selection"),
            Progress::Expansion { mode } => format!("mode {mode}: polynomial chaos expansions"),
            _ => return,
        };
        let mut last = self.last.lock().expect("progress lock");
        if *last != line {
            eprintln!("[{:>7.1} s] {line}", self.started.elapsed().as_secs_f64());
            *last = line;
        }
    }
}

/// The wind speeds the design must cover, from either option.
fn coverage(args: &CalibrateArgs) -> Result<Option<WindCoverage>> {
    if let Some(text) = &args.cover_climate {
        let climate: ClimateSpec =
            serde_json::from_str(text).map_err(|e| Error::invalid("cover_climate", e.to_string()))?;
        let request = ClimateCoverage { climate, annual_probability: args.cover_annual_probability };
        return request.wind_speeds("cover_climate").map(Some);
    }
    let Some(text) = &args.cover_wind_speeds else { return Ok(None) };
    let bad = || Error::invalid("cover_wind_speeds", format!("expected LOWER:UPPER in m/s, got `{text}`"));
    let (lower, upper) = text.split_once(':').ok_or_else(bad)?;
    let speed = |s: &str| s.trim().parse::<f64>().map_err(|_| bad());
    let coverage = WindCoverage { lower: speed(lower)?, upper: speed(upper)? };
    coverage.check()?;
    Ok(Some(coverage))
}

/// Runs `windmeta calibrate`: fits, writes the metamodel and returns a summary of the fit.
pub fn calibrate(args: &CalibrateArgs) -> Result<String> {
    let study = args.study.study()?;
    let mut options = CalibrationOptions { experiments: args.experiments, seed: args.seed, ..Default::default() };
    options.refinement = match args.refinement {
        RefinementChoice::Lm => Refinement::LevenbergMarquardt,
        RefinementChoice::NelderMead => Refinement::NelderMead,
        RefinementChoice::None => Refinement::None,
    };
    options.narx.cross_terms = args.cross_terms;
    options.narx.damper_terms = args.damper_terms;
    options.narx.secant_terms = args.secant_terms;
    options.cover_wind_speeds = coverage(args)?;
    let observer = Terminal { started: Instant::now(), last: Mutex::new(String::new()) };
    let metamodel = run_calibration(&study, &options, &observer)?;
    let json = serde_json::to_string(&metamodel).expect("a metamodel serialises");
    std::fs::write(&args.out, json).map_err(|e| Error::invalid("out", format!("{}: {e}", args.out.display())))?;
    let c = &metamodel.calibration;
    let mut out = format!(
        "{}: {} experiments of {} s, seed {}, in {:.1} s (experiments {:.1} s, structure {:.1} s, coefficients {:.1} s, expansions {:.1} s)\n",
        study.name,
        options.experiments,
        study.storm.duration,
        options.seed,
        c.seconds.total,
        c.seconds.experiments,
        c.seconds.structure,
        c.seconds.coefficients,
        c.seconds.expansion
    );
    if let Some(coverage) = options.cover_wind_speeds {
        out += &format!(
            "design covers wind speeds {:.1}-{:.1} m/s (half the experiments), fits weighted to the input model\n",
            coverage.lower, coverage.upper
        );
    }
    for d in &c.modes {
        out += &format!(
            "mode {}: terms {{{}}}, calibration mean relative error NARX {:.2e}, PC-NARX {:.2e}, PCE terms {:?}, worst LOO {:.1e}{}\n",
            d.mode,
            d.selected_terms.join(", "),
            d.narx_mean_relative_error,
            d.pc_narx_mean_relative_error,
            d.coefficient_pce_terms,
            d.coefficient_loo_errors.iter().fold(0.0f64, |m, v| m.max(*v)),
            if d.diverged_experiments > 0 { format!(", {} diverged", d.diverged_experiments) } else { String::new() }
        );
        let r = &d.refinement;
        if options.refinement != Refinement::None {
            out += &format!(
                "  refinement: {} converged, {} at the iteration cap, {} without an improving step, {} from a diverging start; iterations median {}, max {}\n",
                r.converged,
                r.iteration_cap,
                r.no_improving_step,
                r.undefined_start,
                r.median_iterations,
                r.max_iterations
            );
        }
    }
    out += &format!(
        "mean over modes: NARX {:.2e}, PC-NARX {:.2e}\nmetamodel written to {}\n",
        c.narx_mean_relative_error,
        c.pc_narx_mean_relative_error,
        args.out.display()
    );
    Ok(out)
}
