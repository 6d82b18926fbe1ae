//! The offline commands: what `windmeta modes`, `simulate` and `sample-peaks` do, as functions of
//! their parsed arguments. `main.rs` only parses and dispatches.

mod args;
mod modes;
mod peaks;
mod simulate;

pub use args::ProblemArgs;
pub use modes::{modes, ModesArgs};
pub use peaks::{sample_peaks, SamplePeaksArgs};
pub use simulate::{simulate, SimulateArgs};
