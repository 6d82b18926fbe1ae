//! Asking long work to stop. Every long loop of the core (a storm's integration, structure
//! selection, the refinement of coefficients, an expansion's fit, sampling) checks a [`Cancel`]
//! between pieces of work that take well under a second, so a cancelled job or a server that is
//! shutting down gets its processors back within about a second.

use crate::error::{Error, Result};

/// Whether the work should stop now; cheap enough to ask every few milliseconds.
pub trait Cancel: Sync {
    fn requested(&self) -> bool;
}

/// Work that nobody will stop (the command line, tests).
pub struct Never;

impl Cancel for Never {
    fn requested(&self) -> bool {
        false
    }
}

impl<F: Fn() -> bool + Sync> Cancel for F {
    fn requested(&self) -> bool {
        self()
    }
}

/// `Err(Cancelled)` once a stop is requested.
pub fn check(cancel: &dyn Cancel) -> Result<()> {
    if cancel.requested() { Err(Error::Cancelled) } else { Ok(()) }
}

/// Steps of a time-stepping loop between two checks: a few milliseconds of work at any size.
pub const CHECK_EVERY_STEPS: usize = 4096;
