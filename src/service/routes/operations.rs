//! Long work as operations: state, progress, cancellation.

use super::{ApiQuery, Page};
use crate::analysis::ValidationReport;
use crate::progress::Progress;
use crate::service::AppState;
use crate::service::analyses::AnalysisAnswer;
use crate::service::error::{ApiError, ProblemDetails};
use crate::service::exceedance::ExceedanceAnswer;
use crate::service::store::JobRow;
use crate::service::work::{Job, OperationKind};
use axum::Json;
use axum::extract::{Path, State};
use axum::response::sse::{Event, KeepAlive, Sse};
use futures_util::Stream;
use serde::{Deserialize, Serialize};
use std::convert::Infallible;
use std::time::Duration;
use utoipa::ToSchema;
use utoipa_axum::router::OpenApiRouter;
use utoipa_axum::routes;

/// Seconds a client should wait before opening an event stream again when all are taken.
const STREAMS_FULL_RETRY_S: u64 = 5;

pub fn router() -> OpenApiRouter<AppState> {
    OpenApiRouter::new()
        .routes(routes!(list_operations))
        .routes(routes!(get_operation))
        .routes(routes!(cancel_operation))
        .routes(routes!(operation_events))
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, ToSchema)]
#[serde(rename_all = "snake_case")]
pub enum OperationState {
    Queued,
    Running,
    Succeeded,
    Failed,
    Cancelled,
}

/// What a finished operation produced besides a metamodel.
#[derive(Debug, Clone, Serialize, ToSchema)]
#[serde(untagged)]
pub enum OperationResult {
    Validation(Box<ValidationReport>),
    Exceedance(Box<ExceedanceAnswer>),
    Analysis(Box<AnalysisAnswer>),
}

/// Long-running work: a calibration, a validation, or a large or certified sampling request.
#[derive(Debug, Clone, Serialize, ToSchema)]
pub struct Operation {
    pub id: String,
    pub kind: OperationKind,
    pub state: OperationState,
    /// Whether the state is final (succeeded, failed or cancelled).
    pub done: bool,
    /// The latest progress report, saved every second while it runs.
    pub progress: Option<Progress>,
    /// Why it failed.
    pub error: Option<String>,
    /// The metamodel a succeeded calibration stored, or the one a validation or analysis works on.
    pub metamodel_id: Option<String>,
    /// The report of a succeeded validation, or the answer of a succeeded sampling request.
    pub result: Option<OperationResult>,
    /// How many times a worker took it up (more than one after a restart or a lost lease).
    pub attempts: i64,
    pub created_at_ms: i64,
    pub started_at_ms: Option<i64>,
    pub finished_at_ms: Option<i64>,
    /// Wall time from start to finish.
    pub seconds: Option<f64>,
}

#[derive(Debug, Serialize, ToSchema)]
pub struct OperationList {
    pub operations: Vec<Operation>,
    pub limit: i64,
    pub offset: i64,
}

fn stored<T: serde::de::DeserializeOwned>(text: &str) -> Result<T, ApiError> {
    serde_json::from_str(text).map_err(ApiError::internal)
}

/// The public view of a job.
pub fn operation(row: &JobRow) -> Result<Operation, ApiError> {
    let job = Job::stored(&row.kind, &row.request)?;
    let kind = job.kind();
    let state: OperationState = stored(&format!("\"{}\"", row.state))?;
    let result = match (&row.result, kind) {
        (None, _) | (Some(_), OperationKind::Calibration) => None,
        (Some(text), OperationKind::Validation) => Some(OperationResult::Validation(stored(text)?)),
        (Some(text), OperationKind::Exceedance) => Some(OperationResult::Exceedance(stored(text)?)),
        (
            Some(text),
            OperationKind::Hazard
            | OperationKind::Fragility
            | OperationKind::Sensitivity
            | OperationKind::Serviceability
            | OperationKind::Sweep,
        ) => Some(OperationResult::Analysis(stored(text)?)),
    };
    Ok(Operation {
        id: row.id.clone(),
        kind,
        state,
        done: matches!(state, OperationState::Succeeded | OperationState::Failed | OperationState::Cancelled),
        progress: row.progress.as_deref().map(stored).transpose()?,
        error: row.error.clone(),
        metamodel_id: match &job {
            Job::Calibration(_) => row.metamodel_id.clone(),
            other => other.metamodel_id().map(str::to_string),
        },
        result,
        attempts: row.attempts,
        created_at_ms: row.created_at,
        started_at_ms: row.started_at,
        finished_at_ms: row.finished_at,
        seconds: row.started_at.zip(row.finished_at).map(|(s, f)| (f - s) as f64 / 1000.0),
    })
}

/// Operations, newest first.
#[utoipa::path(get, path = "/v1/operations", tag = "operations", params(Page),
    responses(
        (status = 200, description = "A page of operations", body = OperationList),
        (status = 422, description = "limit or offset out of range", body = ProblemDetails, content_type = "application/problem+json"),
    ))]
async fn list_operations(
    State(state): State<AppState>,
    ApiQuery(page): ApiQuery<Page>,
) -> Result<Json<OperationList>, ApiError> {
    page.check()?;
    let rows = state.store.jobs(page.limit, page.offset).await?;
    let operations = rows.iter().map(operation).collect::<Result<_, _>>()?;
    Ok(Json(OperationList { operations, limit: page.limit, offset: page.offset }))
}

/// One operation: state, progress, timings and, once done, its outcome.
#[utoipa::path(get, path = "/v1/operations/{id}", tag = "operations",
    params(("id" = String, Path, description = "Operation id")),
    responses(
        (status = 200, description = "The operation", body = Operation),
        (status = 404, description = "No such operation", body = ProblemDetails, content_type = "application/problem+json"),
    ))]
async fn get_operation(State(state): State<AppState>, Path(id): Path<String>) -> Result<Json<Operation>, ApiError> {
    let row = state.store.job(&id).await?.ok_or_else(|| ApiError::not_found("operation", &id))?;
    Ok(Json(operation(&row)?))
}

/// Cancels an operation: a queued one at once, a running one within about a second (between
/// experiments or samples). Cancelling a finished operation changes nothing.
#[utoipa::path(post, path = "/v1/operations/{id}/cancel", tag = "operations",
    params(("id" = String, Path, description = "Operation id")),
    responses(
        (status = 200, description = "The operation after the request", body = Operation),
        (status = 404, description = "No such operation", body = ProblemDetails, content_type = "application/problem+json"),
    ))]
async fn cancel_operation(State(state): State<AppState>, Path(id): Path<String>) -> Result<Json<Operation>, ApiError> {
    let row = state.store.request_cancel(&id).await?.ok_or_else(|| ApiError::not_found("operation", &id))?;
    Ok(Json(operation(&row)?))
}

/// The operation as server-sent events: one `operation` event (an `Operation` as JSON) whenever it
/// changes, the stream ending when it is done. It reads the database, so any replica can serve it.
#[utoipa::path(get, path = "/v1/operations/{id}/events", tag = "operations",
    params(("id" = String, Path, description = "Operation id")),
    responses(
        (status = 200, description = "`operation` events, each an Operation as JSON (schema `OperationEvent`)", content_type = "text/event-stream", body = String),
        (status = 404, description = "No such operation", body = ProblemDetails, content_type = "application/problem+json"),
        (status = 503, description = "Too many event streams are open on this server, or the database does not answer now", body = ProblemDetails, content_type = "application/problem+json",
            headers(("Retry-After" = u64, description = "Seconds before trying again"))),
    ))]
async fn operation_events(
    State(state): State<AppState>,
    Path(id): Path<String>,
) -> Result<Sse<impl Stream<Item = Result<Event, Infallible>>>, ApiError> {
    state.store.job(&id).await?.ok_or_else(|| ApiError::not_found("operation", &id))?;
    // Each open stream polls the database; the permit, dropped with the stream, bounds them.
    let permit = state.streams.clone().try_acquire_owned().map_err(|_| {
        ApiError::unavailable(
            format!(
                "{} event streams are open on this server; poll the operation instead",
                state.config.max_event_streams
            ),
            STREAMS_FULL_RETRY_S,
        )
    })?;
    let stream = futures_util::stream::unfold(
        (state, id, None::<String>, false, permit),
        |(state, id, last, finished, permit)| async move {
            if finished {
                return None;
            }
            loop {
                // A failed read (a busy database) is retried; a deleted operation ends the stream.
                let value = match state.store.job(&id).await {
                    Ok(None) => return None,
                    Ok(Some(row)) => operation(&row).ok(),
                    Err(_) => None,
                };
                if let Some(value) = value {
                    let text = serde_json::to_string(&value).expect("an operation serialises");
                    if last.as_deref() != Some(text.as_str()) {
                        return Some((
                            Ok(Event::default().event("operation").data(text.clone())),
                            (state, id, Some(text), value.done, permit),
                        ));
                    }
                }
                tokio::time::sleep(Duration::from_millis(500)).await;
            }
        },
    );
    Ok(Sse::new(stream).keep_alive(KeepAlive::default()))
}
