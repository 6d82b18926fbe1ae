//! The database: jobs as a lease table, and the stored metamodels. One portable schema
//! (migrations/) over sqlx's `AnyPool` on SQLite (one process) or PostgreSQL (several replicas),
//! runtime queries only, times as epoch milliseconds. The only statement that differs is the
//! claim: PostgreSQL skips rows another replica is claiming (`FOR UPDATE SKIP LOCKED`); SQLite
//! has one writer at a time, so its plain claim cannot hand one job to two workers.

mod tasks;

pub use tasks::TaskRow;

use sqlx::any::{AnyPoolOptions, install_default_drivers};
use sqlx::{AnyPool, Row};
use std::time::{SystemTime, UNIX_EPOCH};

pub fn now_ms() -> i64 {
    SystemTime::now().duration_since(UNIX_EPOCH).map_or(0, |d| d.as_millis() as i64)
}

/// A job as stored.
#[derive(Debug, Clone)]
pub struct JobRow {
    pub id: String,
    pub kind: String,
    pub state: String,
    pub request: String,
    pub progress: Option<String>,
    pub error: Option<String>,
    pub metamodel_id: Option<String>,
    /// JSON result of a job that produces a report (a validation).
    pub result: Option<String>,
    pub attempts: i64,
    pub created_at: i64,
    pub started_at: Option<i64>,
    pub finished_at: Option<i64>,
}

/// What became of a job offered to the queue.
#[derive(Debug, Clone, PartialEq)]
pub enum Enqueued {
    New,
    /// The idempotency key was used before, for this operation and request.
    Earlier {
        id: String,
        request: String,
    },
    /// Too many jobs wait already.
    QueueFull,
}

/// A stored metamodel's summary.
#[derive(Debug, Clone)]
pub struct MetamodelRow {
    pub id: String,
    pub job_id: Option<String>,
    pub preset: String,
    pub created_at: i64,
}

/// The database behind the service; cheap to clone (a pool handle).
#[derive(Debug, Clone)]
pub struct Store {
    pool: AnyPool,
    backend: Backend,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Backend {
    Sqlite,
    Postgres,
}

/// A job whose worker died this many times (its lease ran out) is failed rather than tried again.
pub const MAX_ATTEMPTS: i64 = 3;

/// The job columns, spliced into literal queries (sqlx accepts only audited literal SQL).
macro_rules! job_columns {
    () => {
        "id, kind, state, request, progress, error, metamodel_id, result, attempts, created_at, started_at, finished_at"
    };
}

fn job(row: &sqlx::any::AnyRow) -> Result<JobRow, sqlx::Error> {
    Ok(JobRow {
        id: row.try_get("id")?,
        kind: row.try_get("kind")?,
        state: row.try_get("state")?,
        request: row.try_get("request")?,
        progress: row.try_get("progress")?,
        error: row.try_get("error")?,
        metamodel_id: row.try_get("metamodel_id")?,
        result: row.try_get("result")?,
        attempts: row.try_get("attempts")?,
        created_at: row.try_get("created_at")?,
        started_at: row.try_get("started_at")?,
        finished_at: row.try_get("finished_at")?,
    })
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
        Ok(Store { pool, backend })
    }

    /// Whether the database answers with the tables the service needs (a live connection to a
    /// database whose schema is gone is not ready).
    pub async fn ping(&self) -> bool {
        let jobs = sqlx::query("SELECT id FROM jobs LIMIT 1").fetch_optional(&self.pool).await;
        let metamodels = sqlx::query("SELECT id FROM metamodels LIMIT 1").fetch_optional(&self.pool).await;
        jobs.is_ok() && metamodels.is_ok()
    }

    /// Queues a job unless `max_queued` jobs already wait. With an idempotency key (key, endpoint)
    /// the key is recorded in the same transaction; if it was already used since `keys_since_ms`,
    /// nothing is queued and the earlier operation is returned instead (even when the queue is
    /// full). A key recorded before `keys_since_ms` has expired and is used afresh.
    pub async fn insert_job(
        &self,
        id: &str,
        kind: &str,
        request: &str,
        idempotency: Option<(&str, &str)>,
        keys_since_ms: i64,
        max_queued: i64,
    ) -> Result<Enqueued, sqlx::Error> {
        let mut tx = self.pool.begin().await?;
        if let Some((key, endpoint)) = idempotency {
            sqlx::query("DELETE FROM idempotency WHERE idempotency_key = $1 AND endpoint = $2 AND created_at < $3")
                .bind(key)
                .bind(endpoint)
                .bind(keys_since_ms)
                .execute(&mut *tx)
                .await?;
            let earlier = sqlx::query(
                "SELECT operation_id, request FROM idempotency WHERE idempotency_key = $1 AND endpoint = $2",
            )
            .bind(key)
            .bind(endpoint)
            .fetch_optional(&mut *tx)
            .await?;
            if let Some(row) = earlier {
                tx.rollback().await?;
                return Ok(Enqueued::Earlier { id: row.try_get("operation_id")?, request: row.try_get("request")? });
            }
        }
        let queued: i64 = sqlx::query("SELECT COUNT(*) AS n FROM jobs WHERE state = 'queued'")
            .fetch_one(&mut *tx)
            .await?
            .try_get("n")?;
        if queued >= max_queued {
            tx.rollback().await?;
            return Ok(Enqueued::QueueFull);
        }
        if let Some((key, endpoint)) = idempotency {
            sqlx::query("INSERT INTO idempotency (idempotency_key, endpoint, request, operation_id, created_at) VALUES ($1, $2, $3, $4, $5)")
                .bind(key)
                .bind(endpoint)
                .bind(request)
                .bind(id)
                .bind(now_ms())
                .execute(&mut *tx)
                .await?;
        }
        sqlx::query("INSERT INTO jobs (id, kind, state, request, created_at) VALUES ($1, $2, 'queued', $3, $4)")
            .bind(id)
            .bind(kind)
            .bind(request)
            .bind(now_ms())
            .execute(&mut *tx)
            .await?;
        tx.commit().await?;
        Ok(Enqueued::New)
    }

    /// Claims the oldest queued job, or a running one whose lease ran out (its worker died). A job
    /// whose lease ran out [`MAX_ATTEMPTS`] times is failed with the reason instead.
    pub async fn claim(&self, owner: &str, lease_ms: i64) -> Result<Option<JobRow>, sqlx::Error> {
        let now = now_ms();
        sqlx::query(
            "UPDATE jobs SET state = 'failed', finished_at = $1, lease_owner = NULL, \
             error = 'abandoned: its worker stopped renewing the lease ' || CAST(attempts AS TEXT) || ' times' \
             WHERE state = 'running' AND lease_until < $1 AND attempts >= $2",
        )
        .bind(now)
        .bind(MAX_ATTEMPTS)
        .execute(&self.pool)
        .await?;
        // The pieces of ended jobs are of no further use.
        sqlx::query("DELETE FROM tasks WHERE job_id IN (SELECT id FROM jobs WHERE state IN ('succeeded', 'failed', 'cancelled'))")
            .execute(&self.pool)
            .await?;
        let query = match self.backend {
            Backend::Sqlite => concat!(
                "UPDATE jobs SET state = 'running', lease_owner = $1, lease_until = $2, attempts = attempts + 1, ",
                "started_at = COALESCE(started_at, $3) ",
                "WHERE id = (SELECT id FROM jobs WHERE state = 'queued' OR (state = 'running' AND lease_until < $3) ",
                "ORDER BY created_at LIMIT 1) RETURNING ",
                job_columns!()
            ),
            Backend::Postgres => concat!(
                "UPDATE jobs SET state = 'running', lease_owner = $1, lease_until = $2, attempts = attempts + 1, ",
                "started_at = COALESCE(started_at, $3) ",
                "WHERE id = (SELECT id FROM jobs WHERE state = 'queued' OR (state = 'running' AND lease_until < $3) ",
                "ORDER BY created_at LIMIT 1 FOR UPDATE SKIP LOCKED) RETURNING ",
                job_columns!()
            ),
        };
        let row = sqlx::query(query).bind(owner).bind(now + lease_ms).bind(now).fetch_optional(&self.pool).await?;
        row.as_ref().map(job).transpose()
    }

    /// Extends the lease and saves progress; returns whether cancellation was asked for, or None
    /// when the lease is no longer ours.
    pub async fn heartbeat(
        &self,
        id: &str,
        owner: &str,
        lease_ms: i64,
        progress: Option<&str>,
    ) -> Result<Option<bool>, sqlx::Error> {
        let row = sqlx::query(
            "UPDATE jobs SET lease_until = $1, progress = COALESCE($2, progress) \
             WHERE id = $3 AND lease_owner = $4 AND state = 'running' RETURNING cancel_requested",
        )
        .bind(now_ms() + lease_ms)
        .bind(progress)
        .bind(id)
        .bind(owner)
        .fetch_optional(&self.pool)
        .await?;
        Ok(row.map(|r| r.try_get::<i32, _>("cancel_requested").unwrap_or(0) != 0))
    }

    /// Stores the metamodel and marks the job done, both or neither; false when the lease was lost
    /// (another worker owns the job now, so this result is discarded).
    pub async fn complete(
        &self,
        id: &str,
        owner: &str,
        metamodel_id: &str,
        preset: &str,
        body: &str,
    ) -> Result<bool, sqlx::Error> {
        let mut tx = self.pool.begin().await?;
        let now = now_ms();
        let updated = sqlx::query(
            "UPDATE jobs SET state = 'succeeded', metamodel_id = $1, finished_at = $2, lease_owner = NULL \
             WHERE id = $3 AND lease_owner = $4 AND state = 'running'",
        )
        .bind(metamodel_id)
        .bind(now)
        .bind(id)
        .bind(owner)
        .execute(&mut *tx)
        .await?;
        if updated.rows_affected() != 1 {
            tx.rollback().await?;
            return Ok(false);
        }
        sqlx::query("INSERT INTO metamodels (id, job_id, preset, created_at, body) VALUES ($1, $2, $3, $4, $5)")
            .bind(metamodel_id)
            .bind(id)
            .bind(preset)
            .bind(now)
            .bind(body)
            .execute(&mut *tx)
            .await?;
        tx.commit().await?;
        Ok(true)
    }

    /// Ends a job (succeeded with a report as `result`, failed with an `error`, or cancelled) if
    /// the lease is still ours; false when it was lost.
    pub async fn finish(
        &self,
        id: &str,
        owner: &str,
        state: &str,
        error: Option<&str>,
        result: Option<&str>,
    ) -> Result<bool, sqlx::Error> {
        let done = sqlx::query(
            "UPDATE jobs SET state = $1, error = $2, result = $3, finished_at = $4, lease_owner = NULL \
             WHERE id = $5 AND lease_owner = $6 AND state = 'running'",
        )
        .bind(state)
        .bind(error)
        .bind(result)
        .bind(now_ms())
        .bind(id)
        .bind(owner)
        .execute(&self.pool)
        .await?;
        Ok(done.rows_affected() == 1)
    }

    /// Gives a running job back to the queue (graceful shutdown): another start takes it up.
    pub async fn release(&self, id: &str, owner: &str) -> Result<(), sqlx::Error> {
        sqlx::query("UPDATE jobs SET state = 'queued', lease_owner = NULL, lease_until = NULL WHERE id = $1 AND lease_owner = $2 AND state = 'running'")
            .bind(id)
            .bind(owner)
            .execute(&self.pool)
            .await?;
        Ok(())
    }

    /// Asks a job to stop: a queued one is cancelled at once, a running one at its next heartbeat.
    pub async fn request_cancel(&self, id: &str) -> Result<Option<JobRow>, sqlx::Error> {
        sqlx::query("UPDATE jobs SET state = 'cancelled', finished_at = $1 WHERE id = $2 AND state = 'queued'")
            .bind(now_ms())
            .bind(id)
            .execute(&self.pool)
            .await?;
        sqlx::query("UPDATE jobs SET cancel_requested = 1 WHERE id = $1 AND state = 'running'")
            .bind(id)
            .execute(&self.pool)
            .await?;
        self.job(id).await
    }

    /// Forgets the idempotency keys recorded before `keys_since_ms`; how many were pruned.
    pub async fn prune_idempotency(&self, keys_since_ms: i64) -> Result<u64, sqlx::Error> {
        let done = sqlx::query("DELETE FROM idempotency WHERE created_at < $1")
            .bind(keys_since_ms)
            .execute(&self.pool)
            .await?;
        Ok(done.rows_affected())
    }

    pub async fn job(&self, id: &str) -> Result<Option<JobRow>, sqlx::Error> {
        let row = sqlx::query(concat!("SELECT ", job_columns!(), " FROM jobs WHERE id = $1"))
            .bind(id)
            .fetch_optional(&self.pool)
            .await?;
        row.as_ref().map(job).transpose()
    }

    pub async fn jobs(&self, limit: i64, offset: i64) -> Result<Vec<JobRow>, sqlx::Error> {
        let rows = sqlx::query(concat!(
            "SELECT ",
            job_columns!(),
            " FROM jobs ORDER BY created_at DESC, id LIMIT $1 OFFSET $2"
        ))
        .bind(limit)
        .bind(offset)
        .fetch_all(&self.pool)
        .await?;
        rows.iter().map(job).collect()
    }

    pub async fn metamodel_body(&self, id: &str) -> Result<Option<String>, sqlx::Error> {
        let row = sqlx::query("SELECT body FROM metamodels WHERE id = $1").bind(id).fetch_optional(&self.pool).await?;
        row.map(|r| r.try_get("body")).transpose()
    }

    pub async fn metamodel_exists(&self, id: &str) -> Result<bool, sqlx::Error> {
        let row = sqlx::query("SELECT id FROM metamodels WHERE id = $1").bind(id).fetch_optional(&self.pool).await?;
        Ok(row.is_some())
    }

    pub async fn metamodels(&self, limit: i64, offset: i64) -> Result<Vec<MetamodelRow>, sqlx::Error> {
        let rows = sqlx::query(
            "SELECT id, job_id, preset, created_at FROM metamodels ORDER BY created_at DESC, id LIMIT $1 OFFSET $2",
        )
        .bind(limit)
        .bind(offset)
        .fetch_all(&self.pool)
        .await?;
        rows.iter()
            .map(|r| {
                Ok(MetamodelRow {
                    id: r.try_get("id")?,
                    job_id: r.try_get("job_id")?,
                    preset: r.try_get("preset")?,
                    created_at: r.try_get("created_at")?,
                })
            })
            .collect()
    }

    pub async fn delete_metamodel(&self, id: &str) -> Result<bool, sqlx::Error> {
        let done = sqlx::query("DELETE FROM metamodels WHERE id = $1").bind(id).execute(&self.pool).await?;
        Ok(done.rows_affected() == 1)
    }
}

/// Databases for tests: a fresh SQLite file, and a fresh schema on the PostgreSQL at
/// `WINDMETA_TEST_POSTGRES` (default the local server's `test` database) when one is reachable.
/// Public (but hidden) so that the integration tests of several processes can use it too.
#[doc(hidden)]
pub mod testing {

    pub const DEFAULT_POSTGRES: &str = "postgres://postgres@127.0.0.1:5432/test";

    pub fn postgres_url() -> String {
        std::env::var("WINDMETA_TEST_POSTGRES").unwrap_or_else(|_| DEFAULT_POSTGRES.to_string())
    }

    /// A URL to an empty schema of its own on the test PostgreSQL, or None (with the reason
    /// printed) when none is reachable. With `WINDMETA_REQUIRE_POSTGRES=1` (set by CI, where a
    /// server always runs) an unreachable server fails the test instead of skipping it.
    pub async fn fresh_postgres() -> Option<String> {
        sqlx::any::install_default_drivers();
        let base = postgres_url();
        let admin = match sqlx::AnyPool::connect(&base).await {
            Ok(pool) => pool,
            Err(error) if std::env::var("WINDMETA_REQUIRE_POSTGRES").is_ok_and(|v| v == "1") => {
                panic!("PostgreSQL is required (WINDMETA_REQUIRE_POSTGRES=1) but {base} is not reachable: {error}")
            }
            Err(error) => {
                // Straight to the process's stderr: the test harness captures `eprintln!`, and a
                // skip must be seen in the run's output.
                use std::io::Write;
                let _ = writeln!(std::io::stderr(), "PostgreSQL tests SKIPPED: {base} is not reachable ({error})");
                return None;
            }
        };
        drop_stale_schemas(&admin).await;
        let schema = format!("windmeta_test_{}_{}", super::now_ms(), uuid::Uuid::new_v4().simple());
        if let Err(error) = sqlx::query(sqlx::AssertSqlSafe(format!("CREATE SCHEMA {schema}"))).execute(&admin).await {
            panic!("cannot create the test schema {schema} on {base}: {error}");
        }
        let separator = if base.contains('?') { '&' } else { '?' };
        Some(format!("{base}{separator}options=-c%20search_path%3D{schema}"))
    }

    /// Test schemas are named by their creation time; those older than an hour are left-overs.
    async fn drop_stale_schemas(admin: &sqlx::AnyPool) {
        use sqlx::Row;
        let Ok(rows) = sqlx::query(
            "SELECT CAST(nspname AS TEXT) AS schema_name FROM pg_namespace WHERE nspname LIKE 'windmeta_test_%'",
        )
        .fetch_all(admin)
        .await
        else {
            return;
        };
        let hour_ago = super::now_ms() - 3_600_000;
        for row in rows {
            let name: String = row.try_get("schema_name").unwrap_or_default();
            let created = name.split('_').nth(2).and_then(|t| t.parse::<i64>().ok()).unwrap_or(0);
            if created < hour_ago {
                let _ = sqlx::query(sqlx::AssertSqlSafe(format!("DROP SCHEMA {name} CASCADE"))).execute(admin).await;
            }
        }
    }

    #[cfg(test)]
    pub async fn stores() -> Vec<(&'static str, super::Store)> {
        let dir = std::env::temp_dir().join(format!("windmeta-store-{}", uuid::Uuid::new_v4().simple()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut stores =
            vec![("sqlite", super::Store::connect(&format!("sqlite://{}", dir.join("t.db").display())).await.unwrap())];
        if let Some(url) = fresh_postgres().await {
            stores.push(("postgres", super::Store::connect(&url).await.unwrap()));
        }
        stores
    }
}

/// The same suite on both databases.
#[cfg(test)]
mod tests {
    use super::*;

    async fn queue(store: &Store, id: &str) {
        assert_eq!(store.insert_job(id, "calibration", "{}", None, 0, 100).await.unwrap(), Enqueued::New);
    }

    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn a_job_runs_once_and_stores_its_metamodel() {
        for (name, store) in testing::stores().await {
            queue(&store, "j1").await;
            let job = store.claim("w1", 10_000).await.unwrap().expect("a queued job is claimed");
            assert_eq!((job.id.as_str(), job.state.as_str(), job.attempts), ("j1", "running", 1), "{name}");
            assert!(store.claim("w2", 10_000).await.unwrap().is_none(), "{name}: claimed twice");
            assert_eq!(store.heartbeat("j1", "w1", 10_000, Some("{\"stage\":\"x\"}")).await.unwrap(), Some(false));
            assert!(store.complete("j1", "w1", "m1", "frame40", "{\"a\":1}").await.unwrap(), "{name}");
            let done = store.job("j1").await.unwrap().unwrap();
            assert_eq!((done.state.as_str(), done.metamodel_id.as_deref()), ("succeeded", Some("m1")), "{name}");
            assert_eq!(store.metamodel_body("m1").await.unwrap().as_deref(), Some("{\"a\":1}"), "{name}");
            assert_eq!(store.metamodels(10, 0).await.unwrap().len(), 1, "{name}");
            assert!(store.delete_metamodel("m1").await.unwrap() && !store.delete_metamodel("m1").await.unwrap());
        }
    }

    /// Many workers claiming at once from many connections: every job exactly once.
    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn concurrent_claims_hand_out_each_job_once() {
        for (name, store) in testing::stores().await {
            for i in 0..20 {
                queue(&store, &format!("j{i:02}")).await;
            }
            let claimers = (0..8).map(|w| {
                let store = store.clone();
                tokio::spawn(async move {
                    let mut mine = Vec::new();
                    while let Some(job) = store.claim(&format!("w{w}"), 60_000).await.unwrap() {
                        mine.push(job.id);
                    }
                    mine
                })
            });
            let mut claimed: Vec<String> = Vec::new();
            for claimer in claimers.collect::<Vec<_>>() {
                claimed.extend(claimer.await.unwrap());
            }
            claimed.sort();
            let expected: Vec<String> = (0..20).map(|i| format!("j{i:02}")).collect();
            assert_eq!(claimed, expected, "{name}");
        }
    }

    /// A worker that lost its lease cannot complete: the job belongs to the one that took it up.
    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn a_lost_lease_discards_the_stale_result() {
        for (name, store) in testing::stores().await {
            queue(&store, "j").await;
            store.claim("stale", 1).await.unwrap().unwrap();
            tokio::time::sleep(std::time::Duration::from_millis(5)).await;
            let again = store.claim("fresh", 60_000).await.unwrap().expect("an expired lease is taken up");
            assert_eq!(again.attempts, 2, "{name}");
            assert_eq!(store.heartbeat("j", "stale", 60_000, None).await.unwrap(), None, "{name}");
            assert!(!store.complete("j", "stale", "m-stale", "p", "{}").await.unwrap(), "{name}");
            assert!(!store.finish("j", "stale", "failed", Some("x"), None).await.unwrap(), "{name}");
            assert!(store.complete("j", "fresh", "m-fresh", "p", "{}").await.unwrap(), "{name}");
            let ids: Vec<String> = store.metamodels(10, 0).await.unwrap().into_iter().map(|m| m.id).collect();
            assert_eq!(ids, vec!["m-fresh".to_string()], "{name}: completed twice");
        }
    }

    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn a_job_whose_worker_keeps_dying_fails_with_the_reason() {
        for (name, store) in testing::stores().await {
            queue(&store, "j").await;
            for attempt in 1..=MAX_ATTEMPTS {
                let job = store.claim("w", 1).await.unwrap().expect("taken up again");
                assert_eq!(job.attempts, attempt, "{name}");
                tokio::time::sleep(std::time::Duration::from_millis(5)).await;
            }
            assert!(store.claim("w", 1).await.unwrap().is_none(), "{name}: retried without bound");
            let job = store.job("j").await.unwrap().unwrap();
            assert_eq!(job.state, "failed", "{name}");
            assert!(job.error.unwrap().contains("3 times"), "{name}");
        }
    }

    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn cancel_release_idempotency_and_a_full_queue() {
        for (name, store) in testing::stores().await {
            queue(&store, "queued").await;
            let cancelled = store.request_cancel("queued").await.unwrap().unwrap();
            assert_eq!(cancelled.state, "cancelled", "{name}");
            queue(&store, "running").await;
            store.claim("w", 60_000).await.unwrap().unwrap();
            store.request_cancel("running").await.unwrap();
            assert_eq!(store.heartbeat("running", "w", 60_000, None).await.unwrap(), Some(true), "{name}");
            store.release("running", "w").await.unwrap();
            assert_eq!(store.job("running").await.unwrap().unwrap().state, "queued", "{name}");

            let key = Some(("k", "calibrations"));
            assert_eq!(store.insert_job("a", "calibration", "{}", key, 0, 100).await.unwrap(), Enqueued::New);
            let replay = store.insert_job("b", "calibration", "{}", key, 0, 100).await.unwrap();
            assert_eq!(replay, Enqueued::Earlier { id: "a".into(), request: "{}".into() }, "{name}");
            // Two queued now ("running" was released, "a"): a queue of two is full, a replay still answers.
            assert_eq!(store.insert_job("c", "calibration", "{}", None, 0, 2).await.unwrap(), Enqueued::QueueFull);
            assert!(matches!(
                store.insert_job("d", "calibration", "{}", key, 0, 2).await.unwrap(),
                Enqueued::Earlier { .. }
            ));
            assert!(store.job("c").await.unwrap().is_none() && store.ping().await, "{name}");
            // An expired key starts new work; pruning forgets the keys older than the cutoff.
            let later = now_ms() + 1;
            assert_eq!(store.insert_job("e", "calibration", "{}", key, later, 100).await.unwrap(), Enqueued::New);
            let other = Some(("k2", "calibrations"));
            assert_eq!(store.insert_job("f", "calibration", "{}", other, 0, 100).await.unwrap(), Enqueued::New);
            assert_eq!(store.prune_idempotency(now_ms() + 1).await.unwrap(), 2, "{name}");
        }
    }

    use tasks::TaskTally;

    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn tasks_of_a_running_job_are_shared_and_tallied() {
        for (name, store) in testing::stores().await {
            queue(&store, "j").await;
            let requests = ["a".to_string(), "b".to_string()];
            store.insert_tasks("j", &requests).await.unwrap();
            assert!(store.claim_task("w1", 60_000, None).await.unwrap().is_none(), "{name}: the job is not running");
            store.claim("coordinator", 60_000).await.unwrap().unwrap();
            let first = store.claim_task("w1", 60_000, None).await.unwrap().unwrap();
            let second = store.claim_task("w2", 60_000, Some("j")).await.unwrap().unwrap();
            assert_eq!((first.chunk, first.request.as_str(), second.chunk), (0, "a", 1), "{name}");
            assert!(store.claim_task("w3", 60_000, None).await.unwrap().is_none(), "{name}: handed out twice");
            assert_eq!(store.heartbeat_task("j", 0, "w1", 60_000).await.unwrap(), Some(true), "{name}");
            assert_eq!(store.heartbeat_task("j", 0, "w2", 60_000).await.unwrap(), None, "{name}: not w2's");
            assert!(!store.finish_task("j", 0, "w2", "done", "stolen").await.unwrap(), "{name}");
            assert!(store.finish_task("j", 0, "w1", "done", "r0").await.unwrap(), "{name}");
            assert!(store.finish_task("j", 1, "w2", "failed", "boom").await.unwrap(), "{name}");
            let tally = store.task_tally("j").await.unwrap();
            assert_eq!(tally, TaskTally { total: 2, done: 1, failure: Some("boom".into()) }, "{name}");
            assert_eq!(store.task_results("j").await.unwrap(), vec!["r0".to_string()], "{name}");
            // A second attempt at the job: an unchanged chunk keeps its output, a changed one restarts.
            store.insert_tasks("j", &["a".to_string(), "b2".to_string()]).await.unwrap();
            assert_eq!(store.task_tally("j").await.unwrap(), TaskTally { total: 2, done: 1, failure: None });
            // Cancelling the job withdraws its tasks from idle workers and from the one running them.
            let again = store.claim_task("w1", 60_000, None).await.unwrap().unwrap();
            store.request_cancel("j").await.unwrap();
            assert_eq!(store.heartbeat_task("j", again.chunk, "w1", 60_000).await.unwrap(), Some(false), "{name}");
            store.release_task("j", again.chunk, "w1").await.unwrap();
            assert!(store.claim_task("w1", 60_000, None).await.unwrap().is_none(), "{name}");
        }
    }
}
