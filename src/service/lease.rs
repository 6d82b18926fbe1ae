//! Keeping a lease through transient database faults: a renewal or a write that fails is tried
//! again with back-off for as long as the lease, renewed last at a known time, can still be ours.
//! Only then is the work given up (another replica may have taken the job up by now).

use std::future::Future;
use std::time::{Duration, Instant};

/// The longest wait between two attempts.
const MAX_BACKOFF: Duration = Duration::from_secs(8);

/// When a lease was last renewed and when to try again after failures.
#[derive(Debug)]
pub struct LeaseKeeper {
    /// The lease's length: it runs out this long after the last renewal.
    lease: Duration,
    /// When the last renewal succeeded (the claim counts as one).
    renewed: Instant,
    /// Failed attempts since then.
    failures: u32,
    /// No attempt before this.
    next_attempt: Instant,
}

impl LeaseKeeper {
    /// A lease of `lease_ms` claimed just now.
    pub fn claimed(lease_ms: i64) -> Self {
        let now = Instant::now();
        LeaseKeeper {
            lease: Duration::from_millis(lease_ms.max(0) as u64),
            renewed: now,
            failures: 0,
            next_attempt: now,
        }
    }

    /// Whether a renewal should be attempted now (not while backing off).
    pub fn due(&self) -> bool {
        Instant::now() >= self.next_attempt
    }

    pub fn renewed(&mut self) {
        self.renewed = Instant::now();
        self.failures = 0;
        self.next_attempt = self.renewed;
    }

    /// Records a failed attempt; false when the lease has run out since the last renewal, so the
    /// work must stop.
    pub fn failed(&mut self) -> bool {
        self.failures += 1;
        let backoff = Duration::from_millis(250 << self.failures.min(5)).min(MAX_BACKOFF);
        self.next_attempt = Instant::now() + backoff;
        self.alive()
    }

    /// Whether the lease can still be ours.
    pub fn alive(&self) -> bool {
        self.renewed.elapsed() < self.lease
    }

    /// Runs `attempt` until it succeeds, backing off between failures, for as long as the lease
    /// is alive; the last error when it ran out.
    pub async fn persist<T, E: std::fmt::Display, F: Future<Output = Result<T, E>>>(
        &mut self,
        what: &str,
        mut attempt: impl FnMut() -> F,
    ) -> Result<T, E> {
        loop {
            match attempt().await {
                Ok(value) => return Ok(value),
                Err(error) => {
                    if !self.failed() {
                        return Err(error);
                    }
                    tracing::warn!(%error, what, "a database write failed; trying again");
                    tokio::time::sleep_until(self.next_attempt.into()).await;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::LeaseKeeper;
    use std::time::Duration;

    #[tokio::test]
    async fn a_write_is_retried_until_it_succeeds_within_the_lease() {
        let mut keeper = LeaseKeeper::claimed(10_000);
        let mut calls = 0;
        let result: Result<u32, String> = keeper
            .persist("test", || {
                calls += 1;
                let outcome = if calls < 3 { Err(format!("fault {calls}")) } else { Ok(calls) };
                async move { outcome }
            })
            .await;
        assert_eq!(result, Ok(3));
    }

    #[tokio::test]
    async fn a_lease_that_ran_out_ends_the_retries() {
        let mut keeper = LeaseKeeper::claimed(300);
        let started = std::time::Instant::now();
        let result: Result<(), String> = keeper.persist("test", || async { Err("down".to_string()) }).await;
        assert_eq!(result, Err("down".to_string()));
        assert!(started.elapsed() >= Duration::from_millis(300) && started.elapsed() < Duration::from_secs(3));
        assert!(!keeper.alive());
    }

    #[test]
    fn back_off_grows_and_a_renewal_resets_it() {
        let mut keeper = LeaseKeeper::claimed(60_000);
        assert!(keeper.due());
        assert!(keeper.failed());
        assert!(!keeper.due());
        keeper.renewed();
        assert!(keeper.due() && keeper.alive());
    }
}
