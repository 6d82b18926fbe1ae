//! What a job's or a task's blocking work and its async supervisor share, and how the
//! supervisor's own calls are run: off the runtime, and through transient database faults.

use crate::error::{Error, Result};
use crate::progress::{Observer, Progress};
use std::future::Future;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

/// The work reports progress here and reads whether to stop.
#[derive(Default)]
pub(super) struct Supervision {
    /// Latest progress, saved at the next heartbeat.
    pub progress: Mutex<Option<Progress>>,
    /// Set by the supervisor on a cancel request, a shutdown or a lease in doubt; read by the work
    /// between steps.
    pub cancel: AtomicBool,
    /// Whether a client asked for the cancellation. Only then is the job recorded as cancelled: a
    /// shutdown or a lease in doubt gives the job back to the queue for another worker.
    pub requested: AtomicBool,
}

impl Supervision {
    pub fn stop(&self) {
        self.cancel.store(true, Ordering::Relaxed);
    }
}

impl Observer for Supervision {
    fn progress(&self, progress: Progress) {
        *self.progress.lock().expect("progress lock") = Some(progress);
    }
    fn cancelled(&self) -> bool {
        self.cancel.load(Ordering::Relaxed)
    }
}

/// A blocking computation as a future, in the caller's span (its job); a panic becomes an error.
pub(super) async fn blocking<T: Send + 'static>(work: impl FnOnce() -> Result<T> + Send + 'static) -> Result<T> {
    let span = tracing::Span::current();
    tokio::task::spawn_blocking(move || span.in_scope(work))
        .await
        .map_err(|panic| Error::Internal(format!("the job panicked: {panic}")))?
}

/// A database call of a running job, tried again every second through transient faults until it
/// answers or the job is cancelled: the job's heartbeat cancels it when the lease is lost.
pub(super) async fn through_faults<T, F: Future<Output = std::result::Result<T, sqlx::Error>>>(
    supervision: &dyn Observer,
    what: &str,
    mut call: impl FnMut() -> F,
) -> Result<T> {
    loop {
        match call().await {
            Ok(value) => return Ok(value),
            Err(_) if supervision.cancelled() => return Err(Error::Cancelled),
            Err(error) => {
                tracing::warn!(%error, what, "a database call failed; trying again");
                tokio::time::sleep(Duration::from_secs(1)).await;
            }
        }
    }
}
