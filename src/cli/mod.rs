//! The offline commands: what `windmeta modes`, `simulate`, `sample-peaks` and `bench` do, as functions of
//! their parsed arguments. `main.rs` only parses and dispatches.

mod args;
mod bench;
mod calibrate;
mod modes;
mod peaks;
mod simulate;

pub use args::ProblemArgs;
pub use bench::{BenchArgs, BenchRow, bench, physics_rows, table};
pub use calibrate::{CalibrateArgs, calibrate};
pub use modes::{ModesArgs, modes};
pub use peaks::{SamplePeaksArgs, sample_peaks};
pub use simulate::{SimulateArgs, simulate};
