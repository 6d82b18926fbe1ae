//! Starting calibrations: checked at once, then queued as an operation.

use super::ApiJson;
use super::operations::operation;
use crate::service::error::ApiError;
use crate::service::{AppState, CalibrationRequest};
use axum::extract::State;
use axum::http::{StatusCode, header};
use axum::response::IntoResponse;
use axum::routing::post;
use axum::{Json, Router};

pub fn router() -> Router<AppState> {
    Router::new().route("/v1/calibrations", post(start))
}

/// 202 with the operation's `Location`; bad specs are refused now, not in the worker.
async fn start(
    State(state): State<AppState>,
    ApiJson(request): ApiJson<CalibrationRequest>,
) -> Result<impl IntoResponse, ApiError> {
    request.resolve(&state.config)?;
    let id = uuid::Uuid::new_v4().to_string();
    let text = serde_json::to_string(&request).expect("a request serialises");
    state.store.insert_job(&id, "calibration", &text).await?;
    state.wake.notify_one();
    let row = state.store.job(&id).await?.ok_or_else(|| ApiError::internal("a queued job vanished"))?;
    Ok((
        StatusCode::ACCEPTED,
        [(header::LOCATION, format!("/v1/operations/{id}")), (header::RETRY_AFTER, "2".to_string())],
        Json(operation(&row)),
    ))
}
