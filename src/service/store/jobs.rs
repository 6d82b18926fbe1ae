//! Jobs as a lease table: queueing (with the queue's bound and idempotency keys), claiming,
//! renewing, ending, cancelling and reading them.

use super::{Backend, Store, idempotency, now_ms};
use sqlx::Row;

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
        if let Some((key, endpoint)) = idempotency
            && let Some((id, request)) = idempotency::earlier_use(&mut tx, key, endpoint, keys_since_ms).await?
        {
            tx.rollback().await?;
            return Ok(Enqueued::Earlier { id, request });
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
            idempotency::record(&mut tx, key, endpoint, request, id).await?;
        }
        sqlx::query("INSERT INTO jobs (id, kind, state, request, created_at) VALUES ($1, $2, 'queued', $3, $4)")
            .bind(id)
            .bind(kind)
            .bind(request)
            .bind(now_ms())
            .execute(&mut *tx)
            .await?;
        tx.commit().await?;
        self.announce().await;
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
}
