//! How long work reports where it is and learns that it should stop: the observer that a
//! calibration, a validation or a sampling run is given.

use serde::{Deserialize, Serialize};

/// Where a calibration is; reported to an observer as it goes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(tag = "stage", rename_all = "snake_case")]
pub enum Progress {
    /// Experiments through the reference (and, after the structures, their NARX fits).
    Experiments {
        done: usize,
        total: usize,
    },
    Structure {
        mode: usize,
    },
    Expansion {
        mode: usize,
    },
    /// Sampling or validation storms done.
    Samples {
        done: usize,
        total: usize,
    },
}

/// Who watches a calibration: progress reports and a way to stop it.
pub trait Observer: Sync {
    fn progress(&self, progress: Progress);
    fn cancelled(&self) -> bool {
        false
    }
}

/// An observer that ignores progress and never cancels.
pub struct Silent;

impl Observer for Silent {
    fn progress(&self, _: Progress) {}
}
