//! What stops a synchronous request's work: its client leaving, its timeout, or a shutdown.

use crate::progress::{Observer, Progress};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// What stops a synchronous request's sampling: the client went away or the request timed out
/// (`stop`), or the server is shutting down (`draining`). The sampling checks it between batches
/// of a few storms, about every millisecond.
pub struct RequestWatch {
    stop: AtomicBool,
    draining: Arc<AtomicBool>,
}

impl RequestWatch {
    pub fn new(draining: Arc<AtomicBool>) -> Self {
        RequestWatch { stop: AtomicBool::new(false), draining }
    }

    pub fn stop(&self) {
        self.stop.store(true, Ordering::Relaxed);
    }
}

impl Observer for RequestWatch {
    fn progress(&self, _: Progress) {}
    fn cancelled(&self) -> bool {
        self.stop.load(Ordering::Relaxed) || self.draining.load(Ordering::Relaxed)
    }
}

/// Stops the watched work when dropped: axum drops a handler's future when its client
/// disconnects, and with it this guard.
pub struct StopOnDrop(pub Arc<RequestWatch>);

impl Drop for StopOnDrop {
    fn drop(&mut self) {
        self.0.stop();
    }
}
