//! `windmeta`: parse the command line and dispatch to an offline command.

use clap::{Parser, Subcommand};
use std::process::ExitCode;
use windmeta::cli;
use windmeta::error::Error;

/// Sampling allocates and frees buffers of a few hundred kilobytes per storm on every worker
/// thread; glibc's allocator returned them to the kernel and faulted them back in (an eighth of
/// an exceedance request's processor time went to the kernel). mimalloc keeps them per thread.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

#[derive(Debug, Parser)]
#[command(
    name = "windmeta",
    version,
    about = "Rapid uncertainty quantification of tall buildings under stochastic wind"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Run the HTTP service (embedded SQLite by default).
    Serve(windmeta::service::ServeArgs),
    /// Natural frequencies, periods, generalized masses and roof-normalised mode shapes.
    Modes(cli::ModesArgs),
    /// One storm through the reference model at the inputs' means (or fixed values).
    Simulate(cli::SimulateArgs),
    /// Peaks of a response over many storms through the reference model (plane or three-dimensional).
    SamplePeaks(cli::SamplePeaksArgs),
    /// Calibrate a PC-NARX metamodel on a Latin-hypercube design of reference storms.
    Calibrate(cli::CalibrateArgs),
    /// Validate a metamodel against the reference on fresh samples.
    Validate(cli::ValidateArgs),
    /// Exceedance curve of a peak response, sampled from a metamodel.
    Exceedance(cli::ExceedanceArgs),
    /// Profile of a quantile of a response's peaks at every floor, with its band.
    Profile(cli::ProfileArgs),
    /// Annual exceedance curve, return levels and reliability index under a wind climate.
    Hazard(cli::HazardArgs),
    /// Fragility curves P(peak > x | v) over storm speeds, with lognormal fits.
    Fragility(cli::FragilityArgs),
    /// Sobol indices of a peak response for every input and the storm's phases.
    Sensitivity(cli::SensitivityArgs),
    /// Peak floor accelerations and drift ratios of storms at one speed, as a pelicun demand sample.
    Demands(cli::DemandsArgs),
    /// Comfort, drift and strength criteria judged together under a climate, with verdicts.
    Serviceability(cli::ServiceabilityArgs),
    /// The T-year level of a response with one input held at each of several values.
    Sweep(cli::SweepArgs),
    /// Medians of the stages of one full-size storm, measured side by side.
    Bench(cli::BenchArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Serve(args) => windmeta::service::serve(args),
        Command::Modes(args) => cli::modes(args),
        Command::Simulate(args) => cli::simulate(args),
        Command::SamplePeaks(args) => cli::sample_peaks(args),
        Command::Bench(args) => cli::bench(args),
        Command::Calibrate(args) => cli::calibrate(args),
        Command::Validate(args) => cli::validate(args),
        Command::Exceedance(args) => cli::exceedance(args),
        Command::Profile(args) => cli::profile(args),
        Command::Hazard(args) => cli::hazard(args),
        Command::Fragility(args) => cli::fragility(args),
        Command::Sensitivity(args) => cli::sensitivity(args),
        Command::Demands(args) => cli::demands(args),
        Command::Serviceability(args) => cli::serviceability(args),
        Command::Sweep(args) => cli::sweep(args),
    };
    match result {
        Ok(output) => {
            println!("{output}");
            ExitCode::SUCCESS
        }
        Err(error) => {
            eprintln!("error: {error}");
            ExitCode::from(match error {
                Error::Invalid { .. } => 2,
                Error::Internal(_) => 3,
                Error::Numerical(_) | Error::Cancelled => 1,
            })
        }
    }
}
