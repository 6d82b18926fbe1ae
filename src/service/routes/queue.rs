//! Queuing work: a job inserted under its idempotency key, answered 202 with its operation.

use super::operations;
use crate::service::AppState;
use crate::service::error::ApiError;
use crate::service::store::Enqueued;
use crate::service::work::Job;

/// How long a client should wait before offering work to a full queue again (s).
const QUEUE_FULL_RETRY_S: u64 = 30;

/// The request's `Idempotency-Key`, if it has one, checked against the contract's pattern: a
/// malformed key is refused (422) whether the request is then queued or answered at once.
pub fn idempotency_key(headers: &axum::http::HeaderMap) -> Result<Option<String>, ApiError> {
    match headers.get("idempotency-key") {
        None => Ok(None),
        Some(v) if (1..=255).contains(&v.len()) && v.as_bytes().iter().all(u8::is_ascii_graphic) => {
            Ok(Some(String::from_utf8_lossy(v.as_bytes()).into_owned()))
        }
        Some(_) => Err(crate::error::Error::invalid(
            "Idempotency-Key",
            "must be 1 to 255 visible ASCII characters without spaces",
        )
        .into()),
    }
}

/// Queues a job and answers 202 with its `Location`, honouring `Idempotency-Key`: a retry with the
/// same body gets the same operation, a different body under the same key is refused (422). A
/// full queue is 503 with `Retry-After`.
pub async fn accept_job(
    state: &AppState,
    headers: &axum::http::HeaderMap,
    job: Job,
) -> Result<axum::response::Response, ApiError> {
    use axum::http::{StatusCode, header};
    use axum::response::IntoResponse;
    let key = idempotency_key(headers)?;
    let new_id = uuid::Uuid::new_v4().to_string();
    let (kind, request) = (job.kind(), job.request_json());
    let idempotency = key.as_deref().map(|k| (k, job.idempotency_scope()));
    let max_queued = state.config.max_queued_jobs as i64;
    let keys_since = state.config.idempotency_keys_since_ms();
    let id = match state.store.insert_job(&new_id, kind.as_str(), &request, idempotency, keys_since, max_queued).await?
    {
        Enqueued::New => {
            tracing::info!(job = %new_id, kind = kind.as_str(), "job queued");
            state.wake.notify_one();
            new_id
        }
        Enqueued::Earlier { id, request: stored } if stored == request => id,
        Enqueued::Earlier { .. } => {
            return Err(
                crate::error::Error::invalid("Idempotency-Key", "was already used with a different request").into()
            );
        }
        Enqueued::QueueFull => {
            return Err(ApiError::unavailable(
                format!("{} jobs are waiting already; try again later", state.config.max_queued_jobs),
                QUEUE_FULL_RETRY_S,
            ));
        }
    };
    let row = state.store.job(&id).await?.ok_or_else(|| ApiError::internal("a queued job vanished"))?;
    Ok((
        StatusCode::ACCEPTED,
        [(header::LOCATION, format!("/v1/operations/{id}")), (header::RETRY_AFTER, "2".to_string())],
        axum::Json(operations::operation(&row)?),
    )
        .into_response())
}
