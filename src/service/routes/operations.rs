//! Long work as operations: state, progress, cancellation.

use super::Page;
use crate::service::AppState;
use crate::service::error::ApiError;
use crate::service::store::JobRow;
use axum::extract::{Path, Query, State};
use axum::response::sse::{Event, KeepAlive, Sse};
use axum::routing::{get, post};
use axum::{Json, Router};
use futures_util::Stream;
use serde_json::{Value, json};
use std::convert::Infallible;
use std::time::Duration;

pub fn router() -> Router<AppState> {
    Router::new()
        .route("/v1/operations", get(list))
        .route("/v1/operations/{id}", get(one))
        .route("/v1/operations/{id}/cancel", post(cancel))
        .route("/v1/operations/{id}/events", get(events))
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
        "result": row.result.as_deref().and_then(|r| serde_json::from_str::<Value>(r).ok()),
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

/// The operation as server-sent events: one `operation` event whenever it changes, the stream ending
/// when it is done. It reads the database, so any replica can serve it.
async fn events(
    State(state): State<AppState>,
    Path(id): Path<String>,
) -> Result<Sse<impl Stream<Item = Result<Event, Infallible>>>, ApiError> {
    state.store.job(&id).await?.ok_or_else(|| ApiError::not_found("operation", &id))?;
    let stream =
        futures_util::stream::unfold((state, id, None::<String>, false), |(state, id, last, finished)| async move {
            if finished {
                return None;
            }
            loop {
                let row = state.store.job(&id).await.ok().flatten()?;
                let value = operation(&row);
                let text = value.to_string();
                if last.as_deref() != Some(text.as_str()) {
                    let done = value["done"].as_bool().unwrap_or(false);
                    return Some((
                        Ok(Event::default().event("operation").data(text.clone())),
                        (state, id, Some(text), done),
                    ));
                }
                tokio::time::sleep(Duration::from_millis(500)).await;
            }
        });
    Ok(Sse::new(stream).keep_alive(KeepAlive::default()))
}
