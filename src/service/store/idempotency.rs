//! Idempotency keys: the first request under a key (for one endpoint) starts the work, a retry
//! within the keys' lifetime gets the same operation. Keys are recorded in the transaction that
//! queues the job; expired keys are ignored when looked up and pruned.

use super::{Store, now_ms};
use sqlx::{Any, Row, Transaction};

/// The operation and request first queued under (key, endpoint) since `keys_since_ms`; an older
/// use of the key has expired and is forgotten here.
pub(super) async fn earlier_use(
    tx: &mut Transaction<'_, Any>,
    key: &str,
    endpoint: &str,
    keys_since_ms: i64,
) -> Result<Option<(String, String)>, sqlx::Error> {
    sqlx::query("DELETE FROM idempotency WHERE idempotency_key = $1 AND endpoint = $2 AND created_at < $3")
        .bind(key)
        .bind(endpoint)
        .bind(keys_since_ms)
        .execute(&mut **tx)
        .await?;
    let earlier =
        sqlx::query("SELECT operation_id, request FROM idempotency WHERE idempotency_key = $1 AND endpoint = $2")
            .bind(key)
            .bind(endpoint)
            .fetch_optional(&mut **tx)
            .await?;
    earlier.map(|row| Ok((row.try_get("operation_id")?, row.try_get("request")?))).transpose()
}

/// Records that (key, endpoint) queued operation `id` for `request`.
pub(super) async fn record(
    tx: &mut Transaction<'_, Any>,
    key: &str,
    endpoint: &str,
    request: &str,
    id: &str,
) -> Result<(), sqlx::Error> {
    sqlx::query(
        "INSERT INTO idempotency (idempotency_key, endpoint, request, operation_id, created_at) VALUES ($1, $2, $3, $4, $5)",
    )
    .bind(key)
    .bind(endpoint)
    .bind(request)
    .bind(id)
    .bind(now_ms())
    .execute(&mut **tx)
    .await?;
    Ok(())
}

impl Store {
    /// Forgets the idempotency keys recorded before `keys_since_ms`; how many were pruned.
    pub async fn prune_idempotency(&self, keys_since_ms: i64) -> Result<u64, sqlx::Error> {
        let done = sqlx::query("DELETE FROM idempotency WHERE created_at < $1")
            .bind(keys_since_ms)
            .execute(&self.pool)
            .await?;
        Ok(done.rows_affected())
    }
}
