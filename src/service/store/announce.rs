//! Wake-ups across replicas: a replica that queues or finishes tasks announces it on a PostgreSQL
//! channel, and every replica's listener wakes its idle workers and waiting jobs at once, rather
//! than at their next poll (half a second for an idle worker, a quarter for a waiting job: over
//! a calibration's four phases, seconds a replica would sit idle). SQLite serves one process, whose
//! own wake-ups need no database; the polls stay as the fallback for a missed announcement.

use super::{Backend, Store};
use sqlx::postgres::PgListener;
use std::sync::Arc;
use std::time::Duration;
use tokio::sync::Notify;

/// The channel the replicas announce work on, and the statement that announces it.
const CHANNEL: &str = "windmeta_work";
const ANNOUNCE: &str = "NOTIFY windmeta_work";

impl Store {
    /// Tells every replica listening that tasks were queued or finished (PostgreSQL only). A
    /// failed announcement is not an error of the caller's work: the polls find the change.
    pub(super) async fn announce(&self) {
        if self.backend == Backend::Postgres
            && let Err(error) = sqlx::raw_sql(ANNOUNCE).execute(&self.pool).await
        {
            tracing::warn!(%error, "announcing work to the other replicas failed");
        }
    }

    /// Wakes `wake`'s waiters whenever a replica announces work, for as long as the service
    /// runs (PostgreSQL only; with SQLite it returns at once). A lost connection is opened again.
    pub async fn relay_announcements(&self, wake: Arc<Notify>) {
        let Some(url) = self.postgres_url.as_deref() else { return };
        loop {
            match listen(url).await {
                Ok(mut listener) => loop {
                    match listener.recv().await {
                        Ok(_) => wake.notify_waiters(),
                        Err(error) => {
                            tracing::warn!(%error, "listening for the other replicas' work failed");
                            break;
                        }
                    }
                },
                Err(error) => tracing::warn!(%error, "cannot listen for the other replicas' work"),
            }
            tokio::time::sleep(Duration::from_secs(1)).await;
        }
    }
}

async fn listen(url: &str) -> Result<PgListener, sqlx::Error> {
    let mut listener = PgListener::connect(url).await?;
    listener.listen(CHANNEL).await?;
    Ok(listener)
}
