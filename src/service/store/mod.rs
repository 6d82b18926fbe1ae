//! The database: jobs as a lease table (`jobs`, `tasks`), idempotency keys, and the stored
//! metamodels (`metamodels`); this file connects it. One portable schema (migrations/) over sqlx's
//! `AnyPool` on SQLite (one process) or PostgreSQL (several replicas), runtime queries only, times
//! as epoch milliseconds. The only statement that differs is the
//! claim: PostgreSQL skips rows another replica is claiming (`FOR UPDATE SKIP LOCKED`); SQLite
//! has one writer at a time, so its plain claim cannot hand one job to two workers.

mod announce;
mod idempotency;
mod jobs;
mod metamodels;
mod tasks;

pub use jobs::{Enqueued, JobRow, MAX_ATTEMPTS};
pub use tasks::TaskRow;

use sqlx::AnyPool;
use sqlx::any::{AnyPoolOptions, install_default_drivers};
use std::time::{SystemTime, UNIX_EPOCH};

pub fn now_ms() -> i64 {
    SystemTime::now().duration_since(UNIX_EPOCH).map_or(0, |d| d.as_millis() as i64)
}

/// How long a caller waits for a connection (sqlx's default is 30 s).
const ACQUIRE_TIMEOUT: std::time::Duration = std::time::Duration::from_secs(3);

/// The database behind the service; cheap to clone (a pool handle).
#[derive(Debug, Clone)]
pub struct Store {
    pool: AnyPool,
    backend: Backend,
    /// Where to listen for the other replicas' announcements (PostgreSQL only).
    postgres_url: Option<String>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Backend {
    Sqlite,
    Postgres,
}

impl Store {
    /// Connects (creating a SQLite file if needed) and runs the migrations.
    pub async fn connect(url: &str) -> Result<Store, sqlx::Error> {
        install_default_drivers();
        let backend = if url.starts_with("sqlite:") {
            Backend::Sqlite
        } else if url.starts_with("postgres:") || url.starts_with("postgresql:") {
            Backend::Postgres
        } else {
            return Err(sqlx::Error::Configuration(format!("`{url}` is neither sqlite://… nor postgres://…").into()));
        };
        let url = if backend == Backend::Sqlite && !url.contains("mode=") {
            format!("{url}{}mode=rwc", if url.contains('?') { "&" } else { "?" })
        } else {
            url.to_string()
        };
        let pool = AnyPoolOptions::new()
            .max_connections(if backend == Backend::Sqlite { 1 } else { 8 })
            // A request waits this long for a connection before it is answered 503: long enough
            // for a busy pool, short against a client's patience while the database is down.
            .acquire_timeout(ACQUIRE_TIMEOUT)
            .after_connect(|conn, _| {
                Box::pin(async move {
                    if conn.backend_name() == "SQLite" {
                        sqlx::query("PRAGMA journal_mode = WAL").execute(&mut *conn).await?;
                        sqlx::query("PRAGMA busy_timeout = 5000").execute(&mut *conn).await?;
                    }
                    Ok(())
                })
            })
            .connect(&url)
            .await?;
        sqlx::migrate!().run(&pool).await?;
        let postgres_url = (backend == Backend::Postgres).then_some(url);
        Ok(Store { pool, backend, postgres_url })
    }

    /// Whether the database answers with the tables the service needs (a live connection to a
    /// database whose schema is gone is not ready).
    pub async fn ping(&self) -> bool {
        let jobs = sqlx::query("SELECT id FROM jobs LIMIT 1").fetch_optional(&self.pool).await;
        let metamodels = sqlx::query("SELECT id FROM metamodels LIMIT 1").fetch_optional(&self.pool).await;
        jobs.is_ok() && metamodels.is_ok()
    }
}

#[cfg(test)]
mod tests;
