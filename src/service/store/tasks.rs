//! Tasks: pieces of a running job that any replica's idle worker may take (a calibration's
//! experiments, a certified answer's reference storms, in chunks), leased like jobs. A task is only handed out while its job runs and is
//! not being cancelled; a task abandoned `MAX_ATTEMPTS` times fails, and with it the job.

use super::{Backend, MAX_ATTEMPTS, Store, now_ms};
use sqlx::Row;
use std::ops::Range;

/// A task as claimed.
#[derive(Debug, Clone)]
pub struct TaskRow {
    pub job_id: String,
    pub chunk: i64,
    pub request: String,
}

/// Where a job's tasks are.
#[derive(Debug, Clone, PartialEq)]
pub struct TaskTally {
    pub total: i64,
    pub done: i64,
    /// The reason of the first failed task, if any failed.
    pub failure: Option<String>,
}

impl Store {
    /// Queues a job's tasks as chunks `first`, `first + 1`, …. A chunk queued before by an earlier
    /// attempt at the job keeps its state (and output, if done) when its request is the same,
    /// which a deterministic plan makes it; otherwise it is queued afresh.
    pub async fn insert_tasks(&self, job_id: &str, first: i64, requests: &[String]) -> Result<(), sqlx::Error> {
        let mut tx = self.pool.begin().await?;
        for (chunk, request) in (first..).zip(requests) {
            sqlx::query(
                "INSERT INTO tasks (job_id, chunk, state, request) VALUES ($1, $2, 'queued', $3) \
                 ON CONFLICT (job_id, chunk) DO UPDATE SET request = excluded.request, state = 'queued', \
                 result = NULL, lease_owner = NULL, lease_until = NULL WHERE tasks.request <> excluded.request",
            )
            .bind(job_id)
            .bind(chunk)
            .bind(request)
            .execute(&mut *tx)
            .await?;
        }
        tx.commit().await?;
        self.announce().await;
        Ok(())
    }

    /// Claims a queued task (or one whose lease ran out) of a running, uncancelled job; of `job_id`
    /// only, when given.
    pub async fn claim_task(
        &self,
        owner: &str,
        lease_ms: i64,
        job_id: Option<&str>,
    ) -> Result<Option<TaskRow>, sqlx::Error> {
        let now = now_ms();
        sqlx::query(
            "UPDATE tasks SET state = 'failed', lease_owner = NULL, \
             result = 'abandoned: its worker stopped renewing the lease ' || CAST(attempts AS TEXT) || ' times' \
             WHERE state = 'running' AND lease_until < $1 AND attempts >= $2",
        )
        .bind(now)
        .bind(MAX_ATTEMPTS)
        .execute(&self.pool)
        .await?;
        let query = match self.backend {
            Backend::Sqlite => concat!(
                "UPDATE tasks SET state = 'running', lease_owner = $1, lease_until = $2, attempts = attempts + 1 ",
                "WHERE (job_id, chunk) = (SELECT job_id, chunk FROM tasks ",
                "WHERE (state = 'queued' OR (state = 'running' AND lease_until < $3)) AND ($4 IS NULL OR job_id = $4) ",
                "AND job_id IN (SELECT id FROM jobs WHERE state = 'running' AND cancel_requested = 0) ",
                "ORDER BY job_id, chunk LIMIT 1) RETURNING job_id, chunk, request"
            ),
            Backend::Postgres => concat!(
                "UPDATE tasks SET state = 'running', lease_owner = $1, lease_until = $2, attempts = attempts + 1 ",
                "WHERE (job_id, chunk) = (SELECT job_id, chunk FROM tasks ",
                "WHERE (state = 'queued' OR (state = 'running' AND lease_until < $3)) ",
                "AND (CAST($4 AS TEXT) IS NULL OR job_id = $4) ",
                "AND job_id IN (SELECT id FROM jobs WHERE state = 'running' AND cancel_requested = 0) ",
                "ORDER BY job_id, chunk LIMIT 1 FOR UPDATE SKIP LOCKED) RETURNING job_id, chunk, request"
            ),
        };
        let row = sqlx::query(query)
            .bind(owner)
            .bind(now + lease_ms)
            .bind(now)
            .bind(job_id)
            .fetch_optional(&self.pool)
            .await?;
        row.map(|r| {
            Ok(TaskRow { job_id: r.try_get("job_id")?, chunk: r.try_get("chunk")?, request: r.try_get("request")? })
        })
        .transpose()
    }

    /// Extends a task's lease; returns whether its job still wants it (running, not being
    /// cancelled), or None when the lease is no longer ours.
    pub async fn heartbeat_task(
        &self,
        job_id: &str,
        chunk: i64,
        owner: &str,
        lease_ms: i64,
    ) -> Result<Option<bool>, sqlx::Error> {
        let renewed = sqlx::query(
            "UPDATE tasks SET lease_until = $1 WHERE job_id = $2 AND chunk = $3 AND lease_owner = $4 AND state = 'running'",
        )
        .bind(now_ms() + lease_ms)
        .bind(job_id)
        .bind(chunk)
        .bind(owner)
        .execute(&self.pool)
        .await?;
        if renewed.rows_affected() != 1 {
            return Ok(None);
        }
        let wanted = sqlx::query("SELECT id FROM jobs WHERE id = $1 AND state = 'running' AND cancel_requested = 0")
            .bind(job_id)
            .fetch_optional(&self.pool)
            .await?;
        Ok(Some(wanted.is_some()))
    }

    /// Ends a task as `done` with its output or `failed` with the reason, if the lease is still
    /// ours; false when it was lost (the output is discarded).
    pub async fn finish_task(
        &self,
        job_id: &str,
        chunk: i64,
        owner: &str,
        state: &str,
        result: &str,
    ) -> Result<bool, sqlx::Error> {
        let done = sqlx::query(
            "UPDATE tasks SET state = $1, result = $2, lease_owner = NULL \
             WHERE job_id = $3 AND chunk = $4 AND lease_owner = $5 AND state = 'running'",
        )
        .bind(state)
        .bind(result)
        .bind(job_id)
        .bind(chunk)
        .bind(owner)
        .execute(&self.pool)
        .await?;
        self.announce().await;
        Ok(done.rows_affected() == 1)
    }

    /// Gives a task back (its worker is shutting down).
    pub async fn release_task(&self, job_id: &str, chunk: i64, owner: &str) -> Result<(), sqlx::Error> {
        sqlx::query(
            "UPDATE tasks SET state = 'queued', lease_owner = NULL, lease_until = NULL \
             WHERE job_id = $1 AND chunk = $2 AND lease_owner = $3 AND state = 'running'",
        )
        .bind(job_id)
        .bind(chunk)
        .bind(owner)
        .execute(&self.pool)
        .await?;
        Ok(())
    }

    /// Where a job's chunks `chunks` are: how many there are and are done (counted in the
    /// database, no outputs read), and the reason of the first that failed. Only those chunks: a
    /// job taken up again may find later chunks of its earlier attempt, which are not waited on.
    pub async fn task_tally(&self, job_id: &str, chunks: Range<i64>) -> Result<TaskTally, sqlx::Error> {
        let counts = sqlx::query(
            "SELECT COUNT(*) AS total, COALESCE(SUM(CASE WHEN state = 'done' THEN 1 ELSE 0 END), 0) AS done \
             FROM tasks WHERE job_id = $1 AND chunk >= $2 AND chunk < $3",
        )
        .bind(job_id)
        .bind(chunks.start)
        .bind(chunks.end)
        .fetch_one(&self.pool)
        .await?;
        let failure = sqlx::query(
            "SELECT result FROM tasks WHERE job_id = $1 AND chunk >= $2 AND chunk < $3 AND state = 'failed' \
             ORDER BY chunk LIMIT 1",
        )
        .bind(job_id)
        .bind(chunks.start)
        .bind(chunks.end)
        .fetch_optional(&self.pool)
        .await?;
        Ok(TaskTally {
            total: counts.try_get("total")?,
            done: counts.try_get("done")?,
            failure: failure.map(|row| row.try_get("result")).transpose()?,
        })
    }

    /// The outputs of a job's done chunks `chunks`, by chunk.
    pub async fn task_results(&self, job_id: &str, chunks: Range<i64>) -> Result<Vec<String>, sqlx::Error> {
        let rows = sqlx::query(
            "SELECT result FROM tasks WHERE job_id = $1 AND chunk >= $2 AND chunk < $3 AND state = 'done' ORDER BY chunk",
        )
        .bind(job_id)
        .bind(chunks.start)
        .bind(chunks.end)
        .fetch_all(&self.pool)
        .await?;
        rows.iter().map(|r| r.try_get("result")).collect()
    }
}
