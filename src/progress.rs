//! How long work reports where it is and learns that it should stop: the [`Observer`] that a
//! calibration, a validation, a sampling run or a single storm's integration is given. Every long
//! loop of the core (a storm's integration, structure selection, the refinement of coefficients,
//! an expansion's fit, sampling) asks it between pieces of work that take well under a second, so a
//! cancelled job or a server that is shutting down gets its processors back within about a second.

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};

/// Where a calibration is; reported to an observer as it goes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "openapi", derive(utoipa::ToSchema))]
#[serde(tag = "stage", rename_all = "snake_case")]
pub enum Progress {
    /// Experiments through the reference (and, after the structures, their NARX fits).
    Experiments {
        /// Experiments done.
        done: usize,
        /// Experiments in all.
        total: usize,
    },
    /// Structure selection of a mode has begun.
    Structure {
        /// The mode, 1-based.
        mode: usize,
    },
    /// The polynomial chaos expansions of a mode have begun.
    Expansion {
        /// The mode, 1-based.
        mode: usize,
    },
    /// Sampling or validation storms done.
    Samples {
        /// Storms done.
        done: usize,
        /// Storms in all.
        total: usize,
    },
    /// A certified answer's storms through both the reference model and the metamodel done.
    ReferenceStorms {
        /// Storms done.
        done: usize,
        /// Storms in all.
        total: usize,
    },
}

/// Who watches long work: progress reports, and whether it should stop (cheap enough to ask every
/// few milliseconds).
pub trait Observer: Sync {
    /// Takes a report of where the work is.
    fn progress(&self, progress: Progress);
    /// Whether the work should stop; never, by default.
    fn cancelled(&self) -> bool {
        false
    }
}

/// Work that nobody watches or stops (the command line's inner loops, tests).
pub struct Silent;

impl Observer for Silent {
    fn progress(&self, _: Progress) {}
}

/// `Err(Cancelled)` once a stop is requested.
pub fn check(observer: &dyn Observer) -> Result<()> {
    if observer.cancelled() { Err(Error::Cancelled) } else { Ok(()) }
}

/// Steps of a time-stepping loop between two checks: a few milliseconds of work at any size.
pub const CHECK_EVERY_STEPS: usize = 4096;
