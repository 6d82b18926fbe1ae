//! The offline commands: what `windmeta modes`, `simulate`, `sample-peaks`, `calibrate`, `validate`,
//! `exceedance`, `profile`, `hazard`, `fragility`, `sensitivity`, `demands`, `serviceability`, `sweep` and `bench` do, as functions of their parsed arguments. `main.rs` only parses and dispatches.

mod args;
mod bench;
mod calibrate;
mod demands;
mod exceedance;
mod fragility;
mod hazard;
mod modes;
mod peaks;
mod profile;
mod sensitivity;
mod serviceability;
mod simulate;
mod simulate_spatial;
mod sweep;
mod validate;

pub use args::StudyArgs;
pub use bench::{BenchArgs, BenchReport, BenchRow, bench, bench_report, table};
pub use calibrate::{CalibrateArgs, calibrate};
pub use demands::{DemandsArgs, demands};
pub use exceedance::{ExceedanceArgs, exceedance};
pub use fragility::{FragilityArgs, fragility};
pub use hazard::{HazardArgs, hazard};
pub use modes::{ModesArgs, modes};
pub use peaks::{SamplePeaksArgs, sample_peaks};
pub use profile::{ProfileArgs, profile};
pub use sensitivity::{SensitivityArgs, sensitivity};
pub use serviceability::{ServiceabilityArgs, serviceability};
pub use simulate::{SimulateArgs, simulate};
pub use sweep::{SweepArgs, sweep};
pub use validate::{ValidateArgs, validate};

use crate::error::{Error, Result};
use crate::study::Study;
use crate::surrogate::Metamodel;

/// Reads a metamodel file and rebuilds its study.
fn read_metamodel(path: &std::path::Path) -> Result<(Metamodel, Study)> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| Error::invalid("model", format!("cannot read {}: {e}", path.display())))?;
    let metamodel = Metamodel::from_json(&text)?;
    let study = metamodel.study()?;
    Ok((metamodel, study))
}
