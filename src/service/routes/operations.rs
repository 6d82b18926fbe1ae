//! Long work as operations: state, progress, cancellation.

use super::Page;
use crate::service::AppState;
use crate::service::error::ApiError;
use crate::service::store::JobRow;
use axum::extract::{Path, Query, State};
use axum::routing::{get, post};
use axum::{Json, Router};
use serde_json::{Value, json};

pub fn router() -> Router<AppState> {
    Router::new()
        .route("/v1/operations", get(list))
        .route("/v1/operations/{id}", get(one))
        .route("/v1/operations/{id}/cancel", post(cancel))
}

/// The public view of a job.
pub fn operation(row: &JobRow) -> Value {
    let progress: Value = row.progress.as_deref().and_then(|p| serde_json::from_str(p).ok()).unwrap_or(Value::Null);
    json!({
        "id": row.id,
        "kind": row.kind,
        "state": row.state,
        "done": matches!(row.state.as_str(), "succeeded" | "failed" | "cancelled"),
        "progress": progress,
        "error": row.error,
        "metamodel_id": row.metamodel_id,
        "attempts": row.attempts,
        "created_at_ms": row.created_at,
        "started_at_ms": row.started_at,
        "finished_at_ms": row.finished_at,
        "seconds": row.started_at.zip(row.finished_at).map(|(s, f)| (f - s) as f64 / 1000.0),
    })
}

async fn list(State(state): State<AppState>, Query(page): Query<Page>) -> Result<Json<Value>, ApiError> {
    page.check()?;
    let rows = state.store.jobs(page.limit, page.offset).await?;
    Ok(Json(
        json!({"operations": rows.iter().map(operation).collect::<Vec<_>>(), "limit": page.limit, "offset": page.offset}),
    ))
}

async fn one(State(state): State<AppState>, Path(id): Path<String>) -> Result<Json<Value>, ApiError> {
    let row = state.store.job(&id).await?.ok_or_else(|| ApiError::not_found("operation", &id))?;
    Ok(Json(operation(&row)))
}

/// A queued job is cancelled at once; a running one stops within about a second.
async fn cancel(State(state): State<AppState>, Path(id): Path<String>) -> Result<Json<Value>, ApiError> {
    let row = state.store.request_cancel(&id).await?.ok_or_else(|| ApiError::not_found("operation", &id))?;
    Ok(Json(operation(&row)))
}
